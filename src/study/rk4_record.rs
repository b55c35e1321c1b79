//! A random-vibration record integrated by the classical RK4 with fixed steps
//! ([`crate::ode::Rk4`]): the yardstick the benchmark times [`simulate_record`] against, at
//! the number of steps per sample interval that gives the same accuracy.
//!
//! The record is the one [`simulate_record`] computes (the same excitation, pre-roll and
//! analysed samples); only its mean power is kept. The steps divide each 10 us sample
//! interval equally, so they end on the sample instants (the input's breakpoints), and a
//! contact is entered or left where a stop's guard changes sign over a step, located on
//! shortened RK4 steps (see [`crate::ode::FixedStep`]).
//!
//! [`simulate_record`]: crate::study::record::simulate_record

use crate::device::Device;
use crate::drive::noise;
use crate::drive::Sampled;
use crate::ode::{Rk4, Stats};
use crate::physics::contact::Mode;
use crate::physics::harvester::Harvester;
use crate::study::record::{RecordError, RecordSpec};

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
    /// Mean power of both loads over the analysed samples (W).
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
    let gen = spec.generated_noise();
    let accel = noise::generate_shared(&gen, seed, stream)?;
    let model = Harvester::new(device, Sampled::new(accel, gen.sample_rate_hz));
    let n_tr = spec.transient_samples();
    let n = spec.analysed_samples();
    let mut ode = Rk4::new(
        0.0,
        model.rest_state(),
        Mode::Free,
        steps_per_sample,
        EVENT_TIME_TOL,
    );
    let mut p_sum = 0.0;
    for k in 0..n_tr + n {
        ode.integrate(&model, model.excitation.time_of(k))?;
        if k >= n_tr {
            let v = model.electrical(&ode.y()).v;
            p_sum += v[0] * v[0] + v[1] * v[1];
        }
    }
    Ok(Rk4Record {
        p_total_w: p_sum / model.load_resistance() / n as f64,
        stats: ode.stats(),
    })
}
