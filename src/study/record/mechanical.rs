//! The fast path of a record whose model has no transducer: a linear free flight between rigid
//! stops that carries its mechanical state `(x, v)` alone.
//!
//! A model states the components it holds at zero ([`Model::unused`]); where those are every
//! component past the first mass's position and velocity, the free flight's `L` has zero rows
//! there and the drive's column has zeros there (checked), so the exact solution keeps them at
//! zero and `(x, v)` evolves by the leading 2 x 2 blocks of the propagator and of `L` alone. The
//! 2 x 2 products are the full ones' leading rows with the products by those zeros left out, so
//! the record is the one [`ExpFlight`] computes, bit for bit, at a quarter of the products;
//! the rebounds are located on the same Taylor series of the mechanical block
//! (`impacts.rs`). Intervals that leave free flight (chatter, a mass resting on a stop) still
//! go to Dormand-Prince on the whole state.

use nalgebra::{SMatrix, SVector};

use crate::model::{Mode, Model, Remainder, MAX_OUTPUTS};

use super::books::Books;
use super::exponential::{hermite_within, ExpFlight};
use super::impacts::{self, Rebounds, RigidStop};
use super::stepping::{FastPath, POSITION, VELOCITY};
use super::FreeFlightPath;

/// The mechanical state's dimension.
const M: usize = 2;

/// The fast path on `(x, v)` alone (see the module docs).
pub(super) struct Mechanical<R> {
    /// The leading block of `e^{hL}` and of the input's two columns.
    propagator: SMatrix<f64, M, M>,
    input_start: SVector<f64, M>,
    input_end: SVector<f64, M>,
    /// The leading block of `L`, of the drive's column and of `1 / scales`, for the rebounds.
    l: SMatrix<f64, M, M>,
    c: SVector<f64, M>,
    inv_scales: SVector<f64, M>,
    stops: Vec<RigidStop>,
    /// The sample interval (s).
    h: f64,
    /// Largest x and -x an interval may reach without a search for rebounds.
    upper: f64,
    lower: f64,
    /// The model's outputs at the end of each interval.
    remainder: R,
    /// The rebounds of the last interval.
    rebounds: Rebounds,
}

impl<R: Remainder<N>, const N: usize> ExpFlight<R, N> {
    /// The fast path on the mechanical state alone, where it applies: a linear free flight
    /// between rigid stops whose model holds every component past `(x, v)` at zero, with `L`
    /// and the drive's column zero in those rows, and no books to keep (they read the whole
    /// state's dense output).
    pub(super) fn mechanical<Mo: Model<N>>(
        &self,
        model: &Mo,
        books: bool,
    ) -> Option<Mechanical<R>> {
        let stops = self.rigid.as_ref()?;
        let mut unused = model.unused().to_vec();
        unused.sort_unstable();
        let held = unused == (M..N).collect::<Vec<_>>();
        let decoupled = (M..N).all(|i| self.c[i] == 0.0 && self.l.row(i).iter().all(|&v| v == 0.0));
        if books || !self.linear || N <= M || !held || !decoupled {
            return None;
        }
        let m = &self.method;
        Some(Mechanical {
            propagator: m.propagator.fixed_view::<M, M>(0, 0).into_owned(),
            input_start: m.input_start.fixed_rows::<M>(0).into_owned(),
            input_end: m.input_end.fixed_rows::<M>(0).into_owned(),
            l: self.l.fixed_view::<M, M>(0, 0).into_owned(),
            c: self.c.fixed_rows::<M>(0).into_owned(),
            inv_scales: self.inv_scales.fixed_rows::<M>(0).into_owned(),
            stops: stops.clone(),
            h: m.h,
            upper: self.upper,
            lower: self.lower,
            remainder: self.remainder,
            rebounds: Rebounds::default(),
        })
    }
}

impl<Mo: Model<N>, R: Remainder<N>, const N: usize> FastPath<Mo, N> for Mechanical<R> {
    /// The outputs' one evaluation per interval, as [`ExpFlight`] counts its remainder's.
    const RHS_EVALS: u64 = 1;

    fn path(&self) -> FreeFlightPath {
        FreeFlightPath::Exponential
    }

    /// One interval of free flight on `(x, v)`: the propagator's block, or where the cubic
    /// through its ends may come near a stop, its rebounds on the exact solution.
    #[inline(always)]
    fn step(
        &mut self,
        model: &Mo,
        _t0: f64,
        y: &SVector<f64, N>,
        mode: Mode,
        [a0, a1]: [f64; 2],
        outputs: &mut [f64; MAX_OUTPUTS],
        _books: Option<&mut Books<N>>,
    ) -> Option<(SVector<f64, N>, bool)> {
        self.rebounds.len = 0;
        if mode != Mode::FREE {
            return None;
        }
        let (x, v) = (POSITION, VELOCITY);
        let ym = SVector::<f64, M>::new(y[x], y[v]);
        let mut end = self.propagator * ym + self.input_start * a0 + self.input_end * a1;
        let h = self.h;
        if !hermite_within(ym[x], h * ym[v], end[x], h * end[v], self.upper, self.lower) {
            let whole = |at: &SVector<f64, M>| {
                let mut w = *y;
                w[x] = at[x];
                w[v] = at[v];
                w
            };
            let (found, rebounds) = impacts::interval(
                &self.l,
                &self.c,
                &self.inv_scales,
                &self.stops,
                &ym,
                h,
                [a0, a1],
                |guard, at: &mut SVector<f64, M>, a| {
                    let mut w = whole(at);
                    let free = model.switch(Mode::FREE, guard, &mut w, a) == Mode::FREE;
                    (at[x], at[v]) = (w[x], w[v]);
                    free
                },
            )?;
            self.rebounds = rebounds;
            end = found;
        }
        let mut next = *y;
        next[x] = end[x];
        next[v] = end[v];
        self.remainder.remainder_and_outputs(&next, outputs);
        Some((next, true))
    }

    fn rebounds(&self) -> &[(f64, f64)] {
        self.rebounds.found()
    }
}
