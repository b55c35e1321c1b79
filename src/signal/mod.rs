//! Spectral estimation: Welch's power spectral density ([`welch()`], scipy's conventions) and the
//! widths and edges read from a density ([`bandwidth`]).
//!
//! Densities are one-sided (every bin but DC and Nyquist doubled), so their integral is the
//! variance of the signal:
//!
//! ```
//! use endstop::signal::{welch, WelchOptions};
//!
//! // A sine of amplitude 2 at 1 kHz, sampled at 16 kHz for 1 s: variance 2^2 / 2 = 2.
//! let fs = 16e3;
//! let x: Vec<f64> = (0..16_000)
//!     .map(|n| 2.0 * (2.0 * std::f64::consts::PI * 1e3 * n as f64 / fs).sin())
//!     .collect();
//! let psd = welch(&x, fs, &WelchOptions::half_overlap(256)).unwrap();
//! assert_eq!(psd.peak().0, 1e3); // 1 kHz falls on bin 16 of 62.5 Hz
//! assert!((psd.integral() - 2.0).abs() < 1e-3);
//! ```

pub mod bandwidth;
pub mod welch;

pub use bandwidth::{width_at_fraction, Bandwidth, Widths};
pub use welch::{hann_periodic, welch, welch_of_zeros, Psd, SpectralError, WelchOptions};
