//! The uncertainty of a fit at its optimum (see the parent module's "Uncertainty" and "What
//! the data do not determine"): the Gauss-Newton covariance from the column-scaled Jacobian's
//! singular value decomposition, the 95 % intervals mapped back through the transforms, the
//! correlations, and the combinations the data do not determine.

use nalgebra::DMatrix;

use super::params::Transform;
use super::{FitWarning, FittedParam, COLUMN_NOISE_REL, NUMERICALLY_ZERO, SINGULAR_RATIO_WARN};
use crate::device::ParamRange;

/// The Jacobian at the optimum with its columns scaled to unit length, and what the
/// covariance and the identifiability test need of it.
pub(super) struct Scaled {
    /// Column norms (zero: a column below the model's numerical noise).
    norms: Vec<f64>,
    /// Singular values of the scaled Jacobian.
    sv: Vec<f64>,
    /// Its right singular vectors, as rows.
    v_t: DMatrix<f64>,
}

impl Scaled {
    /// The decomposition of `jac` (rows: residuals, columns: parameters).
    pub(super) fn of(jac: &DMatrix<f64>) -> Self {
        let (n, p) = jac.shape();
        let norms: Vec<f64> = (0..p).map(|j| jac.column(j).norm()).collect();
        let norm_max = norms.iter().copied().fold(0.0, f64::max);
        // A column below the model's numerical noise is a parameter the model does not
        // depend on.
        let norms: Vec<f64> = norms
            .into_iter()
            .map(|c| {
                if c < COLUMN_NOISE_REL * norm_max {
                    0.0
                } else {
                    c
                }
            })
            .collect();
        let scaled = DMatrix::from_fn(n, p, |i, j| {
            if norms[j] > 0.0 {
                jac[(i, j)] / norms[j]
            } else {
                0.0
            }
        });
        let svd = scaled.svd(false, true);
        let v_t = svd.v_t.unwrap_or_else(|| DMatrix::identity(p, p));
        Self {
            norms,
            sv: svd.singular_values.iter().copied().collect(),
            v_t,
        }
    }

    fn smax(&self) -> f64 {
        self.sv.iter().copied().fold(0.0, f64::max)
    }

    /// The covariance of the transformed coordinates, `scale2 (J^T J)^-1`
    /// `= scale2 D^-1 V S^-2 V^T D^-1` (D: the column norms). A direction with a zero
    /// singular value (relative to the largest, below [`NUMERICALLY_ZERO`]) has an infinite
    /// variance, and so has every parameter that takes part in it: its interval is then the
    /// whole range, never a spuriously narrow one.
    pub(super) fn covariance(&self, scale2: f64) -> DMatrix<f64> {
        let p = self.norms.len();
        let (sv, v_t, norms, smax) = (&self.sv, &self.v_t, &self.norms, self.smax());
        DMatrix::from_fn(p, p, |i, j| {
            let mut c = 0.0;
            for k in 0..sv.len() {
                let w = v_t[(k, i)] * v_t[(k, j)];
                if sv[k] <= NUMERICALLY_ZERO * smax {
                    if w.abs() > NUMERICALLY_ZERO || (i == j && norms[i] == 0.0) {
                        c += if i == j { f64::INFINITY } else { f64::NAN };
                    }
                } else {
                    c += w / (sv[k] * sv[k]);
                }
            }
            if norms[i] > 0.0 && norms[j] > 0.0 {
                scale2 * c / (norms[i] * norms[j])
            } else if i == j {
                f64::INFINITY
            } else {
                f64::NAN
            }
        })
    }

    /// The combinations the data do not determine (singular values below
    /// [`SINGULAR_RATIO_WARN`] times the largest), each as relative changes of the
    /// parameters at `u` (values `p_fit`), and the smallest ratio.
    pub(super) fn undetermined(
        &self,
        free: &[ParamRange],
        tr: &[Transform],
        u: &[f64],
        p_fit: &[f64],
    ) -> (Vec<FitWarning>, f64) {
        let p = free.len();
        let smax = self.smax();
        let mut warnings = Vec::new();
        let mut singular_ratio = 1.0;
        for (k, &s) in self.sv.iter().enumerate() {
            let ratio = if smax > 0.0 { s / smax } else { 0.0 };
            singular_ratio = f64::min(singular_ratio, ratio);
            if ratio >= SINGULAR_RATIO_WARN {
                continue;
            }
            // The direction in the scaled coordinates, back to du and then to relative
            // changes. A parameter pinned at an end of its range has dp/du = 0: its component
            // is 0 here and it is reported by [`FitWarning::AtBound`].
            let comps: Vec<f64> = (0..p)
                .map(|j| {
                    let v = self.v_t[(k, j)];
                    let du = if self.norms[j] > 0.0 {
                        v / self.norms[j]
                    } else {
                        v
                    };
                    let dp = du * tr[j].dp_du(u[j]);
                    let c = if p_fit[j] != 0.0 && free[j].lo > 0.0 {
                        dp / p_fit[j]
                    } else {
                        dp
                    };
                    if c.is_finite() {
                        c
                    } else {
                        0.0
                    }
                })
                .collect();
            let big = comps.iter().fold(0.0_f64, |m, c| m.max(c.abs()));
            let sign = comps
                .iter()
                .copied()
                .find(|c| c.abs() == big)
                .map_or(1.0, f64::signum);
            warnings.push(FitWarning::Undetermined {
                direction: free
                    .iter()
                    .zip(&comps)
                    .filter(|(_, c)| c.abs() >= 1e-3 * big)
                    .map(|(f, c)| (f.path.clone(), sign * c / big))
                    .collect(),
                ratio,
            });
        }
        (warnings, singular_ratio)
    }
}

/// The fitted parameters with their standard errors and 95 % intervals (`u +- q se_u` mapped
/// back; the whole range where the variance is infinite, NaN where there is none), and the
/// correlation matrix, from the covariance `cov_u` of the transformed coordinates at `u`.
pub(super) fn parameters(
    free: &[ParamRange],
    tr: &[Transform],
    starts: &[f64],
    u: &[f64],
    cov_u: &DMatrix<f64>,
    q: f64,
) -> (Vec<FittedParam>, Vec<Vec<f64>>) {
    let p = free.len();
    let params = (0..p)
        .map(|k| {
            let se_u = cov_u[(k, k)].max(0.0).sqrt();
            let (a, b) = (tr[k].to_p(u[k] - q * se_u), tr[k].to_p(u[k] + q * se_u));
            let (interval, std_err) = if !q.is_finite() || se_u.is_nan() {
                ((f64::NAN, f64::NAN), f64::NAN)
            } else if se_u.is_infinite() {
                ((free[k].lo, free[k].hi), f64::INFINITY)
            } else {
                ((a.min(b), a.max(b)), tr[k].dp_du(u[k]).abs() * se_u)
            };
            FittedParam {
                path: free[k].path.clone(),
                start: starts[k],
                value: tr[k].to_p(u[k]),
                std_err,
                interval,
                range: (free[k].lo, free[k].hi),
            }
        })
        .collect();
    let correlation = (0..p)
        .map(|i| {
            (0..p)
                .map(|j| cov_u[(i, j)] / (cov_u[(i, i)] * cov_u[(j, j)]).sqrt())
                .collect()
        })
        .collect();
    (params, correlation)
}
