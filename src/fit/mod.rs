//! Fitting a device to measured sweeps: named free parameters with ranges, a weighted
//! least-squares misfit evaluated on the branches of periodic orbits the sweeps follow
//! (`branch.rs`), a Levenberg-Marquardt search ([`lm`]) in bounded-transformed coordinates from
//! one or several starts, and an honest account of what the data determine.
//!
//! # Misfit
//! Each measured point contributes `(model - measured) / sigma`, each measured feature (impact
//! onset, end of the impacting branch) `(model - measured) / sigma_hz`. A stepped sweep's
//! value at a fixed frequency jumps when a fold passes that frequency, so a misfit built on
//! the sweep itself is discontinuous in the parameters and a search stalls at the jump. The
//! model therefore compares each measured point with the stable periodic orbit of the branch
//! the point lies on ([`crate::study::orbit`]), which exists past the jump up to its fold; a
//! point beyond the fold of its branch is compared with the fold's orbit. The onset and a
//! gradual end of contact are grazing orbits (where the branch of the device without stops
//! reaches a stop), a jump is the fold ([`crate::study::continuation`]), each located to far
//! below a measured feature's standard deviation and smooth in the parameters.
//!
//! The branches are identified once from the stepped sweep at the starting values
//! ([`crate::study::sweep::SweepSettings::for_device`]), then followed by Newton's method as
//! the search moves: an evaluation costs a few periods per measured value. After the search
//! the model is identified afresh at the fitted values; if it differs from the one followed
//! (the data assigned to another branch, a feature the sweep now shows elsewhere) the search
//! is run again from there ([`MAX_ROUNDS`] times at most) and a remaining difference is a
//! warning ([`FitWarning::BranchChanged`]). Where the branches cannot be identified (a response
//! that is not periodic, a jump that is not a fold) the model is the stepped sweep itself
//! ([`model`]), with a warning ([`FitWarning::SteppedSweepModel`]).
//!
//! # Several starts
//! A search from the device's values that does not converge, or whose chi-square (with stated
//! standard deviations) exceeds its 99.9 % quantile, is followed by searches from the points of
//! a Sobol sequence in the transformed box ([`FitSettings::starts`] in all); the best
//! converged one is reported, with the number of starts tried.
//!
//! # Coordinates
//! A free parameter ([`ParamRange`]) with range `lo..hi` is searched as
//! `u = logit((p - lo) / (hi - lo))`, or, when its spacing is [`Spacing::Log`] (the default of
//! a range written with `lo > 0` and `hi / lo >= 10`, [`Spacing::auto`]), as the logit of
//! `ln p` between `ln lo` and `ln hi`: the search cannot leave the range, and wide ranges are
//! searched by ratios.
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
//! A column below [`COLUMN_NOISE_REL`] of the largest is taken as zero (the model's numerical
//! noise). The Jacobian's columns are scaled to unit length (which makes the test independent of each
//! parameter's unit and transform) and its singular values computed. A combination whose
//! singular value is below [`SINGULAR_RATIO_WARN`] times the largest is reported
//! ([`FitWarning::Undetermined`]) with its direction in relative changes of the parameters. A
//! direction whose singular value is zero to round-off ([`NUMERICALLY_ZERO`]) gives every
//! parameter in it an infinite standard error and its whole range as interval.

mod branch;
pub mod data;
pub mod lm;
pub mod model;
pub mod params;
pub mod report;
mod search;
pub mod spectrum;
mod track;

use nalgebra::DMatrix;
use statrs::distribution::{ChiSquared, ContinuousCDF};
use thiserror::Error;

pub use data::{DataError, Direction, Feature, FeatureKind, Point, Quantity, SweepData};
pub use lm::{LmSettings, Termination};
pub use model::{model_curve, model_sweep, model_values, ModelSweep};
pub use params::check_free;
pub use report::{FitReport, FitWarning, FittedParam, Residual, Uncertainty};

use params::{apply, Transform};

#[cfg(doc)]
use crate::device::Spacing;
use crate::device::{Device, ParamError, ParamRange};
use crate::num::stats::student_t_975;
use crate::ode::SolverError;

/// The path of the one free parameter that is not the device's: a factor on every data set's
/// stated acceleration (an accelerometer's calibration error).
pub use crate::device::ACCEL_SCALE_PATH;

/// Steady-state criterion of the stepped-sweep model ([`model`]): the relative change of the RMS voltages between
/// blocks (the sweeps' default is 1e-3, as large as the forward-difference change of a
/// measured value for a step of 1e-2 in the transformed coordinates).
pub const FIT_REL_CHANGE_TOL: f64 = 1e-6;

/// Bracket width to which the stepped-sweep model's sweeps refine the onset and the jump (Hz): a refined
/// feature is the midpoint of its final bracket, a step function of the parameters, so the
/// bracket must be far narrower than the change a finite-difference step causes (about 1 Hz
/// for a step of 1e-2 in the transformed coordinates of a gap range of a factor 2).
pub const FIT_REFINE_TOL_HZ: f64 = 0.01;

/// Most searches of one start: the first from the branches identified at the start, each
/// further one from those identified afresh at the previous optimum when they differ from the
/// ones followed (see the module docs).
pub const MAX_ROUNDS: usize = 3;

/// The branches identified afresh agree with the ones followed when every model value differs
/// by at most this many standard deviations (where stated; else [`AGREE_REL`] of the value).
pub const AGREE_SIGMA: f64 = 0.1;

/// The relative agreement of model values without a stated standard deviation.
pub const AGREE_REL: f64 = 1e-4;

/// A fit with stated standard deviations is accepted from one start unless its chi-square
/// exceeds this quantile of the chi-square distribution with n - p degrees of freedom.
pub const CHI2_QUANTILE: f64 = 0.999;

/// A singular value below this fraction of the largest counts as zero (round-off of the
/// decomposition is about 1e-16).
pub const NUMERICALLY_ZERO: f64 = 1e-12;

/// A Jacobian column smaller than this fraction of the largest is taken as zero: the orbits
/// are converged to about 1e-9 of their values and differenced over a step of 1e-4 in the
/// transformed coordinates, so a column is resolved to about 1e-5 of the values it
/// differences, and one a million times smaller than the best-determined parameter's is the
/// model's numerical noise (a parameter that enters it only through its scales, like a gap
/// the orbits never reach).
pub const COLUMN_NOISE_REL: f64 = 1e-6;

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
    /// An orbit, grazing or fold of the model could not be followed to new parameter values.
    #[error("model branch lost: {0}")]
    Lost(String),
}

/// Settings of [`fit()`]: the search, and how many starts it may take.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitSettings {
    /// The Levenberg-Marquardt search.
    pub lm: LmSettings,
    /// Most starts: the device's values, then points of a Sobol sequence (see the module
    /// docs). 1: the device's values only.
    pub starts: usize,
}

impl Default for FitSettings {
    fn default() -> Self {
        Self {
            lm: LmSettings::default(),
            starts: 8,
        }
    }
}

/// The measured values, their weights (standard deviations; 1 where none is stated) and
/// whether each states its own.
fn measured(data: &[SweepData]) -> (Vec<f64>, Vec<f64>, Vec<bool>) {
    let mut y = Vec::new();
    let mut s = Vec::new();
    let mut stated = Vec::new();
    for d in data {
        for p in &d.points {
            y.push(p.value);
            s.push(p.sigma.unwrap_or(1.0));
            stated.push(p.sigma.is_some());
        }
        for f in &d.features {
            y.push(f.freq_hz);
            s.push(f.sigma_hz);
            stated.push(true);
        }
    }
    (y, s, stated)
}

/// Fits the free parameters of `device` to the data sets (see the module docs).
///
/// Recovering the gap of the piezoelectric example's stop from a noise-free up-sweep made by
/// the model itself, started 25 % off:
///
/// ```
/// use endstop::device::{Device, ParamRange};
/// use endstop::fit::{fit, model_values, Direction, FitSettings, Point, Quantity, SweepData};
///
/// let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/examples/piezo_cantilever.toml"));
/// let truth = Device::from_toml_str(text, "piezo_cantilever.toml")?;
/// let free = [ParamRange::auto("stops.upper.gap_m", 0.05e-3, 0.3e-3)];
/// // An up-sweep at 0.5 g rms, 100 to 160 Hz in 4 Hz steps, valued by the model.
/// let mut data = SweepData {
///     label: "synthetic".into(),
///     direction: Direction::Up,
///     accel_rms_g: 0.5,
///     quantity: Quantity::V1RmsV,
///     points: (0..=15)
///         .map(|i| Point { freq_hz: 100.0 + 4.0 * i as f64, value: 0.0, sigma: None })
///         .collect(),
///     grid_hz: None,
///     features: vec![],
/// };
/// let values = model_values(&truth, 1.0, &data)?;
/// for (p, v) in data.points.iter_mut().zip(values) {
///     p.value = v;
///     p.sigma = Some(0.01 * v);
/// }
/// let gap_m = truth.stops.upper.as_ref().unwrap().gap_m;
/// let start = truth.with_param("stops.upper.gap_m", 1.25 * gap_m)?;
/// let report = fit(&start, &[data], &free, &FitSettings::default())?;
/// assert!(report.stop.converged());
/// assert!((report.params[0].value - gap_m).abs() < 1e-3 * gap_m);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn fit(
    device: &Device,
    data: &[SweepData],
    free: &[ParamRange],
    settings: &FitSettings,
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
    let tr: Vec<Transform> = free.iter().map(Transform::of).collect();
    let u0: Vec<f64> = tr.iter().zip(&starts).map(|(t, &v)| t.to_u(v)).collect();
    let (y, sigma, stated) = measured(data);
    let all_stated = stated.iter().all(|&s| s);
    let pb = search::Problem {
        device,
        data,
        free,
        tr: tr.clone(),
        y: y.clone(),
        sigma: sigma.clone(),
        stated,
    };
    let dof = n - p;
    // With stated standard deviations a fit is accepted from one start unless its
    // chi-square is improbably large; without, a converged search is accepted.
    let chi2_limit = if all_stated && dof > 0 {
        ChiSquared::new(dof as f64)
            .map(|c| c.inverse_cdf(CHI2_QUANTILE))
            .unwrap_or(f64::INFINITY)
    } else {
        f64::INFINITY
    };
    let (run, starts_tried, best_start) =
        search::search(&pb, &u0, settings, all_stated, |ssr| ssr <= chi2_limit)?;
    let lm = &run.lm;
    let p_fit = pb.to_p(&lm.u);
    let (fitted_device, accel_scale) = apply(device, free, &p_fit)?;
    let mut fitted_device = fitted_device;
    fitted_device.params = "fitted".into();

    let ssr: f64 = lm.residuals.iter().map(|r| r * r).sum();
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
    // A column below the model's numerical noise is a parameter the model does not depend on.
    let norms: Vec<f64> = (0..p).map(|j| jac.column(j).norm()).collect();
    let norm_max = norms.iter().copied().fold(0.0, f64::max);
    let norms: Vec<f64> = norms
        .into_iter()
        .map(|n| {
            if n < COLUMN_NOISE_REL * norm_max {
                0.0
            } else {
                n
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
    let model = match &run.used {
        search::Used::Branches {
            disagreement,
            rounds,
        } => {
            match disagreement {
                Some(d) if *d <= 1.0 => {}
                d => warnings.push(FitWarning::BranchChanged {
                    disagreement: d.unwrap_or(f64::NAN),
                    rounds: *rounds,
                }),
            }
            "branches of periodic orbits".to_string()
        }
        search::Used::SteppedSweep { why } => {
            warnings.push(FitWarning::SteppedSweepModel { why: why.clone() });
            "stepped sweep".to_string()
        }
    };
    if all_stated && dof > 0 && ssr > chi2_limit {
        warnings.push(FitWarning::PoorFit {
            reduced_chi2: ssr / dof as f64,
            quantile: CHI2_QUANTILE,
        });
    }
    let chi2_p = if all_stated && dof > 0 {
        ChiSquared::new(dof as f64).ok().map(|c| c.sf(ssr))
    } else {
        None
    };

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
        reduced_chi2: if dof > 0 { ssr / dof as f64 } else { f64::NAN },
        chi2_p,
        singular_ratio,
        iterations: run.iterations,
        evaluations: run.evaluations,
        failed_trials: lm.failed_trials,
        stop: lm.stop,
        model,
        starts_tried,
        best_start,
    })
}
