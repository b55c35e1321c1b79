//! Sinusoidal acceleration a(t) = sqrt(2) a_rms sin(2 pi f t + phi), a_rms given in g
//! (g = 9.81 m/s^2): the drive of the stepped-sine sweeps (Figures 8, 9 and 13).

use crate::drive::Excitation;

/// A parameter of a sine drive: what a continuation varies, and what a parameter column of
/// the variational equations differentiates by.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Parameter {
    /// Frequency (Hz).
    Frequency,
    /// RMS acceleration (g).
    Amplitude,
}

impl Parameter {
    /// Label with unit, for messages.
    pub fn label(self) -> &'static str {
        match self {
            Parameter::Frequency => "frequency (Hz)",
            Parameter::Amplitude => "RMS acceleration (g)",
        }
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
