//! History matching in waves (Craig et al. 1997; Vernon, Goldstein and Bower 2010): which
//! inputs of an expensive, noisy simulator are consistent with a set of observations, given
//! the emulators' uncertainty, the simulator's own sampling variance and the observations'.
//!
//! Each output `j` has an observation `z_j` with variance `v_obs,j` and, at each wave, an
//! emulator ([`Emulator`]: a [`Gp`] of the output with each run's sampling variance as its
//! nugget, and a model of that sampling variance over the inputs). The implausibility of an
//! input `x` for output `j` is
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
//! The module reads better whole: a wave's design, its emulators, the cut and the pool that
//! measures what is left are one loop over shared state (the runs so far, the waves' emulators,
//! the pool's implausibilities), and each step is written against the others.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::gp::{Gp, GpError, GpSettings, Loo};

/// Variance of the logarithm of a sampling variance estimated from about 30 records (the
/// nugget of the emulator of `ln Var_ensemble`): `Var[ln s^2] ~ 2 / (n - 1)` for a chi-square
/// estimate, 0.07 at 30, rounded up to 0.1 because the jackknife's is larger.
pub const LOG_VARIANCE_NUGGET: f64 = 0.1;

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

/// The emulator of one output's expected value, or the value where it is constant over the
/// runs.
#[derive(Debug, Clone)]
pub enum Mean {
    /// A Gaussian process.
    Gp(Box<Gp>),
    /// The same value at every run (no variance to emulate).
    Constant(f64),
}

/// The model of one output's sampling variance over the inputs.
#[derive(Debug, Clone)]
pub enum SamplingVariance {
    /// A deterministic output.
    None,
    /// The median of the runs' variances (too few runs with a variance to emulate it).
    Constant(f64),
    /// A Gaussian process of its logarithm (stochastic kriging, Ankenman et al. 2010).
    LogGp(Box<Gp>),
}

/// One output's emulator at one wave.
#[derive(Debug, Clone)]
pub struct Emulator {
    /// Its expected value.
    pub mean: Mean,
    /// Its sampling variance.
    pub sampling: SamplingVariance,
}

/// A prediction of one output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Prediction {
    /// Expected value.
    pub mean: f64,
    /// The emulator's variance of it (the process's, the mean's and the fitted nugget).
    pub emulator_var: f64,
    /// The simulator's sampling variance there.
    pub sampling_var: f64,
}

impl Emulator {
    /// Fits the emulator of one output to its runs (inputs, values, sampling variances).
    pub fn fit(x: &[Vec<f64>], y: &[f64], var: &[f64], gp: GpSettings) -> Result<Self, GpError> {
        let mean = if y.iter().all(|v| *v == y[0]) {
            Mean::Constant(y[0])
        } else {
            Mean::Gp(Box::new(Gp::fit(x, y, var, gp)?))
        };
        let with_var: Vec<usize> = (0..y.len()).filter(|&i| var[i] > 0.0).collect();
        let sampling = if with_var.is_empty() {
            SamplingVariance::None
        } else if with_var.len() < x[0].len() + 3 {
            let mut v: Vec<f64> = with_var.iter().map(|&i| var[i]).collect();
            v.sort_by(f64::total_cmp);
            SamplingVariance::Constant(v[v.len() / 2])
        } else {
            let xs: Vec<Vec<f64>> = with_var.iter().map(|&i| x[i].clone()).collect();
            let ln: Vec<f64> = with_var.iter().map(|&i| var[i].ln()).collect();
            let nugget = vec![LOG_VARIANCE_NUGGET; ln.len()];
            SamplingVariance::LogGp(Box::new(Gp::fit(&xs, &ln, &nugget, gp)?))
        };
        Ok(Self { mean, sampling })
    }

    /// The prediction at `x`.
    pub fn predict(&self, x: &[f64]) -> Prediction {
        // The emulator's variance holds its fitted nugget: what the smooth process does not
        // follow (a step where a fold appears) is as unknown at a new input as at a run.
        let (mean, emulator_var) = match &self.mean {
            Mean::Gp(g) => {
                let (m, v) = g.predict(x);
                (m, v + g.nugget_var())
            }
            Mean::Constant(c) => (*c, 0.0),
        };
        let sampling_var = match &self.sampling {
            SamplingVariance::None => 0.0,
            SamplingVariance::Constant(v) => *v,
            SamplingVariance::LogGp(g) => g.mean(x).exp(),
        };
        Prediction {
            mean,
            emulator_var,
            sampling_var,
        }
    }

    /// The leave-one-out predictions of the expected value (empty for a constant).
    pub fn loo(&self) -> &[Loo] {
        match &self.mean {
            Mean::Gp(g) => g.loo(),
            Mean::Constant(_) => &[],
        }
    }
}

/// The implausibility of a prediction against an observation.
pub fn implausibility(p: &Prediction, obs: &Observation) -> f64 {
    (obs.value - p.mean).abs() / (p.emulator_var + p.sampling_var + obs.variance).sqrt()
}

/// The `rank`-th largest of `values` (1: the largest); 0 when there are fewer.
pub fn ranked(values: &[f64], rank: usize) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(|a, b| b.total_cmp(a));
    v.get(rank.saturating_sub(1)).copied().unwrap_or(0.0)
}

/// One wave's emulators.
#[derive(Debug, Clone)]
pub struct Wave {
    /// One per output.
    pub emulators: Vec<Emulator>,
    /// Indices (into all runs) of the runs the emulators were fitted to.
    pub training: Vec<usize>,
}

impl Wave {
    /// The implausibility of every output at `x`, the input as the emulators see it
    /// ([`HistoryMatch::emulator_input`]).
    pub fn implausibilities(&self, obs: &[Observation], x: &[f64]) -> Vec<f64> {
        self.emulators
            .iter()
            .zip(obs)
            .map(|(e, o)| implausibility(&e.predict(x), o))
            .collect()
    }
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

impl HistoryMatch {
    /// A non-implausible point found by minimising the statistic from `x0` (at most 400
    /// Nelder-Mead iterations inside the cube), if any.
    fn descend(&self, x0: &[f64]) -> Option<Vec<f64>> {
        let cost = |x: &[f64]| {
            let inside: Vec<f64> = x.iter().map(|u| u.clamp(0.0, 1.0)).collect();
            // Outside the cube: the clamped point's statistic plus the distance, so the
            // simplex turns back.
            let out: f64 = x.iter().map(|u| (u - u.clamp(0.0, 1.0)).abs()).sum();
            (self.statistics(&inside).0 + 10.0 * out, inside)
        };
        let d = x0.len();
        let mut simplex: Vec<(f64, Vec<f64>)> = (0..=d)
            .map(|k| {
                let mut x = x0.to_vec();
                if k > 0 {
                    x[k - 1] += if x[k - 1] < 0.5 { 0.05 } else { -0.05 };
                }
                (cost(&x).0, x)
            })
            .collect();
        for _ in 0..400 {
            simplex.sort_by(|a, b| a.0.total_cmp(&b.0));
            if simplex[0].0 <= self.settings.cut {
                return Some(cost(&simplex[0].1).1);
            }
            let centroid: Vec<f64> = (0..d)
                .map(|j| simplex[..d].iter().map(|s| s.1[j]).sum::<f64>() / d as f64)
                .collect();
            let along = |t: f64| -> Vec<f64> {
                centroid
                    .iter()
                    .zip(&simplex[d].1)
                    .map(|(c, w)| c + t * (w - c))
                    .collect()
            };
            let r = along(-1.0);
            let fr = cost(&r).0;
            if fr < simplex[0].0 {
                let e = along(-2.0);
                let fe = cost(&e).0;
                simplex[d] = if fe < fr { (fe, e) } else { (fr, r) };
            } else if fr < simplex[d - 1].0 {
                simplex[d] = (fr, r);
            } else {
                let c = along(0.5);
                let fc = cost(&c).0;
                if fc < simplex[d].0 {
                    simplex[d] = (fc, c);
                } else {
                    let best = simplex[0].1.clone();
                    for s in simplex.iter_mut().skip(1) {
                        s.1 =
                            s.1.iter()
                                .zip(&best)
                                .map(|(x, b)| b + 0.5 * (x - b))
                                .collect();
                        s.0 = cost(&s.1).0;
                    }
                }
            }
        }
        simplex.sort_by(|a, b| a.0.total_cmp(&b.0));
        (simplex[0].0 <= self.settings.cut).then(|| cost(&simplex[0].1).1)
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

fn min_distance(points: &[Vec<f64>]) -> f64 {
    let mut best = f64::INFINITY;
    for (a, p) in points.iter().enumerate() {
        for q in &points[a + 1..] {
            best = best.min(p.iter().zip(q).map(|(x, y)| (x - y).powi(2)).sum::<f64>());
        }
    }
    best.sqrt()
}

/// The Latin hypercube of `n` points over `dim` inputs with the largest least distance
/// between its points, among 100 random ones.
pub fn maximin_lhs(n: usize, dim: usize, rng: &mut ChaCha8Rng) -> Vec<Vec<f64>> {
    let mut best: Option<(f64, Vec<Vec<f64>>)> = None;
    for _ in 0..100 {
        let mut pts = vec![vec![0.0; dim]; n];
        for d in 0..dim {
            let mut perm: Vec<usize> = (0..n).collect();
            for k in (1..n).rev() {
                perm.swap(k, rng.random_range(0..=k));
            }
            for (p, s) in pts.iter_mut().zip(perm) {
                p[d] = (s as f64 + rng.random::<f64>()) / n as f64;
            }
        }
        let m = min_distance(&pts);
        if best.as_ref().is_none_or(|b| m > b.0) {
            best = Some((m, pts));
        }
    }
    best.map(|b| b.1).unwrap_or_default()
}

/// `n` of `points` chosen greedily to spread them: the first point, then each time the point
/// farthest from those chosen (all of them when there are at most `n`).
pub fn maximin_subset(points: &[Vec<f64>], n: usize) -> Vec<Vec<f64>> {
    if points.len() <= n {
        return points.to_vec();
    }
    let d2 = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>();
    let mut chosen = vec![0usize];
    let mut near: Vec<f64> = points.iter().map(|p| d2(p, &points[0])).collect();
    while chosen.len() < n {
        let (k, _) = near
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .expect("points");
        chosen.push(k);
        for (m, p) in points.iter().enumerate() {
            near[m] = near[m].min(d2(p, &points[k]));
        }
    }
    chosen.into_iter().map(|k| points[k].clone()).collect()
}
