//! Base accelerations a(t) that drive the harvester: a sine ([`Sine`]) and one swept in
//! frequency and amplitude at a continuous phase ([`Chirp`]), a sampled record read
//! between samples by linear interpolation ([`Sampled`]), and band-limited white noise to fill
//! such a record ([`noise`], Figure 10), and a measured record checked and resampled to the
//! integrator's rate ([`measured`]).

mod chirp;
pub mod measured;
pub mod noise;
mod sampled;
mod sine;

pub use chirp::{Chirp, Profile};
pub use sampled::Sampled;
pub use sine::Sine;

/// A base acceleration (m/s^2) as a function of time, with the instants where it is not
/// smooth.
pub trait Excitation {
    /// Acceleration at time t (m/s^2).
    fn accel(&self, t: f64) -> f64;
    /// First instant strictly after t where the acceleration is not smooth (s).
    fn next_breakpoint(&self, _t: f64) -> f64 {
        f64::INFINITY
    }
}
