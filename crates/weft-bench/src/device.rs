//! Which device a bench runs on (`--device`), and how its timings wait for it.
//!
//! burn's GPU backends queue kernels and return before they have run, so a timing that
//! stopped the clock when the last call returned would measure the launches, not the work:
//! every timed run here ends in [`wait`] (the device's `sync`), or reads its result back
//! to the host, before the clock is read.

use burn::tensor::{Device, Tensor};
use serde::Serialize;

use crate::BenchError;

/// The device of a bench.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BenchDevice {
    /// burn's flex CPU backend (weft's fused CPU kernels apply).
    #[default]
    Cpu,
    /// burn's wgpu backend on the default adapter (generic tensor path); needs the
    /// `wgpu` feature of this crate (of weft-cli for the binary).
    Wgpu,
}

impl BenchDevice {
    /// Its name, as `--device` spells it.
    pub fn name(self) -> &'static str {
        match self {
            BenchDevice::Cpu => "cpu",
            BenchDevice::Wgpu => "wgpu",
        }
    }

    /// Whether this binary can open the device: wgpu needs the `wgpu` feature.
    pub fn check(self) -> Result<(), BenchError> {
        self.inference().map(drop)
    }

    /// The inference device (opening it is lazy: the first tensor starts the runtime).
    pub fn inference(self) -> Result<Device, BenchError> {
        match self {
            BenchDevice::Cpu => Ok(weft_nn::backend::cpu()),
            BenchDevice::Wgpu => {
                #[cfg(feature = "wgpu")]
                {
                    Ok(weft_nn::backend::wgpu())
                }
                #[cfg(not(feature = "wgpu"))]
                {
                    Err(BenchError::Option {
                        what: "--device",
                        message: "wgpu: this binary was built without the `wgpu` feature; \
                                  build it with `cargo build --release -p weft-cli --features \
                                  wgpu`"
                            .to_string(),
                    })
                }
            }
        }
    }

    /// The training device: [`BenchDevice::inference`] with autodiff.
    pub fn autodiff(self) -> Result<Device, BenchError> {
        Ok(self.inference()?.autodiff())
    }
}

impl std::fmt::Display for BenchDevice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A table cell naming the device and, where known, its adapter: `wgpu (NVIDIA H200)`.
pub fn label(device: BenchDevice, adapter: &Option<String>) -> String {
    match adapter {
        Some(name) => format!("{device} ({name})"),
        None => device.to_string(),
    }
}

/// Waits until `device` has run every operation queued on it (a no-op on flex, which runs
/// each operation as it is called). An execution error is reported, not swallowed.
pub fn wait(device: &Device) -> Result<(), BenchError> {
    device
        .sync()
        .map_err(|e| BenchError::Device(format!("{e:?}")))
}

/// Waits for the operations that computed `t` on its device, without reading it back.
pub fn wait_for<const D: usize>(t: Tensor<D>) -> Result<(), BenchError> {
    let device = t.device();
    drop(t);
    wait(&device)
}
