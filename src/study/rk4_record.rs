//! A random-vibration record integrated by the classical RK4 with fixed steps
//! ([`crate::ode::Rk4`]): the yardstick the benchmark times [`simulate_record`] against, at
//! the number of steps per sample interval that gives the same accuracy.
//!
//! The record is the one [`simulate_record`] computes (the same model, excitation, pre-roll and
//! analysed samples); only the mean power of its outputs' loads is kept. The steps divide each 10 us sample
//! interval equally, so they end on the sample instants (the input's breakpoints), and a
//! contact is entered or left where a stop's guard changes sign over a step, located on
//! shortened RK4 steps (see [`crate::ode::FixedStep`]).
//!
//! [`simulate_record`]: crate::study::record::simulate_record

use crate::device::Device;
use crate::drive::Sampled;
use crate::model::{Driven, Model, MAX_OUTPUTS};
use crate::ode::{Rk4, Stats};
use crate::study::record::{RecordError, RecordSpec, SampledDrive};

/// RK4 steps per sample interval at which the power of the prototypes' impact-free records is
/// within 1e-6 of Dormand-Prince at rtol 1e-10, the accuracy asked of a record (the fewest of
/// 1, 2, 4, 8; asserted by `tests/record_accuracy.rs`).
pub const RK4_STEPS_AT_TARGET: usize = 1;

/// RK4 steps per sample interval at which that power is within 1e-8, the accuracy of
/// [`crate::study::record::simulate_record`] there (the fewest of 1, 2, 4, 8; asserted by
/// `tests/record_accuracy.rs`).
pub const RK4_STEPS_AT_OUR_ACCURACY: usize = 4;

/// Time tolerance of a located contact (s).
const EVENT_TIME_TOL: f64 = 1e-15;

/// A record by RK4: its mean power and the integrator's counters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rk4Record {
    /// Mean power of the outputs' loads over the analysed samples (W): both loads of a
    /// transducer with its own loads.
    pub p_total_w: f64,
    /// The integrator's counters (steps, right-hand-side evaluations, events).
    pub stats: Stats,
}

/// Simulates the record of [`crate::study::record::simulate_record`] (realisation `stream` of
/// seed `seed`) by RK4 with `steps_per_sample` equal steps per sample interval; see the module
/// docs. The only allocation is the excitation.
pub fn simulate_rk4_record(
    device: &Device,
    spec: &RecordSpec,
    seed: u64,
    stream: u64,
    steps_per_sample: usize,
) -> Result<Rk4Record, RecordError> {
    spec.validate()?;
    let drive = SampledDrive::noise(spec, seed, stream)?;
    crate::with_harvester!(device, |h| rk4_on(&h, &drive, steps_per_sample))
}

/// [`simulate_rk4_record`] of any model under a sampled drive.
pub fn rk4_on<M: Model<N>, const N: usize>(
    model: &M,
    drive: &SampledDrive,
    steps_per_sample: usize,
) -> Result<Rk4Record, RecordError> {
    let sampled = Sampled::new(drive.accel.clone(), drive.sample_rate_hz);
    let sys = Driven::new(model, sampled.clone());
    let n_tr = drive.transient_samples;
    let n = drive.accel.len().saturating_sub(n_tr);
    let y0 = model.rest_state();
    let mut ode = Rk4::new(
        0.0,
        y0,
        model.mode_of(&y0),
        steps_per_sample,
        EVENT_TIME_TOL,
    );
    let outputs = model.layout().outputs.len().min(MAX_OUTPUTS);
    let (mut sums, mut squares) = ([0.0; MAX_OUTPUTS], [0.0; MAX_OUTPUTS]);
    let mut out = [0.0; MAX_OUTPUTS];
    for k in 0..n_tr + n {
        ode.integrate(&sys, sampled.time_of(k))?;
        if k >= n_tr {
            model.outputs(ode.mode(), &ode.y(), &mut out);
            for i in 0..outputs {
                sums[i] += out[i];
                squares[i] += out[i] * out[i];
            }
        }
    }
    Ok(Rk4Record {
        p_total_w: model
            .layout()
            .load_power(&squares[..outputs], &sums[..outputs], n as f64),
        stats: ode.stats(),
    })
}
