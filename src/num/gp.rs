//! Gaussian-process emulators of noisy simulators: universal kriging with a linear mean, an
//! anisotropic Matérn 5/2 covariance, a **heteroscedastic nugget** (each training point's own
//! sampling variance, known) plus a fitted homoscedastic one, hyperparameters by restricted
//! maximum likelihood, and closed-form leave-one-out diagnostics.
//!
//! # Model
//! `y_i = h(x_i)^T beta + f(x_i) + e_i`, with `h(x) = (1, x_1, ..., x_d)` (a linear mean whose
//! coefficients have a flat prior: universal kriging), `f` a zero-mean process with covariance
//! `s2 k(x, x')`, `k` the Matérn 5/2 correlation of the scaled distance
//! `r = sqrt(sum_j ((x_j - x'_j) / l_j)^2)`, `k = (1 + sqrt5 r + 5 r^2 / 3) exp(-sqrt5 r)`, and
//! `e_i ~ N(0, v_i + t2)`: `v_i` the point's own sampling variance (an ensemble's squared
//! standard error, given) and `t2` a fitted nugget for what the smooth process does not follow
//! (a censored value, a switch of branch). Outputs are standardised by their sample mean and
//! standard deviation before the fit and mapped back on prediction.
//!
//! # Fit
//! The hyperparameters `(ln l_1..d, ln s2, ln t2)` maximise the restricted likelihood
//! `-1/2 y^T Q y - 1/2 ln|K| - 1/2 ln|H^T K^-1 H|`, `Q = K^-1 - K^-1 H (H^T K^-1 H)^-1 H^T K^-1`,
//! whose gradient is `1/2 (Qy)^T dK (Qy) - 1/2 tr(Q dK)`, by argmin's L-BFGS from a few starts,
//! each parameter kept inside its box by a logistic map ([`GpSettings`] gives the boxes).
//!
//! # Leave-one-out
//! With the hyperparameters fixed, the prediction of `y_i` from the other points has error
//! `(Qy)_i / Q_ii` and variance `1 / Q_ii` (Dubrule 1983, universal kriging), which include the
//! point's nugget: the standardised error `(Qy)_i / sqrt(Q_ii)` is N(0, 1) when the emulator is
//! right, so about 95 % of them lie within +-2 and nearly all within +-3.
//!
//! Written here rather than taken from a crate: the two Rust Gaussian-process crates lack the
//! heteroscedastic nugget this study needs (each ensemble point has its own sampling variance).
//! `friedrich` has isotropic kernels only (one length scale for all inputs, where the study's
//! inputs differ in relevance by orders of magnitude) and one noise level; `egobox-gp` is
//! anisotropic but noise-free (a relative nugget for conditioning only) and brings the linfa and
//! ndarray stacks beside the nalgebra this crate uses. The nugget enters the matrix that is
//! factorised, so it cannot be added around either crate's model.

use argmin::core::{CostFunction, Error as ArgminError, Executor, Gradient, State};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::LBFGS;
use nalgebra::{Cholesky, DMatrix, DVector, Dyn};

/// Why an emulator could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GpError {
    /// Inputs, outputs and variances differ in length, or an input has the wrong dimension.
    #[error("emulator: {0}")]
    Shape(String),
    /// An output or a variance is not finite (or a variance is negative).
    #[error("emulator: training value {index} is not usable: {what}")]
    NotFinite {
        /// The training point.
        index: usize,
        /// What is wrong.
        what: String,
    },
    /// Too few points for the linear mean (at least `d + 3`).
    #[error("emulator: {got} training points, at least {need} needed")]
    TooFew {
        /// Points given.
        got: usize,
        /// Points needed.
        need: usize,
    },
    /// No start of the likelihood search gave a positive-definite covariance.
    #[error("emulator: the covariance is not positive definite at any start")]
    NotPositiveDefinite,
}

/// The boxes and the search of the hyperparameters (outputs standardised, inputs on the unit
/// cube).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GpSettings {
    /// Range of each length scale.
    pub lengthscale: (f64, f64),
    /// Range of the process variance `s2` (in units of the outputs' variance).
    pub signal_var: (f64, f64),
    /// Range of the fitted nugget `t2` (in units of the outputs' variance).
    pub nugget_var: (f64, f64),
    /// L-BFGS iterations per start.
    pub max_iters: u64,
}

impl Default for GpSettings {
    /// Length scales from 0.05 (a twentieth of a range) to 20 (flat across it); process
    /// variance from 1e-2 to 1e2 of the outputs'; nugget from 1e-8 (conditioning) to 1;
    /// 200 iterations.
    fn default() -> Self {
        Self {
            lengthscale: (0.05, 20.0),
            signal_var: (1e-2, 1e2),
            nugget_var: (1e-8, 1.0),
            max_iters: 200,
        }
    }
}

/// The hyperparameters of a fitted emulator (in standardised output units).
#[derive(Debug, Clone, PartialEq)]
pub struct Hyper {
    /// Length scale of each input.
    pub lengthscales: Vec<f64>,
    /// Process variance `s2`.
    pub signal_var: f64,
    /// Fitted nugget `t2`.
    pub nugget_var: f64,
}

/// One point's leave-one-out prediction (output units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Loo {
    /// The observed output.
    pub observed: f64,
    /// Its prediction from the other points.
    pub predicted: f64,
    /// The standard deviation of that prediction (process, mean and nugget).
    pub sd: f64,
}

impl Loo {
    /// (observed - predicted) / sd.
    pub fn standardised(&self) -> f64 {
        (self.observed - self.predicted) / self.sd
    }
}

/// A fitted emulator.
#[derive(Debug, Clone)]
pub struct Gp {
    x: Vec<Vec<f64>>,
    hyper: Hyper,
    y_mean: f64,
    y_scale: f64,
    beta: DVector<f64>,
    /// `K^-1 (y - H beta)`.
    alpha: DVector<f64>,
    chol: Cholesky<f64, Dyn>,
    /// `K^-1 H`.
    kinv_h: DMatrix<f64>,
    /// Cholesky factor of `H^T K^-1 H`.
    hkh: Cholesky<f64, Dyn>,
    loo: Vec<Loo>,
    log_likelihood: f64,
}

/// Matérn 5/2 correlation and its factor for the log-length-scale derivatives: returns
/// `(k, g)` with `dk / d ln l_j = g (dx_j / l_j)^2`.
fn matern52(r: f64) -> (f64, f64) {
    let s5r = 5f64.sqrt() * r;
    let e = (-s5r).exp();
    (
        (1.0 + s5r + 5.0 * r * r / 3.0) * e,
        5.0 / 3.0 * (1.0 + s5r) * e,
    )
}

fn scaled_r(a: &[f64], b: &[f64], l: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .zip(l)
        .map(|((a, b), l)| ((a - b) / l).powi(2))
        .sum::<f64>()
        .sqrt()
}

fn basis(x: &[f64]) -> impl Iterator<Item = f64> + '_ {
    std::iter::once(1.0).chain(x.iter().copied())
}

/// The pieces of the restricted likelihood at one set of hyperparameters.
struct Reml {
    chol: Cholesky<f64, Dyn>,
    kinv_h: DMatrix<f64>,
    hkh: Cholesky<f64, Dyn>,
    beta: DVector<f64>,
    q: DMatrix<f64>,
    qy: DVector<f64>,
    value: f64,
}

/// The training data in standardised units, shared by the likelihood and the fit.
struct Data<'a> {
    x: &'a [Vec<f64>],
    y: DVector<f64>,
    noise: Vec<f64>,
    h: DMatrix<f64>,
}

impl Data<'_> {
    fn covariance(&self, hy: &Hyper) -> DMatrix<f64> {
        let n = self.x.len();
        DMatrix::from_fn(n, n, |i, j| {
            let k = hy.signal_var * matern52(scaled_r(&self.x[i], &self.x[j], &hy.lengthscales)).0;
            if i == j {
                k + self.noise[i] + hy.nugget_var
            } else {
                k
            }
        })
    }

    fn reml(&self, hy: &Hyper) -> Option<Reml> {
        let chol = self.covariance(hy).cholesky()?;
        let kinv_h = chol.solve(&self.h);
        let hkh = (self.h.transpose() * &kinv_h).cholesky()?;
        let kinv_y = chol.solve(&self.y);
        let beta = hkh.solve(&(self.h.transpose() * &kinv_y));
        let kinv = chol.inverse();
        let q = &kinv - &kinv_h * hkh.solve(&kinv_h.transpose());
        let qy = &kinv_y - &kinv_h * &beta;
        let logdet =
            |c: &Cholesky<f64, Dyn>| 2.0 * c.l().diagonal().iter().map(|d| d.ln()).sum::<f64>();
        let value = -0.5 * self.y.dot(&qy) - 0.5 * logdet(&chol) - 0.5 * logdet(&hkh);
        value.is_finite().then_some(Reml {
            chol,
            kinv_h,
            hkh,
            beta,
            q,
            qy,
            value,
        })
    }

    /// The gradient of the restricted likelihood in `(ln l, ln s2, ln t2)`.
    fn gradient(&self, hy: &Hyper, r: &Reml) -> Vec<f64> {
        let n = self.x.len();
        let d = hy.lengthscales.len();
        let mut g = vec![0.0; d + 2];
        for i in 0..n {
            for j in 0..n {
                // Each term: 1/2 (qy_i qy_j - Q_ij) dK_ij.
                let w = 0.5 * (r.qy[i] * r.qy[j] - r.q[(i, j)]);
                let (k, gk) = matern52(scaled_r(&self.x[i], &self.x[j], &hy.lengthscales));
                for (m, l) in hy.lengthscales.iter().enumerate() {
                    g[m] += w * hy.signal_var * gk * ((self.x[i][m] - self.x[j][m]) / l).powi(2);
                }
                g[d] += w * hy.signal_var * k;
                if i == j {
                    g[d + 1] += w * hy.nugget_var;
                }
            }
        }
        g
    }
}

/// The likelihood search in logistic coordinates `z`: each hyperparameter's logarithm is
/// `lo + (hi - lo) / (1 + exp(-z))`.
#[derive(Clone)]
struct Search<'a> {
    data: &'a Data<'a>,
    boxes: Vec<(f64, f64)>,
}

impl Search<'_> {
    fn hyper(&self, z: &[f64]) -> (Hyper, Vec<f64>) {
        let mut logs = Vec::with_capacity(z.len());
        let mut dlog = Vec::with_capacity(z.len());
        for (z, (lo, hi)) in z.iter().zip(&self.boxes) {
            let s = 1.0 / (1.0 + (-z).exp());
            logs.push(lo + (hi - lo) * s);
            dlog.push((hi - lo) * s * (1.0 - s));
        }
        let d = z.len() - 2;
        (
            Hyper {
                lengthscales: logs[..d].iter().map(|v| v.exp()).collect(),
                signal_var: logs[d].exp(),
                nugget_var: logs[d + 1].exp(),
            },
            dlog,
        )
    }
}

impl CostFunction for Search<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, z: &Vec<f64>) -> Result<f64, ArgminError> {
        let (hy, _) = self.hyper(z);
        self.data
            .reml(&hy)
            .map(|r| -r.value)
            .ok_or_else(|| ArgminError::msg("covariance not positive definite"))
    }
}

impl Gradient for Search<'_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;
    fn gradient(&self, z: &Vec<f64>) -> Result<Vec<f64>, ArgminError> {
        let (hy, dlog) = self.hyper(z);
        let r = self
            .data
            .reml(&hy)
            .ok_or_else(|| ArgminError::msg("covariance not positive definite"))?;
        Ok(self
            .data
            .gradient(&hy, &r)
            .iter()
            .zip(dlog)
            .map(|(g, d)| -g * d)
            .collect())
    }
}

impl Gp {
    /// Fits an emulator to outputs `y` at inputs `x` (each of one length `d`, on the unit cube)
    /// with known sampling variances `noise_var` (0 for a deterministic output).
    pub fn fit(
        x: &[Vec<f64>],
        y: &[f64],
        noise_var: &[f64],
        settings: GpSettings,
    ) -> Result<Self, GpError> {
        let (data, y_mean, y_scale) = Self::data(x, y, noise_var)?;
        let d = x[0].len();
        let ln = |(a, b): (f64, f64)| (a.ln(), b.ln());
        let mut boxes = vec![ln(settings.lengthscale); d];
        boxes.push(ln(settings.signal_var));
        boxes.push(ln(settings.nugget_var));
        let search = Search { data: &data, boxes };
        // Starts: every length scale at a fifth, a half and twice the unit range (short,
        // medium, long correlation), process variance 1, nugget 1e-4 of the outputs' variance.
        let z_of = |v: f64, (lo, hi): (f64, f64)| {
            let s = ((v.ln() - lo) / (hi - lo)).clamp(1e-6, 1.0 - 1e-6);
            (s / (1.0 - s)).ln()
        };
        let mut best: Option<(f64, Vec<f64>)> = None;
        for l0 in [0.2, 0.5, 2.0] {
            let mut z0: Vec<f64> = (0..d).map(|j| z_of(l0, search.boxes[j])).collect();
            z0.push(z_of(1.0, search.boxes[d]));
            z0.push(z_of(1e-4, search.boxes[d + 1]));
            let start_cost = search.cost(&z0).ok();
            let solver = LBFGS::new(MoreThuenteLineSearch::new(), 7);
            let run = Executor::new(search.clone(), solver)
                .configure(|s| s.param(z0.clone()).max_iters(settings.max_iters))
                .run();
            let found = match run {
                Ok(r) => r
                    .state()
                    .get_best_param()
                    .cloned()
                    .map(|p| (r.state().get_best_cost(), p)),
                // A start whose line search left the positive-definite region keeps its start.
                Err(_) => start_cost.map(|c| (c, z0)),
            };
            if let Some((c, p)) = found {
                if c.is_finite() && best.as_ref().is_none_or(|b| c < b.0) {
                    best = Some((c, p));
                }
            }
        }
        let (_, z) = best.ok_or(GpError::NotPositiveDefinite)?;
        let (hyper, _) = search.hyper(&z);
        Self::assemble(x, &data, hyper, y_mean, y_scale)
    }

    /// The emulator with given hyperparameters (standardised units), no search.
    pub fn with_hyper(
        x: &[Vec<f64>],
        y: &[f64],
        noise_var: &[f64],
        hyper: Hyper,
    ) -> Result<Self, GpError> {
        let (data, y_mean, y_scale) = Self::data(x, y, noise_var)?;
        if hyper.lengthscales.len() != x[0].len() {
            return Err(GpError::Shape(format!(
                "{} length scales for {} inputs",
                hyper.lengthscales.len(),
                x[0].len()
            )));
        }
        Self::assemble(x, &data, hyper, y_mean, y_scale)
    }

    fn data<'a>(
        x: &'a [Vec<f64>],
        y: &[f64],
        noise_var: &[f64],
    ) -> Result<(Data<'a>, f64, f64), GpError> {
        let n = x.len();
        if y.len() != n || noise_var.len() != n {
            return Err(GpError::Shape(format!(
                "{n} inputs, {} outputs, {} variances",
                y.len(),
                noise_var.len()
            )));
        }
        let d = x.first().map_or(0, Vec::len);
        if d == 0 || x.iter().any(|p| p.len() != d) {
            return Err(GpError::Shape("inputs of unequal or zero dimension".into()));
        }
        if n < d + 3 {
            return Err(GpError::TooFew {
                got: n,
                need: d + 3,
            });
        }
        for (i, (y, v)) in y.iter().zip(noise_var).enumerate() {
            if !y.is_finite() || !v.is_finite() || *v < 0.0 {
                return Err(GpError::NotFinite {
                    index: i,
                    what: format!("output {y}, variance {v}"),
                });
            }
        }
        let mean = y.iter().sum::<f64>() / n as f64;
        let var = y.iter().map(|y| (y - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        // A constant output keeps unit scale: its process variance then fits to the floor.
        let scale = if var > 0.0 { var.sqrt() } else { 1.0 };
        let h = DMatrix::from_fn(n, d + 1, |i, j| if j == 0 { 1.0 } else { x[i][j - 1] });
        Ok((
            Data {
                x,
                y: DVector::from_iterator(n, y.iter().map(|y| (y - mean) / scale)),
                noise: noise_var.iter().map(|v| v / (scale * scale)).collect(),
                h,
            },
            mean,
            scale,
        ))
    }

    fn assemble(
        x: &[Vec<f64>],
        data: &Data,
        hyper: Hyper,
        y_mean: f64,
        y_scale: f64,
    ) -> Result<Self, GpError> {
        let r = data.reml(&hyper).ok_or(GpError::NotPositiveDefinite)?;
        let loo = (0..x.len())
            .map(|i| {
                let qii = r.q[(i, i)];
                Loo {
                    observed: y_mean + y_scale * data.y[i],
                    predicted: y_mean + y_scale * (data.y[i] - r.qy[i] / qii),
                    sd: y_scale / qii.sqrt(),
                }
            })
            .collect();
        Ok(Self {
            x: x.to_vec(),
            hyper,
            y_mean,
            y_scale,
            alpha: r.qy,
            beta: r.beta,
            chol: r.chol,
            kinv_h: r.kinv_h,
            hkh: r.hkh,
            loo,
            log_likelihood: r.value,
        })
    }

    /// The hyperparameters (standardised output units).
    pub fn hyper(&self) -> &Hyper {
        &self.hyper
    }

    /// The fitted nugget `t2` in output units: the part of the output the smooth process
    /// does not follow, beside the training points' own sampling variances.
    pub fn nugget_var(&self) -> f64 {
        self.hyper.nugget_var * self.y_scale * self.y_scale
    }

    /// The restricted log-likelihood at the hyperparameters (standardised outputs).
    pub fn log_likelihood(&self) -> f64 {
        self.log_likelihood
    }

    /// Each training point's leave-one-out prediction, in training order.
    pub fn loo(&self) -> &[Loo] {
        &self.loo
    }

    /// The training inputs.
    pub fn inputs(&self) -> &[Vec<f64>] {
        &self.x
    }

    fn cross(&self, x: &[f64]) -> DVector<f64> {
        DVector::from_iterator(
            self.x.len(),
            self.x.iter().map(|t| {
                self.hyper.signal_var * matern52(scaled_r(t, x, &self.hyper.lengthscales)).0
            }),
        )
    }

    /// The emulator's mean at `x` (output units): `O(n d)`.
    pub fn mean(&self, x: &[f64]) -> f64 {
        let m: f64 = basis(x).zip(self.beta.iter()).map(|(h, b)| h * b).sum();
        self.y_mean + self.y_scale * (m + self.cross(x).dot(&self.alpha))
    }

    /// The emulator's mean and variance at `x` (output units): the variance of the smooth
    /// process and of the mean's coefficients, without the nuggets (the emulator's own
    /// uncertainty about the expected output): `O(n^2)`.
    pub fn predict(&self, x: &[f64]) -> (f64, f64) {
        let k = self.cross(x);
        let h = DVector::from_iterator(x.len() + 1, basis(x));
        let m = h.dot(&self.beta) + k.dot(&self.alpha);
        let kinv_k = self.chol.solve(&k);
        let r = h - self.kinv_h.transpose() * &k;
        let v = self.hyper.signal_var - k.dot(&kinv_k) + r.dot(&self.hkh.solve(&r));
        (
            self.y_mean + self.y_scale * m,
            v.max(0.0) * self.y_scale * self.y_scale,
        )
    }

    /// Posterior covariance of the emulator's means at `points` (output units), for joint
    /// draws.
    pub fn covariance(&self, points: &[Vec<f64>]) -> (Vec<f64>, DMatrix<f64>) {
        let m = points.len();
        let ks: Vec<DVector<f64>> = points.iter().map(|p| self.cross(p)).collect();
        let kinv: Vec<DVector<f64>> = ks.iter().map(|k| self.chol.solve(k)).collect();
        let rs: Vec<DVector<f64>> = points
            .iter()
            .zip(&ks)
            .map(|(p, k)| {
                DVector::from_iterator(p.len() + 1, basis(p)) - self.kinv_h.transpose() * k
            })
            .collect();
        let hr: Vec<DVector<f64>> = rs.iter().map(|r| self.hkh.solve(r)).collect();
        let s2 = self.y_scale * self.y_scale;
        let cov = DMatrix::from_fn(m, m, |a, b| {
            let prior = self.hyper.signal_var
                * matern52(scaled_r(&points[a], &points[b], &self.hyper.lengthscales)).0;
            s2 * (prior - ks[a].dot(&kinv[b]) + rs[a].dot(&hr[b]))
        });
        let means = points.iter().map(|p| self.mean(p)).collect();
        (means, cov)
    }
}

#[cfg(test)]
mod tests;
