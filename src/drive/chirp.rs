//! A sine whose frequency and amplitude move in time, with a continuous phase: linearly, the
//! drive of a swept-sine measurement; smoothly (at rates that start and end at zero), the
//! ramp between two steps of a stepped one.

use super::Excitation;

/// How a [`Chirp`] moves from its start to its end over its duration T, as a fraction s(u) of
/// the way at u = t / T.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Profile {
    /// s = u: a constant rate (a swept sine).
    Linear,
    /// s = u - sin(2 pi u) / (2 pi): the rate rises from zero and falls back to zero, so that
    /// a response that follows the drive is not kicked where the ramp starts or stops.
    Smooth,
}

impl Profile {
    /// The fraction of the way at u in [0, 1].
    pub fn s(self, u: f64) -> f64 {
        match self {
            Profile::Linear => u,
            Profile::Smooth => {
                u - (2.0 * std::f64::consts::PI * u).sin() / (2.0 * std::f64::consts::PI)
            }
        }
    }

    /// Its integral from 0 to u (the phase's share of the frequency change).
    fn integral(self, u: f64) -> f64 {
        let tau = 2.0 * std::f64::consts::PI;
        match self {
            Profile::Linear => 0.5 * u * u,
            Profile::Smooth => 0.5 * u * u + ((tau * u).cos() - 1.0) / (tau * tau),
        }
    }
}

/// a(t) = A(t) sin(phi(t)) with f and A moving from (f0, A0) at t = 0 to (f1, A1) at t = T
/// along a [`Profile`] and staying there: f(t) = f0 + (f1 - f0) s(t/T) and
/// phi(t) = phi0 + 2 pi int_0^t f. Both profiles advance the phase over the ramp by
/// 2 pi T (f0 + f1) / 2.
///
/// ```
/// use endstop::drive::{Chirp, Excitation, Profile};
///
/// // 100 Hz to 120 Hz over 0.5 s at 1 m/s^2.
/// let chirp = Chirp {
///     f0_hz: 100.0,
///     f1_hz: 120.0,
///     a0_m_s2: 1.0,
///     a1_m_s2: 1.0,
///     duration_s: 0.5,
///     phase_rad: 0.0,
///     profile: Profile::Linear,
/// };
/// assert_eq!(chirp.freq_hz(0.5), 120.0);
/// assert_eq!(chirp.freq_hz(0.7), 120.0);
/// // The ramp advances the phase by 2 pi T (f0 + f1) / 2 = 2 pi 55 (to rounding).
/// let turns = chirp.phase(0.5) / (2.0 * std::f64::consts::PI);
/// assert!((turns - 55.0).abs() < 1e-9);
/// assert_eq!(chirp.next_breakpoint(0.1), 0.5);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Chirp {
    /// Frequency at t = 0 (Hz).
    pub f0_hz: f64,
    /// Frequency from t = T on (Hz).
    pub f1_hz: f64,
    /// Peak amplitude at t = 0 (m/s^2).
    pub a0_m_s2: f64,
    /// Peak amplitude from t = T on (m/s^2).
    pub a1_m_s2: f64,
    /// The duration T of the ramp (s).
    pub duration_s: f64,
    /// Phase at t = 0 (rad).
    pub phase_rad: f64,
    /// How frequency and amplitude move.
    pub profile: Profile,
}

impl Chirp {
    /// The phase at time t (rad).
    pub fn phase(&self, t: f64) -> f64 {
        let tt = t.clamp(0.0, self.duration_s);
        let df = self.f1_hz - self.f0_hz;
        let ramp =
            self.f0_hz * tt + df * self.duration_s * self.profile.integral(tt / self.duration_s);
        let after = self.f1_hz * (t - self.duration_s).max(0.0);
        self.phase_rad + 2.0 * std::f64::consts::PI * (ramp + after)
    }

    /// The instantaneous frequency at time t (Hz).
    pub fn freq_hz(&self, t: f64) -> f64 {
        let s = self.profile.s((t / self.duration_s).clamp(0.0, 1.0));
        self.f0_hz + (self.f1_hz - self.f0_hz) * s
    }

    /// The peak amplitude at time t (m/s^2).
    pub fn amplitude_m_s2(&self, t: f64) -> f64 {
        let s = self.profile.s((t / self.duration_s).clamp(0.0, 1.0));
        self.a0_m_s2 + (self.a1_m_s2 - self.a0_m_s2) * s
    }
}

impl Excitation for Chirp {
    #[inline]
    fn accel(&self, t: f64) -> f64 {
        self.amplitude_m_s2(t) * self.phase(t).sin()
    }

    /// The end of the ramp, where the frequency's and amplitude's rates jump.
    fn next_breakpoint(&self, t: f64) -> f64 {
        if t < self.duration_s {
            self.duration_s
        } else {
            f64::INFINITY
        }
    }
}
