//! Parameter initialisers named by seed 000 supplement §4: "Default Glorot initialization
//! is used for GAT blocks, while the Kaiming method is employed for LSTM and linear layers."

use burn::nn::Initializer;

/// Glorot / Xavier uniform (Glorot & Bengio 2010): `U(±√(6 / (fan_in + fan_out)))`.
pub fn glorot() -> Initializer {
    Initializer::XavierUniform { gain: 1.0 }
}

/// Kaiming / He uniform for ReLU layers (He et al. 2015): `U(±√2 · √(3 / fan_in))`.
pub fn kaiming() -> Initializer {
    Initializer::KaimingUniform {
        gain: std::f64::consts::SQRT_2,
        fan_out_only: false,
    }
}
