//! Which burn backend the layers run on.
//!
//! burn 0.22 tensors carry their backend in their [`Device`], not in their type, so layers
//! are written once and the device picks the backend at run time:
//!
//! - default: burn's pure-Rust CPU backend **flex** ([`cpu`]), with autodiff for training
//!   ([`cpu_autodiff`]). The fused GAT kernel ([`crate::gat`]) and the sparse unpooling
//!   product ([`crate::sparse`]) have hand-written CPU implementations here;
//! - `wgpu` and `cuda` cargo features of this crate switch on burn's GPU backends
//!   (`Device::wgpu(..)`, `Device::cuda(..)`); every layer then takes the generic tensor
//!   path, which is the same code the tests compare the fused kernels with.

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flex_is_recognised_with_and_without_autodiff() {
        assert!(is_flex(&cpu()));
        assert!(is_flex(&cpu_autodiff()));
        assert!(cpu_autodiff().is_autodiff());
    }
}
