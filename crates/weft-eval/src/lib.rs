//! Evaluation for weft (seed 000 §4): how far a model's garments are from the simulated
//! ground truth, compared with the no-learning LBS baseline and with the other pooling
//! variants of Table 1, and why a vertex moves the way it does (attribution, §4.1).

pub mod stats;
