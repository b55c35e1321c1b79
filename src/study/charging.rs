//! Charging the storage: the time for its voltage to go from a start value to a target under a
//! drive (a sine, a noise record, a measured record), with the voltage sampled on the way. The
//! storage is the model's output [`STORAGE`] (and the state's component of that name, which the
//! start voltage sets); a model without one is refused ([`ChargeError::NoStorage`]).
//!
//! # How the drive starts
//! The harvester starts at rest (x = v = 0, the element discharged) with the storage at the
//! start voltage, and the drive starts at t = 0 at its phase zero, multiplied by a linear
//! ramp from 0 to 1 over `ramp_s` seconds (zero: the drive starts at once). A drive that starts
//! at once excites a transient whose first peaks can exceed the steady response; without a
//! load the storage keeps the highest voltage a peak charged it to, so the reachable voltage
//! and the time to a target depend on the ramp, and every result states it.
//!
//! # Out of reach
//! Without a load the storage approaches a limit (the element's open-circuit peak less the
//! diodes' drop, for a plain bridge). The charging integrates in blocks and, once the rise per
//! block shrinks geometrically, extrapolates the limit from the last three block ends
//! (Aitken's delta-squared); a target above it ends in [`ChargeError::OutOfReach`] with the
//! estimate, and a run that has not reached the target by `t_max_s` ends in
//! [`ChargeError::NotReached`]. Neither hangs.

use nalgebra::SVector;
use thiserror::Error;

use crate::device::Device;
use crate::drive::Excitation;
use crate::model::{Driven, Model, MAX_OUTPUTS};
use crate::ode::{Dopri5, SolverError};
use crate::physics::harvester::AssemblyError;
use crate::progress::{share, Progress};
use crate::study::record::STORAGE;

/// A drive multiplied by a linear ramp from 0 at t = 0 to 1 at `ramp_s`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ramped<E> {
    /// The drive.
    pub inner: E,
    /// Ramp duration (s); zero: none.
    pub ramp_s: f64,
}

impl<E: Excitation> Excitation for Ramped<E> {
    #[inline]
    fn accel(&self, t: f64) -> f64 {
        let k = if self.ramp_s > 0.0 {
            (t / self.ramp_s).min(1.0)
        } else {
            1.0
        };
        k * self.inner.accel(t)
    }

    fn next_breakpoint(&self, t: f64) -> f64 {
        let b = self.inner.next_breakpoint(t);
        if self.ramp_s > t {
            b.min(self.ramp_s)
        } else {
            b
        }
    }
}

/// Settings of a charging run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChargeSettings {
    /// Storage voltage at the start (V).
    pub start_v: f64,
    /// Target storage voltage (V).
    pub target_v: f64,
    /// The drive's ramp (s); see the module docs.
    pub ramp_s: f64,
    /// Longest simulated time (s).
    pub t_max_s: f64,
    /// Interval of the sampled storage voltage (s).
    pub sample_s: f64,
    /// Length of a block, between progress reports and reach checks (s).
    pub block_s: f64,
    /// Integrator relative tolerance.
    pub rtol: f64,
}

/// A charging run's result.
#[derive(Debug, Clone, PartialEq)]
pub struct ChargeRun {
    /// Time at which the storage reached the target (s).
    pub time_to_target_s: f64,
    /// Sample times (s).
    pub t_s: Vec<f64>,
    /// Storage voltage at the sample times (V).
    pub vs_v: Vec<f64>,
    /// Energy in the storage at the target minus at the start (J).
    pub stored_j: f64,
}

/// A charging run that failed.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ChargeError {
    /// The model has no storage: no output and state component [`STORAGE`] (a device with
    /// resistive loads, not an interface circuit).
    #[error("`{0}` has no storage (no output and state component `vs`): it has resistive loads, not an interface circuit")]
    NoStorage(String),
    /// The target is at or below the start.
    #[error("charging target {target_v} V is not above the start voltage {start_v} V")]
    TargetBelowStart {
        /// Target (V).
        target_v: f64,
        /// Start (V).
        start_v: f64,
    },
    /// The storage approaches a limit below the target.
    #[error(
        "charging target {target_v} V is out of reach: the storage approaches {limit_v:.4} V \
         under this drive (reached {reached_v:.4} V after {t_s:.3} s)"
    )]
    OutOfReach {
        /// Target (V).
        target_v: f64,
        /// Extrapolated limit (V).
        limit_v: f64,
        /// Reached (V).
        reached_v: f64,
        /// Time simulated (s).
        t_s: f64,
    },
    /// The target was not reached within the longest time.
    #[error(
        "charging target {target_v} V not reached within {t_max_s} s (reached {reached_v:.4} V)"
    )]
    NotReached {
        /// Target (V).
        target_v: f64,
        /// Longest time (s).
        t_max_s: f64,
        /// Reached (V).
        reached_v: f64,
    },
    /// The integrator failed.
    #[error("integration failed: {0}")]
    Solver(#[from] SolverError),
    /// The device's parts do not assemble into a model (or a conduction mode is too stiff).
    #[error("model: {0}")]
    Assembly(#[from] AssemblyError),
}

/// Charges the storage of `device` under `drive` (see the module docs); `progress` is told at
/// the end of each block how far the storage voltage has come from the start to the target. A
/// device whose model has no storage (resistive loads) is [`ChargeError::NoStorage`].
///
/// ```
/// use endstop::device::Device;
/// use endstop::drive::Sine;
/// use endstop::progress::Silent;
/// use endstop::study::charging::{charge, ChargeError, ChargeSettings};
///
/// let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/examples/piezo_bridge.toml"));
/// let device = Device::from_toml_str(text, "piezo_bridge.toml")?;
/// let s = ChargeSettings {
///     start_v: 0.0,
///     target_v: 0.5,
///     ramp_s: 0.0,
///     t_max_s: 2.0,
///     sample_s: 1e-3,
///     block_s: 0.05,
///     rtol: 1e-8,
/// };
/// let run = charge(&device, Sine::from_rms_g(0.3, 120.0), &s, &Silent)?;
/// assert!(run.time_to_target_s > 0.0 && run.time_to_target_s < s.t_max_s);
/// // No sample before the target time is above the target.
/// let before = run.t_s.iter().zip(&run.vs_v).filter(|(t, _)| **t < run.time_to_target_s);
/// assert!(before.into_iter().all(|(_, v)| *v <= s.target_v));
/// // The storage (10 uF) gains Cs V^2 / 2 = 1.25 uJ.
/// assert!((run.stored_j / (0.5 * 10e-6 * 0.25) - 1.0).abs() < 1e-12);
///
/// // The same cantilever with a plain resistive load has no storage to charge.
/// let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/examples/piezo_cantilever.toml"));
/// let plain = Device::from_toml_str(text, "piezo_cantilever.toml")?;
/// let err = charge(&plain, Sine::from_rms_g(0.3, 120.0), &s, &Silent).unwrap_err();
/// assert!(matches!(err, ChargeError::NoStorage(_)));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn charge<E: Excitation + Clone>(
    device: &Device,
    drive: E,
    s: &ChargeSettings,
    progress: &dyn Progress,
) -> Result<ChargeRun, ChargeError> {
    crate::with_harvester!(device, |h| charge_on(&h, &device.name, drive, s, progress))
}

/// [`charge`] on any model with a storage; `name` names it in errors.
pub fn charge_on<M: Model<N>, E: Excitation + Clone, const N: usize>(
    model: &M,
    name: &str,
    drive: E,
    s: &ChargeSettings,
    progress: &dyn Progress,
) -> Result<ChargeRun, ChargeError> {
    if s.target_v <= s.start_v {
        return Err(ChargeError::TargetBelowStart {
            target_v: s.target_v,
            start_v: s.start_v,
        });
    }
    let layout = model.layout();
    let (Some(out), Some(state)) = (layout.output(STORAGE), layout.component(STORAGE)) else {
        return Err(ChargeError::NoStorage(name.to_string()));
    };
    let sys = Driven::new(
        model,
        Ramped {
            inner: drive,
            ramp_s: s.ramp_s,
        },
    );
    let storage = |y: &SVector<f64, N>, mode| {
        let mut o = [0.0; MAX_OUTPUTS];
        model.outputs(mode, y, &mut o);
        o[out]
    };
    let mut y0 = model.rest_state();
    y0[state] = s.start_v;
    let mut ode = Dopri5::new(0.0, y0, model.mode_of(&y0), model.solver_options(s.rtol));
    let (mut t_s, mut vs_v) = (vec![0.0], vec![s.start_v]);
    let mut next_sample = s.sample_s;
    let mut hit: Option<f64> = None;
    let mut ends: Vec<f64> = Vec::new();
    let mut t_end = 0.0;
    while hit.is_none() {
        if t_end >= s.t_max_s {
            return Err(ChargeError::NotReached {
                target_v: s.target_v,
                t_max_s: s.t_max_s,
                reached_v: storage(&ode.y(), ode.mode()),
            });
        }
        t_end = (t_end + s.block_s).min(s.t_max_s);
        let target = s.target_v;
        // Stops at the end of the step that reaches the target; the crossing is found on the
        // step's dense output.
        let mut stop_at: Option<f64> = None;
        let sample = s.sample_s;
        ode.integrate(&sys, t_end, |st, mode| {
            while next_sample <= st.t1() {
                t_s.push(next_sample);
                vs_v.push(storage(&st.at(next_sample), mode));
                next_sample += sample;
            }
            if stop_at.is_none() && storage(&st.y1, mode) >= target {
                let (mut a, mut b) = (st.t0, st.t1());
                for _ in 0..60 {
                    let m = 0.5 * (a + b);
                    if storage(&st.at(m), mode) >= target {
                        b = m;
                    } else {
                        a = m;
                    }
                }
                stop_at = Some(b);
            }
        })?;
        if let Some(t) = stop_at {
            hit = Some(t);
            break;
        }
        let v = storage(&ode.y(), ode.mode());
        progress.fraction(share(s.start_v, s.target_v, v));
        ends.push(v);
        if let [.., a, b, c] = ends[..] {
            let (d1, d2) = (b - a, c - b);
            // Past the ramp, with the rise shrinking geometrically: extrapolate the limit.
            if t_end > s.ramp_s + 3.0 * s.block_s && d1 > 0.0 && d2 > 0.0 && d2 < 0.9 * d1 {
                let limit = c + d2 * d2 / (d1 - d2);
                if limit < target {
                    return Err(ChargeError::OutOfReach {
                        target_v: target,
                        limit_v: limit,
                        reached_v: c,
                        t_s: t_end,
                    });
                }
            }
        }
    }
    let t_hit = hit.unwrap_or(t_end);
    // The energy the storage gained: the model's stored energy at the target less at the start,
    // with everything but the storage at rest.
    let at = |v: f64| {
        let mut y = model.rest_state();
        y[state] = v;
        model.stored_energy(model.mode_of(&y), &y)
    };
    Ok(ChargeRun {
        time_to_target_s: t_hit,
        t_s,
        vs_v,
        stored_j: at(s.target_v) - at(s.start_v),
    })
}
