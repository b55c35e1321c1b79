//! The search of a fit: the misfit on the branches ([`super::branch`]) or, where they cannot
//! be identified, on the stepped sweep ([`super::model`]); the rounds of one start; and the
//! global search, a design of starts ranked by a cheap model with the best few refined (see
//! the parent module's docs).

use super::branch::{self, SetModel};
use super::lm::{self, levenberg_marquardt_tracked, LmResult, LmSettings, Tracked};
use super::model::{design_values, SweepRun};
use super::params::{apply, Transform};
use super::report::{Refined, StartOrigin, StartTried};
use super::{
    model_values, FitError, FitSettings, SweepData, AGREE_REL, AGREE_SIGMA, MAX_ROUNDS,
    STATED_COST_ABS_TOL,
};
use crate::device::{Device, ParamRange};
use rayon::prelude::*;

/// What every evaluation needs: the device, the data, the free parameters with their
/// transforms, and the measured values with their weights.
pub(super) struct Problem<'a> {
    pub(super) device: &'a Device,
    pub(super) data: &'a [SweepData],
    pub(super) free: &'a [ParamRange],
    pub(super) tr: Vec<Transform>,
    pub(super) y: Vec<f64>,
    pub(super) sigma: Vec<f64>,
    /// Which measured values state their standard deviation (features always do).
    pub(super) stated: Vec<bool>,
}

impl Problem<'_> {
    pub(super) fn to_p(&self, u: &[f64]) -> Vec<f64> {
        self.tr.iter().zip(u).map(|(t, &u)| t.to_p(u)).collect()
    }

    fn weighted(&self, m: &[f64]) -> Vec<f64> {
        m.iter()
            .zip(&self.y)
            .zip(&self.sigma)
            .map(|((m, y), s)| (m - y) / s)
            .collect()
    }

    /// The branches of every data set identified afresh at `u`, from the plain sweeps `swept`
    /// of every data set at `u` when given (the design's), else from sweeps run here.
    fn identify(&self, u: &[f64], swept: Option<&[SweepRun]>) -> Result<Vec<SetModel>, FitError> {
        let (d, scale) = apply(self.device, self.free, &self.to_p(u))?;
        self.data
            .iter()
            .enumerate()
            .map(|(i, ds)| {
                branch::identify(&d, scale, ds, swept.and_then(|w| w.get(i)))
                    .map_err(|l| FitError::Lost(l.0))
            })
            .collect()
    }

    /// The weighted residuals of the models `states` (without following them).
    fn residuals_of(&self, states: &[SetModel]) -> Vec<f64> {
        let m: Vec<f64> = self
            .data
            .iter()
            .zip(states)
            .flat_map(|(ds, s)| s.values(ds))
            .collect();
        self.weighted(&m)
    }

    /// The largest difference between two sets of weighted residuals in units of its
    /// tolerance ([`AGREE_SIGMA`] standard deviations, or [`AGREE_REL`] of the value); at most
    /// 1 when they agree.
    fn disagreement(&self, a: &[f64], b: &[f64]) -> f64 {
        a.iter()
            .zip(b)
            .enumerate()
            .map(|(i, (a, b))| {
                let tol = if self.stated[i] {
                    AGREE_SIGMA
                } else {
                    AGREE_REL * self.y[i].abs() / self.sigma[i]
                };
                let d = (a - b).abs() / tol;
                if d.is_nan() {
                    f64::INFINITY
                } else {
                    d
                }
            })
            .fold(0.0, f64::max)
    }
}

/// The misfit on the branches, followed from the accepted point's.
struct OnBranches<'a, 'b>(&'a Problem<'b>);

impl Tracked for OnBranches<'_, '_> {
    type State = Vec<SetModel>;
    type Error = FitError;

    fn residuals(
        &self,
        u: &[f64],
        from: &Vec<SetModel>,
    ) -> Result<(Vec<f64>, Vec<SetModel>), FitError> {
        let pb = self.0;
        let (d, scale) = apply(pb.device, pb.free, &pb.to_p(u))?;
        let states = pb
            .data
            .iter()
            .zip(from)
            .map(|(ds, prev)| branch::track(&d, scale, ds, prev).map_err(|l| FitError::Lost(l.0)))
            .collect::<Result<Vec<_>, _>>()?;
        Ok((pb.residuals_of(&states), states))
    }
}

/// Which model a search used.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum Used {
    /// The branches; `disagreement` is that of the last fresh identification (at most 1: they
    /// agree), `None` when it failed.
    Branches {
        disagreement: Option<f64>,
        rounds: usize,
    },
    /// The stepped sweep, because the branches could not be identified.
    SteppedSweep { why: String },
}

/// The outcome of the search from one start.
pub(super) struct Run {
    pub(super) lm: LmResult,
    pub(super) used: Used,
    /// Evaluations of every round (the fresh identifications not counted).
    pub(super) evaluations: usize,
    /// Iterations of every round.
    pub(super) iterations: usize,
}

impl Run {
    pub(super) fn ssr(&self) -> f64 {
        self.lm.residuals.iter().map(|r| r * r).sum()
    }

    /// True when the search converged, on branches that agree with the ones identified afresh
    /// or on the stepped sweep (which has nothing to agree with).
    pub(super) fn settled(&self) -> bool {
        self.lm.stop.converged()
            && match self.used {
                Used::Branches { disagreement, .. } => disagreement.is_some_and(|d| d <= 1.0),
                Used::SteppedSweep { .. } => true,
            }
    }
}

/// The search from `u0`: on the branches, identified there (from the plain sweeps `swept` at
/// `u0` when the design ran them) and afresh after each round while they differ; on the
/// stepped sweep where they cannot be identified.
pub(super) fn search_from(
    pb: &Problem<'_>,
    u0: &[f64],
    swept: Option<&[SweepRun]>,
    settings: &LmSettings,
) -> Result<Run, FitError> {
    let states = match pb.identify(u0, swept) {
        Ok(s) => s,
        Err(e) => return stepped(pb, u0, settings, e.to_string()),
    };
    let mut states = states;
    let mut u = u0.to_vec();
    let (mut evaluations, mut iterations) = (0, 0);
    for round in 1..=MAX_ROUNDS {
        let r0 = pb.residuals_of(&states);
        let (lm, followed) =
            levenberg_marquardt_tracked(&OnBranches(pb), &u, states, Some(r0), settings)?;
        evaluations += lm.evaluations;
        iterations += lm.iterations;
        let fresh = pb.identify(&lm.u, None);
        let disagreement = fresh
            .as_ref()
            .ok()
            .map(|f| pb.disagreement(&pb.residuals_of(f), &pb.residuals_of(&followed)));
        let done = disagreement.is_none_or(|d| d <= 1.0) || round == MAX_ROUNDS;
        if done {
            return Ok(Run {
                lm,
                used: Used::Branches {
                    disagreement,
                    rounds: round,
                },
                evaluations,
                iterations,
            });
        }
        states = fresh.expect("checked above");
        u = lm.u;
    }
    unreachable!("the last round returns")
}

/// The search on the stepped sweep (the model of [`super::model`]).
fn stepped(
    pb: &Problem<'_>,
    u0: &[f64],
    settings: &LmSettings,
    why: String,
) -> Result<Run, FitError> {
    let residuals = |u: &[f64]| -> Result<Vec<f64>, FitError> {
        let (d, scale) = apply(pb.device, pb.free, &pb.to_p(u))?;
        let mut m = Vec::with_capacity(pb.y.len());
        for ds in pb.data {
            m.extend(model_values(&d, scale, ds)?);
        }
        Ok(pb.weighted(&m))
    };
    let settings = LmSettings {
        fd_step: settings.fd_step.max(lm::STEPPED_FD_STEP),
        ..*settings
    };
    let lm = lm::levenberg_marquardt(residuals, u0, &settings)?;
    Ok(Run {
        evaluations: lm.evaluations,
        iterations: lm.iterations,
        lm,
        used: Used::SteppedSweep { why },
    })
}

/// The point `k` (from 1) of the Sobol sequence in the transformed box: each parameter's
/// range with a twentieth cut off at either end (a start at an end would sit where the
/// transform is flat).
fn sobol_start(tr: &[Transform], k: usize) -> Vec<f64> {
    tr.iter()
        .enumerate()
        .map(|(d, t)| {
            let s = f64::from(sobol_burley::sample(k as u32, d as u32, 0x5eed));
            t.to_u_frac(0.05 + 0.9 * s)
        })
        .collect()
}

/// The weighted SSR of the cheap model ([`design_values`]) at `u`, infinite where it cannot
/// be evaluated, and its plain sweeps of every data set where each is the one the branches
/// are identified from ([`SweepRun::plain`]).
fn design_ssr(pb: &Problem<'_>, u: &[f64]) -> (f64, Option<Vec<SweepRun>>) {
    let eval = || -> Result<(f64, Option<Vec<SweepRun>>), FitError> {
        let (d, scale) = apply(pb.device, pb.free, &pb.to_p(u))?;
        let mut m = Vec::with_capacity(pb.y.len());
        let mut runs = Some(Vec::with_capacity(pb.data.len()));
        for ds in pb.data {
            let (values, run) = design_values(&d, scale, ds)?;
            m.extend(values);
            runs = runs.zip(run).map(|(mut rs, r)| {
                rs.push(r);
                rs
            });
        }
        Ok((pb.weighted(&m).iter().map(|r| r * r).sum(), runs))
    };
    match eval() {
        Ok((c, runs)) if c.is_finite() => (c, runs),
        _ => (f64::INFINITY, None),
    }
}

/// The searches of a fit: the design (the device's values and [`FitSettings::design_points`] points
/// of a Sobol sequence) ranked by the cheap model's SSR, then the best
/// [`FitSettings::refine`] refined by Levenberg-Marquardt in that order, stopping early at a
/// refined start that settles with a chi-square within `chi2_limit` (when the standard
/// deviations are stated). Returns the best refined run (settled first, then the smallest SSR),
/// every start with what became of it, and the index of the best among them.
pub(super) fn search(
    pb: &Problem<'_>,
    u_file: &[f64],
    settings: &FitSettings,
    all_stated: bool,
    chi2_limit: Option<f64>,
) -> Result<(Run, Vec<StartTried>, usize), FitError> {
    let mut lm = settings.lm;
    if all_stated {
        lm.cost_abs_tol = lm.cost_abs_tol.max(STATED_COST_ABS_TOL);
    }
    let us: Vec<Vec<f64>> = std::iter::once(u_file.to_vec())
        .chain((1..=settings.design_points(pb.free.len())).map(|k| sobol_start(&pb.tr, k)))
        .collect();
    let mut starts: Vec<StartTried> = us
        .iter()
        .enumerate()
        .map(|(i, u)| StartTried {
            origin: if i == 0 {
                StartOrigin::DeviceFile
            } else {
                StartOrigin::Sobol(i)
            },
            values: pb.to_p(u),
            design_ssr: f64::NAN,
            refined: None,
        })
        .collect();
    // One design point alone (no design) is refined without being ranked.
    let mut swept: Vec<Option<Vec<SweepRun>>> = vec![None; starts.len()];
    if starts.len() > 1 {
        let costs: Vec<(f64, Option<Vec<SweepRun>>)> =
            us.par_iter().map(|u| design_ssr(pb, u)).collect();
        for ((s, w), (c, runs)) in starts.iter_mut().zip(&mut swept).zip(costs) {
            s.design_ssr = c;
            *w = runs;
        }
    }
    // The best ranked starts whose cheap model could be evaluated (the device's values when
    // there is none, or no design).
    let mut order: Vec<usize> = (0..starts.len())
        .filter(|&i| starts.len() == 1 || starts[i].design_ssr.is_finite())
        .collect();
    order.sort_by(|&a, &b| starts[a].design_ssr.total_cmp(&starts[b].design_ssr));
    order.truncate(settings.refine.max(1));
    if order.is_empty() {
        order.push(0);
    }
    // Only the sweeps of the starts to be refined are kept.
    for (i, w) in swept.iter_mut().enumerate() {
        if !order.contains(&i) {
            *w = None;
        }
    }
    let mut best: Option<(Run, usize)> = None;
    let mut last_err = None;
    for i in order {
        let run = match search_from(pb, &us[i], swept[i].as_deref(), &lm) {
            Ok(run) => run,
            Err(e) => {
                last_err = Some(e);
                continue;
            }
        };
        starts[i].refined = Some(Refined {
            ssr: run.ssr(),
            settled: run.settled(),
            values: pb.to_p(&run.lm.u),
        });
        let good = run.settled() && chi2_limit.is_some_and(|l| run.ssr() <= l);
        let better = best
            .as_ref()
            .is_none_or(|(b, _)| (run.settled(), -run.ssr()) > (b.settled(), -b.ssr()));
        if better {
            best = Some((run, i));
        }
        if good {
            break;
        }
    }
    match best {
        Some((run, i)) => Ok((run, starts, i)),
        None => Err(last_err.unwrap_or_else(|| {
            FitError::Lost("the model could not be evaluated at any start of the design".into())
        })),
    }
}
