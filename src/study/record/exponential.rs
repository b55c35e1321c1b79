//! The exponential free-flight step of [`Scheme::Exponential`](super::Scheme::Exponential) for
//! a model that splits its free flight ([`crate::model::FlightSplit`]), with its check against
//! the stops.

use nalgebra::{SMatrix, SVector};

use crate::model::{FlightSplit, Mode, Model, Remainder, MAX_OUTPUTS};
use crate::num::polynomial::hermite_range;
use crate::ode::exponential::{resolves, ExpAdams, History};
use crate::ode::GAUSS_LEGENDRE_3;

use super::books::Books;
use super::impacts::{self, Rebounds, RigidStop};
use super::stepping::{FastPath, POSITION, VELOCITY};
use super::{Fallback, FreeFlightPath, EXPONENTIAL_ORDER, STOP_MARGIN};

/// The exponential step for one model, remainder type `R` and sample interval (see the module
/// docs).
pub(super) struct ExpFlight<R, const N: usize> {
    pub(super) remainder: R,
    pub(super) method: ExpAdams<N, EXPONENTIAL_ORDER>,
    /// The remainder at the last samples since the last mode switch.
    history: History<N, EXPONENTIAL_ORDER>,
    /// Largest x an exponential step may reach: the upper gap less [`STOP_MARGIN`] of it
    /// (infinite without a stop), or the split's reach.
    pub(super) upper: f64,
    /// Largest -x an exponential step may reach.
    pub(super) lower: f64,
    /// `L`, `c` and the scales, for the dense output the books read.
    pub(super) l: SMatrix<f64, N, N>,
    pub(super) c: SVector<f64, N>,
    scales: SVector<f64, N>,
    /// The step's dense output at the Gauss nodes, once the books ask for it.
    dense: Option<[ExpAdams<N, EXPONENTIAL_ORDER>; 3]>,
    /// The free flight is linear: its remainder is identically zero, so a step needs no
    /// history and is the propagator's product with the input's two columns alone.
    pub(super) linear: bool,
    /// A linear free flight resolved by the sample interval between rigid stops: its stops,
    /// where an interval's rebounds are located on the exact solution (`impacts.rs`).
    pub(super) rigid: Option<Vec<RigidStop>>,
    /// `1 / scales`.
    pub(super) inv_scales: SVector<f64, N>,
    /// The rebounds of the last step.
    rebounds: Rebounds,
}

impl<R: Remainder<N>, const N: usize> ExpFlight<R, N> {
    /// The fast path of a model with a free-flight split, or why the record goes to
    /// Dormand-Prince throughout: the free flight is nonlinear and the sample interval `dt`
    /// does not resolve its dynamics ([`resolves`]), or a nonlinear suspension's reach does not
    /// cover the point it is linearised about. A linear free flight is integrated exactly
    /// whatever its time constants ([`ExpAdams::new`]).
    pub(super) fn new<M: Model<N>>(
        model: &M,
        dt: f64,
        split: FlightSplit<N>,
        remainder: R,
    ) -> Result<Self, Fallback> {
        let scales = model.scales();
        if !split.linear && !resolves(&split.l, dt, &scales) {
            return Err(Fallback::Unresolved);
        }
        let method = ExpAdams::new(&split.l, &split.c, dt, &scales);
        // A nonlinear suspension bounds the step's reach like a stop (see `Spring`).
        if split.reach_m <= split.centre_m.abs() {
            return Err(Fallback::StiffSuspension);
        }
        let gap = |side: f64| {
            model
                .contacts()
                .iter()
                .filter(|c| c.mass == 0 && c.other.is_none() && c.side == side)
                .map(|c| c.gap)
                .fold(f64::INFINITY, f64::min)
        };
        Ok(Self {
            remainder,
            method,
            history: History::default(),
            upper: (gap(1.0) * (1.0 - STOP_MARGIN)).min(split.reach_m),
            lower: (gap(-1.0) * (1.0 - STOP_MARGIN)).min(split.reach_m),
            l: split.l,
            c: split.c,
            scales,
            dense: None,
            linear: split.linear,
            rigid: (split.linear && resolves(&split.l, dt, &scales))
                .then(|| impacts::rigid_stops(model))
                .flatten(),
            inv_scales: scales.map(|s| 1.0 / s),
            rebounds: Rebounds::default(),
        })
    }
}

impl<M: Model<N>, R: Remainder<N>, const N: usize> FastPath<M, N> for ExpFlight<R, N> {
    const RHS_EVALS: u64 = 1;

    fn path(&self) -> FreeFlightPath {
        FreeFlightPath::Exponential
    }

    fn start(&mut self, _model: &M, y: &SVector<f64, N>, _mode: Mode) {
        self.history.push(self.remainder.remainder(y));
    }

    /// One exponential step where the mass flies free, the remainder has
    /// [`EXPONENTIAL_ORDER`] values since the last switch (or the free flight is linear, its
    /// remainder zero), and the cubic through the
    /// positions and velocities at the step's ends stays [`STOP_MARGIN`] clear of the stops.
    ///
    /// Forced inline, with the exponential step and the stop check it calls: this is the
    /// record's inner loop, and with the loop generic over its observer the compiler does not
    /// inline them on its own, which costs 14 to 16 % of a record (measured; the profile shows
    /// them as functions of their own).
    #[inline(always)]
    fn step(
        &mut self,
        model: &M,
        t0: f64,
        y: &SVector<f64, N>,
        mode: Mode,
        [a0, a1]: [f64; 2],
        outputs: &mut [f64; MAX_OUTPUTS],
        books: Option<&mut Books<N>>,
    ) -> Option<(SVector<f64, N>, bool)> {
        self.rebounds.len = 0;
        if mode != Mode::FREE || !(self.linear || self.history.is_full()) {
            return None;
        }
        let next = if self.linear {
            // The remainder's terms are products with exact zeros.
            let m = &self.method;
            m.propagator * y + m.input_start * a0 + m.input_end * a1
        } else {
            self.method.step(y, a0, a1, &self.history)
        };
        let h = self.method.h;
        let (x, v) = (POSITION, VELOCITY);
        if !hermite_within(y[x], h * y[v], next[x], h * next[v], self.upper, self.lower) {
            // Rebounds on the exact solution, where no books ask for the interval's integrals.
            let (Some(stops), None) = (&self.rigid, &books) else {
                return None;
            };
            let (end, rebounds) = impacts::interval(
                &self.l,
                &self.c,
                &self.inv_scales,
                stops,
                y,
                h,
                [a0, a1],
                |guard, at, a| model.switch(Mode::FREE, guard, at, a) == Mode::FREE,
            )?;
            self.rebounds = rebounds;
            let r = self.remainder.remainder_and_outputs(&end, outputs);
            self.history.push(r);
            return Some((end, true));
        }
        if let Some(b) = books {
            let (l, c, scales) = (&self.l, &self.c, &self.scales);
            let dense = self.dense.get_or_insert_with(|| {
                GAUSS_LEGENDRE_3.map(|(x, _)| ExpAdams::dense(l, c, h, x, scales))
            });
            b.open(model, mode, y);
            let history = &self.history;
            b.add_nodes(model, mode, t0, h, |i| dense[i].step(y, a0, a1, history));
            b.close(mode, &next);
        }
        let r = self.remainder.remainder_and_outputs(&next, outputs);
        self.history.push(r);
        Some((next, true))
    }

    fn rebounds(&self) -> &[(f64, f64)] {
        self.rebounds.found()
    }

    /// The remainder is smooth only between mode switches.
    fn after_dopri(&mut self, _model: &M, y: &SVector<f64, N>, mode: Mode, switched: bool) {
        if switched {
            self.history.clear();
        }
        if mode == Mode::FREE {
            self.history.push(self.remainder.remainder(y));
        } else {
            self.history.clear();
        }
    }
}

/// Checks that the cubic Hermite interpolant of x over a step (end values `x0`, `x1`, end
/// slopes times the step `m0`, `m1`) stays below `upper` and above `-lower`.
///
/// The Hermite basis functions of the slopes are at most 4/27 in absolute value and those of
/// the values are non-negative and sum to one, so `max(x0, x1) + 4/27 (|m0| + |m1|)` bounds
/// the cubic from above (and its mirror from below); most steps stop at that test. Otherwise
/// the cubic's interior extrema (the roots of its derivative) are checked.
#[inline(always)]
pub(super) fn hermite_within(x0: f64, m0: f64, x1: f64, m1: f64, upper: f64, lower: f64) -> bool {
    let slack = 4.0 / 27.0 * (m0.abs() + m1.abs());
    let (hi, lo) = (max2(x0, x1), -max2(-x0, -x1));
    if hi + slack < upper && -lo + slack < lower {
        return true;
    }
    let (min, max) = hermite_range(x0, m0, x1, m1);
    max < upper && -min < lower
}

/// The larger of two values by plain comparison.
#[inline(always)]
fn max2(a: f64, b: f64) -> f64 {
    if a > b {
        a
    } else {
        b
    }
}

#[cfg(test)]
mod tests {
    use super::hermite_within;

    /// A cubic that bulges past the bound between two ends inside it is caught by the
    /// interior-extremum test, and one that stays inside passes; the mirror bound likewise.
    #[test]
    fn the_hermite_check_sees_an_interior_excursion() {
        // x(θ) = 4 θ (1 - θ): ends at 0 with slopes 4 and -4, peak 1 at θ = 1/2.
        assert!(!hermite_within(0.0, 4.0, 0.0, -4.0, 0.99, 1.0));
        assert!(hermite_within(0.0, 4.0, 0.0, -4.0, 1.01, 1.0));
        assert!(!hermite_within(0.0, -4.0, 0.0, 4.0, 1.0, 0.99));
        assert!(hermite_within(0.0, -4.0, 0.0, 4.0, 1.0, 1.01));
    }
}
