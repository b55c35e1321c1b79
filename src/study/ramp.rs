//! The phase-continuous ramp that joins two steps of a stepped sweep ([`ramp`]), so that the
//! sweep's answer does not depend on its step.
//!
//! # Why a frequency step kicks the response
//! Near a resonance of quality factor Q the steady response's phase moves by about
//! 2 Q df / f0 per step df: a step taken at once leaves the state of the old frequency as the
//! initial condition at the new one, and the transient that follows overshoots the new steady
//! response by a fraction of order df / w (w = f0 / Q the half-power width). Next to the end of
//! a branch (a fold, or the grazing of the non-impacting orbit) that overshoot is enough to
//! carry the state across to the other branch, so that a stepped sweep leaves the branch early,
//! by an amount that depends on the step rather than on the device.
//!
//! # The ramp
//! Here a step is instead reached by a ramp: frequency and amplitude move at a continuous
//! phase over a whole number of cycles, at a rate that rises from zero and falls back to zero
//! ([`crate::drive::Profile::Smooth`]) and on average moves the frequency by a fiftieth of
//! the half-power width per ring-up time 1/(pi w) ([`default_ramp_rate_hz_per_s`](crate::study::chirp::default_ramp_rate_hz_per_s)): the
//! response follows the branch adiabatically, and the sweep leaves it where it ends. The ramp
//! ends at drive phase zero, where the next step's steady state starts, so that the drive's
//! phase is continuous across the whole sweep.
//!
//! The ramp moves in stairs of one cycle: each cycle is a whole sine period at the profile's
//! frequency and amplitude at the cycle's middle, so that it starts and ends at phase zero and
//! is integrated by [`SineFlow`], exactly where the device is affine (a coil whose time
//! constant is far below the drive's period costs what its slow modes cost) and by
//! Dormand-Prince elsewhere. A stair moves the frequency by at most twice the rate times
//! the period, whatever the step: at the default rate 0.04 pi w / f0 = 0.13 w / Q at the
//! resonance f0 of quality factor Q, a kick far below the step's w / 4.
//!

use nalgebra::SVector;

use crate::drive::{Profile, Sine};
use crate::model::{Mode, Model};
use crate::ode::{SolverError, Stats};
use crate::study::flow::SineFlow;

/// Moves the drive of `base` from (frequency, RMS acceleration) `from` to `to` by a smooth ramp
/// of at least `min_duration_s` (as many whole cycles as the mean frequency makes in it, at
/// least one), in stairs of one cycle (see the module docs), from the state `y` in `mode` at
/// drive phase zero, with relative tolerance `rtol`. Returns the state and mode at the end
/// (at drive phase zero) and the counters.
pub fn ramp<M: Model<N>, const N: usize>(
    base: &M,
    from: (f64, f64),
    to: (f64, f64),
    min_duration_s: f64,
    y: SVector<f64, N>,
    mode: Mode,
    rtol: f64,
) -> Result<(SVector<f64, N>, Mode, Stats), SolverError> {
    let f_mean = 0.5 * (from.0 + to.0);
    let cycles = (min_duration_s * f_mean).ceil().max(1.0) as usize;
    let (mut y, mut mode, mut stats) = (y, mode, Stats::default());
    for k in 0..cycles {
        let s = Profile::Smooth.s((k as f64 + 0.5) / cycles as f64);
        let f = from.0 + (to.0 - from.0) * s;
        let g = from.1 + (to.1 - from.1) * s;
        let mut flow = SineFlow::new(base, Sine::from_rms_g(g, f), 0.0, y, mode, rtol);
        flow.advance(1.0 / f)?;
        (y, mode) = (flow.y(), flow.mode());
        stats += flow.stats();
    }
    Ok((y, mode, stats))
}
