//! Spectral estimation: Welch's power spectral density ([`welch()`], scipy's conventions) and the
//! widths and edges read from a density ([`bandwidth`]).

pub mod bandwidth;
pub mod welch;

pub use bandwidth::{width_at_fraction, Bandwidth, Widths};
pub use welch::{hann_periodic, welch, Psd, SpectralError, WelchConfig};
