//! The recovery family: synthetic measured sweeps of known devices, each with its free
//! parameters, their true values, a start up to 50 % off inside the ranges and a noise seed,
//! all fixed before the fit ([`crate::fit::fit`]) was run on any of them (it was not developed
//! on them). `tests/fit_family.rs` fits every case and asserts the coverage of the 95 % intervals
//! and the law of the chi-square; `bench --fits` times every fit.
//!
//! The data are the stepped sweep of the true device over each sweep's grid
//! ([`model_values`]: what a stepped-sine measurement shows, not the fit's own model on the
//! branches), with Gaussian noise of standard deviation `noise_rel` times each true value
//! (stated to the fit) and, where a case measures them, the impact onset and the end of the
//! branch with a standard deviation of a quarter of the grid step (also stated).
//!
//! | devices | cases |
//! |---|---|
//! | piezoelectric cantilever, one-sided linear stop (`data/examples/piezo_cantilever.toml`) | 1-12 |
//! | electromagnetic, asymmetric Hunt-Crossley and Hertz stops (`data/examples/em_asymmetric.toml`, mechanical damping 0.2 N s/m) | 13-16 |
//! | electrostatic comb pair, the paper's prototype 2 at 10 V (`data/prototype2.toml`, gap 9 um) | 17-20 |
//! | the piezoelectric cantilever with a rigid stop (restitution 0.7): jumps at grazing | 21-22 |

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::{model_values, Direction, Feature, FeatureKind, FitError, Point, Quantity, SweepData};
use crate::device::{Device, ParamError, ParamRange};
use crate::num::gaussian::box_muller_cosine;

const PIEZO: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/data/examples/piezo_cantilever.toml"
));
const EM: &str = include_str!(concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/data/examples/em_asymmetric.toml"
));
const P2: &str = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/prototype2.toml"));

/// The piezoelectric cantilever of `data/examples/piezo_cantilever.toml` with its stopper
/// rigid: an instantaneous impact with restitution 0.7 instead of the stiff spring.
const PIEZO_RIGID: &str = r#"
name = "piezo_rigid"
params = "hypothetical"
description = "The piezoelectric cantilever of piezo_cantilever.toml with a rigid stopper (restitution 0.7)"

[mechanics]
mass_kg = 5e-3
stiffness_n_per_m = 2842.0
damping_n_s_per_m = 0.0754

[stops.upper]
gap_m = 0.1e-3
law = "restitution"
coefficient = 0.7

[transducer]
kind = "piezoelectric"
coupling_n_per_v = 2.67e-3
capacitance_f = 50e-9
load_resistance_ohm = 26.5e3
"#;

/// Which device a case is made from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Base {
    /// `data/examples/piezo_cantilever.toml`.
    Piezo,
    /// `data/examples/em_asymmetric.toml` with a mechanical damping of 0.2 N s/m (a quality
    /// factor near 16, so that a sweep settles in tens of periods).
    Em,
    /// `data/prototype2.toml` at 10 V (Figure 13's bias) with its gap at 9 um (inside the
    /// finger overlap, so that the gap can be free on both sides of its value).
    P2,
    /// The piezoelectric cantilever with a rigid stopper (`PIEZO_RIGID`).
    PiezoRigid,
}

impl Base {
    /// The device before the case's true values are set.
    pub fn device(self) -> Result<Device, ParamError> {
        match self {
            Base::Piezo => Device::from_toml_str(PIEZO, "piezo_cantilever.toml"),
            Base::Em => Device::from_toml_str(EM, "em_asymmetric.toml")?
                .with_param("mechanics.damping_n_s_per_m", 0.2),
            Base::P2 => Device::from_toml_str(P2, "prototype2.toml")?
                .with_param("transducer.bias_v", 10.0)?
                .with_param("stops.both.gap_m", 9e-6),
            Base::PiezoRigid => Device::from_toml_str(PIEZO_RIGID, "piezo_rigid"),
        }
    }
}

/// One synthetic sweep of a case.
#[derive(Debug, Clone, PartialEq)]
pub struct SyntheticSweep {
    /// Up or down.
    pub direction: Direction,
    /// RMS acceleration (g).
    pub accel_rms_g: f64,
    /// Lowest and highest frequency of the grid (Hz).
    pub span_hz: (f64, f64),
    /// Grid step (Hz).
    pub step_hz: f64,
    /// The measured quantity.
    pub quantity: Quantity,
    /// The measured features (onset, branch end), if any.
    pub features: &'static [FeatureKind],
}

/// One case of the family.
#[derive(Debug, Clone, PartialEq)]
pub struct FamilyCase {
    /// Number (from 1) and what the case is.
    pub name: &'static str,
    /// The device.
    pub base: Base,
    /// The free parameters.
    pub free: Vec<ParamRange>,
    /// Their true values.
    pub truth: Vec<f64>,
    /// Their starting values (the device file's values of the fit).
    pub start: Vec<f64>,
    /// The sweeps.
    pub sweeps: Vec<SyntheticSweep>,
    /// Relative standard deviation of the noise on every value.
    pub noise_rel: f64,
    /// Seed of the noise (ChaCha8).
    pub seed: u64,
}

fn up(accel_rms_g: f64, lo: f64, hi: f64, step_hz: f64) -> SyntheticSweep {
    SyntheticSweep {
        direction: Direction::Up,
        accel_rms_g,
        span_hz: (lo, hi),
        step_hz,
        quantity: Quantity::V1RmsV,
        features: &[],
    }
}

fn down(accel_rms_g: f64, lo: f64, hi: f64, step_hz: f64) -> SyntheticSweep {
    SyntheticSweep {
        direction: Direction::Down,
        ..up(accel_rms_g, lo, hi, step_hz)
    }
}

fn features(s: SyntheticSweep, features: &'static [FeatureKind]) -> SyntheticSweep {
    SyntheticSweep { features, ..s }
}

fn r(path: &str, lo: f64, hi: f64) -> ParamRange {
    ParamRange::auto(path, lo, hi)
}

const GAP_U: &str = "stops.upper.gap_m";
const BIM_U: &str = "stops.upper.damping_n_s_per_m";
const ONSET_END: &[FeatureKind] = &[FeatureKind::Onset, FeatureKind::BranchEnd];
const END: &[FeatureKind] = &[FeatureKind::BranchEnd];

#[allow(clippy::too_many_arguments)]
fn case(
    name: &'static str,
    base: Base,
    free: Vec<ParamRange>,
    truth: &[f64],
    start: &[f64],
    sweeps: Vec<SyntheticSweep>,
    noise_rel: f64,
    seed: u64,
) -> FamilyCase {
    FamilyCase {
        name,
        base,
        free,
        truth: truth.to_vec(),
        start: start.to_vec(),
        sweeps,
        noise_rel,
        seed,
    }
}

/// The piezoelectric cases (1-12).
fn piezo_cases() -> Vec<FamilyCase> {
    let gb = || vec![r(GAP_U, 0.05e-3, 0.3e-3), r(BIM_U, 0.05, 5.0)];
    let p = Base::Piezo;
    vec![
        case(
            "1 piezo up, jump between points, from the file's values",
            p,
            gb(),
            &[0.12e-3, 0.8],
            &[0.1e-3, 0.5],
            vec![up(0.5, 100.0, 160.0, 2.0)],
            0.02,
            4901,
        ),
        case(
            "2 piezo up, 0.5 % noise, from +50 %, -50 %",
            p,
            gb(),
            &[0.08e-3, 0.3],
            &[0.12e-3, 0.15],
            vec![up(0.3, 100.0, 150.0, 2.0)],
            0.005,
            4902,
        ),
        case(
            "3 piezo up with onset and jump, 5 % noise",
            p,
            gb(),
            &[0.15e-3, 1.5],
            &[0.09e-3, 2.25],
            vec![features(up(0.6, 100.0, 170.0, 2.0), ONSET_END)],
            0.05,
            4903,
        ),
        case(
            "4 piezo down-sweep",
            p,
            gb(),
            &[0.11e-3, 0.6],
            &[0.14e-3, 0.35],
            vec![down(0.5, 100.0, 160.0, 2.0)],
            0.02,
            4904,
        ),
        case(
            "5 piezo up, the gap alone",
            p,
            vec![r(GAP_U, 0.05e-3, 0.3e-3)],
            &[0.1e-3],
            &[0.14e-3],
            vec![up(0.4, 100.0, 160.0, 2.5)],
            0.01,
            4905,
        ),
        case(
            "6 piezo up, gap, stop and mechanical damping",
            p,
            vec![
                r(GAP_U, 0.05e-3, 0.3e-3),
                r(BIM_U, 0.05, 5.0),
                r("mechanics.damping_n_s_per_m", 0.03, 0.3),
            ],
            &[0.12e-3, 0.8, 0.0754],
            &[0.09e-3, 1.1, 0.1],
            vec![up(0.5, 100.0, 160.0, 2.0)],
            0.01,
            4906,
        ),
        case(
            "7 piezo up and down, gap, damping and acceleration factor",
            p,
            vec![
                r(GAP_U, 0.05e-3, 0.3e-3),
                r(BIM_U, 0.05, 5.0),
                r(super::ACCEL_SCALE_PATH, 0.7, 1.4),
            ],
            &[0.1e-3, 0.5, 1.1],
            &[0.13e-3, 0.7, 1.0],
            vec![up(0.5, 100.0, 160.0, 2.0), down(0.5, 100.0, 160.0, 2.0)],
            0.02,
            4907,
        ),
        case(
            "8 piezo up, gap and stop stiffness",
            p,
            vec![
                r(GAP_U, 0.05e-3, 0.3e-3),
                r("stops.upper.stiffness_n_per_m", 5e3, 2e5),
            ],
            &[0.1e-3, 28420.0],
            &[0.14e-3, 15000.0],
            vec![up(0.5, 100.0, 160.0, 2.0)],
            0.03,
            4908,
        ),
        case(
            "9 piezo up, wide gap at 0.8 g",
            p,
            gb(),
            &[0.2e-3, 0.2],
            &[0.12e-3, 0.3],
            vec![up(0.8, 100.0, 170.0, 2.5)],
            0.03,
            4909,
        ),
        case(
            "10 piezo up, power measured",
            p,
            gb(),
            &[0.09e-3, 2.0],
            &[0.13e-3, 1.2],
            vec![SyntheticSweep {
                quantity: Quantity::PTotalW,
                ..up(0.4, 100.0, 160.0, 2.0)
            }],
            0.04,
            4910,
        ),
        case(
            "11 piezo down, the stop damping alone",
            p,
            vec![r(BIM_U, 0.05, 5.0)],
            &[1.0],
            &[0.6],
            vec![down(0.5, 100.0, 160.0, 2.0)],
            0.005,
            4911,
        ),
        case(
            "12 piezo up, 5 Hz steps",
            p,
            gb(),
            &[0.1e-3, 0.5],
            &[0.07e-3, 0.75],
            vec![up(0.5, 100.0, 170.0, 5.0)],
            0.02,
            4912,
        ),
    ]
}

/// The electromagnetic, electrostatic and rigid-stop cases (13-22).
fn other_cases() -> Vec<FamilyCase> {
    let em = Base::Em;
    let es = Base::P2;
    let gap2 = || {
        vec![
            r("stops.both.gap_m", 6e-6, 9.95e-6),
            r("stops.both.damping_n_s_per_m", 0.1, 2.0),
        ]
    };
    let rigid = Base::PiezoRigid;
    vec![
        case(
            "13 em up, both gaps",
            em,
            vec![r(GAP_U, 0.5e-3, 2e-3), r("stops.lower.gap_m", 0.7e-3, 3e-3)],
            &[1e-3, 1.5e-3],
            &[1.3e-3, 1.1e-3],
            vec![up(1.0, 40.0, 70.0, 1.0)],
            0.02,
            4913,
        ),
        case(
            "14 em down, the upper gap alone",
            em,
            vec![r(GAP_U, 0.5e-3, 2e-3)],
            &[1e-3],
            &[0.7e-3],
            vec![down(1.0, 40.0, 70.0, 1.0)],
            0.01,
            4914,
        ),
        case(
            "15 em up with onset and jump, gap and mechanical damping",
            em,
            vec![
                r(GAP_U, 0.5e-3, 2e-3),
                r("mechanics.damping_n_s_per_m", 0.05, 0.8),
            ],
            &[1.1e-3, 0.2],
            &[0.8e-3, 0.28],
            vec![features(up(1.0, 40.0, 70.0, 1.0), ONSET_END)],
            0.03,
            4915,
        ),
        case(
            "16 em up, gap and transduction, 5 % noise",
            em,
            vec![
                r(GAP_U, 0.5e-3, 2e-3),
                r("transducer.transduction_n_per_a", 2.0, 10.0),
            ],
            &[1e-3, 5.0],
            &[1.4e-3, 3.5],
            vec![up(1.0, 40.0, 70.0, 1.0)],
            0.05,
            4916,
        ),
        case(
            "17 prototype 2 up, gap and stop damping",
            es,
            gap2(),
            &[9e-6, 0.4],
            &[7e-6, 0.6],
            vec![up(0.31, 640.0, 760.0, 4.0)],
            0.02,
            4917,
        ),
        case(
            "18 prototype 2 up, mechanical damping and gap",
            es,
            vec![
                r("mechanics.damping_n_s_per_m", 1e-5, 1e-4),
                r("stops.both.gap_m", 6e-6, 9.95e-6),
            ],
            &[2.5e-5, 9e-6],
            &[3.5e-5, 7.5e-6],
            vec![up(0.31, 640.0, 760.0, 4.0)],
            0.01,
            4918,
        ),
        case(
            "19 prototype 2 down, gap and stop damping",
            es,
            gap2(),
            &[9e-6, 0.4],
            &[8e-6, 0.25],
            vec![down(0.31, 640.0, 760.0, 4.0)],
            0.02,
            4919,
        ),
        case(
            "20 prototype 2 up with the jump, gap, damping and acceleration factor",
            es,
            {
                let mut f = gap2();
                f.push(r(super::ACCEL_SCALE_PATH, 0.7, 1.4));
                f
            },
            &[9e-6, 0.4, 0.95],
            &[7.5e-6, 0.3, 1.15],
            vec![features(up(0.31, 640.0, 760.0, 4.0), END)],
            0.005,
            4920,
        ),
        case(
            "21 rigid stop up, gap and mechanical damping",
            rigid,
            vec![
                r(GAP_U, 0.05e-3, 0.3e-3),
                r("mechanics.damping_n_s_per_m", 0.03, 0.3),
            ],
            &[0.1e-3, 0.0754],
            &[0.13e-3, 0.05],
            vec![up(0.5, 100.0, 170.0, 2.0)],
            0.02,
            4921,
        ),
        case(
            "22 rigid stop down, the gap alone",
            rigid,
            vec![r(GAP_U, 0.05e-3, 0.3e-3)],
            &[0.12e-3],
            &[0.08e-3],
            vec![down(0.5, 100.0, 170.0, 2.0)],
            0.01,
            4922,
        ),
    ]
}

/// Every case of the family, in order.
pub fn recovery_family() -> Vec<FamilyCase> {
    let mut all = piezo_cases();
    all.extend(other_cases());
    all
}

fn with_values(d: &Device, free: &[ParamRange], values: &[f64]) -> Result<Device, ParamError> {
    free.iter()
        .filter(|f| f.path != super::ACCEL_SCALE_PATH)
        .zip(values)
        .try_fold(d.clone(), |d, (f, &v)| d.with_param(&f.path, v))
}

impl FamilyCase {
    /// The true acceleration factor (1 unless it is free).
    fn accel_scale(&self) -> f64 {
        self.free
            .iter()
            .zip(&self.truth)
            .find(|(f, _)| f.path == super::ACCEL_SCALE_PATH)
            .map_or(1.0, |(_, &v)| v)
    }

    /// The true device.
    pub fn truth_device(&self) -> Result<Device, FitError> {
        let (free, truth) = self.device_params(&self.truth);
        with_values(&self.base.device().map_err(bad)?, &free, &truth).map_err(bad)
    }

    /// The device the fit starts from.
    pub fn start_device(&self) -> Result<Device, FitError> {
        let (free, start) = self.device_params(&self.start);
        let mut d = with_values(&self.base.device().map_err(bad)?, &free, &start).map_err(bad)?;
        d.params = "start".into();
        Ok(d)
    }

    /// The device's own free parameters and `values` of them (the acceleration factor left
    /// out).
    fn device_params(&self, values: &[f64]) -> (Vec<ParamRange>, Vec<f64>) {
        self.free
            .iter()
            .zip(values)
            .filter(|(f, _)| f.path != super::ACCEL_SCALE_PATH)
            .map(|(f, &v)| (f.clone(), v))
            .unzip()
    }

    /// The case's measured sweeps (see the module docs).
    pub fn data(&self) -> Result<Vec<SweepData>, FitError> {
        let truth = self.truth_device()?;
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let mut out = Vec::new();
        for (k, s) in self.sweeps.iter().enumerate() {
            let n = ((s.span_hz.1 - s.span_hz.0) / s.step_hz).round() as usize;
            let mut freqs: Vec<f64> = (0..=n)
                .map(|i| s.span_hz.0 + s.step_hz * i as f64)
                .collect();
            if s.direction == Direction::Down {
                freqs.reverse();
            }
            let mid = 0.5 * (s.span_hz.0 + s.span_hz.1);
            let mut d = SweepData {
                label: format!("sweep {k}"),
                direction: s.direction,
                accel_rms_g: s.accel_rms_g,
                quantity: s.quantity,
                points: freqs
                    .iter()
                    .map(|&f| Point {
                        freq_hz: f,
                        value: 0.0,
                        sigma: None,
                    })
                    .collect(),
                grid_hz: None,
                features: s
                    .features
                    .iter()
                    .map(|&kind| Feature {
                        kind,
                        freq_hz: mid,
                        sigma_hz: 0.25 * s.step_hz,
                    })
                    .collect(),
            };
            let exact = model_values(&truth, self.accel_scale(), &d)?;
            for (p, &v) in d.points.iter_mut().zip(&exact) {
                let sigma = self.noise_rel * v.abs();
                p.value = v + sigma * box_muller_cosine(&mut rng);
                p.sigma = Some(sigma);
            }
            let np = d.points.len();
            for (f, &v) in d.features.iter_mut().zip(&exact[np..]) {
                f.freq_hz =
                    (v + f.sigma_hz * box_muller_cosine(&mut rng)).clamp(s.span_hz.0, s.span_hz.1);
            }
            out.push(d);
        }
        Ok(out)
    }
}

fn bad(error: ParamError) -> FitError {
    FitError::Param {
        path: "the family's device".into(),
        error,
    }
}
