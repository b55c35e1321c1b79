//! The problem of a fit and the search on the branches from one start: what every evaluation
//! needs (the device, the data, the free parameters, the measured values and their weights),
//! the misfit on the branches followed from the accepted point's, and the rounds of
//! Levenberg-Marquardt on them, the branches identified afresh after each round while they
//! differ.

use super::branch::{self, SetModel};
use super::lm::{levenberg_marquardt_tracked, LmResult, LmSettings, Tracked};
use super::params::{apply, Transform};
use super::{FitError, SweepData, AGREE_REL, AGREE_SIGMA, MAX_ROUNDS};
use crate::device::{Device, ParamRange};

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

    pub(super) fn weighted(&self, m: &[f64]) -> Vec<f64> {
        m.iter()
            .zip(&self.y)
            .zip(&self.sigma)
            .map(|((m, y), s)| (m - y) / s)
            .collect()
    }

    /// The branches of every data set identified afresh at `u`.
    pub(super) fn identify(&self, u: &[f64]) -> Result<Vec<SetModel>, FitError> {
        let (d, scale) = apply(self.device, self.free, &self.to_p(u))?;
        self.data
            .iter()
            .map(|ds| branch::identify(&d, scale, ds).map_err(|l| FitError::Lost(l.0)))
            .collect()
    }

    /// The weighted SSR at `u` on the branches `from` (the models at `from_u`) followed
    /// there, with the branches followed; `None` where they are lost.
    pub(super) fn followed_ssr(
        &self,
        u: &[f64],
        from_u: &[f64],
        from: &[SetModel],
    ) -> Option<(f64, Vec<SetModel>)> {
        let from = Followed {
            u: from_u.to_vec(),
            sets: from.to_vec(),
        };
        let (r, followed) = OnBranches(self).residuals(u, &from).ok()?;
        Some((r.iter().map(|r| r * r).sum(), followed.sets))
    }

    /// The weighted residuals of the models `states` (without following them).
    pub(super) fn residuals_of(&self, states: &[SetModel]) -> Vec<f64> {
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
    pub(super) fn disagreement(&self, a: &[f64], b: &[f64]) -> f64 {
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

/// Halvings of a step of the parameters tried where the branches are lost over the whole
/// step. Newton's method from the accepted point's orbits fails where a long trial step of the
/// search moves an orbit further than its iterations reach; over half the step, from the
/// orbits there, it reaches (a homotopy in the parameters). A branch that ends inside the step
/// is lost over its parts too, at the cost of their evaluations: one halving, since a second
/// cost more time than it saved where the search meets a branch's end again and again (the
/// recovery family's case 18 on one thread: 6.0 to 7.5 s with none, 7.3 to 7.8 s with one,
/// 9.8 to 11.6 s with two, by the `fit_cost` example; `bench --fits --fit-only 15,18` is the
/// benchmark of record). It changes the speed of a fit, not its outcome: the recovery
/// family's results are the same with it.
const MAX_HALVINGS: u32 = 1;

/// The models of the data sets at the parameters `u` (unbounded coordinates) they were
/// followed to.
#[derive(Clone)]
struct Followed {
    u: Vec<f64>,
    sets: Vec<SetModel>,
}

/// The misfit on the branches, followed from the accepted point's.
struct OnBranches<'a, 'b>(&'a Problem<'b>);

impl OnBranches<'_, '_> {
    /// The branches `from` followed to `u` in one step.
    fn follow_step(&self, u: &[f64], from: &Followed) -> Result<Followed, FitError> {
        let pb = self.0;
        let (d, scale) = apply(pb.device, pb.free, &pb.to_p(u))?;
        let sets = pb
            .data
            .iter()
            .zip(&from.sets)
            .map(|(ds, prev)| branch::track(&d, scale, ds, prev).map_err(|l| FitError::Lost(l.0)))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Followed {
            u: u.to_vec(),
            sets,
        })
    }

    /// The branches `from` followed to `u`: in one step, else over its halves with up to
    /// `halvings` further halvings each; the error is the whole step's.
    fn follow(&self, u: &[f64], from: &Followed, halvings: u32) -> Result<Followed, FitError> {
        match self.follow_step(u, from) {
            Err(FitError::Lost(why)) if halvings > 0 => {
                let mid: Vec<f64> = from.u.iter().zip(u).map(|(a, b)| 0.5 * (a + b)).collect();
                self.follow(&mid, from, halvings - 1)
                    .and_then(|m| self.follow(u, &m, halvings - 1))
                    .map_err(|_| FitError::Lost(why))
            }
            other => other,
        }
    }
}

impl Tracked for OnBranches<'_, '_> {
    type State = Followed;
    type Error = FitError;

    fn residuals(&self, u: &[f64], from: &Followed) -> Result<(Vec<f64>, Followed), FitError> {
        let followed = self.follow(u, from, MAX_HALVINGS)?;
        Ok((self.0.residuals_of(&followed.sets), followed))
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
    /// The branches identified afresh at `lm.u` by the last round (none on the stepped
    /// sweep, or where the identification failed): kept so that a later look at the same
    /// point does not repeat it.
    pub(super) identified: Option<Vec<SetModel>>,
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

/// The rounds of the search on the branches from `u0`, whose branches `states` are
/// identified there.
pub(super) fn on_branches(
    pb: &Problem<'_>,
    u0: &[f64],
    states: Vec<SetModel>,
    settings: &LmSettings,
) -> Result<Run, FitError> {
    let mut states = states;
    let mut u = u0.to_vec();
    let (mut evaluations, mut iterations) = (0, 0);
    for round in 1..=MAX_ROUNDS {
        let r0 = pb.residuals_of(&states);
        let from = Followed {
            u: u.clone(),
            sets: states,
        };
        let (lm, followed) =
            levenberg_marquardt_tracked(&OnBranches(pb), &u, from, Some(r0), settings)?;
        let followed = followed.sets;
        evaluations += lm.evaluations;
        iterations += lm.iterations;
        let fresh = pb.identify(&lm.u);
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
                identified: fresh.ok(),
            });
        }
        states = fresh.expect("checked above");
        u = lm.u;
    }
    unreachable!("the last round returns")
}
