//! Base accelerations a(t) that drive the harvester (SPEC 5).
//!
//! * [`Sine`]: a(t) = sqrt(2) a_rms sin(2 pi f t + phi), a_rms given in g (g = 9.81 m/s^2).
//! * [`Sampled`]: a sampled record (the band-limited noise of Figures 10-15), read between
//!   samples by **linear interpolation**. Every sample instant is a breakpoint of the
//!   integrator, so no step straddles a kink of the interpolant; the step size in free flight
//!   is then bounded by the sample interval (10 us at 100 kHz), not by the dynamics. Linear
//!   interpolation attenuates the input by sinc^2(f/fs): 0.05 % at 1.2 kHz, 3 % at 10 kHz.
//!   Past the last sample the acceleration is zero.

use std::sync::Arc;

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

/// Sinusoidal acceleration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sine {
    /// Peak amplitude (m/s^2).
    pub amplitude_m_s2: f64,
    /// Frequency (Hz).
    pub freq_hz: f64,
    /// Phase at t = 0 (rad).
    pub phase_rad: f64,
}

impl Sine {
    /// A sine of RMS acceleration `accel_rms_g` (in g) at `freq_hz`, phase 0.
    pub fn from_rms_g(accel_rms_g: f64, freq_hz: f64) -> Self {
        Self {
            amplitude_m_s2: std::f64::consts::SQRT_2 * accel_rms_g * crate::G,
            freq_hz,
            phase_rad: 0.0,
        }
    }

    /// Period (s).
    pub fn period_s(&self) -> f64 {
        1.0 / self.freq_hz
    }
}

impl Excitation for Sine {
    #[inline]
    fn accel(&self, t: f64) -> f64 {
        self.amplitude_m_s2 * (2.0 * std::f64::consts::PI * self.freq_hz * t + self.phase_rad).sin()
    }
}

/// A sampled acceleration record, linearly interpolated.
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
        let i = u.floor();
        let k = i as usize;
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
