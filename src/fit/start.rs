//! The search from one start: on the branches where they can be identified there
//! ([`super::problem`]), else on the stepped sweep ([`super::model`]) until the branches can
//! take over.

use super::branch::SetModel;
use super::lm::{
    self, levenberg_marquardt_resumed, levenberg_marquardt_tracked, LmResult, LmSettings, Tracked,
};
use super::params::apply;
use super::problem::{on_branches, Problem, Run, Used};
use super::{model_values, FitError};

/// The search from `u0`, with the branches there identified (`identified`, or why they could
/// not be): on the branches, identified afresh after each round while they differ; where they
/// cannot be identified at `u0`, on the stepped sweep until the branches can be identified and
/// their search settles with an SSR of at most `good_ssr`, or until the stepped sweep is near
/// its optimum and on the branches from there ([`stepped`]).
pub(super) fn search_from(
    pb: &Problem<'_>,
    u0: &[f64],
    identified: Result<Vec<SetModel>, FitError>,
    settings: &LmSettings,
    good_ssr: Option<f64>,
) -> Result<Run, FitError> {
    match identified {
        Ok(states) => on_branches(pb, u0, states, settings),
        Err(e) => stepped(pb, u0, settings, good_ssr, e.to_string()),
    }
}

/// The stepped-sweep search hands over to the branches once an accepted step lowers its cost
/// by less than this fraction: near a minimum of chi-square `c` a step that lowers it by
/// `1e-2 c` lies within about `sqrt(1e-2 c)` standard errors of it (`c` of the order of the
/// degrees of freedom), close enough for Newton's method to identify the branches the data
/// follow, where the start may lie in a region without them (a response that is not periodic
/// below the onset of impacts).
pub(super) const HANDOVER_COST_REL_TOL: f64 = 1e-2;

/// The search on the stepped sweep (the model of [`super::model`]) from `u0`, where the
/// branches cannot be identified (`why`). At each point the search accepts, the branches are
/// looked for; where they can be identified, the search on them takes over there, and its
/// result is kept when it settles with an SSR of at most `good_ssr` (each stepped evaluation
/// costs a whole sweep to a tight steady state, an identification one plain sweep, and each
/// evaluation on the branches a few periods per measured value). Else the stepped search goes
/// on where it handed over, taking the steps it would have taken, loosely
/// ([`HANDOVER_COST_REL_TOL`]) to near its optimum, then the branches are tried from there:
/// kept when they settle no worse than the stepped sweep; else the stepped search is carried on
/// to its own tolerances where the loose one stopped short of them. A settled search on the
/// branches from the handover point is kept over whatever follows when its SSR is smaller.
fn stepped(
    pb: &Problem<'_>,
    u0: &[f64],
    settings: &LmSettings,
    good_ssr: Option<f64>,
    why: String,
) -> Result<Run, FitError> {
    let tight = LmSettings {
        fd_step: settings.fd_step.max(lm::STEPPED_FD_STEP),
        ..*settings
    };
    // The Jacobian where the loose search converges serves only a search carried on there
    // (each of its columns a whole sweep): it is differenced when the branches do not take
    // over.
    let loose = LmSettings {
        cost_rel_tol: tight.cost_rel_tol.max(HANDOVER_COST_REL_TOL),
        jacobian_at_stop: false,
        ..tight
    };
    let watched = Stepped::watching(pb);
    let (mut near, mut last) =
        levenberg_marquardt_tracked(&watched, u0, Costs::none(), None, &loose)?;
    let mut handed: Option<Run> = None;
    if near.stop == lm::Termination::HandedOver {
        let states = watched
            .found
            .into_inner()
            .unwrap_or_else(|e| e.into_inner());
        if let Some(Ok(mut run)) = states.map(|s| on_branches(pb, &near.u, s, settings)) {
            run.evaluations += near.evaluations;
            run.iterations += near.iterations;
            if run.settled() && good_ssr.is_some_and(|l| run.ssr() <= l) {
                return Ok(run);
            }
            handed = run.settled().then_some(run);
        }
        // The loose search goes on from the handover point with its damping and remaining
        // iterations, without looking for the branches again.
        let rest = LmSettings {
            lambda0: near.lambda,
            max_iter: loose.max_iter.saturating_sub(near.iterations),
            ..loose
        };
        let r0 = near.residuals.clone();
        let (more, more_last) =
            levenberg_marquardt_tracked(&Stepped::plain(pb), &near.u, last, Some(r0), &rest)?;
        near = LmResult {
            evaluations: near.evaluations + more.evaluations - 1,
            iterations: near.iterations + more.iterations,
            failed_trials: near.failed_trials + more.failed_trials,
            ..more
        };
        last = more_last;
    }
    let near_ssr = last.here;
    let kept = |run: Run| match handed {
        Some(h) if h.ssr() < run.ssr() => h,
        _ => run,
    };
    if let Ok(states) = pb.identify(&near.u) {
        if let Ok(mut run) = on_branches(pb, &near.u, states, settings) {
            run.evaluations += near.evaluations;
            run.iterations += near.iterations;
            if run.settled() && run.ssr() <= near_ssr {
                return Ok(kept(run));
            }
        }
    }
    if !near.jacobian_at_u {
        near.jacobian = lm::jacobian(
            &Stepped::plain(pb),
            &near.u,
            &near.residuals,
            &last,
            tight.fd_step,
        )?;
        near.evaluations += pb.free.len();
        near.jacobian_at_u = true;
    }
    // The loose search stopped where the tight one would not have: carry it on from its
    // point, Jacobian and damping, so that it takes the tight search's own steps.
    let drop = last.before - last.here;
    let step = last
        .u_here
        .iter()
        .zip(&last.u_before)
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        .sqrt();
    let loose_stop = near.stop == lm::Termination::CostConverged
        && !(drop < tight.cost_rel_tol * last.before || drop < tight.cost_abs_tol);
    let short = loose_stop && step >= tight.step_tol;
    let lm = if short {
        let (r0, j0) = (near.residuals.clone(), near.jacobian.clone());
        let rest = LmSettings {
            lambda0: near.lambda,
            max_iter: tight.max_iter.saturating_sub(near.iterations),
            ..tight
        };
        let (more, _) =
            levenberg_marquardt_resumed(&Stepped::plain(pb), &near.u, last, r0, j0, &rest)?;
        LmResult {
            evaluations: near.evaluations + more.evaluations - 1,
            iterations: near.iterations + more.iterations,
            failed_trials: near.failed_trials + more.failed_trials,
            ..more
        }
    } else if loose_stop {
        // Where the tight search stops by the step's length.
        LmResult {
            stop: lm::Termination::StepConverged,
            ..near
        }
    } else {
        near
    };
    Ok(kept(Run {
        evaluations: lm.evaluations,
        iterations: lm.iterations,
        lm,
        used: Used::SteppedSweep { why },
        identified: None,
    }))
}

/// The weighted SSR and the point of an evaluation and of the accepted point it was evaluated
/// from: what the stepped search carries, so that the last accepted step's decrease and length
/// are known.
#[derive(Debug, Clone, PartialEq)]
struct Costs {
    here: f64,
    before: f64,
    u_here: Vec<f64>,
    u_before: Vec<f64>,
}

impl Costs {
    fn none() -> Costs {
        Costs {
            here: f64::NAN,
            before: f64::NAN,
            u_here: Vec::new(),
            u_before: Vec::new(),
        }
    }
}

/// The misfit on the stepped sweep; when it watches for the branches, it hands over at the
/// first accepted point where they can be identified and agree with the stepped sweep (as the
/// branches followed and identified afresh must, [`Problem::disagreement`]), and keeps them in
/// `found`. Where they disagree, the sweep there does not follow the branches found (it jumps
/// elsewhere, or settles on another orbit), and a search on them would fit another response.
struct Stepped<'a, 'b> {
    pb: &'a Problem<'b>,
    watch: bool,
    found: std::sync::Mutex<Option<Vec<SetModel>>>,
}

impl<'a, 'b> Stepped<'a, 'b> {
    fn plain(pb: &'a Problem<'b>) -> Self {
        Self {
            pb,
            watch: false,
            found: std::sync::Mutex::new(None),
        }
    }

    fn watching(pb: &'a Problem<'b>) -> Self {
        Self {
            watch: true,
            ..Self::plain(pb)
        }
    }
}

impl Tracked for Stepped<'_, '_> {
    type State = Costs;
    type Error = FitError;

    fn residuals(&self, u: &[f64], from: &Costs) -> Result<(Vec<f64>, Costs), FitError> {
        let pb = self.pb;
        let (d, scale) = apply(pb.device, pb.free, &pb.to_p(u))?;
        let mut m = Vec::with_capacity(pb.y.len());
        for ds in pb.data {
            m.extend(model_values(&d, scale, ds)?);
        }
        let r = pb.weighted(&m);
        let here = r.iter().map(|x| x * x).sum();
        Ok((
            r,
            Costs {
                here,
                before: from.here,
                u_here: u.to_vec(),
                u_before: from.u_here.clone(),
            },
        ))
    }

    fn hand_over(&self, u: &[f64], r: &[f64], _: &Costs) -> bool {
        if !self.watch {
            return false;
        }
        let Ok(states) = self.pb.identify(u) else {
            return false;
        };
        if self.pb.disagreement(&self.pb.residuals_of(&states), r) > 1.0 {
            return false;
        }
        *self.found.lock().unwrap_or_else(|e| e.into_inner()) = Some(states);
        true
    }
}
