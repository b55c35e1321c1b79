//! An affine mode of a model under a sine, `y' = L y + c a(t) + d` ([`crate::model::Affine`]),
//! with its closed-form forced response.
//!
//! For `a(t) = A sin(w t + phi)` the periodic particular solution is
//!
//! `p(t) = A Im[z e^{i(w t + phi)}] + y_s`, with `z = (i w - L)^-1 c` and `L y_s + d = 0`,
//!
//! and every solution is `y(t0 + s) = e^{sL} (y(t0) - p(t0)) + p(t0 + s)`. Its derivatives
//! with respect to the drive's frequency and amplitude, the particular solutions of the
//! variational equations' parameter column, are
//! `dp/df = 2 pi A Im[(z' + i t z) e^{i(w t + phi)}]` with `z' = dz/dw = -i (i w - L)^-1 z`,
//! and `dp/da_rms = sqrt(2) g Im[z e^{i(w t + phi)}]`.

use nalgebra::{Complex, SMatrix, SVector};

use crate::drive::{Parameter, Sine};
use crate::model::{Affine, AffineGuard, Mode};

/// One affine mode under one sine drive (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct AffineMode<const N: usize> {
    /// The mode.
    pub(crate) mode: Mode,
    /// `L`.
    pub(crate) l: SMatrix<f64, N, N>,
    /// `c`, the drive's column.
    c: SVector<f64, N>,
    /// `d`, the constant term.
    pub(crate) d: SVector<f64, N>,
    /// The static part of the particular solution, `y_s`.
    y_s: SVector<f64, N>,
    /// `z = (i w - L)^-1 c`.
    z: SVector<Complex<f64>, N>,
    /// `dz/dw`.
    dz_dw: SVector<Complex<f64>, N>,
    /// The drive: peak amplitude (m/s^2), angular frequency (rad/s), phase (rad).
    amplitude: f64,
    omega: f64,
    phase: f64,
    /// The guards that can fire.
    pub(crate) guards: Vec<AffineGuard<N>>,
}

impl<const N: usize> AffineMode<N> {
    /// The forced response of the affine form `a` of `mode` under `sine`, or `None` when its
    /// static solution is not unique or its forced response not finite; `unused` are the
    /// components held at zero (their rows and columns of `L` vanish).
    pub(crate) fn of(mode: Mode, a: Affine<N>, sine: &Sine, unused: &[usize]) -> Option<Self> {
        let y_s = static_solution(&a.l, &a.d, unused)?;
        let omega = 2.0 * std::f64::consts::PI * sine.freq_hz;
        let c = a.c.map(|v| Complex::new(v, 0.0));
        let m = SMatrix::<Complex<f64>, N, N>::from_fn(|i, j| {
            let diag = if i == j { omega } else { 0.0 };
            Complex::new(-a.l[(i, j)], diag)
        });
        let lu = crate::num::dense::ComplexLu::of(&m);
        let z = lu.solve(&c)?;
        // dz/dw = -(i w - L)^-1 i z.
        let dz_dw = lu.solve(&z.map(|v| -Complex::<f64>::i() * v))?;
        if !(z
            .iter()
            .chain(dz_dw.iter())
            .all(|v| v.re.is_finite() && v.im.is_finite()))
        {
            return None;
        }
        Some(Self {
            mode,
            l: a.l,
            c: a.c,
            d: a.d,
            y_s,
            z,
            dz_dw,
            amplitude: sine.amplitude_m_s2,
            omega,
            phase: sine.phase_rad,
            guards: a.guards,
        })
    }

    /// The drive's phase at time `t` as (sin, cos).
    #[inline(always)]
    fn phase_at(&self, t: f64) -> (f64, f64) {
        (self.omega * t + self.phase).sin_cos()
    }

    /// The periodic particular solution `p(t)`.
    #[cfg(test)]
    pub(crate) fn particular(&self, t: f64) -> SVector<f64, N> {
        self.forced(t).0
    }

    /// The periodic particular solution `p(t)` and the drive `a(t)`.
    #[inline(always)]
    pub(crate) fn forced(&self, t: f64) -> (SVector<f64, N>, f64) {
        self.forced_at_phase(self.phase_at(t))
    }

    /// The periodic particular solution and the drive where the drive's phase has the sine
    /// and cosine `(s, c)`.
    #[inline(always)]
    pub(crate) fn forced_at_phase(&self, (s, c): (f64, f64)) -> (SVector<f64, N>, f64) {
        let mut p = self.y_s;
        for i in 0..N {
            p[i] += self.amplitude * (self.z[i].re * s + self.z[i].im * c);
        }
        (p, self.amplitude * s)
    }

    /// The right-hand side `L y + c a + d` under the drive `a`.
    #[inline(always)]
    pub(crate) fn rhs_with(&self, a: f64, y: &SVector<f64, N>) -> SVector<f64, N> {
        let mut f = self.l * y + self.d;
        for i in 0..N {
            if self.c[i] != 0.0 {
                f[i] += self.c[i] * a;
            }
        }
        f
    }

    /// The particular solution of the variational equations' parameter column: `dp/dp` at
    /// time `t` (see the module docs).
    pub(crate) fn sensitivity(&self, param: Parameter, t: f64) -> SVector<f64, N> {
        let (s, c) = self.phase_at(t);
        let e = Complex::new(c, s);
        let mut q = SVector::<f64, N>::zeros();
        match param {
            Parameter::Frequency => {
                let k = 2.0 * std::f64::consts::PI * self.amplitude;
                for i in 0..N {
                    q[i] = k * ((self.dz_dw[i] + Complex::<f64>::i() * t * self.z[i]) * e).im;
                }
            }
            Parameter::Amplitude => {
                let k = std::f64::consts::SQRT_2 * crate::G;
                for i in 0..N {
                    q[i] = k * (self.z[i] * e).im;
                }
            }
        }
        q
    }
}

/// The solution of `L y + d = 0` on the components not in `unused` (those are held at zero and
/// their rows and columns of `L` vanish); `None` when that block is singular.
fn static_solution<const N: usize>(
    l: &SMatrix<f64, N, N>,
    d: &SVector<f64, N>,
    unused: &[usize],
) -> Option<SVector<f64, N>> {
    if d.iter().all(|v| *v == 0.0) {
        return Some(SVector::zeros());
    }
    let live: Vec<usize> = (0..N).filter(|i| !unused.contains(i)).collect();
    let k = live.len();
    let block = nalgebra::DMatrix::from_fn(k, k, |i, j| l[(live[i], live[j])]);
    let rhs = nalgebra::DVector::from_fn(k, |i, _| -d[live[i]]);
    let sol = block.lu().solve(&rhs)?;
    let mut y = SVector::<f64, N>::zeros();
    for (i, &c) in live.iter().enumerate() {
        y[c] = sol[i];
    }
    y.iter().all(|v| v.is_finite()).then_some(y)
}

/// The largest angular frequency of the oscillations of `L` on the components not in `unused`
/// (the imaginary parts of its eigenvalues there, rad/s).
pub(crate) fn fastest_oscillation<const N: usize>(l: &SMatrix<f64, N, N>, unused: &[usize]) -> f64 {
    let live: Vec<usize> = (0..N).filter(|i| !unused.contains(i)).collect();
    let k = live.len();
    let block = nalgebra::DMatrix::from_fn(k, k, |i, j| l[(live[i], live[j])]);
    block
        .complex_eigenvalues()
        .iter()
        .fold(0.0f64, |m, ev| m.max(ev.im.abs()))
}
