//! One explicit Runge-Kutta step driven by a [`Tableau`]: the stages, the end state, the
//! embedded error estimate and the dense output, shared by the adaptive driver
//! ([`crate::ode::Adaptive`]) and the fixed-step one ([`crate::ode::FixedStep`]).
//!
//! # Sums
//! Every weighted sum of stages runs over the **nonzero** coefficients only, left to right in
//! stage order, and is scaled by the step at the end: `(w_1 k_1 + w_3 k_3 + ...) h`. A single
//! nonzero coefficient is scaled first, `k_j (w_j h)`. These are the formulas as one writes
//! them out for a given method (Hairer's DOPRI5 does), so a method driven by its tableau
//! rounds exactly as the written-out method does. Dropping a zero term is not a matter of
//! speed only: `x + 0 k` is `x` for finite `k`, but `-0 + 0` is `+0` and `0 k` is NaN for an
//! infinite `k`.
//!
//! The tableau is an associated constant of the method's type ([`Method`]), and the functions
//! here are inlined into the drivers, which are compiled once per method: the coefficients
//! are constants, the loops over stages have constant bounds, and the zero tests fold away.
//! The loop over the stages is written out ([`each_stage`]): a `for` loop whose body calls the
//! right-hand side is not unrolled by the compiler, and each stage's coefficients would then
//! be read from memory and tested for zero at run time (the records took about 10 % longer).

use crate::ode::tableau::{Method, Tableau};
use crate::ode::{HybridSystem, Vector};

/// Most stages a method may have (the loop over stages is written out up to this).
pub(crate) const MAX_STAGES: usize = 16;

/// Runs `$body` with `$i` bound to each constant `1, 2, ..., $s - 1` in turn (stages after the
/// first), each a literal, so that the stage's coefficients are constants in its copy of the
/// body; `$s` is at most [`MAX_STAGES`].
macro_rules! each_stage {
    ($s:expr, $i:ident => $body:block) => {
        each_stage!(@ $s, $i, $body, 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15)
    };
    (@ $s:expr, $i:ident, $body:block, $($n:literal)*) => {
        $(
            if $n < $s {
                let $i: usize = $n;
                $body
            }
        )*
    };
}

/// `(sum_j w_j k_j) h` over the nonzero `w_j`, in order (`k_j (w_j h)` for a single one; zero
/// for none).
#[inline(always)]
pub(crate) fn weighted<V: Vector, const S: usize>(w: &[f64; S], k: &[V; S], h: f64) -> V {
    let mut nonzero = 0;
    let mut last = 0;
    for (j, &wj) in w.iter().enumerate() {
        if wj != 0.0 {
            nonzero += 1;
            last = j;
        }
    }
    if nonzero == 0 {
        return V::zeros();
    }
    if nonzero == 1 {
        return k[last] * (w[last] * h);
    }
    let mut sum: Option<V> = None;
    for (j, &wj) in w.iter().enumerate() {
        if wj != 0.0 {
            let term = k[j] * wj;
            sum = Some(match sum {
                None => term,
                Some(s) => s + term,
            });
        }
    }
    sum.unwrap_or_else(V::zeros) * h
}

/// The stages of one step of length `h` from `(t, y)` in `mode`, given the first stage
/// `k1 = f(t, y)`, and the end state `y1`. Evaluates the right-hand side `S - 1` times. For a
/// first-same-as-last method the last stage's argument is `y1` and the last stage is
/// `f(t + h, y1)`.
#[inline(always)]
pub(crate) fn stages<Sys, M, const S: usize>(
    sys: &Sys,
    mode: Sys::Mode,
    t: f64,
    y: &Sys::State,
    k1: Sys::State,
    h: f64,
) -> ([Sys::State; S], Sys::State)
where
    Sys: HybridSystem,
    M: Method<S>,
{
    let tab: &Tableau<S> = &M::TABLEAU;
    let fsal = const {
        assert!(S <= MAX_STAGES, "more stages than MAX_STAGES");
        M::TABLEAU.is_fsal()
    };
    let mut k = [Sys::State::zeros(); S];
    k[0] = k1;
    let mut y1 = *y;
    each_stage!(S, i => {
        let yi = *y + weighted(&tab.a[i], &k, h);
        k[i] = sys.rhs(mode, t + tab.c[i] * h, &yi);
        if fsal && i == S - 1 {
            y1 = yi;
        }
    });
    if !fsal {
        y1 = *y + weighted(&tab.b, &k, h);
    }
    (k, y1)
}

/// The embedded error estimate `h sum_j error_j k_j` of a step's stages (see
/// [`Tableau::error`]); a method without one does not compile here.
#[inline(always)]
pub(crate) fn error_estimate<M, V: Vector, const S: usize>(k: &[V; S], h: f64) -> V
where
    M: Method<S>,
{
    let e = const {
        match M::TABLEAU.error {
            Some(e) => e,
            None => panic!("the method has no embedded error estimate"),
        }
    };
    weighted(&e, k, h)
}

/// The coefficients of the dense output over a step from `y0` to `y1` with stages `k` (see
/// [`Tableau::dense`]), as [`crate::ode::Step`] evaluates them:
/// `[y0, y1 - y0, h f0 - (y1 - y0), (y1 - y0) - h f1 - (h f0 - (y1 - y0)), h sum_j d_j k_j]`.
/// A method without dense output, or whose last stage is not `f(t1, y1)`, does not compile
/// here.
#[inline]
pub(crate) fn dense_output<M, V: Vector, const S: usize>(
    y0: &V,
    y1: &V,
    k: &[V; S],
    h: f64,
) -> [V; 5]
where
    M: Method<S>,
{
    let d = const {
        assert!(
            M::TABLEAU.is_fsal(),
            "the dense output needs the last stage at the step's end"
        );
        match M::TABLEAU.dense {
            Some(d) => d,
            None => panic!("the method has no dense output"),
        }
    };
    let ydiff = *y1 - *y0;
    let bspl = k[0] * h - ydiff;
    let r3 = ydiff - k[S - 1] * h - bspl;
    let r4 = weighted(&d, k, h);
    [*y0, ydiff, bspl, r3, r4]
}
