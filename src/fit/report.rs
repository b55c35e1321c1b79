//! What a fit reports: the fitted values with their uncertainty, the correlations, the
//! residuals, and the warnings (see the parent module's docs for the method).

use serde::Serialize;

use super::{Termination, SINGULAR_RATIO_WARN};
use crate::device::Device;

/// How the covariance is scaled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Uncertainty {
    /// Every measured value states its standard deviation: covariance `(J^T J)^-1`.
    Stated,
    /// Some do not: covariance `s^2 (J^T J)^-1`, `s^2 = SSR / (n - p)`.
    ResidualScaled,
}

impl Uncertainty {
    /// The method, in words, for the output.
    pub fn describe(self) -> &'static str {
        match self {
            Uncertainty::Stated => {
                "Gauss-Newton covariance (J^T J)^-1 of the residuals weighted by the stated \
                 standard deviations; 95 % intervals u +- 1.96 se_u in the transformed \
                 coordinates, mapped back"
            }
            Uncertainty::ResidualScaled => {
                "Gauss-Newton covariance s^2 (J^T J)^-1 scaled by the residual variance \
                 s^2 = SSR/(n-p); 95 % intervals u +- t(n-p, 0.975) se_u in the transformed \
                 coordinates, mapped back"
            }
        }
    }
}

/// Something the caller must know about a fit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub enum FitWarning {
    /// A combination of parameters the data do not determine: the smallest singular value of
    /// the column-scaled Jacobian is `ratio` times the largest (below [`SINGULAR_RATIO_WARN`]).
    /// `direction` gives the combination as relative changes (d ln p, or dp for a parameter
    /// whose range includes zero), largest component 1.
    Undetermined {
        /// (path, component).
        direction: Vec<(String, f64)>,
        /// Smallest over largest singular value.
        ratio: f64,
    },
    /// A fitted value lies within 1e-3 of its range (as a fraction of the range).
    AtBound {
        /// The parameter.
        path: String,
        /// Its fitted value.
        value: f64,
    },
    /// As many measured values as free parameters and no stated standard deviations: no
    /// residual variance, hence no uncertainty.
    NoResidualDof,
    /// The search stopped without meeting a convergence criterion.
    NotConverged {
        /// Why it stopped.
        stop: String,
    },
    /// The branches identified afresh at the fitted values (from the stepped sweep) differ
    /// from the ones the search followed after every round: by `disagreement` times the
    /// tolerance ([`crate::fit::AGREE_SIGMA`] standard deviations; NaN: they could not be
    /// identified).
    BranchChanged {
        /// Largest difference over its tolerance.
        disagreement: f64,
        /// Rounds of the search.
        rounds: usize,
    },
    /// The branches could not be identified, and the model was the stepped sweep, whose
    /// misfit jumps where a fold passes a measured frequency.
    SteppedSweepModel {
        /// Why the branches could not be identified.
        why: String,
    },
    /// The chi-square of the residuals weighted by the stated standard deviations exceeds its
    /// `quantile`: the model does not describe the data within their stated uncertainty (or
    /// the uncertainty is understated).
    PoorFit {
        /// Chi-square per degree of freedom.
        reduced_chi2: f64,
        /// The quantile exceeded.
        quantile: f64,
    },
}

impl std::fmt::Display for FitWarning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FitWarning::Undetermined { direction, ratio } => {
                let combo: Vec<String> = direction
                    .iter()
                    .map(|(p, c)| format!("{c:+.3} d({p})"))
                    .collect();
                write!(
                    f,
                    "undetermined: the data do not determine the combination {} (relative \
                     changes; smallest/largest singular value of the column-scaled Jacobian \
                     {ratio:.2e} < {SINGULAR_RATIO_WARN})",
                    combo.join(" ")
                )
            }
            FitWarning::AtBound { path, value } => write!(
                f,
                "at bound: `{path}` = {value:e} is at an end of its range; the optimum may lie \
                 outside it and the interval is not meaningful"
            ),
            FitWarning::NoResidualDof => write!(
                f,
                "no residual degrees of freedom: as many measured values as free parameters \
                 and no stated standard deviations, so no uncertainty can be given"
            ),
            FitWarning::NotConverged { stop } => {
                write!(f, "not converged: the search stopped ({stop})")
            }
            FitWarning::BranchChanged {
                disagreement,
                rounds,
            } => write!(
                f,
                "branch changed: after {rounds} rounds the branches identified afresh at the \
                 fitted values still differ from the ones followed ({disagreement:.3} times \
                 the tolerance); the fit may describe a branch the sweep does not show"
            ),
            FitWarning::SteppedSweepModel { why } => write!(
                f,
                "stepped-sweep model: the branches could not be identified ({why}); the \
                 misfit is the stepped sweep's, which jumps where a fold passes a measured \
                 frequency"
            ),
            FitWarning::PoorFit {
                reduced_chi2,
                quantile,
            } => write!(
                f,
                "poor fit: chi-square per degree of freedom {reduced_chi2:.3} exceeds the \
                 {quantile} quantile; the model does not describe the data within their stated \
                 standard deviations"
            ),
        }
    }
}

/// A fitted parameter.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FittedParam {
    /// Dotted path.
    pub path: String,
    /// Starting value.
    pub start: f64,
    /// Fitted value.
    pub value: f64,
    /// Standard error in the parameter's unit (`|dp/du| se_u`); infinite when the data do
    /// not determine the parameter at all (its interval is then the whole range).
    pub std_err: f64,
    /// 95 % interval (see the module docs).
    pub interval: (f64, f64),
    /// The range searched.
    pub range: (f64, f64),
}

/// One residual of the fitted model.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Residual {
    /// Data set label.
    pub dataset: String,
    /// "point" or the feature's label.
    pub what: String,
    /// Frequency of the measured value (Hz).
    pub freq_hz: f64,
    /// Measured value.
    pub measured: f64,
    /// Model value.
    pub model: f64,
    /// Standard deviation used as weight (1 where none was stated).
    pub sigma: f64,
}

/// The result of [`crate::fit::fit()`].
#[derive(Debug, Clone)]
pub struct FitReport {
    /// The fitted device (device parameters at their fitted values).
    pub device: Device,
    /// The fitted acceleration factor (1 if it was not free).
    pub accel_scale: f64,
    /// The fitted parameters, in the order given.
    pub params: Vec<FittedParam>,
    /// Correlation matrix of the estimates (transformed coordinates).
    pub correlation: Vec<Vec<f64>>,
    /// Warnings.
    pub warnings: Vec<FitWarning>,
    /// How the covariance was scaled.
    pub uncertainty: Uncertainty,
    /// Residuals at the fitted values, data set by data set.
    pub residuals: Vec<Residual>,
    /// Weighted sum of squared residuals.
    pub ssr: f64,
    /// n - p.
    pub dof: usize,
    /// Chi-square per degree of freedom, SSR / (n - p) (NaN without degrees of freedom); about
    /// 1 when the model describes the data within their stated standard deviations.
    pub reduced_chi2: f64,
    /// Probability of a chi-square at least as large, when every value states its standard
    /// deviation and n > p.
    pub chi2_p: Option<f64>,
    /// Smallest over largest singular value of the column-scaled Jacobian.
    pub singular_ratio: f64,
    /// Outer iterations of the search.
    pub iterations: usize,
    /// Model evaluations of the reported start (every data set counts once per evaluation).
    pub evaluations: usize,
    /// Trial points of the reported search whose model could not be evaluated.
    pub failed_trials: usize,
    /// Why the search stopped.
    pub stop: Termination,
    /// The model the search used, in words.
    pub model: String,
    /// Every start of the design with its cheap misfit and, for those refined, the outcome
    /// (see [`crate::fit::FitSettings`]).
    pub starts: Vec<StartTried>,
    /// Index in `starts` of the start reported.
    pub best_start: usize,
}

impl FitReport {
    /// Starts refined by Levenberg-Marquardt.
    pub fn starts_refined(&self) -> usize {
        self.starts.iter().filter(|s| s.refined.is_some()).count()
    }

    /// What must head the report: a fitted value at an end of its range, a chi-square
    /// improbably large for its law, a search that did not converge. `None` when there is
    /// none of these.
    pub fn headline(&self) -> Option<String> {
        let mut parts: Vec<String> = Vec::new();
        for w in &self.warnings {
            match w {
                FitWarning::AtBound { path, value } => parts.push(format!(
                    "`{path}` = {value:e} sits at an end of its range (the optimum may lie \
                     outside it; its interval means nothing)"
                )),
                FitWarning::PoorFit {
                    reduced_chi2,
                    quantile,
                } => parts.push(format!(
                    "the chi-square per degree of freedom {reduced_chi2:.3} exceeds its \
                     {:.1} % quantile (probability of a larger one {}): the model does not \
                     describe the data within their stated standard deviations, and the \
                     intervals are not to be trusted",
                    100.0 * quantile,
                    self.chi2_p.map_or("-".to_string(), |p| format!("{p:.2e}"))
                )),
                FitWarning::NotConverged { stop } => {
                    parts.push(format!("the search did not converge ({stop})"))
                }
                _ => {}
            }
        }
        (!parts.is_empty()).then(|| format!("NOT A GOOD FIT: {}.", parts.join("; ")))
    }
}

/// Where a start of the design lies.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub enum StartOrigin {
    /// The device's own values.
    DeviceFile,
    /// The k-th point (from 1) of the Sobol sequence over the ranges.
    Sobol(usize),
    /// Start `from` (an index into the starts), or the fit refined from it, with the gap
    /// `param`, beyond the reach of every orbit there, moved inside it (`fit::untouched`).
    Untouched {
        /// The start whose values (or fit) it moved (an index into the starts).
        from: usize,
        /// The parameter moved (its path).
        param: String,
        /// True when the fit refined from the start was moved, false when the start itself
        /// was (and it was refined from there instead).
        of_fit: bool,
    },
}

impl std::fmt::Display for StartOrigin {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StartOrigin::DeviceFile => write!(f, "the device file's values"),
            StartOrigin::Sobol(k) => write!(f, "Sobol point {k}"),
            StartOrigin::Untouched {
                from,
                param,
                of_fit,
            } => write!(
                f,
                "start {from}{} with `{param}`, beyond every orbit's reach there, moved \
                 inside it",
                if *of_fit { "'s fit" } else { "" }
            ),
        }
    }
}

/// A start refined by Levenberg-Marquardt.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Refined {
    /// Weighted SSR of the refined fit (the model on the branches).
    pub ssr: f64,
    /// Converged, on branches that agree with the ones identified afresh.
    pub settled: bool,
    /// The refined values, in the order of the free parameters.
    pub values: Vec<f64>,
}

/// A start of the global search.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StartTried {
    /// Where it lies.
    pub origin: StartOrigin,
    /// Its values, in the order of the free parameters.
    pub values: Vec<f64>,
    /// Weighted SSR of the cheap model (a stepped sweep with short blocks) there; infinite
    /// where it could not be evaluated, NaN when the design had one start only.
    pub design_ssr: f64,
    /// True when the cheap model's sweeps were stopped once the SSR of the points they had
    /// swept exceeded that of the last start kept for refinement (such a start cannot be among
    /// them): `design_ssr` is then the SSR of those points, a lower bound of the whole.
    pub design_cut: bool,
    /// The refinement from it, when it was among the best ranked.
    pub refined: Option<Refined>,
}
