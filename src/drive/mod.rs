//! Base accelerations a(t) that drive the harvester: a sine ([`Sine`]) and one swept in
//! frequency and amplitude at a continuous phase ([`Chirp`]), a sampled record read
//! between samples by linear interpolation ([`Sampled`]), and band-limited white noise to fill
//! such a record ([`noise`], Figure 10), and a measured record checked and resampled to the
//! integrator's rate ([`measured`]).
//!
//! A noise level is **two-sided** (`Sa` per Hz over `-B..B`, in g^2/Hz); a one-sided Welch
//! estimate of the record reads `2 Sa` in the band:
//!
//! ```
//! use endstop::drive::noise::{generate, NoiseSpec};
//! use endstop::drive::{Excitation, Sine};
//! use endstop::signal::{welch, WelchOptions};
//!
//! // 1e-3 g^2/Hz flat to 1 kHz, sampled at 10 kHz for 2 s (seed 7, stream 0).
//! let spec = NoiseSpec {
//!     psd_g2_per_hz: 1e-3,
//!     bandwidth_hz: 1e3,
//!     sample_rate_hz: 10e3,
//!     duration_s: 2.0,
//! };
//! let a = generate(&spec, 7, 0)?; // m/s^2
//! let g2 = endstop::G * endstop::G;
//! let mean_square = a.iter().map(|x| x * x).sum::<f64>() / a.len() as f64;
//! assert!((mean_square / g2 / spec.mean_square_g2() - 1.0).abs() < 0.05); // 2 B Sa
//! let psd = welch(&a, spec.sample_rate_hz, &WelchOptions::half_overlap(1000))?;
//! let level = psd.two_sided_level_in_band(100.0, 900.0) / g2;
//! assert!((level / spec.psd_g2_per_hz - 1.0).abs() < 0.05);
//!
//! // A sine is given by its RMS acceleration in g: its peak is sqrt(2) times that.
//! let sine = Sine::from_rms_g(0.5, 100.0);
//! assert!((sine.accel(0.25 / 100.0) - 2f64.sqrt() * 0.5 * endstop::G).abs() < 1e-12);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod chirp;
pub mod measured;
pub mod noise;
mod sampled;
mod sine;

pub use chirp::{swept_sine_samples, Chirp, Profile};
pub use sampled::Sampled;
pub use sine::{Parameter, Sine};

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
