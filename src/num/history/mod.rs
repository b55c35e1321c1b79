//! History matching in waves (Craig et al. 1997; Vernon, Goldstein and Bower 2010): which
//! inputs of an expensive, noisy simulator are consistent with a set of observations, given
//! the emulators' uncertainty, the simulator's own sampling variance and the observations'.
//!
//! Each output `j` has an observation `z_j` with variance `v_obs,j` and, at each wave, an
//! emulator ([`Emulator`]: a [`Gp`](super::gp::Gp) of the output with each run's sampling
//! variance as its nugget, and a model of that sampling variance over the inputs). The
//! implausibility of an input `x` for output `j` is
//!
//! `I_j(x) = |z_j - E[f_j(x)]| / sqrt(Var_emulator,j(x) + Var_ensemble,j(x) + v_obs,j)`,
//!
//! and `x` is ruled out by a wave when the `rank`-th largest `I_j(x)` exceeds the cut (the
//! second-largest at 3 by default: three standard deviations of a unimodal distribution hold at
//! least 95 % of it, Pukelsheim's three-sigma rule, and the second-largest tolerates one
//! emulator that misfits). An input is non-implausible when no wave rules it out. Wave 1 runs a
//! maximin Latin hypercube over the unit cube; each later wave runs a maximin subset of the
//! non-implausible inputs of a uniform pool (topped up around them where the pool holds too
//! few), fits new emulators on every run inside the space so far, and shrinks the space
//! further, until it is empty, stops shrinking, or the waves run out ([`Termination`]).
//!
//! The non-implausible fraction is measured on a scrambled Sobol pool of the whole cube: an
//! empty pool of `P` points puts the fraction below `3 / P` (95 %). Before the space is called
//! empty the implausibility is also minimised (Nelder-Mead on the emulators, written here in a
//! few lines: the statistic is a cheap closure over the waves, and argmin's solver would need
//! a problem type for it) from the pool's ten least implausible points, so that a thin
//! non-implausible set between the pool's points is not missed. The same pool gives the
//! 2-D projections: per cell of each pair of inputs, the least implausibility over the pool's
//! points there and the share of them that are non-implausible (the optical depth).
//!
//! The loop ([`HistoryMatch`]) reads better whole: a wave's design, its emulators, the cut and
//! the pool that measures what is left are one loop over shared state (the runs so far, the
//! waves' emulators, the pool's implausibilities), and each step is written against the
//! others. What each step calls on is a submodule written against its inputs only: the
//! emulator of one output and its implausibility (`emulator`), the space-filling designs
//! (`design`) and the Nelder-Mead search of the statistic (`descent`).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::gp::{GpError, GpSettings, Loo};

mod descent;
mod design;
mod emulator;

pub use design::{maximin_lhs, maximin_subset};
pub use emulator::{
    implausibility, ranked, Emulator, Mean, Prediction, SamplingVariance, Wave, LOG_VARIANCE_NUGGET,
};

/// One output's observation.
#[derive(Debug, Clone, PartialEq)]
pub struct Observation {
    /// The output's name (for reports).
    pub name: String,
    /// The observed value.
    pub value: f64,
    /// Its variance (measurement and model discrepancy).
    pub variance: f64,
}

/// One run of the simulator: its input and each output's value and sampling variance.
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    /// Input (unit cube).
    pub point: Vec<f64>,
    /// Each output's value.
    pub values: Vec<f64>,
    /// Each output's sampling variance (0 for a deterministic output).
    pub variances: Vec<f64>,
}

/// The settings of a history match.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HistorySettings {
    /// Implausibility cut-off.
    pub cut: f64,
    /// Which largest implausibility is cut (1: the largest, 2: the second-largest, ...).
    pub rank: usize,
    /// Runs per input in each wave's design.
    pub per_input: usize,
    /// Points of the uniform pool that measures the space (a power of two).
    pub pool: usize,
    /// Most waves.
    pub max_waves: usize,
    /// A wave whose non-implausible fraction is more than this share of the previous one's
    /// does not shrink the space: the match stops.
    pub shrink: f64,
    /// Cells per axis of the 2-D projections.
    pub cells: usize,
    /// Seed of the designs and of the pool's scramble.
    pub seed: u32,
    /// The emulators' hyperparameter search.
    pub gp: GpSettings,
}

impl Default for HistorySettings {
    /// Cut 3 on the second-largest, ten runs per input, a pool of 2^14, at most 4 waves,
    /// stop when a wave keeps more than 80 % of the previous space, 10 cells per axis.
    fn default() -> Self {
        Self {
            cut: 3.0,
            rank: 2,
            per_input: 10,
            pool: 1 << 14,
            max_waves: 4,
            shrink: 0.8,
            cells: 10,
            seed: 13,
            gp: GpSettings::default(),
        }
    }
}

/// Why a history match ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Termination {
    /// No point of the pool (nor of the search around the last survivors) is non-implausible.
    Empty,
    /// The last wave kept more than [`HistorySettings::shrink`] of the previous space.
    NotShrinking,
    /// [`HistorySettings::max_waves`] waves ran.
    MaxWaves,
    /// The non-implausible points found (the pool's and the searches' around them) are fewer
    /// than the next wave's emulators need (the input dimension plus 3, for their linear
    /// mean): the space has shrunk below what a design placed in it resolves.
    TooFewRuns,
}

impl Termination {
    /// Label for tables.
    pub fn label(self) -> &'static str {
        match self {
            Termination::Empty => "empty",
            Termination::NotShrinking => "not shrinking",
            Termination::MaxWaves => "last wave",
            Termination::TooFewRuns => "too few runs to emulate",
        }
    }
}

/// Why a history match failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HistoryError {
    /// An emulator could not be fitted.
    #[error("output {output}: {source}")]
    Emulator {
        /// The output's name.
        output: String,
        /// The error.
        source: GpError,
    },
    /// Runs that do not fit the outputs, or settings out of range.
    #[error("history match: {0}")]
    Input(String),
}

/// A 2-D projection of the space onto inputs `(i, j)`: per cell (row-major, `i` slow), the
/// least cut statistic over the pool's points in it and their non-implausible share.
#[derive(Debug, Clone, PartialEq)]
pub struct Projection {
    /// First input.
    pub i: usize,
    /// Second input.
    pub j: usize,
    /// Least statistic per cell (infinite for an empty cell).
    pub min_implausibility: Vec<f64>,
    /// Non-implausible share per cell (NaN for an empty cell).
    pub optical_depth: Vec<f64>,
}

/// What one wave found.
#[derive(Debug, Clone)]
pub struct WaveSummary {
    /// 1-based wave number.
    pub wave: usize,
    /// Runs this wave added.
    pub new_runs: usize,
    /// Runs its emulators were fitted to.
    pub training_runs: usize,
    /// Pool points non-implausible after this wave (the cut on the rank-th largest).
    pub non_implausible: usize,
    /// Pool points with every output's implausibility below the cut at every wave.
    pub all_within_cut: usize,
    /// Pool size.
    pub pool: usize,
    /// Per output: the share of the pool's points non-implausible before this wave whose
    /// implausibility at this wave exceeds the cut.
    pub ruled_out: Vec<f64>,
    /// Per output: the leave-one-out standardised errors of this wave's emulator.
    pub loo: Vec<Vec<f64>>,
    /// The 2-D projections after this wave.
    pub projections: Vec<Projection>,
    /// Non-implausible points (the pool's, and those found around them).
    pub kept: Vec<Vec<f64>>,
    /// How many of `kept` have every output's implausibility below the cut at every wave.
    pub kept_all: usize,
    /// Why the match ended here (`None`: another wave follows).
    pub stop: Option<Termination>,
}

impl WaveSummary {
    /// The non-implausible share of the cube.
    pub fn fraction(&self) -> f64 {
        self.non_implausible as f64 / self.pool as f64
    }

    /// The share of the cube where every output is within the cut.
    pub fn fraction_all(&self) -> f64 {
        self.all_within_cut as f64 / self.pool as f64
    }
}

/// A history match: the observations, the runs so far, the waves' emulators and summaries.
/// [`HistoryMatch::next_design`] gives the inputs to run next and [`HistoryMatch::add_wave`]
/// takes their runs, so the runs can be made anywhere (one machine, a cluster) and the match
/// is the same.
#[derive(Debug, Clone)]
pub struct HistoryMatch {
    /// Input dimension.
    pub dim: usize,
    /// The observations, one per output.
    pub observations: Vec<Observation>,
    /// The settings.
    pub settings: HistorySettings,
    /// Every run so far, in order, with its wave.
    pub runs: Vec<(usize, Run)>,
    /// Each wave's emulators.
    pub waves: Vec<Wave>,
    /// Each wave's summary.
    pub summaries: Vec<WaveSummary>,
    /// Inputs that are switches: the simulator reads only which half of the unit interval
    /// the coordinate lies in, so the emulators see it at the middle of its half (0.25 or
    /// 0.75) and do not smooth a step.
    pub switches: Vec<usize>,
}

impl HistoryMatch {
    /// A match of `dim` inputs against `observations`.
    pub fn new(
        dim: usize,
        observations: Vec<Observation>,
        settings: HistorySettings,
    ) -> Result<Self, HistoryError> {
        if dim == 0 || observations.is_empty() || settings.rank == 0 || settings.per_input == 0 {
            return Err(HistoryError::Input(
                "needs inputs, observations, a rank and runs per input of at least 1".into(),
            ));
        }
        if !settings.pool.is_power_of_two() || settings.pool > 1 << 20 || settings.cells == 0 {
            return Err(HistoryError::Input(format!(
                "pool {} must be a power of two up to 2^20, cells at least 1",
                settings.pool
            )));
        }
        if let Some(o) = observations
            .iter()
            .find(|o| !o.value.is_finite() || o.variance.is_nan() || o.variance <= 0.0)
        {
            return Err(HistoryError::Input(format!(
                "observation {}: value {} and variance {} must be finite, the variance positive",
                o.name, o.value, o.variance
            )));
        }
        Ok(Self {
            dim,
            observations,
            settings,
            runs: Vec::new(),
            waves: Vec::new(),
            summaries: Vec::new(),
            switches: Vec::new(),
        })
    }

    /// The same match with inputs `switches` read as switches ([`HistoryMatch::switches`]).
    pub fn with_switches(mut self, switches: Vec<usize>) -> Self {
        self.switches = switches;
        self
    }

    /// The input as the emulators see it (switches at the middle of their half).
    pub fn emulator_input(&self, x: &[f64]) -> Vec<f64> {
        let mut v = x.to_vec();
        for &s in &self.switches {
            if let Some(u) = v.get_mut(s) {
                *u = if *u < 0.5 { 0.25 } else { 0.75 };
            }
        }
        v
    }

    /// Runs of each wave's design: `per_input` times the dimension.
    pub fn design_size(&self) -> usize {
        self.settings.per_input * self.dim
    }

    /// Whether the match has ended.
    pub fn stopped(&self) -> Option<Termination> {
        self.summaries.last().and_then(|s| s.stop)
    }

    /// The inputs of the next wave: a maximin Latin hypercube for the first, a maximin subset
    /// of the non-implausible points for a later one; `None` once the match has ended.
    pub fn next_design(&self) -> Option<Vec<Vec<f64>>> {
        if self.stopped().is_some() {
            return None;
        }
        let n = self.design_size();
        let mut rng = ChaCha8Rng::seed_from_u64(
            u64::from(self.settings.seed) + 1000 * self.waves.len() as u64,
        );
        Some(match self.summaries.last() {
            None => maximin_lhs(n, self.dim, &mut rng),
            Some(s) => maximin_subset(&s.kept, n),
        })
    }

    /// The rank-th largest implausibility of every wave, and the largest, at `x`: each the
    /// largest over the waves.
    fn statistics(&self, x: &[f64]) -> (f64, f64) {
        let x = self.emulator_input(x);
        self.waves.iter().fold((0.0, 0.0), |(r, m), w| {
            let i = w.implausibilities(&self.observations, &x);
            (r.max(ranked(&i, self.settings.rank)), m.max(ranked(&i, 1)))
        })
    }

    fn check_run(&self, r: &Run) -> Result<(), HistoryError> {
        let m = self.observations.len();
        if r.point.len() != self.dim || r.values.len() != m || r.variances.len() != m {
            return Err(HistoryError::Input(format!(
                "a run has {} inputs, {} values and {} variances, the match {} and {m}",
                r.point.len(),
                r.values.len(),
                r.variances.len(),
                self.dim
            )));
        }
        Ok(())
    }

    /// Adds the runs of the next design, fits the wave's emulators (on every run so far that
    /// is non-implausible under the earlier waves) and measures the space.
    pub fn add_wave(&mut self, runs: Vec<Run>) -> Result<&WaveSummary, HistoryError> {
        if self.stopped().is_some() {
            return Err(HistoryError::Input("the match has ended".into()));
        }
        for r in &runs {
            self.check_run(r)?;
        }
        let wave = self.waves.len() + 1;
        let new_runs = runs.len();
        let before = self.summaries.last().map(|s| s.non_implausible);
        self.runs.extend(runs.into_iter().map(|r| (wave, r)));
        let cut = self.settings.cut;
        let training: Vec<usize> = (0..self.runs.len())
            .filter(|&k| self.statistics(&self.runs[k].1.point).0 <= cut)
            .collect();
        let x: Vec<Vec<f64>> = training
            .iter()
            .map(|&k| self.runs[k].1.point.clone())
            .collect();
        let emulators = (0..self.observations.len())
            .into_par_iter()
            .map(|j| {
                let y: Vec<f64> = training.iter().map(|&k| self.runs[k].1.values[j]).collect();
                let v: Vec<f64> = training
                    .iter()
                    .map(|&k| self.runs[k].1.variances[j])
                    .collect();
                Emulator::fit(&x, &y, &v, self.settings.gp).map_err(|source| {
                    HistoryError::Emulator {
                        output: self.observations[j].name.clone(),
                        source,
                    }
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let loo = emulators
            .iter()
            .map(|e| e.loo().iter().map(Loo::standardised).collect())
            .collect();
        let previous: Vec<(f64, f64)> = self.pool_statistics();
        self.waves.push(Wave {
            emulators,
            training,
        });
        let (summary, kept) = self.measure(&previous);
        let mut summary = WaveSummary {
            wave,
            new_runs,
            training_runs: self.waves[wave - 1].training.len(),
            loo,
            kept,
            ..summary
        };
        summary.stop = if summary.kept.is_empty() {
            Some(Termination::Empty)
        } else if before
            .is_some_and(|b| summary.non_implausible as f64 > self.settings.shrink * b as f64)
        {
            Some(Termination::NotShrinking)
        } else if wave >= self.settings.max_waves {
            Some(Termination::MaxWaves)
        } else if summary.kept.len() < self.dim + 3 {
            Some(Termination::TooFewRuns)
        } else {
            None
        };
        self.summaries.push(summary);
        Ok(self.summaries.last().expect("just pushed"))
    }

    /// The pool: a scrambled Sobol sequence over the cube.
    pub fn pool(&self) -> Vec<Vec<f64>> {
        (0..self.settings.pool)
            .map(|i| {
                (0..self.dim)
                    .map(|d| {
                        f64::from(sobol_burley::sample(
                            i as u32,
                            d as u32,
                            self.settings.seed.wrapping_add(7),
                        ))
                    })
                    .collect()
            })
            .collect()
    }

    fn pool_statistics(&self) -> Vec<(f64, f64)> {
        self.pool().par_iter().map(|x| self.statistics(x)).collect()
    }

    /// The pool measured after the last wave (`previous`: the statistics before it).
    fn measure(&self, previous: &[(f64, f64)]) -> (WaveSummary, Vec<Vec<f64>>) {
        let pool = self.pool();
        let cut = self.settings.cut;
        let last = self.waves.last().expect("a wave");
        let rows: Vec<(f64, f64, Vec<f64>)> = pool
            .par_iter()
            .map(|x| {
                let (r, m) = self.statistics(x);
                (
                    r,
                    m,
                    last.implausibilities(&self.observations, &self.emulator_input(x)),
                )
            })
            .collect();
        let inside_before: Vec<usize> = (0..pool.len()).filter(|&k| previous[k].0 <= cut).collect();
        let ruled_out = (0..self.observations.len())
            .map(|j| {
                let n = inside_before
                    .iter()
                    .filter(|&&k| rows[k].2[j] > cut)
                    .count();
                n as f64 / inside_before.len().max(1) as f64
            })
            .collect();
        let mut kept: Vec<Vec<f64>> = (0..pool.len())
            .filter(|&k| rows[k].0 <= cut)
            .map(|k| pool[k].clone())
            .collect();
        let non_implausible = kept.len();
        let all_within_cut = rows.iter().filter(|r| r.1 <= cut).count();
        let stat: Vec<f64> = rows.iter().map(|r| r.0).collect();
        let projections = projections(&pool, &stat, cut, self.dim, self.settings.cells);
        // No survivor in the pool: a thin non-implausible set can fall between its points, so
        // the statistic is minimised (Nelder-Mead on the emulators, cheap) from the pool's ten
        // least implausible points before the space is called empty.
        if kept.is_empty() {
            let mut order: Vec<usize> = (0..pool.len()).collect();
            order.sort_by(|&a, &b| rows[a].0.total_cmp(&rows[b].0));
            kept.extend(
                order
                    .iter()
                    .take(10)
                    .collect::<Vec<_>>()
                    .par_iter()
                    .filter_map(|&&k| self.descend(&pool[k]))
                    .collect::<Vec<_>>(),
            );
        }
        // Too few survivors for a design: search around them (boxes of a pool cell's width).
        let want = 4 * self.design_size();
        if !kept.is_empty() && kept.len() < want {
            let mut rng = ChaCha8Rng::seed_from_u64(
                u64::from(self.settings.seed) + 77 * self.waves.len() as u64,
            );
            let half = 0.5 / (self.settings.pool as f64).powf(1.0 / self.dim as f64);
            let seeds = kept.clone();
            for _ in 0..50 {
                let tries: Vec<Vec<f64>> = (0..want)
                    .map(|t| {
                        let c = &seeds[t % seeds.len()];
                        c.iter()
                            .map(|u| (u + half * (2.0 * rng.random::<f64>() - 1.0)).clamp(0.0, 1.0))
                            .collect()
                    })
                    .collect();
                kept.extend(
                    tries
                        .into_par_iter()
                        .filter(|x| self.statistics(x).0 <= cut)
                        .collect::<Vec<_>>(),
                );
                if kept.len() >= want {
                    break;
                }
            }
        }
        let kept_all = kept
            .par_iter()
            .filter(|x| self.statistics(x).1 <= cut)
            .count();
        (
            WaveSummary {
                kept_all,
                wave: 0,
                new_runs: 0,
                training_runs: 0,
                non_implausible,
                all_within_cut,
                pool: pool.len(),
                ruled_out,
                loo: Vec::new(),
                projections,
                kept: Vec::new(),
                stop: None,
            },
            kept,
        )
    }
}

/// The projections of `stat` over `pool` on every pair of inputs.
fn projections(
    pool: &[Vec<f64>],
    stat: &[f64],
    cut: f64,
    dim: usize,
    cells: usize,
) -> Vec<Projection> {
    let cell = |u: f64| ((u * cells as f64) as usize).min(cells - 1);
    let mut out = Vec::new();
    for i in 0..dim {
        for j in i + 1..dim {
            let mut min = vec![f64::INFINITY; cells * cells];
            let mut count = vec![0usize; cells * cells];
            let mut inside = vec![0usize; cells * cells];
            for (x, s) in pool.iter().zip(stat) {
                let c = cell(x[i]) * cells + cell(x[j]);
                min[c] = min[c].min(*s);
                count[c] += 1;
                inside[c] += usize::from(*s <= cut);
            }
            let optical_depth = count
                .iter()
                .zip(&inside)
                .map(|(&n, &k)| {
                    if n == 0 {
                        f64::NAN
                    } else {
                        k as f64 / n as f64
                    }
                })
                .collect();
            out.push(Projection {
                i,
                j,
                min_implausibility: min,
                optical_depth,
            });
        }
    }
    out
}
