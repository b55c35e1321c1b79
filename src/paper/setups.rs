//! The prototypes as the paper simulates them: bias voltage and end-stop model of each figure,
//! each said once, the two parameter sets of prototype 1, and the devices a figure runs on.

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::device::{
    AreaOverlapPair, Device, HertzLineStop, StiffnessModel, Stop, StopLaw, Transducer,
};
use crate::drive::noise::NoiseSpec;
use crate::study::record::RecordSpec;

/// Prototype 1, Figures 8-12 and Table 3: bias voltage (V).
pub const P1_BIAS_V: f64 = 30.0;

/// Prototype 2, Figures 14 and 15 and Table 3: bias voltage (V).
pub const P2_BIAS_V: f64 = 15.0;

/// Figure 13's bias voltage (V).
pub const FIG13_BIAS_V: f64 = 10.0;

/// Prototype 1 as Figures 8-12 simulate it: 30 V, Hertz contact (eq 6), b_im = 1.5 N s/m.
pub fn prototype1_setup(device: &Device) -> Device {
    with_endstop(&device.with_bias(P1_BIAS_V), StiffnessModel::Hertz, 1.5)
}

/// Prototype 2 as Figures 14 and 15 simulate it: 15 V, linear k_im (eq 19), b_im = 0.4 N s/m.
pub fn prototype2_setup(device: &Device) -> Device {
    with_endstop(&device.with_bias(P2_BIAS_V), StiffnessModel::Linear, 0.4)
}

/// A copy of one of the paper's devices whose Hertz line stops follow eq 6
/// ([`StiffnessModel::Hertz`]) or its linear fit of eq 19 ([`StiffnessModel::Linear`]), with
/// end-stop damping b_im = `damping_n_s_per_m`; other stops get the damping only where their
/// law takes it.
pub fn with_endstop(device: &Device, stiffness: StiffnessModel, damping_n_s_per_m: f64) -> Device {
    with_stops(device, |s| {
        if let StopLaw::HertzLine(h) = &mut s.law {
            h.linear_fit = stiffness == StiffnessModel::Linear;
        }
        if s.law.takes_viscous_damper() {
            s.damping_n_s_per_m = damping_n_s_per_m;
        }
    })
}

/// The paper's random excitation (section 4): band-limited white noise of two-sided level
/// `psd_g2_per_hz` (g²/Hz), 10 kHz band, sampled at 100 kHz, 10 s.
pub fn paper_noise(psd_g2_per_hz: f64) -> NoiseSpec {
    NoiseSpec {
        psd_g2_per_hz,
        bandwidth_hz: 10e3,
        sample_rate_hz: 100e3,
        duration_s: 10.0,
    }
}

/// The paper's record: [`paper_noise`] at `psd_g2_per_hz`, 10 s analysed after the device's
/// pre-roll ([`RecordSpec::of`]).
pub fn paper_record(device: &Device, psd_g2_per_hz: f64) -> RecordSpec {
    RecordSpec::of(device, paper_noise(psd_g2_per_hz))
}

/// The parameter sets of prototype 1 under which its claims are scored: Tables 1 and 2 as
/// printed, and the set whose end-stop gap is fitted to Figure 8's measured kink
/// ([`crate::paper::calibration::calibrate_prototype1`]). In files it is its
/// [`label`](ParamSet::label).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ParamSet {
    /// Tables 1 and 2 as printed.
    Published,
    /// The end-stop gap fitted to the measured impact onset.
    Calibrated,
}

impl ParamSet {
    /// Both sets, published first.
    pub const BOTH: [ParamSet; 2] = [ParamSet::Published, ParamSet::Calibrated];

    /// The label of a file or table that holds both sets.
    pub const BOTH_LABEL: &'static str = "published+calibrated";

    /// The label of the set in files, the scorecard and the book.
    pub fn label(self) -> &'static str {
        match self {
            ParamSet::Published => "published",
            ParamSet::Calibrated => "calibrated",
        }
    }

    /// The position of the set in [`ParamSet::BOTH`] (runs of both sets keep that order).
    pub fn index(self) -> usize {
        match self {
            ParamSet::Published => 0,
            ParamSet::Calibrated => 1,
        }
    }
}

impl fmt::Display for ParamSet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.label())
    }
}

/// Both prototypes as their parameter files give them (Figure 5, Table 3).
#[derive(Debug, Clone, PartialEq)]
pub struct Prototypes {
    /// Prototype 1 as published.
    pub prototype1: Device,
    /// Prototype 2 as published.
    pub prototype2: Device,
}

/// Prototype 1 under both parameter sets, as loaded (the figures set bias and end-stop
/// model themselves): Figures 8, 9, 11 and 12.
#[derive(Debug, Clone, PartialEq)]
pub struct Prototype1Sets {
    /// Tables 1 and 2 as printed.
    pub published: Device,
    /// The end-stop gap fitted to the measured impact onset.
    pub calibrated: Device,
}

impl Prototype1Sets {
    /// The device of a set.
    pub fn get(&self, set: ParamSet) -> &Device {
        match set {
            ParamSet::Published => &self.published,
            ParamSet::Calibrated => &self.calibrated,
        }
    }

    /// Both sets with their devices, in the order of [`ParamSet::BOTH`].
    pub fn each(&self) -> [(ParamSet, &Device); 2] {
        ParamSet::BOTH.map(|s| (s, self.get(s)))
    }
}

/// A device that cannot stand in for one of the paper's prototypes.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "device `{device}`: {what}; the paper's figures and calibration need an area-overlap comb \
     pair and the same Hertz line stop on both sides"
)]
pub struct TopologyError {
    /// The device's name.
    pub device: String,
    /// What it has instead.
    pub what: String,
}

/// Checks that a device has the paper's topology, which [`comb`], [`endstop`] and
/// [`hertz_stop`] assume (and panic without): an area-overlap comb pair, and one Hertz line
/// stop for both sides. The entry points that take a device from a user call it first.
pub fn check_topology(d: &Device) -> Result<(), TopologyError> {
    let err = |what: String| TopologyError {
        device: d.name.clone(),
        what,
    };
    if !matches!(d.transducer, Transducer::AreaOverlapPair(_)) {
        return Err(err(format!("its transducer is `{}`", d.transducer.key())));
    }
    let Some(stop) = d.stops.symmetric() else {
        return Err(err("its two stops differ or one is missing".into()));
    };
    if !matches!(stop.law, StopLaw::HertzLine(_)) {
        return Err(err(format!("its stops are `{}`", stop.law.key())));
    }
    Ok(())
}

/// The comb pair of one of the paper's devices (eqs 7-10).
///
/// # Panics
/// When the device is not of the paper's topology (the paper layer only reads
/// `data/prototype1.toml` and `data/prototype2.toml`).
pub fn comb(d: &Device) -> &AreaOverlapPair {
    match &d.transducer {
        Transducer::AreaOverlapPair(p) => p,
        other => panic!(
            "the paper's devices have an area-overlap pair, not `{}`",
            other.key()
        ),
    }
}

/// The comb pair of one of the paper's devices, to change it (see [`comb`]).
pub fn comb_mut(d: &mut Device) -> &mut AreaOverlapPair {
    match &mut d.transducer {
        Transducer::AreaOverlapPair(p) => p,
        other => panic!(
            "the paper's devices have an area-overlap pair, not `{}`",
            other.key()
        ),
    }
}

/// The end-stop of one of the paper's devices: one stop for both sides (eqs 1-2).
///
/// # Panics
/// When the device's two stops differ or one is missing.
pub fn endstop(d: &Device) -> &Stop {
    d.stops
        .symmetric()
        .expect("the paper's devices have one end-stop for both sides")
}

/// The Hertz line law of one of the paper's devices (eq 6, with its fit of eq 19).
///
/// # Panics
/// When the device's stop is not a Hertz line stop.
pub fn hertz_stop(d: &Device) -> &HertzLineStop {
    match &endstop(d).law {
        StopLaw::HertzLine(h) => h,
        other => panic!(
            "the paper's end-stops are Hertz line stops, not `{}`",
            other.key()
        ),
    }
}

/// A copy of one of the paper's devices with both stops changed by `f`.
pub fn with_stops(d: &Device, f: impl FnMut(&mut Stop)) -> Device {
    let mut d = d.clone();
    d.stops.for_each_mut(f);
    d
}

/// A copy of one of the paper's devices with both stops' Hertz line law changed by `f`.
pub fn with_hertz(d: &Device, mut f: impl FnMut(&mut HertzLineStop)) -> Device {
    with_stops(d, |s| {
        if let StopLaw::HertzLine(h) = &mut s.law {
            f(h)
        }
    })
}

/// Which law the Hertz line stops of one of the paper's devices follow: eq 6 or eq 19.
pub fn stiffness_model(d: &Device) -> StiffnessModel {
    if hertz_stop(d).linear_fit {
        StiffnessModel::Linear
    } else {
        StiffnessModel::Hertz
    }
}
