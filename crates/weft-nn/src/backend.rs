//! Which burn backend the layers run on.
//!
//! burn 0.22 tensors carry their backend in their [`Device`], not in their type, so layers
//! are written once and the device picks the backend at run time:
//!
//! - default: burn's pure-Rust CPU backend **flex** ([`cpu`]), with autodiff for training
//!   ([`cpu_autodiff`]). The fused GAT kernel ([`crate::gat`]) and the sparse unpooling
//!   product ([`crate::sparse`]) have hand-written CPU implementations here;
//! - `wgpu` and `cuda` cargo features of this crate switch on burn's GPU backends
//!   (`Device::wgpu(..)`, `Device::cuda(..)`; `wgpu()` and `wgpu_autodiff()` here); every
//!   layer then takes the generic tensor path, which is the same code the tests compare the
//!   fused kernels with.

use burn::backend::DispatchDevice;
use burn::tensor::Device;

/// The flex CPU device, without autodiff (inference).
pub fn cpu() -> Device {
    Device::flex()
}

/// The flex CPU device with autodiff (training).
pub fn cpu_autodiff() -> Device {
    Device::flex().autodiff()
}

/// burn's wgpu device on the default adapter (wgpu prefers a discrete, "high power" GPU;
/// `CUBECL_WGPU_DEFAULT_DEVICE` overrides the choice), without autodiff; the graphics API
/// (Vulkan on Linux) is the runtime's to settle. Every layer takes the generic tensor path
/// there. Opening the device is lazy: the first tensor on it starts the runtime.
#[cfg(feature = "wgpu")]
pub fn wgpu() -> Device {
    Device::wgpu(burn::tensor::DeviceKind::DefaultDevice)
}

/// [`wgpu`] with autodiff (training).
#[cfg(feature = "wgpu")]
pub fn wgpu_autodiff() -> Device {
    wgpu().autodiff()
}

/// The flex CPU device seeded for deterministic parameter initialisation.
pub fn seeded(device: &Device, seed: u64) -> Device {
    device.seed(seed);
    device.clone()
}

/// Whether `device` runs on flex (with or without autodiff): the fused CPU kernels apply.
pub fn is_flex(device: &Device) -> bool {
    matches!(
        device.clone().inner().as_dispatch(),
        DispatchDevice::Flex(_)
    )
}

/// The name a GPU device's adapter gives itself (`NVIDIA H100 80GB HBM3`, say), opening the
/// device; `None` on flex, in a build without a GPU feature, or where the runtime reports none.
pub fn adapter_name(device: &Device) -> Option<String> {
    #[cfg(any(feature = "wgpu", feature = "cuda"))]
    {
        device
            .as_dispatch()
            .identity()
            .map(|identity| identity.name)
    }
    #[cfg(not(any(feature = "wgpu", feature = "cuda")))]
    {
        let _ = device;
        None
    }
}

/// Asks glibc's malloc to keep freed memory in the process instead of handing it back to the
/// kernel after every large free; returns whether the setting took (false off glibc).
///
/// Why: a training step allocates and frees megabyte-sized activation and gradient buffers
/// every iteration. With glibc's defaults a buffer above the dynamic mmap threshold is
/// mapped fresh and a large free trims the heap top, so the next step page-faults the same
/// memory back in: measured on one GAT layer at N = 4 000 (docs/nn.md), about 1 500 page
/// faults and several milliseconds of kernel time per forward + backward. Raising
/// `M_MMAP_THRESHOLD` (to glibc's maximum, 32 MiB) and `M_TRIM_THRESHOLD` (1 GiB) keeps
/// the pages mapped. Process-wide, so it is for binaries (training, inference, benches) to
/// call once at start-up, never called implicitly by a layer.
pub fn retain_freed_memory() -> bool {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // SAFETY: mallopt only changes malloc's tuning parameters; both values are in the
        // ranges glibc documents.
        unsafe {
            libc::mallopt(libc::M_MMAP_THRESHOLD, 32 << 20) == 1
                && libc::mallopt(libc::M_TRIM_THRESHOLD, 1 << 30) == 1
        }
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flex_is_recognised_with_and_without_autodiff() {
        assert!(is_flex(&cpu()));
        assert!(is_flex(&cpu_autodiff()));
        assert!(cpu_autodiff().is_autodiff());
    }

    #[test]
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    fn malloc_tuning_is_accepted() {
        assert!(retain_freed_memory());
    }
}
