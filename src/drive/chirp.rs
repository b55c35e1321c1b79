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

/// The samples `a(k / fs)`, `k = 0 ..= n`, of a record under a sine of peak `amplitude_m_s2`
/// that holds `f0_hz` through its first `hold` samples (a record's pre-roll) and from there
/// sweeps linearly to `f1_hz` at sample `n`, at a continuous phase: `A sin(2 pi f0 k / fs)` up
/// to sample `hold`, then a [`Chirp`] (linear profile, from the phase `2 pi f0 hold / fs`,
/// over `(n - hold) / fs`) at `(k - hold) / fs`. With `f1 = f0`, or no sample after `hold`,
/// every sample is the sine's.
///
/// ```
/// use endstop::drive::swept_sine_samples;
///
/// // 1 m/s^2 at 100 Hz for 0.1 s, then swept to 200 Hz over 1 s, at 10 kHz.
/// let a = swept_sine_samples(1.0, 100.0, 200.0, 10e3, 1000, 11_000);
/// assert_eq!(a.len(), 11_001);
/// // Over the sweep the phase advances by 2 pi T (f0 + f1) / 2: 150 turns, so the samples
/// // cross zero upwards 150 times (to one at the window's ends).
/// let ups = a[1000..].windows(2).filter(|w| w[0] < 0.0 && w[1] >= 0.0).count();
/// assert!((ups as i64 - 150).abs() <= 1);
/// ```
pub fn swept_sine_samples(
    amplitude_m_s2: f64,
    f0_hz: f64,
    f1_hz: f64,
    sample_rate_hz: f64,
    hold: usize,
    n: usize,
) -> Vec<f64> {
    let tau = 2.0 * std::f64::consts::PI;
    let w = tau * f0_hz / sample_rate_hz;
    let sine = |k: usize| amplitude_m_s2 * (w * k as f64).sin();
    if f1_hz == f0_hz || n <= hold {
        return (0..=n).map(sine).collect();
    }
    let chirp = Chirp {
        f0_hz,
        f1_hz,
        a0_m_s2: amplitude_m_s2,
        a1_m_s2: amplitude_m_s2,
        duration_s: (n - hold) as f64 / sample_rate_hz,
        phase_rad: w * hold as f64,
        profile: Profile::Linear,
    };
    (0..=n)
        .map(|k| match k.checked_sub(hold) {
            Some(j) if j > 0 => chirp.accel(j as f64 / sample_rate_hz),
            _ => sine(k),
        })
        .collect()
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

#[cfg(test)]
mod tests {
    use super::swept_sine_samples;
    use std::f64::consts::PI;

    /// The swept samples hold the closed-form phase of a sine at f0 through the hold and of a
    /// linear chirp after it, `phi(t) = 2 pi (f0 t + (f1 - f0) (t - th)^2 / (2 T))`: between
    /// successive upward zero crossings of the samples (located by linear interpolation) the
    /// closed form advances by one turn.
    ///
    /// Tolerance: linear interpolation between samples `h` apart places a root of `A sin phi`
    /// within `max|a''| h^2 / (8 |a'|)`, with `|a''| <= A (phi'^3 h + phi'')` near the root
    /// (`|sin phi| <= phi' h` there) and `|a'| = A phi'`; each turn carries two such errors,
    /// read as phase at `phi'`: `2 f1 (phi1'^2 h^3 + phi'' h^2 / phi0') / 8` turns, 8.4e-8 here.
    /// Rounding of the samples (phases up to about 1e3 rad) moves a root by about 1e-16 s.
    #[test]
    fn the_swept_samples_follow_the_chirps_closed_form_phase() {
        let (f0, f1, fs) = (100.0, 200.0, 100e3);
        let (hold, n) = (10_000, 110_000);
        let (th, sweep) = (hold as f64 / fs, (n - hold) as f64 / fs);
        let a = swept_sine_samples(2.0, f0, f1, fs, hold, n);
        assert_eq!(a.len(), n + 1);
        let phase = |t: f64| {
            let late = (t - th).max(0.0);
            2.0 * PI * (f0 * t + (f1 - f0) * late * late / (2.0 * sweep))
        };
        let h = 1.0 / fs;
        let (w0, w1, dw) = (2.0 * PI * f0, 2.0 * PI * f1, 2.0 * PI * (f1 - f0) / sweep);
        let tol = 2.0 * f1 * (w1 * w1 * h * h * h + dw * h * h / w0) / 8.0;
        let ups: Vec<f64> = a
            .windows(2)
            .enumerate()
            .filter(|(_, w)| w[0] < 0.0 && w[1] >= 0.0)
            .map(|(k, w)| (k as f64 + w[0] / (w[0] - w[1])) * h)
            .collect();
        // 10 turns in the hold, 150 in the sweep.
        assert!(
            (ups.len() as i64 - 160).abs() <= 1,
            "{} crossings",
            ups.len()
        );
        let worst = ups
            .windows(2)
            .map(|t| ((phase(t[1]) - phase(t[0])) / (2.0 * PI) - 1.0).abs())
            .fold(0.0, f64::max);
        assert!(
            worst <= tol,
            "worst turn off by {worst:e}, tolerance {tol:e}"
        );
    }

    /// Without a sweep the samples are the sine's, `A sin(2 pi f0 k / fs)`, bit for bit.
    #[test]
    fn an_unswept_record_is_the_sine() {
        let a = swept_sine_samples(3.0, 50.0, 50.0, 1e3, 10, 100);
        let w = 2.0 * PI * 50.0 / 1e3;
        assert!(a
            .iter()
            .enumerate()
            .all(|(k, &v)| v == 3.0 * (w * k as f64).sin()));
    }
}
