//! Can any parameter set reproduce the paper? The history match of a prototype's claims over
//! the unit cube of [`super::ranges`] ([`crate::num::history`]): every quantitative claim is an
//! output, emulated by a Gaussian process of its normalised deviation (value - paper) /
//! tolerance, with each run's ensemble variance as its nugget.
//!
//! # The observation's variance
//! A claim is reproduced when our value lies within its tolerance of the paper's
//! ([`crate::paper::claims::Claim::tolerance`]); the tolerance says how far apart a reading of
//! the paper's figure and a model of the device may honestly be (reading error, the paper's
//! own rounding, what the lumped model leaves out). The match takes it as
//! [`TOLERANCE_SIGMAS`] standard deviations of the observation: with an exact emulator and no
//! sampling error an input is non-implausible for a claim (implausibility at most 3) exactly
//! where the claim would be reproduced, and the emulator's and the ensembles' variances widen
//! that only by what they do not know. In deviation units the observation is 0 with variance
//! `1 / TOLERANCE_SIGMAS^2`.
//!
//! # Yes/no claims
//! A step function gives a Gaussian process nothing to follow; the yes/no claims (Figure 13's,
//! the order of Figure 8's jumps, Figure 9's common onset, Figure 15's widening) are not
//! emulated. Every run of every wave evaluates them directly, and [`HistoryRun`] reports which
//! runs inside the space meet them, and which meet every claim.

use rayon::prelude::*;

use super::evaluation::evaluate_at;
use super::quantity::{Evaluation, Prototype, Quantity, Scope};
use super::ranges::Ranges;
use super::DeviationsError;
use crate::device::Device;
use crate::num::gp_sensitivity::{emulated_indices, EmulatedIndices, EmulatedSobol};
use crate::num::history::{HistoryMatch, HistorySettings, Mean, Observation, Run, Termination};
use crate::paper::claims::{Claims, Kind};
use crate::progress::Progress;

/// The emulated Sobol indices of each emulated quantity (`None`: constant over the runs).
pub type ClaimIndices = Vec<(Quantity, Option<EmulatedIndices>)>;

/// A claim's tolerance in standard deviations of its observation (see the module doc).
pub const TOLERANCE_SIGMAS: f64 = 3.0;

/// The history match of one prototype: its emulated quantities (the quantitative claims in
/// the scope) and the match.
#[derive(Debug, Clone)]
pub struct HistoryRun {
    /// The prototype.
    pub prototype: Prototype,
    /// The factors' names, in the order of the unit cube's coordinates.
    pub factors: Vec<String>,
    /// What each run evaluates.
    pub scope: Scope,
    /// Every quantity a run evaluates, in [`Prototype::quantities`] order.
    pub quantities: Vec<Quantity>,
    /// Indices into `quantities` of the emulated (quantitative) ones, in output order.
    pub emulated: Vec<usize>,
    /// The tolerance of each emulated quantity's claim, in output order.
    pub tolerances: Vec<f64>,
    /// The match.
    pub matcher: HistoryMatch,
    /// Every run's evaluations, in run order.
    pub evaluations: Vec<Vec<Evaluation>>,
}

impl HistoryRun {
    /// An empty match of `prototype` over `ranges` in `scope`.
    pub fn new(
        prototype: Prototype,
        ranges: &Ranges,
        scope: Scope,
        claims: &Claims,
        settings: HistorySettings,
    ) -> Result<Self, DeviationsError> {
        let quantities = prototype.quantities(scope);
        let mut emulated = Vec::new();
        let mut observations = Vec::new();
        let mut tolerances = Vec::new();
        for (k, q) in quantities.iter().enumerate() {
            let c = claims
                .get(q.claim, q.quantity)
                .ok_or(DeviationsError::UnknownClaim(q.claim, q.quantity))?;
            if c.kind == Kind::Quantitative {
                emulated.push(k);
                tolerances.push(c.tolerance());
                observations.push(Observation {
                    name: format!("{} {}", q.claim, q.quantity),
                    value: 0.0,
                    variance: 1.0 / (TOLERANCE_SIGMAS * TOLERANCE_SIGMAS),
                });
            }
        }
        let matcher = HistoryMatch::new(ranges.len(), observations, settings)
            .map_err(|e| DeviationsError::Evaluations(e.to_string()))?
            .with_switches(ranges.switches());
        Ok(Self {
            prototype,
            factors: ranges.names().iter().map(|n| n.to_string()).collect(),
            scope,
            quantities,
            emulated,
            tolerances,
            matcher,
            evaluations: Vec::new(),
        })
    }

    /// The emulated quantities, in output order.
    pub fn outputs(&self) -> Vec<Quantity> {
        self.emulated.iter().map(|&k| self.quantities[k]).collect()
    }

    /// The inputs of the next wave (`None` once the match has ended).
    pub fn next_design(&self) -> Option<Vec<Vec<f64>>> {
        self.matcher.next_design()
    }

    /// Adds a wave: the evaluations (each [`evaluate_at`]'s output in this scope) at the points
    /// of [`HistoryRun::next_design`], in order.
    pub fn add_wave(
        &mut self,
        points: &[Vec<f64>],
        evaluations: Vec<Vec<Evaluation>>,
    ) -> Result<(), DeviationsError> {
        let design = self
            .next_design()
            .ok_or_else(|| DeviationsError::Evaluations("the history match has ended".into()))?;
        if design.as_slice() != points || evaluations.len() != points.len() {
            return Err(DeviationsError::Evaluations(format!(
                "wave {}: the {} points given are not the wave's design of {} (or the \
                 evaluations are not one per point)",
                self.matcher.waves.len() + 1,
                points.len(),
                design.len()
            )));
        }
        let runs = points
            .iter()
            .zip(&evaluations)
            .map(|(p, e)| self.run_of(p, e))
            .collect::<Result<Vec<_>, _>>()?;
        self.matcher
            .add_wave(runs)
            .map_err(|e| DeviationsError::Evaluations(e.to_string()))?;
        self.evaluations.extend(evaluations);
        Ok(())
    }

    /// One run of the match from a point's evaluations: each emulated quantity's deviation and
    /// its sampling variance in deviation units, `(ci95 / 1.96 / tolerance)^2`.
    fn run_of(&self, point: &[f64], e: &[Evaluation]) -> Result<Run, DeviationsError> {
        if e.len() != self.quantities.len()
            || e.iter()
                .zip(&self.quantities)
                .any(|(e, q)| e.quantity != *q)
        {
            return Err(DeviationsError::Evaluations(format!(
                "an evaluation does not hold the quantities of {} in this scope, in order",
                self.prototype.key()
            )));
        }
        let (mut values, mut variances) = (Vec::new(), Vec::new());
        for (k, &q) in self.emulated.iter().enumerate() {
            let ev = &e[q];
            values.push(ev.deviation);
            variances.push(
                ev.ci95
                    .map_or(0.0, |c| (c / 1.96 / self.tolerances[k]).powi(2)),
            );
        }
        Ok(Run {
            point: point.to_vec(),
            values,
            variances,
        })
    }

    /// Indices of the runs that meet every claim they evaluate (directly, not emulated).
    pub fn runs_meeting_all(&self) -> Vec<usize> {
        (0..self.evaluations.len())
            .filter(|&r| self.evaluations[r].iter().all(|e| e.meets))
            .collect()
    }

    /// Per quantity, how many of wave `wave`'s runs (1-based) meet it.
    pub fn met_in_wave(&self, wave: usize) -> Vec<usize> {
        let runs: Vec<usize> = (0..self.matcher.runs.len())
            .filter(|&r| self.matcher.runs[r].0 == wave)
            .collect();
        (0..self.quantities.len())
            .map(|k| {
                runs.iter()
                    .filter(|&&r| self.evaluations[r][k].meets)
                    .count()
            })
            .collect()
    }

    /// The answer: whether the space emptied, and how much of the cube is left under the
    /// second-largest and under the largest implausibility.
    pub fn answer(&self) -> Option<Answer> {
        let last = self.matcher.summaries.last()?;
        Some(Answer {
            stop: last.stop,
            waves: self.matcher.summaries.len(),
            fraction: last.fraction(),
            fraction_all: last.fraction_all(),
            pool: last.pool,
            runs: self.evaluations.len(),
            runs_meeting_all: self.runs_meeting_all().len(),
            kept_all: last.kept_all,
        })
    }

    /// Sobol indices of every emulated quantity from the first wave's emulators (fitted over
    /// the whole cube), with their intervals from posterior draws.
    pub fn sobol(&self, s: EmulatedSobol) -> Result<ClaimIndices, DeviationsError> {
        let Some(w) = self.matcher.waves.first() else {
            return Ok(Vec::new());
        };
        let input = |p: &[f64]| self.matcher.emulator_input(p);
        w.emulators
            .par_iter()
            .zip(self.outputs())
            .map(|(e, q)| match &e.mean {
                Mean::Gp(g) => Ok((q, emulated_indices(g, self.factors.len(), &input, s)?)),
                Mean::Constant(_) => Ok((q, None)),
            })
            .collect()
    }
}

/// What a history match concluded.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Answer {
    /// Why it ended.
    pub stop: Option<Termination>,
    /// Waves run.
    pub waves: usize,
    /// Non-implausible share of the cube (second-largest implausibility, or the match's rank).
    pub fraction: f64,
    /// Share of the cube where every emulated claim's implausibility is below the cut.
    pub fraction_all: f64,
    /// Points of the pool that measured the shares (an empty pool bounds a share by 3 / pool).
    pub pool: usize,
    /// Runs of the simulator.
    pub runs: usize,
    /// Runs at which every claim evaluated is met.
    pub runs_meeting_all: usize,
    /// Non-implausible points found (the pool's and the searches') with every emulated
    /// claim's implausibility below the cut.
    pub kept_all: usize,
}

impl Answer {
    /// True when no set within the ranges was found consistent with every emulated claim: no
    /// point of the pool or of the searches has every implausibility below the cut, and no
    /// run meets every claim.
    pub fn none_reproduces(&self) -> bool {
        self.fraction_all == 0.0 && self.kept_all == 0 && self.runs_meeting_all == 0
    }
}

/// The history match of `prototype` over `ranges` on this machine: each wave's runs in
/// parallel (`on_run.tick()` after each), until the match ends.
pub fn history_match(
    prototype: Prototype,
    ranges: &Ranges,
    base: &Device,
    claims: &Claims,
    scope: Scope,
    settings: HistorySettings,
    on_run: &dyn Progress,
) -> Result<HistoryRun, DeviationsError> {
    let mut run = HistoryRun::new(prototype, ranges, scope, claims, settings)?;
    while let Some(design) = run.next_design() {
        let evaluations = design
            .par_iter()
            .map(|p| {
                let e = evaluate_at(prototype, ranges, base, p, claims, scope);
                on_run.tick();
                e
            })
            .collect::<Result<Vec<_>, _>>()?;
        run.add_wave(&design, evaluations)?;
    }
    Ok(run)
}
