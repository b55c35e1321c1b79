//! Fitting a device to measured sweeps: named free parameters with ranges, a weighted
//! least-squares misfit evaluated on the branches of periodic orbits the sweeps follow
//! (`branch.rs`), a global search (a design of starts ranked by a cheap model, the best few
//! refined by Levenberg-Marquardt, [`lm`]) in bounded-transformed coordinates, and an honest
//! account of what the data determine.
//!
//! # What it models
//! A device whose transducer drives its resistive load (the device file without an
//! `[interface]` table); any suspension, stops and transducer of the device description. A
//! device with an interface circuit is refused ([`FitError::Unmodelled`]), never fitted as if
//! the circuit were not there.
//!
//! # Misfit
//! Each measured point contributes `(model - measured) / sigma`, each measured feature (impact
//! onset, end of the impacting branch) `(model - measured) / sigma_hz`. A stepped sweep's
//! value at a fixed frequency jumps when a fold passes that frequency, so a misfit built on
//! the sweep itself is discontinuous in the parameters and a search stalls at the jump. The
//! model therefore compares each measured point with the stable periodic orbit of the branch
//! the point lies on ([`crate::study::orbit`]), which exists past the jump up to its fold; a
//! point beyond the fold of its branch is compared with the fold's orbit, and a point of the
//! second branch where that branch does not reach with the orbit where it ends. The
//! measurement says which branch a point lies on: the points before a measured branch end
//! (a feature) or before the jump the points themselves show ([`SweepData::measured_jump`])
//! lie on the first, the others on the second; without either, the stepped sweep at the
//! parameters of the identification assigns them. The onset and a gradual end of contact are
//! grazing orbits (where the branch of the device without stops reaches a stop), a jump is
//! the fold ([`crate::study::continuation`]), each located to far below a measured feature's
//! standard deviation and smooth in the parameters. A jump the points show enters as what it
//! is, the end of the first branch between the last point before it and the first after: a
//! residual of the fold (or grazing) frequency against the middle of that bracket with the
//! standard deviation of a frequency uniform across it (its width over sqrt 12).
//!
//! The branches are identified from the stepped sweep at a start's values
//! ([`crate::study::sweep::SweepSettings::for_device`]), then followed by Newton's method as
//! the search moves: an evaluation costs a few periods per measured value. After the search
//! the model is identified afresh at the fitted values; if it differs from the one followed
//! (the data assigned to another branch, a feature the sweep now shows elsewhere) the search
//! is run again from there ([`MAX_ROUNDS`] times at most) and a remaining difference is a
//! warning ([`FitWarning::BranchChanged`]). Where the branches cannot be identified (a response
//! that is not periodic, a jump that is not a fold) the model is the stepped sweep itself
//! ([`model`]), with a warning ([`FitWarning::SteppedSweepModel`]). A start where they cannot
//! be identified but the optimum lies where they can (a band without a periodic response below
//! the onset of impacts at the start's values) is searched on the stepped sweep until its steps
//! lower the misfit by less than a percent and on the branches from there, each of whose
//! evaluations costs a few periods per measured value instead of a whole sweep; the branches'
//! result is kept when it settles with a misfit no larger than the stepped sweep's.
//!
//! # Global search
//! The starts are the device's values and the points of a Sobol sequence over the transformed
//! box ([`FitSettings::design_points`]: `DESIGN_BASE + DESIGN_PER_PARAM p` of them for `p`
//! free parameters), each ranked by the misfit of a cheap model, the stepped sweep over
//! each data set's grid with steady-state blocks a quarter of a plain sweep's
//! ([`model::DESIGN_BLOCK_PERIODS`], [`model::DESIGN_RING_FRACTION`]; one sweep per data set
//! and start, evaluated in parallel). A start's sweeps stop as soon as the misfit of the points
//! they have swept exceeds that of the last of the best [`FitSettings::refine`] evaluated whole
//! so far: the rest could only raise it, so the best ranked are those of the whole sweeps, with
//! the same misfits. The best
//! ranked [`FitSettings::refine`] are refined by Levenberg-Marquardt on the branches in their
//! order, stopping early at one that converges with a chi-square (with stated standard
//! deviations) below its [`CHI2_QUANTILE`] quantile; the report is the best refined one
//! (converged first, then the smallest SSR), whichever start it came from, and lists every
//! start with its cheap misfit and refinement ([`FitReport::starts`]).
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
mod clear;
pub mod data;
pub mod family;
pub mod lm;
pub mod model;
pub mod params;
mod problem;
pub mod report;
mod search;
pub mod spectrum;
mod start;
mod track;
mod uncertainty;
mod untouched;

use statrs::distribution::{ChiSquared, ContinuousCDF};
use thiserror::Error;

pub use data::{
    DataError, Direction, Feature, FeatureKind, MeasuredJump, Point, Quantity, SweepData,
};
pub use lm::{LmSettings, Termination};
pub use model::{model_curve, model_sweep, model_values, ModelSweep};
pub use params::check_free;
pub use report::{
    FitReport, FitWarning, FittedParam, Refined, Residual, StartOrigin, StartTried, Uncertainty,
};

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
    /// The device has a part the fit's model leaves out.
    #[error("device `{device}` cannot be fitted: the fit models a transducer on its resistive load, not {part}")]
    Unmodelled {
        /// The device's name.
        device: String,
        /// The part, named as in the device file.
        part: String,
    },
}

/// Settings of [`fit()`]: the search, the design of starts and how many are refined.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitSettings {
    /// The Levenberg-Marquardt search.
    pub lm: LmSettings,
    /// Points of the Sobol design beside the device's own values (see the module docs);
    /// `None`: `DESIGN_BASE + DESIGN_PER_PARAM p` for `p` free parameters; `Some(0)`: the
    /// device's values alone, refined without a design.
    pub design: Option<usize>,
    /// Most starts refined, the best ranked first.
    pub refine: usize,
}

/// Points of the design per free parameter, beside [`DESIGN_BASE`]: a Sobol sequence of
/// `DESIGN_BASE + DESIGN_PER_PARAM p` points puts points in each half of every range and in
/// every quadrant of each pair, at the price of one cheap stepped sweep per data set each.
pub const DESIGN_PER_PARAM: usize = 4;

/// Points of the design whatever the number of free parameters.
pub const DESIGN_BASE: usize = 4;

/// Starts refined by default: the best ranked three.
pub const REFINE_DEFAULT: usize = 3;

impl Default for FitSettings {
    fn default() -> Self {
        Self {
            lm: LmSettings::default(),
            design: None,
            refine: REFINE_DEFAULT,
        }
    }
}

impl FitSettings {
    /// The device's values alone, refined without a design (a fit that must stay on the
    /// branch it starts on).
    pub fn from_device_only() -> Self {
        Self {
            design: Some(0),
            refine: 1,
            ..Self::default()
        }
    }

    /// Points of the design for `p` free parameters.
    pub fn design_points(&self, p: usize) -> usize {
        self.design.unwrap_or(DESIGN_BASE + DESIGN_PER_PARAM * p)
    }
}

/// Why a device cannot be fitted: a part of it the fit's model leaves out.
pub fn check_modelled(device: &Device) -> Result<(), FitError> {
    if crate::study::record::has_storage(device) {
        return Err(FitError::Unmodelled {
            device: device.name.clone(),
            part: format!(
                "its interface circuit `[interface]` of kind `{}`",
                device.interface.key()
            ),
        });
    }
    Ok(())
}

/// The measured values, their weights (standard deviations; 1 where none is stated) and
/// whether each states its own: each data set's points, features, and the bracket of a jump
/// its points show.
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
        if let Some(j) = d.measured_jump() {
            y.push(j.mid_hz());
            s.push(j.sigma_hz());
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
    check_modelled(device)?;
    for d in data {
        d.validate()?;
    }
    let starts = check_free(device, free)?;
    let n: usize = data.iter().map(SweepData::n_values).sum();
    let p = free.len();
    if n < p {
        return Err(FitError::TooFewData { n, p });
    }
    let tr: Vec<Transform> = free.iter().map(Transform::of).collect();
    let u0: Vec<f64> = tr.iter().zip(&starts).map(|(t, &v)| t.to_u(v)).collect();
    let (y, sigma, stated) = measured(data);
    let all_stated = stated.iter().all(|&s| s);
    let pb = problem::Problem {
        device,
        data,
        free,
        tr,
        y,
        sigma,
        stated,
    };
    let dof = n - p;
    // A chi-square above this is improbably large (with stated standard deviations).
    let chi2_limit = (all_stated && dof > 0)
        .then(|| ChiSquared::new(dof as f64).ok())
        .flatten()
        .map(|c| c.inverse_cdf(CHI2_QUANTILE));
    // The refinements stop early at a chi-square that is not improbably large; with as many
    // values as parameters (no law), at one not improbable for a single degree of freedom.
    // Without stated standard deviations every start ranked among the best is refined.
    let early = all_stated
        .then(|| ChiSquared::new(dof.max(1) as f64).ok())
        .flatten()
        .map(|c| c.inverse_cdf(CHI2_QUANTILE));
    let (run, tried, best_start) = search::search(&pb, &u0, settings, all_stated, early)?;
    summarise(&pb, &starts, run, tried, best_start, chi2_limit)
}

/// The report of the search's best run `run` (see [`fit()`]).
fn summarise(
    pb: &problem::Problem<'_>,
    starts: &[f64],
    run: problem::Run,
    tried: Vec<report::StartTried>,
    best_start: usize,
    chi2_limit: Option<f64>,
) -> Result<FitReport, FitError> {
    let (free, tr) = (pb.free, &pb.tr);
    let (n, p) = (pb.y.len(), free.len());
    let dof = n - p;
    let all_stated = pb.stated.iter().all(|&s| s);
    let lm = &run.lm;
    let p_fit = pb.to_p(&lm.u);
    let (mut fitted_device, accel_scale) = apply(pb.device, free, &p_fit)?;
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
    let scaled = uncertainty::Scaled::of(&lm.jacobian);
    let cov_u = scaled.covariance(scale2);
    let (params, correlation) = uncertainty::parameters(free, tr, starts, &lm.u, &cov_u, q);
    let (undetermined, singular_ratio) = scaled.undetermined(free, tr, &lm.u, &p_fit);
    warnings.extend(undetermined);
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
    let model = model_warning(&run.used, &mut warnings);
    if chi2_limit.is_some_and(|l| ssr > l) {
        warnings.push(FitWarning::PoorFit {
            reduced_chi2: ssr / dof as f64,
            quantile: CHI2_QUANTILE,
        });
    }
    let chi2_p = (all_stated && dof > 0)
        .then(|| ChiSquared::new(dof as f64).ok().map(|c| c.sf(ssr)))
        .flatten();
    Ok(FitReport {
        device: fitted_device,
        accel_scale,
        params,
        correlation,
        warnings,
        uncertainty,
        residuals: residual_rows(pb, &lm.residuals),
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
        starts: tried,
        best_start,
    })
}

/// The model a search used, in words, with its warning.
fn model_warning(used: &problem::Used, warnings: &mut Vec<FitWarning>) -> String {
    match used {
        problem::Used::Branches {
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
        problem::Used::SteppedSweep { why } => {
            warnings.push(FitWarning::SteppedSweepModel { why: why.clone() });
            "stepped sweep".to_string()
        }
    }
}

/// The residual rows at the optimum (weighted residuals `r`), data set by data set: points,
/// features, then the jump the points show.
fn residual_rows(pb: &problem::Problem<'_>, r: &[f64]) -> Vec<Residual> {
    let mut rows = Vec::with_capacity(r.len());
    let mut i = 0;
    for d in pb.data {
        let items = d
            .points
            .iter()
            .map(|pt| ("point".to_string(), pt.freq_hz))
            .chain(
                d.features
                    .iter()
                    .map(|f| (f.kind.label().to_string(), f.freq_hz)),
            )
            .chain(
                d.measured_jump()
                    .map(|j| ("jump between points".to_string(), j.mid_hz())),
            );
        for (what, freq_hz) in items {
            rows.push(Residual {
                dataset: d.label.clone(),
                what,
                freq_hz,
                measured: pb.y[i],
                model: pb.y[i] + r[i] * pb.sigma[i],
                sigma: pb.sigma[i],
            });
            i += 1;
        }
    }
    rows
}
