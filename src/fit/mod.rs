//! Fitting a device to measured sweeps: named free parameters with ranges, a weighted
//! least-squares misfit evaluated by the stepped sweep ([`crate::study::sweep`]), a
//! Levenberg-Marquardt search ([`lm`]) in bounded-transformed coordinates, and an honest
//! account of what the data determine.
//!
//! # Misfit
//! Each measured point contributes `(model - measured) / sigma`, each measured feature (impact
//! onset, end of the impacting branch) `(model - measured) / sigma_hz`. The model of a data
//! set is the stepped sweep ([`crate::study::sweep::SweepSettings::for_device`]) over the data
//! set's grid (by default its measured frequencies) at its stated acceleration, with a
//! steady-state criterion tightened to [`FIT_REL_CHANGE_TOL`] and transitions refined to
//! [`FIT_REFINE_TOL_HZ`], so that the finite-difference Jacobian sees the model and not the
//! convergence criterion ([`model`]). A feature the model does not show inside the grid is
//! placed at the grid end it lies beyond, so that the misfit still points towards it.
//!
//! # Coordinates
//! A free parameter with range `lo..hi` is searched as `u = logit((p - lo) / (hi - lo))`, or,
//! when `lo > 0` and `hi / lo >= 10`, as the logit of `ln p` between `ln lo` and `ln hi`: the
//! search cannot leave the range, and wide ranges are searched by ratios.
//!
//! # Uncertainty
//! The covariance of the estimates is the Gauss-Newton one, `(J^T J)^-1` in the transformed
//! coordinates (J of the weighted residuals), scaled by the residual variance
//! `s^2 = SSR / (n - p)` unless every measured value states its standard deviation
//! ([`Uncertainty`]). The 95 % interval of a parameter is `u +- q se_u` mapped back through the
//! transform (q: Student's t with n - p degrees of freedom when scaled, the normal quantile
//! otherwise), so it stays inside the range; the standard error reported in the parameter's
//! unit is `|dp/du| se_u`. This is a linearisation at the optimum: it is as good as the model
//! is nearly linear in the parameters over the interval.
//!
//! # What the data do not determine
//! The Jacobian's columns are scaled to unit length (which makes the test independent of each
//! parameter's unit and transform) and its singular values computed. A combination whose
//! singular value is below [`SINGULAR_RATIO_WARN`] times the largest is reported
//! ([`FitWarning::Undetermined`]) with its direction in relative changes of the parameters. A
//! direction whose singular value is zero to round-off ([`NUMERICALLY_ZERO`]) gives every
//! parameter in it an infinite standard error and its whole range as interval.

pub mod data;
pub mod lm;
pub mod model;
pub mod params;
pub mod report;
pub mod spectrum;

use nalgebra::DMatrix;
use thiserror::Error;

pub use data::{DataError, Direction, Feature, FeatureKind, Point, Quantity, SweepData};
pub use lm::{LmSettings, LmStop};
pub use model::{model_sweep, model_values, ModelSweep};
pub use params::{check_free, FreeParam};
pub use report::{FitReport, FitWarning, FittedParam, Residual, Uncertainty};

use params::{apply, Transform};

use crate::device::{Device, ParamError};
use crate::num::stats::student_t_975;
use crate::ode::SolverError;

/// The path of the one free parameter that is not the device's: a factor on every data set's
/// stated acceleration (an accelerometer's calibration error).
pub const ACCEL_SCALE_PATH: &str = "drive.accel_scale";

/// Steady-state criterion of the fit's sweeps: the relative change of the RMS voltages between
/// blocks (the sweeps' default is 1e-3, as large as the forward-difference change of a
/// measured value for a step of 1e-2 in the transformed coordinates).
pub const FIT_REL_CHANGE_TOL: f64 = 1e-6;

/// Bracket width to which the fit's sweeps refine the onset and the jump (Hz): a refined
/// feature is the midpoint of its final bracket, a step function of the parameters, so the
/// bracket must be far narrower than the change a finite-difference step causes (about 1 Hz
/// for a step of 1e-2 in the transformed coordinates of a gap range of a factor 2).
pub const FIT_REFINE_TOL_HZ: f64 = 0.01;

/// A singular value below this fraction of the largest counts as zero (round-off of the
/// decomposition is about 1e-16).
pub const NUMERICALLY_ZERO: f64 = 1e-12;

/// When every measured value states its standard deviation the search also stops when the
/// weighted SSR changes by less than this: a change of 1e-3 in chi-square moves no estimate by
/// more than a few hundredths of its standard error.
pub const STATED_COST_ABS_TOL: f64 = 1e-3;

/// A combination of parameters is reported as not determined by the data when the smallest
/// singular value of the column-scaled Jacobian is below this fraction of the largest: the
/// data then determine that combination at least 100 times worse than the best one (a
/// convention, stated with every warning).
pub const SINGULAR_RATIO_WARN: f64 = 1e-2;

/// Why a fit could not be set up or run.
#[derive(Debug, Error)]
pub enum FitError {
    /// A data set is unusable.
    #[error(transparent)]
    Data(#[from] DataError),
    /// A free parameter does not exist, or an end of its range is not a valid value.
    #[error("free parameter `{path}`: {error}")]
    Param {
        /// The path as given.
        path: String,
        /// The device's error, naming the field.
        error: ParamError,
    },
    /// A range is not finite with `lo < hi`, or does not contain the starting value.
    #[error("free parameter `{path}`: range {lo:e} .. {hi:e} {what}")]
    Range {
        /// The path as given.
        path: String,
        /// Lower end.
        lo: f64,
        /// Upper end.
        hi: f64,
        /// What is wrong.
        what: String,
    },
    /// The same parameter is free twice.
    #[error("free parameter `{path}` is given twice")]
    Duplicate {
        /// The path.
        path: String,
    },
    /// Fewer measured values than free parameters.
    #[error("{n} measured values cannot determine {p} free parameters")]
    TooFewData {
        /// Measured values (points and features).
        n: usize,
        /// Free parameters.
        p: usize,
    },
    /// No free parameter.
    #[error("no free parameter")]
    NoFreeParam,
    /// The integrator failed on a sweep.
    #[error("model sweep failed: {0}")]
    Model(#[from] SolverError),
}

/// The measured values and their weights (standard deviations; 1 where none is stated).
fn measured(data: &[SweepData]) -> (Vec<f64>, Vec<f64>, bool) {
    let mut y = Vec::new();
    let mut s = Vec::new();
    let mut all_stated = true;
    for d in data {
        for p in &d.points {
            y.push(p.value);
            s.push(p.sigma.unwrap_or(1.0));
            all_stated &= p.sigma.is_some();
        }
        for f in &d.features {
            y.push(f.freq_hz);
            s.push(f.sigma_hz);
        }
    }
    (y, s, all_stated)
}

/// Fits the free parameters of `device` to the data sets (see the module docs).
pub fn fit(
    device: &Device,
    data: &[SweepData],
    free: &[FreeParam],
    settings: &LmSettings,
) -> Result<FitReport, FitError> {
    for d in data {
        d.validate()?;
    }
    let starts = check_free(device, free)?;
    let n: usize = data.iter().map(SweepData::len).sum();
    let p = free.len();
    if n < p {
        return Err(FitError::TooFewData { n, p });
    }
    let tr: Vec<Transform> = free.iter().map(|f| Transform::new(f.lo, f.hi)).collect();
    let u0: Vec<f64> = tr.iter().zip(&starts).map(|(t, &v)| t.to_u(v)).collect();
    let (y, sigma, all_stated) = measured(data);
    let to_p = |u: &[f64]| -> Vec<f64> { tr.iter().zip(u).map(|(t, &u)| t.to_p(u)).collect() };
    let model = |pv: &[f64]| -> Result<Vec<f64>, FitError> {
        let (d, scale) = apply(device, free, pv)?;
        let mut out = Vec::with_capacity(n);
        for ds in data {
            out.extend(model_values(&d, scale, ds)?);
        }
        Ok(out)
    };
    let residuals = |u: &[f64]| -> Result<Vec<f64>, FitError> {
        let m = model(&to_p(u))?;
        Ok(m.iter()
            .zip(&y)
            .zip(&sigma)
            .map(|((m, y), s)| (m - y) / s)
            .collect())
    };
    let mut settings = *settings;
    if all_stated {
        settings.cost_abs_tol = settings.cost_abs_tol.max(STATED_COST_ABS_TOL);
    }
    let lm = lm::levenberg_marquardt(residuals, &u0, &settings)?;
    let p_fit = to_p(&lm.u);
    let (fitted_device, accel_scale) = apply(device, free, &p_fit)?;
    let mut fitted_device = fitted_device;
    fitted_device.params = "fitted".into();

    let ssr: f64 = lm.residuals.iter().map(|r| r * r).sum();
    let dof = n - p;
    let uncertainty = if all_stated {
        Uncertainty::Stated
    } else {
        Uncertainty::ResidualScaled
    };
    let mut warnings = Vec::new();
    let (scale2, q) = match uncertainty {
        Uncertainty::Stated => (1.0, 1.959_963_984_540_054),
        Uncertainty::ResidualScaled if dof > 0 => (ssr / dof as f64, student_t_975(dof)),
        Uncertainty::ResidualScaled => {
            warnings.push(FitWarning::NoResidualDof);
            (f64::NAN, f64::NAN)
        }
    };
    let jac = &lm.jacobian;
    // The Jacobian with its columns scaled to unit length, and its singular value
    // decomposition: the covariance below and the identifiability test after it.
    let norms: Vec<f64> = (0..p).map(|j| jac.column(j).norm()).collect();
    let scaled = DMatrix::from_fn(n, p, |i, j| {
        if norms[j] > 0.0 {
            jac[(i, j)] / norms[j]
        } else {
            0.0
        }
    });
    let svd = scaled.svd(false, true);
    let sv = &svd.singular_values;
    let smax = sv.max();
    let v_t = svd.v_t.as_ref().expect("V^T requested");
    // (J^T J)^-1 = D^-1 V S^-2 V^T D^-1 (D: the column norms). A direction with a zero
    // singular value (relative to the largest, below [`NUMERICALLY_ZERO`]) has an infinite
    // variance, and so has every parameter that takes part in it: its interval is then the
    // whole range, never a spuriously narrow one.
    let cov_u = DMatrix::from_fn(p, p, |i, j| {
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
    });
    let params: Vec<FittedParam> = (0..p)
        .map(|k| {
            let se_u = cov_u[(k, k)].max(0.0).sqrt();
            let (a, b) = (
                tr[k].to_p(lm.u[k] - q * se_u),
                tr[k].to_p(lm.u[k] + q * se_u),
            );
            let (interval, std_err) = if !q.is_finite() || se_u.is_nan() {
                ((f64::NAN, f64::NAN), f64::NAN)
            } else if se_u.is_infinite() {
                ((free[k].lo, free[k].hi), f64::INFINITY)
            } else {
                ((a.min(b), a.max(b)), tr[k].dp_du(lm.u[k]).abs() * se_u)
            };
            FittedParam {
                path: free[k].path.clone(),
                start: starts[k],
                value: p_fit[k],
                std_err,
                interval,
                range: (free[k].lo, free[k].hi),
            }
        })
        .collect();
    let correlation: Vec<Vec<f64>> = (0..p)
        .map(|i| {
            (0..p)
                .map(|j| cov_u[(i, j)] / (cov_u[(i, i)] * cov_u[(j, j)]).sqrt())
                .collect()
        })
        .collect();

    // Identifiability: the singular values of the column-scaled Jacobian.
    let mut singular_ratio = 1.0;
    for (k, &s) in sv.iter().enumerate() {
        let ratio = if smax > 0.0 { s / smax } else { 0.0 };
        singular_ratio = f64::min(singular_ratio, ratio);
        if ratio >= SINGULAR_RATIO_WARN {
            continue;
        }
        // The direction in the scaled coordinates, back to du and then to relative changes.
        let comps: Vec<f64> = (0..p)
            .map(|j| {
                let du = if norms[j] > 0.0 {
                    v_t[(k, j)] / norms[j]
                } else {
                    v_t[(k, j)]
                };
                let dp = du * tr[j].dp_du(lm.u[j]);
                if p_fit[j] != 0.0 && free[j].lo > 0.0 {
                    dp / p_fit[j]
                } else {
                    dp
                }
            })
            .collect();
        // A parameter pinned at an end of its range has dp/du = 0: its component is 0 here
        // and it is reported by [`FitWarning::AtBound`].
        let comps: Vec<f64> = comps
            .into_iter()
            .map(|c| if c.is_finite() { c } else { 0.0 })
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
    for (k, f) in free.iter().enumerate() {
        let frac = (p_fit[k] - f.lo) / (f.hi - f.lo);
        if !(1e-3..=1.0 - 1e-3).contains(&frac) {
            warnings.push(FitWarning::AtBound {
                path: f.path.clone(),
                value: p_fit[k],
            });
        }
    }
    if !lm.stop.converged() {
        warnings.push(FitWarning::NotConverged {
            stop: format!("{:?}", lm.stop),
        });
    }

    let mut residual_rows = Vec::with_capacity(n);
    let mut i = 0;
    for d in data {
        let items = d
            .points
            .iter()
            .map(|pt| ("point".to_string(), pt.freq_hz))
            .chain(
                d.features
                    .iter()
                    .map(|f| (f.kind.label().to_string(), f.freq_hz)),
            );
        for (what, freq_hz) in items {
            residual_rows.push(Residual {
                dataset: d.label.clone(),
                what,
                freq_hz,
                measured: y[i],
                model: y[i] + lm.residuals[i] * sigma[i],
                sigma: sigma[i],
            });
            i += 1;
        }
    }
    Ok(FitReport {
        device: fitted_device,
        accel_scale,
        params,
        correlation,
        warnings,
        uncertainty,
        residuals: residual_rows,
        ssr,
        dof,
        singular_ratio,
        iterations: lm.iterations,
        evaluations: lm.evaluations,
        stop: lm.stop,
    })
}
