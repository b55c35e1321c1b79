//! The drive's phase on the half-grid of the exact steps, kept in a table of one period.
//!
//! The grid step is a whole fraction of the drive period (`h = T / n`), so the drive's phase at
//! the grid points and at the steps' midpoints, the times `k h / 2`, repeats every `2 n` of
//! them: its sine and cosine are found once per point of one period, when first needed, and
//! read back at every later period. A point whose neighbour one half-step or one step before
//! it is known is that neighbour turned by the rotation of `w h / 2` or `w h` (a few
//! multiplications instead of `sin_cos`); the first points of every [`SYNC`] half-steps are
//! computed by `sin_cos` of `w (j h / 2) + phi`, so that no chain of rotations is longer than
//! [`SYNC`] and their rounding cannot grow. The table's angle, `j = k mod 2n`, stays within one
//! period and is rounded less than `w t + phi` at `t = k h / 2`. Times off the half-grid (an
//! event) get the sine and cosine of `w t + phi`. The bisection of an event, whose points lie
//! at `t0 + sum of h / 2^j`, turns the phase at its lower end by the rotations of `w h / 2^j`
//! ([`PhaseGrid::turn`], each found once), a chain of at most 63 rotations from the phase at
//! `t0` (a value of the table, or `sin_cos` when the step starts at an event).

use crate::drive::Sine;

/// Largest distance of a time from the half-grid, in half-steps relative to its index, that
/// counts as on it: about a hundred times the rounding of `k h` and of a step's midpoint.
const ON_GRID: f64 = 1e-13;

/// The half-steps of the table filled from one `sin_cos` by rotations (see the module docs).
pub(crate) const SYNC: usize = 32;

/// The drive's (sin, cos) at the half-grid points of one period (see the module docs).
#[derive(Debug, Clone)]
pub(crate) struct PhaseGrid {
    /// Half the grid step (s).
    half_h: f64,
    /// The drive's angular frequency (rad/s) and phase (rad).
    omega: f64,
    phase: f64,
    /// (sin, cos) of `w h`.
    step_turn: (f64, f64),
    /// (sin, cos) at `j h / 2` for `j` in `0..2n`; NaN until first needed.
    table: Vec<(f64, f64)>,
    /// `dyadic_turns[j - 1]` = (sin, cos) of `w h / 2^j`: the half-step's from the start, the
    /// others when first needed.
    dyadic_turns: Vec<(f64, f64)>,
}

/// The phase `(s, c)` turned by the rotation `(sr, cr)`: (sin, cos) of the sum of the angles.
#[inline(always)]
pub(crate) fn turned((s, c): (f64, f64), (sr, cr): (f64, f64)) -> (f64, f64) {
    (s * cr + c * sr, c * cr - s * sr)
}

impl PhaseGrid {
    /// The table of `sine` on a grid of `steps` steps of `h` (s) per period.
    pub(crate) fn new(sine: &Sine, steps: usize, h: f64) -> Self {
        let omega = 2.0 * std::f64::consts::PI * sine.freq_hz;
        Self {
            half_h: 0.5 * h,
            omega,
            phase: sine.phase_rad,
            step_turn: (omega * h).sin_cos(),
            table: vec![(f64::NAN, f64::NAN); 2 * steps],
            dyadic_turns: vec![(omega * 0.5 * h).sin_cos()],
        }
    }

    /// (sin, cos) of `w h / 2^j`, `j >= 1`: the rotation of the phase by the bisection's step
    /// `h / 2^j`.
    #[inline(always)]
    pub(crate) fn turn(&mut self, j: usize) -> (f64, f64) {
        while self.dyadic_turns.len() < j {
            let k = self.dyadic_turns.len() + 1;
            let angle = self.omega * (2.0 * self.half_h) * 0.5f64.powi(k as i32);
            self.dyadic_turns.push(angle.sin_cos());
        }
        self.dyadic_turns[j - 1]
    }

    /// The drive's phase at time `t` as (sin, cos): from the table on the half-grid, by
    /// `sin_cos` elsewhere.
    #[inline(always)]
    pub(crate) fn at(&mut self, t: f64) -> (f64, f64) {
        let idx = t / self.half_h;
        // The nearest index (a negative time is never on the grid here: it takes `sin_cos`).
        let k = (idx + 0.5) as i64;
        if idx < 0.0 || (idx - k as f64).abs() > ON_GRID * idx.max(1.0) {
            return (self.omega * t + self.phase).sin_cos();
        }
        let j = (k as usize) % self.table.len();
        if self.table[j].0.is_nan() {
            self.table[j] = self.fill(j);
        }
        self.table[j]
    }

    /// The entry `j`: turned from its neighbour one step or one half-step before it within
    /// the same [`SYNC`] half-steps, else by `sin_cos`.
    fn fill(&self, j: usize) -> (f64, f64) {
        let known = |i: usize| i / SYNC == j / SYNC && !self.table[i].0.is_nan();
        if j >= 2 && known(j - 2) {
            turned(self.table[j - 2], self.step_turn)
        } else if j >= 1 && known(j - 1) {
            turned(self.table[j - 1], self.dyadic_turns[0])
        } else {
            (self.omega * (j as f64 * self.half_h) + self.phase).sin_cos()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table agrees with `sin_cos` of `w t + phi` on the grid, many periods on, to the
    /// rounding of the angle and of [`SYNC`] rotations, whether it is filled by the steps
    /// alone (a transient) or by the steps and their midpoints; off the grid it is `sin_cos`.
    #[test]
    fn table_matches_the_phase_on_and_off_the_grid() {
        let sine = Sine {
            freq_hz: 17.3,
            amplitude_m_s2: 1.0,
            phase_rad: 0.4,
        };
        let steps = 320;
        let h = sine.period_s() / steps as f64;
        let omega = 2.0 * std::f64::consts::PI * sine.freq_hz;
        for midpoints in [false, true] {
            let mut g = PhaseGrid::new(&sine, steps, h);
            for k in (0..3 * steps).chain(20_000..20_000 + steps) {
                let t = k as f64 * h;
                let ts = if midpoints {
                    vec![t, t + 0.5 * h]
                } else {
                    vec![t]
                };
                for t in ts {
                    let (s, c) = g.at(t);
                    let angle = omega * t + sine.phase_rad;
                    let (s0, c0) = angle.sin_cos();
                    let tol = 4.0 * f64::EPSILON * angle.abs() + 4.0 * SYNC as f64 * f64::EPSILON;
                    assert!(
                        (s - s0).abs() <= tol && (c - c0).abs() <= tol,
                        "{k} {t}: {s} {s0} {c} {c0}"
                    );
                }
            }
        }
        let mut g = PhaseGrid::new(&sine, steps, h);
        let t = 3.3 * h;
        assert_eq!(g.at(t), (omega * t + sine.phase_rad).sin_cos());
    }

    /// A bisection from a grid point far on, its lower end turned by the dyadic rotations
    /// (going up at every odd halving), agrees with `sin_cos` of `w t + phi` at every point to
    /// the rounding of the angle and of the chain (the table's [`SYNC`] rotations and one per
    /// halving).
    #[test]
    fn dyadic_turns_follow_the_phase_through_a_bisection() {
        let sine = Sine {
            freq_hz: 23.9,
            amplitude_m_s2: 1.0,
            phase_rad: -1.1,
        };
        let steps = 640;
        let h = sine.period_s() / steps as f64;
        let omega = 2.0 * std::f64::consts::PI * sine.freq_hz;
        let mut g = PhaseGrid::new(&sine, steps, h);
        let t0 = 70_001.0 * h;
        let mut lo = 0.0;
        let mut phase_lo = g.at(t0);
        for j in 1..=52usize {
            let ds = h * 0.5f64.powi(j as i32);
            let phase_c = turned(phase_lo, g.turn(j));
            let angle = omega * (t0 + lo + ds) + sine.phase_rad;
            let (s0, c0) = angle.sin_cos();
            let tol = 4.0 * f64::EPSILON * angle.abs() + 4.0 * (SYNC + j) as f64 * f64::EPSILON;
            assert!(
                (phase_c.0 - s0).abs() <= tol && (phase_c.1 - c0).abs() <= tol,
                "halving {j}: {phase_c:?} against ({s0}, {c0})"
            );
            if j % 2 == 1 {
                (lo, phase_lo) = (lo + ds, phase_c);
            }
        }
    }
}
