//! The designer's inverse question: which values of a device's parameters, within ranges the
//! designer names, and which interface circuit deliver the most DC power under a given
//! vibration, within what the device survives.
//!
//! * **Objective**: the mean DC power the design delivers to its load (the storage's DC load
//!   behind a circuit, the resistive load otherwise) at its periodic steady state under a sine;
//!   over a band of frequencies, the worst of them ([`evaluate`]); or, under band-limited white
//!   noise, its mean over an ensemble of records on common random numbers, the answer
//!   confirmed on a fresh seed ([`noise`], [`Problem::with_noise`], [`Problem::confirm`]);
//!   or, over a measured acceleration record, its mean over that record, deterministic
//!   ([`record`], [`Problem::with_record`]).
//! * **Decision variables**: ranges of device-file keys ([`ParamRange`], as the fit and the
//!   Sobol study use them), with [`LOAD_PATH`] standing for whichever load the interface has;
//!   and a discrete choice among interface circuits, each searched in turn.
//! * **Constraints** ([`Limits`]): the largest impact speed, contact force, displacement and
//!   impacts per second, each read from the orbit. A design's violation is the sum of its
//!   relative exceedances, `sum max(0, value / limit - 1)`.
//! * **Answer** ([`Answer`]): the feasible design of most power, or, when no design the search
//!   tried meets every limit, [`Verdict::Infeasible`] with the least violating design, never an
//!   optimum.
//!
//! The search ([`search`]) samples the unit cube of the ranges by a scrambled Sobol sequence,
//! then polishes the best points by argmin's Nelder-Mead; the figures of merit a designer
//! reports are in [`merit`]. The interfaces come as a designer names them ([`interfaces`]);
//! the `endstop design` command and Python's `endstop.design` build their problem by
//! [`Problem::new`] and solve it by [`Problem::solve`].

pub mod evaluate;
pub mod interfaces;
pub mod merit;
pub mod noise;
pub mod record;
pub mod search;

use rayon::prelude::*;

use crate::device::{own_value, Device, Interface, ParamError, ParamRange};
use crate::progress::Progress;
use crate::study::periodic::SteadySettings;

pub use evaluate::{performance, EvalError, OrbitLimits, Performance};
pub use noise::NoiseObjective;
pub use record::RecordObjective;
pub use search::SearchSettings;

/// The path that stands for the design's load resistance, whatever its interface: the
/// transducer's `load_resistance_ohm` behind the resistive interface, the DC load's
/// `interface.load.resistance_ohm` behind a circuit.
pub const LOAD_PATH: &str = "load.resistance_ohm";

/// The limits a design must keep (none: not limited).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct Limits {
    /// Largest impact speed (m/s).
    pub impact_speed_m_s: Option<f64>,
    /// Largest contact force (N).
    pub contact_force_n: Option<f64>,
    /// Largest |x| (m).
    pub displacement_m: Option<f64>,
    /// Most impacts per second.
    pub impacts_per_s: Option<f64>,
}

impl Limits {
    /// The violation of a performance: the sum of its relative exceedances (zero when it keeps
    /// every limit).
    pub fn violation(&self, p: &Performance) -> f64 {
        [
            (self.impact_speed_m_s, p.impact_speed_m_s),
            (self.contact_force_n, p.contact_force_n),
            (self.displacement_m, p.displacement_m),
            (self.impacts_per_s, p.impacts_per_s),
        ]
        .iter()
        .filter_map(|(limit, value)| limit.map(|l| (value / l - 1.0).max(0.0)))
        .sum()
    }

    /// The margin of a performance on each limit, in the order impact speed, contact force,
    /// displacement, impacts per second: `1 - value / limit` (positive within the limit,
    /// negative beyond it), `None` where there is no limit.
    pub fn margins(&self, p: &Performance) -> [Option<f64>; 4] {
        [
            (self.impact_speed_m_s, p.impact_speed_m_s),
            (self.contact_force_n, p.contact_force_n),
            (self.displacement_m, p.displacement_m),
            (self.impacts_per_s, p.impacts_per_s),
        ]
        .map(|(limit, value)| limit.map(|l| 1.0 - value / l))
    }
}

/// The names of the limits, in the order of [`Limits::margins`].
pub const LIMIT_NAMES: [&str; 4] = [
    "impact_speed_m_s",
    "contact_force_n",
    "displacement_m",
    "impacts_per_s",
];

/// The vibration a design is judged under: sines of one RMS acceleration at one or more
/// frequencies (the objective is the worst).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Vibration {
    /// The frequencies (Hz), in increasing order.
    pub freqs_hz: Vec<f64>,
    /// RMS acceleration (g).
    pub accel_rms_g: f64,
}

/// A design problem (see the module docs).
#[derive(Debug, Clone)]
pub struct Problem {
    /// The device the ranges are set on.
    pub device: Device,
    /// The interfaces to choose among.
    pub interfaces: Vec<Interface>,
    /// The decision variables.
    pub ranges: Vec<ParamRange>,
    /// The vibration.
    pub vibration: Vibration,
    /// The limits.
    pub limits: Limits,
    /// How each steady state is found.
    pub steady: SteadySettings,
    /// The noise objective, in place of the sines of [`Problem::vibration`] ([`noise`]);
    /// set by [`Problem::with_noise`].
    pub noise: Option<NoiseObjective>,
    /// The measured record, in place of the sines and the noise ([`record`]); set by
    /// [`Problem::with_record`].
    pub record: Option<RecordObjective>,
}

/// Why a design problem could not be solved.
#[derive(Debug, thiserror::Error)]
pub enum DesignError {
    /// The problem is malformed (no interface, no range, a bad vibration or limit).
    #[error("design problem: {0}")]
    Invalid(String),
    /// An interface table or name is not valid on the device.
    #[error("{0}")]
    Interface(ParamError),
    /// A range does not fit the device behind an interface.
    #[error("interface `{interface}`: {error}")]
    Range {
        /// The interface's key.
        interface: String,
        /// Why (in the message, so not also a source that a chain would print again).
        error: ParamError,
    },
    /// The search settings are out of range, or the optimiser failed.
    #[error("search: {0}")]
    Search(String),
    /// No design the search tried could be evaluated.
    #[error("no design could be evaluated; the first failure: {0}")]
    NoEvaluation(String),
}

/// One design and what it gave.
#[derive(Debug, Clone)]
pub struct Evaluated {
    /// Index of the interface in [`Problem::interfaces`].
    pub interface: usize,
    /// The point on the unit cube of the ranges.
    pub unit: Vec<f64>,
    /// The parameters' values, in the order of the ranges.
    pub values: Vec<f64>,
    /// The performance, or why there is none.
    pub result: Result<Performance, String>,
    /// The violation of the limits ([`Limits::violation`]); infinite without a performance.
    pub violation: f64,
}

impl Evaluated {
    /// True when evaluated and within every limit.
    pub fn feasible(&self) -> bool {
        self.result.is_ok() && self.violation == 0.0
    }

    /// The objective (W), NaN without a performance.
    pub fn power_w(&self) -> f64 {
        self.result.as_ref().map_or(f64::NAN, |p| p.power_w)
    }
}

/// Whether an answer is an optimum.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Verdict {
    /// The best feasible design found.
    Optimum,
    /// No design tried meets every limit: the answer is the least violating design.
    Infeasible,
}

/// The answer to a problem (or to one interface of it).
#[derive(Debug, Clone)]
pub struct Answer {
    /// Optimum or infeasible.
    pub verdict: Verdict,
    /// The best feasible design, or the least violating one.
    pub design: Evaluated,
}

/// The best of a set of evaluations: the feasible one of most power, else the least violating
/// (ties in order); `None` when none was evaluated.
pub fn answer(evals: &[Evaluated]) -> Option<Answer> {
    let evaluated = evals.iter().filter(|e| e.result.is_ok());
    if let Some(best) = evaluated.clone().filter(|e| e.feasible()).reduce(|a, b| {
        if b.power_w() > a.power_w() {
            b
        } else {
            a
        }
    }) {
        return Some(Answer {
            verdict: Verdict::Optimum,
            design: best.clone(),
        });
    }
    evaluated
        .reduce(|a, b| {
            let better = b.violation < a.violation
                || (b.violation == a.violation && b.power_w() > a.power_w());
            if better {
                b
            } else {
                a
            }
        })
        .map(|least| Answer {
            verdict: Verdict::Infeasible,
            design: least.clone(),
        })
}

/// A solved problem: the answer overall and per interface, and every design evaluated.
#[derive(Debug, Clone)]
pub struct Study {
    /// The answer over every interface.
    pub answer: Answer,
    /// Per interface (in the problem's order), its answer, `None` where no design of it could
    /// be evaluated.
    pub per_interface: Vec<Option<Answer>>,
    /// Every design evaluated, in the order of evaluation.
    pub evaluations: Vec<Evaluated>,
}

impl Problem {
    /// The problem of `device` with these interfaces, ranges, vibration and limits, each
    /// steady state found with the default settings; checked ([`Problem::check`]).
    pub fn new(
        device: Device,
        interfaces: Vec<Interface>,
        ranges: Vec<ParamRange>,
        vibration: Vibration,
        limits: Limits,
    ) -> Result<Problem, DesignError> {
        let p = Problem {
            device,
            interfaces,
            ranges,
            vibration,
            limits,
            steady: SteadySettings::default(),
            noise: None,
            record: None,
        };
        p.check()?;
        Ok(p)
    }

    /// Checks the problem: at least one interface and one range, a vibration of positive
    /// increasing frequencies and positive acceleration (or a valid noise objective in its
    /// place), positive limits, and every range valid on the device behind every interface at
    /// both ends.
    pub fn check(&self) -> Result<(), DesignError> {
        let bad = |m: String| Err(DesignError::Invalid(m));
        if self.interfaces.is_empty() {
            return bad("no interface to choose from".into());
        }
        if self.ranges.is_empty() {
            return bad("no range to design over".into());
        }
        match (&self.noise, &self.record) {
            (Some(_), Some(_)) => return bad("give a noise or a measured record, not both".into()),
            (Some(n), None) => n.check().map_err(DesignError::Invalid)?,
            (None, Some(r)) => r.check().map_err(DesignError::Invalid)?,
            (None, None) => self.check_vibration()?,
        }
        let l = &self.limits;
        for (name, limit) in [
            ("impact speed", l.impact_speed_m_s),
            ("contact force", l.contact_force_n),
            ("displacement", l.displacement_m),
            ("impacts per second", l.impacts_per_s),
        ] {
            if let Some(x) = limit {
                if !(x.is_finite() && x > 0.0) {
                    return bad(format!("the {name} limit must be positive, got {x}"));
                }
            }
        }
        for (i, r) in self.ranges.iter().enumerate() {
            if self.ranges[..i].iter().any(|q| q.path == r.path) {
                return bad(format!("`{}` is ranged twice", r.path));
            }
            if r.path == crate::device::ACCEL_SCALE_PATH {
                return bad(format!("`{}` is the vibration's, not the design's", r.path));
            }
        }
        for i in 0..self.interfaces.len() {
            for u in [0.0, 1.0] {
                self.device_at(i, &vec![u; self.ranges.len()])?;
            }
        }
        Ok(())
    }

    /// Checks the sines: positive increasing frequencies, a positive acceleration.
    fn check_vibration(&self) -> Result<(), DesignError> {
        let bad = |m: String| Err(DesignError::Invalid(m));
        let v = &self.vibration;
        if v.freqs_hz.is_empty()
            || v.freqs_hz.iter().any(|f| !(f.is_finite() && *f > 0.0))
            || v.freqs_hz.windows(2).any(|w| w[1] <= w[0])
        {
            return bad(format!(
                "the frequencies must be positive and increasing, got {:?}",
                v.freqs_hz
            ));
        }
        if !(v.accel_rms_g.is_finite() && v.accel_rms_g > 0.0) {
            return bad(format!(
                "the RMS acceleration must be positive, got {}",
                v.accel_rms_g
            ));
        }
        Ok(())
    }

    /// The device with interface `i` and the ranges at the unit point `unit`, with the values.
    pub fn device_at(&self, i: usize, unit: &[f64]) -> Result<(Device, Vec<f64>), DesignError> {
        let iface = &self.interfaces[i];
        let err = |error| DesignError::Range {
            interface: iface.key().to_string(),
            error,
        };
        let mut base = self.device.behind(iface.clone());
        // Behind the resistive interface the range of `LOAD_PATH` sets the transducer's own
        // load; where the device's file had none it needs a finite placeholder until the range
        // sets it (left absent otherwise, which the device's check names).
        let ranged_load = self.ranges.iter().any(|r| r.path == LOAD_PATH);
        if ranged_load && iface.load_resistance_path() == "transducer.load_resistance_ohm" {
            if let Some(r) = base.own_load_mut().filter(|r| r.is_infinite()) {
                *r = 1.0;
            }
        }
        let paths: Vec<&str> = self
            .ranges
            .iter()
            .map(|r| {
                if r.path == LOAD_PATH {
                    iface.load_resistance_path()
                } else {
                    r.path.as_str()
                }
            })
            .collect();
        let values = self
            .ranges
            .iter()
            .zip(&paths)
            .zip(unit)
            .map(|((r, p), &u)| {
                // The device's own value matters to a relative range only.
                let own = if r.relative {
                    own_value(&base, p)?
                } else {
                    f64::NAN
                };
                Ok(r.value(own, u))
            })
            .collect::<Result<Vec<f64>, ParamError>>()
            .map_err(err)?;
        let set: Vec<(&str, f64)> = paths.iter().copied().zip(values.iter().copied()).collect();
        let dev = base.with_params(&set).map_err(err)?;
        Ok((dev, values))
    }

    /// True when a design's orbit measures its impact speed and contact force: under sines,
    /// not under a noise or a record, which measure the displacement and the impacts only.
    pub fn measures_impacts(&self) -> bool {
        self.noise.is_none() && self.record.is_none()
    }

    /// Evaluates interface `i` at the unit point `unit` (never fails: a failure is the
    /// evaluation's result).
    pub fn evaluate(&self, i: usize, unit: &[f64]) -> Evaluated {
        let unit: Vec<f64> = unit.iter().map(|u| u.clamp(0.0, 1.0)).collect();
        let (result, values) = match self.device_at(i, &unit) {
            Ok((dev, values)) => (
                match (&self.noise, &self.record) {
                    (Some(n), _) => noise::noise_power(&dev, n, n.seed)
                        .map(|(_, p)| p)
                        .map_err(|e| e.to_string()),
                    (None, Some(r)) => record::record_power(&dev, r).map_err(|e| e.to_string()),
                    (None, None) => performance(
                        &dev,
                        &self.vibration.freqs_hz,
                        self.vibration.accel_rms_g,
                        &self.steady,
                    )
                    .map_err(|e| e.to_string()),
                },
                values,
            ),
            Err(e) => (Err(e.to_string()), vec![f64::NAN; unit.len()]),
        };
        let violation = match &result {
            Ok(p) => self.limits.violation(p),
            Err(_) => f64::INFINITY,
        };
        Evaluated {
            interface: i,
            unit,
            values,
            result,
            violation,
        }
    }

    /// Solves the problem: every interface searched in turn ([`search::search`]), `progress`
    /// told of each evaluation.
    pub fn solve(
        &self,
        settings: &SearchSettings,
        progress: &dyn Progress,
    ) -> Result<Study, DesignError> {
        self.check()?;
        let mut evaluations = Vec::new();
        let mut per_interface = Vec::new();
        for i in 0..self.interfaces.len() {
            progress.stage(self.interfaces[i].key());
            let evals = search::search(
                self.ranges.len(),
                |u: &[f64]| {
                    let e = self.evaluate(i, u);
                    progress.tick();
                    e
                },
                settings,
            )?;
            per_interface.push(answer(&evals));
            evaluations.extend(evals);
        }
        let answer = answer(&evaluations).ok_or_else(|| {
            DesignError::NoEvaluation(
                evaluations
                    .iter()
                    .find_map(|e| e.result.as_ref().err().cloned())
                    .unwrap_or_default(),
            )
        })?;
        Ok(Study {
            answer,
            per_interface,
            evaluations,
        })
    }

    /// Evaluates interface `i` on an `n` x `n` grid over ranges `a` and `b` (evenly on the unit
    /// interval, ends included), the other ranges at `rest` (unit coordinates); rows in `a`,
    /// then `b`; in parallel. The brute-force reference of the search and the power maps.
    pub fn grid(&self, i: usize, a: usize, b: usize, n: usize, rest: &[f64]) -> Vec<Evaluated> {
        let step = 1.0 / (n.max(2) - 1) as f64;
        (0..n * n)
            .into_par_iter()
            .map(|k| {
                let mut u = rest.to_vec();
                u[a] = (k / n) as f64 * step;
                u[b] = (k % n) as f64 * step;
                self.evaluate(i, &u)
            })
            .collect()
    }
}
