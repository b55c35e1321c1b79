//!
//! A sampled record (the band-limited noise of Figures 10-15), read between
//! samples by **linear interpolation**. Every sample instant is a breakpoint of the
//! integrator, so no step straddles a kink of the interpolant; the step size in free flight
//! is then bounded by the sample interval (10 us at 100 kHz), not by the dynamics. Linear
//! interpolation attenuates the input by sinc^2(f/fs): 0.05 % at 1.2 kHz, 3 % at 10 kHz.
//! Past the last sample the acceleration is zero.

use std::sync::Arc;

use crate::drive::Excitation;

/// A sampled acceleration record, linearly interpolated.
///
/// ```
/// use std::sync::Arc;
/// use endstop::drive::{Excitation, Sampled};
///
/// let record = Sampled::new(Arc::from(vec![0.0, 2.0, -1.0]), 1000.0);
/// assert_eq!(record.duration_s(), 2e-3);
/// // Halfway between samples the acceleration is their mean (to rounding), and every sample
/// // instant is a breakpoint for the integrator.
/// assert!((record.accel(0.5e-3) - 1.0).abs() < 1e-12);
/// assert!((record.accel(1.5e-3) - 0.5).abs() < 1e-12);
/// assert_eq!(record.next_breakpoint(0.2e-3), record.time_of(1));
/// // Past the last sample the drive is off.
/// assert_eq!(record.accel(5e-3), 0.0);
/// ```
#[derive(Debug, Clone)]
pub struct Sampled {
    /// Sample interval (s).
    pub dt_s: f64,
    /// Samples (m/s^2), sample k at t = k dt.
    pub samples: Arc<[f64]>,
}

impl Sampled {
    /// A record with sample rate `sample_rate_hz`.
    pub fn new(samples: Arc<[f64]>, sample_rate_hz: f64) -> Self {
        Self {
            dt_s: 1.0 / sample_rate_hz,
            samples,
        }
    }

    /// Duration covered by the samples (s).
    pub fn duration_s(&self) -> f64 {
        (self.samples.len().saturating_sub(1)) as f64 * self.dt_s
    }

    /// Time of sample k (s).
    #[inline]
    pub fn time_of(&self, k: usize) -> f64 {
        k as f64 * self.dt_s
    }
}

impl Excitation for Sampled {
    #[inline]
    fn accel(&self, t: f64) -> f64 {
        if t < 0.0 {
            return 0.0;
        }
        let u = t / self.dt_s;
        // t >= 0, so truncation is the floor (and cheaper: no call into libm).
        let k = u as usize;
        let i = k as f64;
        if k + 1 >= self.samples.len() {
            return if k + 1 == self.samples.len() {
                self.samples[k]
            } else {
                0.0
            };
        }
        let frac = u - i;
        self.samples[k] * (1.0 - frac) + self.samples[k + 1] * frac
    }

    fn next_breakpoint(&self, t: f64) -> f64 {
        let k = (t / self.dt_s).floor().max(0.0) as usize;
        let mut bp = self.time_of(k + 1);
        if bp <= t {
            bp = self.time_of(k + 2);
        }
        bp
    }
}
