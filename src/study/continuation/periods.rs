//! The orbit at a fixed parameter value past a grazing that adds a strike, sought on the maps
//! over several drive periods where Newton's method on the one-period map fails.
//!
//! Past such a grazing the period map's derivatives grow like the inverse square root of the
//! distance from it (Nordmark, J. Sound Vib. 145, 1991), so that Newton's method on the
//! one-period map P from the last orbit before the grazing can miss the orbit with the added
//! strike even where that orbit is stable. The map over k periods, P^k, has the same fixed
//! point with the multipliers raised to the power k, and its Newton iteration from the same
//! start is another iteration, which can converge where the one on P does not. A fixed point
//! of P^k is an orbit of one period when P fixes it too: P moves it by less than
//! [`DISTINCT_REL`] (a thousand times the shooting tolerance) and Newton's method on P from it
//! then converges, so that its residual on P is below the shooting tolerance. Otherwise it is
//! an orbit of the least number of periods d dividing k whose map P^d moves it by less than
//! that, an orbit of another branch.

use nalgebra::SVector;

use crate::model::Model;
use crate::study::orbit::{Forcing, Orbit, DISTINCT_REL};

use super::corrector::Continuer;

/// The most drive periods of the maps on which an orbit is sought.
pub(super) const MAX_PERIODS: usize = 4;

/// An orbit found at a fixed parameter value.
pub(super) enum Shot {
    /// An orbit of one drive period (its residual on the one-period map below the shooting
    /// tolerance).
    One(Orbit),
    /// An orbit of several drive periods, its least number in [`Orbit::periods`].
    Several(Orbit),
}

impl<M: Model<N>, const N: usize> Continuer<'_, '_, M, N> {
    /// The orbits at `forcing` found by Newton's method on the maps over k = 1, 2, ...,
    /// [`MAX_PERIODS`] drive periods from the section state of `from` (at its section phase),
    /// in that order, each as the orbit of its least period (see the module docs). The first
    /// orbit of one period that `accept` takes ends the search; else the first orbit of
    /// several periods, if any.
    pub(super) fn shoot_periods(
        &mut self,
        forcing: &Forcing,
        from: &Orbit,
        accept: impl Fn(&Orbit) -> bool,
    ) -> Option<Shot> {
        let guess: SVector<f64, N> = from.state_n();
        let mut several = None;
        for k in 1..=MAX_PERIODS {
            match self.shot(forcing, from.phase_rad, guess, k) {
                Some(Shot::One(o)) if accept(&o) => return Some(Shot::One(o)),
                Some(Shot::Several(o)) if several.is_none() => several = Some(o),
                _ => {}
            }
        }
        several.map(Shot::Several)
    }

    /// The first stable orbit at `forcing` found by Newton's method on the maps over k = 1,
    /// 2, ..., [`MAX_PERIODS`] drive periods from the state `y` at drive phase `phase_rad`,
    /// each as the orbit of its least period, with its section moved into free flight.
    pub(super) fn stable_orbit_from(
        &mut self,
        forcing: &Forcing,
        phase_rad: f64,
        y: SVector<f64, N>,
    ) -> Option<Orbit> {
        let param = self.settings.parameter;
        for k in 1..=MAX_PERIODS {
            let Some(Shot::One(o) | Shot::Several(o)) = self.shot(forcing, phase_rad, y, k) else {
                continue;
            };
            if !o.is_stable() {
                continue;
            }
            if self.shooter.section_is_free(&o) {
                return Some(o);
            }
            if let Ok(o) = self.shooter.reanchor(&o, param, &mut self.stats) {
                return Some(o);
            }
        }
        None
    }

    /// The orbit found by Newton's method on the map over `k` drive periods from the state
    /// `y` at drive phase `phase_rad`, as the orbit of its least period; `None` where Newton's
    /// method or the reduction fails.
    fn shot(
        &mut self,
        forcing: &Forcing,
        phase_rad: f64,
        y: SVector<f64, N>,
        k: usize,
    ) -> Option<Shot> {
        let param = self.settings.parameter;
        let o = self
            .shooter
            .solve_periods(forcing, param, phase_rad, y, k, &mut self.stats)
            .ok()?;
        self.least_period(o)
    }

    /// The orbit `o`, a fixed point of the map over its `periods` drive periods, as an orbit
    /// of its least period: the least d dividing them whose map P^d moves its section state
    /// by less than [`DISTINCT_REL`] of its scaled norm, solved again by Newton's method on
    /// P^d from that state. `None` when an integration or that Newton iteration fails.
    fn least_period(&mut self, o: Orbit) -> Option<Shot> {
        let param = self.settings.parameter;
        let k = o.periods;
        let y: SVector<f64, N> = o.state_n();
        let d = (1..k)
            .filter(|&d| k.is_multiple_of(d))
            .find(|&d| {
                self.split(&o.forcing, o.phase_rad, y, d)
                    .is_some_and(|s| s < DISTINCT_REL)
            })
            .unwrap_or(k);
        let o = if d == k {
            o
        } else {
            self.shooter
                .solve_periods(&o.forcing, param, o.phase_rad, y, d, &mut self.stats)
                .ok()?
        };
        Some(if d == 1 {
            Shot::One(o)
        } else {
            Shot::Several(o)
        })
    }

    /// How far the map over `d` drive periods moves the state `y` (at drive phase
    /// `phase_rad`), relative to its scaled norm.
    fn split(
        &mut self,
        forcing: &Forcing,
        phase_rad: f64,
        y: SVector<f64, N>,
        d: usize,
    ) -> Option<f64> {
        let end = self.settle(forcing, phase_rad, y, d).ok()?;
        Some(self.shooter.norm(&(end - y)) / self.shooter.norm(&y).max(1e-300))
    }
}
