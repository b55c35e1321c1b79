//! The prototypes as the paper simulates them: bias voltage and end-stop model of each figure,
//! each said once, and the two parameter sets of prototype 1.

use crate::device::{Device, StiffnessModel};

/// Prototype 1, Figures 8-12 and Table 3: bias voltage (V).
pub const P1_BIAS_V: f64 = 30.0;

/// Prototype 2, Figures 14 and 15 and Table 3: bias voltage (V).
pub const P2_BIAS_V: f64 = 15.0;

/// Figure 13's bias voltage (V).
pub const FIG13_BIAS_V: f64 = 10.0;

/// Prototype 1 as Figures 8-12 simulate it: 30 V, Hertz contact (eq 6), b_im = 1.5 N s/m.
pub fn prototype1_setup(device: &Device) -> Device {
    device
        .with_bias(P1_BIAS_V)
        .with_endstop(StiffnessModel::Hertz, 1.5)
}

/// Prototype 2 as Figures 14 and 15 simulate it: 15 V, linear k_im (eq 19), b_im = 0.4 N s/m.
pub fn prototype2_setup(device: &Device) -> Device {
    device
        .with_bias(P2_BIAS_V)
        .with_endstop(StiffnessModel::Linear, 0.4)
}

/// The parameter sets of prototype 1 under which its claims are scored: Tables 1 and 2 as
/// printed, and the set whose end-stop gap is fitted to Figure 8's measured kink
/// ([`crate::paper::calibration::calibrate_prototype1`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ParamSet {
    /// Tables 1 and 2 as printed.
    Published,
    /// The end-stop gap fitted to the measured impact onset.
    Calibrated,
}

impl ParamSet {
    /// Both sets, published first.
    pub const BOTH: [ParamSet; 2] = [ParamSet::Published, ParamSet::Calibrated];

    /// The label of the set in files, the scorecard and the book.
    pub fn label(self) -> &'static str {
        match self {
            ParamSet::Published => "published",
            ParamSet::Calibrated => "calibrated",
        }
    }
}
