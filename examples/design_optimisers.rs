//! The design search against CMA-ES: on the design checks' three two-variable problems (the
//! cantilever's load and stopper gap, the bridge's load and tuning, and the electromagnetic
//! harvester of `em_asymmetric`, on which no search setting was chosen), how many evaluations
//! and how much wall time each optimiser takes to reach a feasible design within 1 % of the
//! best of a brute-force 31 x 31 grid, over several seeds (the kept search's Sobol scramble,
//! CMA-ES's sampling seed).
//!
//! Both optimisers see the same objective: the kept search's score on the unit cube of the
//! ranges (feasible designs by power ahead of every infeasible one, by its violation), a point
//! outside the cube evaluated at its clamp with the distance outside added. CMA-ES (the
//! `cmaes` crate, N. Hansen's algorithm with its default population, 6 in two dimensions)
//! starts at the cube's centre with a step of 0.3, a third of the range, and runs to its own
//! termination (the crate's default tolerances) or to as many evaluations as the kept search's
//! whole budget; the kept search runs to its end. Neither is told the target: it only marks
//! when each run reached it. Evaluations are counted in the order they complete (both
//! evaluate in parallel: the sample and the two polishes, CMA-ES's population).
//!
//! Usage: `cargo run --release --example design_optimisers -- [SEEDS]` (15 by default); prints
//! CSV, one row per case, optimiser and seed, for `data/recorded/design-optimisers/runs.csv`.

use std::sync::Mutex;
use std::time::Instant;

use cmaes::{CMAESOptions, DVector};
use endstop::design::search::{score, search};
use endstop::design::{Evaluated, Limits, Problem, SearchSettings, Vibration, LOAD_PATH};
use endstop::device::{Device, ParamRange, Spacing};

/// The grid's points per range (the design checks' grid).
const GRID_N: usize = 31;
/// The target: a feasible design of at least this fraction of the grid's best power.
const TARGET: f64 = 0.99;
/// CMA-ES's initial step, in unit-cube coordinates.
const CMAES_STEP: f64 = 0.3;
/// The score CMA-ES sees for a design that could not be evaluated (the kept search's score is
/// infinite there, which CMA-ES refuses); above every infeasible design's `1 + violation` of
/// the problems here.
const UNEVALUATED_SCORE: f64 = 1e6;

fn device(name: &str) -> Result<Device, Box<dyn std::error::Error>> {
    let path = format!("{}/data/examples/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path)?;
    Ok(Device::from_toml_str(
        &text,
        &format!("data/examples/{name}.toml"),
    )?)
}

fn range(path: &str, lo: f64, hi: f64) -> Result<ParamRange, Box<dyn std::error::Error>> {
    Ok(ParamRange::new(path, lo, hi, Spacing::auto(lo, hi))?)
}

fn problem(
    device: Device,
    ranges: Vec<ParamRange>,
    freqs_hz: Vec<f64>,
    g: f64,
    limits: Limits,
) -> Result<Problem, Box<dyn std::error::Error>> {
    let interfaces = vec![device.interface.clone()];
    let vibration = Vibration {
        freqs_hz,
        accel_rms_g: g,
    };
    Ok(Problem::new(device, interfaces, ranges, vibration, limits)?)
}

/// The three problems of the design checks, named.
fn cases() -> Result<Vec<(&'static str, Problem)>, Box<dyn std::error::Error>> {
    let gap = problem(
        device("piezo_cantilever")?,
        vec![
            range(LOAD_PATH, 3e3, 3e5)?,
            range("stops.upper.gap_m", 0.03e-3, 0.3e-3)?,
        ],
        vec![120.0],
        0.3,
        Limits {
            impact_speed_m_s: Some(0.08),
            ..Limits::default()
        },
    )?;
    let tuning = problem(
        device("piezo_bridge")?,
        vec![
            range(LOAD_PATH, 5e3, 5e5)?,
            range("mechanics.stiffness_n_per_m", 2400.0, 3300.0)?,
        ],
        vec![118.0, 122.0],
        0.05,
        Limits::default(),
    )?;
    let em = problem(
        device("em_asymmetric")?,
        vec![
            range(LOAD_PATH, 40.0, 4000.0)?,
            range("stops.upper.gap_m", 0.6e-3, 2.0e-3)?,
        ],
        vec![50.0],
        0.2,
        Limits {
            contact_force_n: Some(0.02),
            ..Limits::default()
        },
    )?;
    Ok(vec![
        ("cantilever_load_gap", gap),
        ("bridge_load_tuning", tuning),
        ("em_asymmetric_load_gap", em),
    ])
}

/// The evaluations of one run in the order they complete: the wall time since the run's
/// start (s) and the design's power if it is feasible.
struct Log {
    start: Instant,
    done: Mutex<Vec<(f64, Option<f64>)>>,
}

impl Log {
    fn new() -> Self {
        Self {
            start: Instant::now(),
            done: Mutex::new(Vec::new()),
        }
    }

    fn push(&self, e: &Evaluated) {
        let t = self.start.elapsed().as_secs_f64();
        let p = e.feasible().then(|| e.power_w());
        if let Ok(mut d) = self.done.lock() {
            d.push((t, p));
        }
    }

    /// The evaluations and wall time to the first feasible design of at least `target_w`, the
    /// evaluations and time in all, and the best feasible power.
    fn summary(&self, target_w: f64) -> (Option<(usize, f64)>, usize, f64, f64) {
        let d = self.done.lock().map(|d| d.clone()).unwrap_or_default();
        let reached = d
            .iter()
            .position(|(_, p)| p.is_some_and(|p| p >= target_w))
            .map(|k| (k + 1, d[k].0));
        let best = d.iter().filter_map(|(_, p)| *p).fold(f64::NAN, f64::max);
        (reached, d.len(), d.last().map_or(0.0, |x| x.0), best)
    }
}

/// One CMA-ES run on `p` from `seed`, to its own termination or `budget` evaluations.
fn cmaes_run(p: &Problem, seed: u64, budget: usize, p_ref: f64) -> Log {
    let log = Log::new();
    let objective = |x: &DVector<f64>| -> f64 {
        let clamped: Vec<f64> = x.iter().map(|u| u.clamp(0.0, 1.0)).collect();
        let outside: f64 = x.iter().zip(&clamped).map(|(u, c)| (u - c).abs()).sum();
        let e = p.evaluate(0, &clamped);
        log.push(&e);
        let s = score(&e, p_ref);
        (if s.is_finite() { s } else { UNEVALUATED_SCORE }) + outside
    };
    let built = CMAESOptions::new(vec![0.5; p.ranges.len()], CMAES_STEP)
        .seed(seed)
        .max_function_evals(budget)
        .build(objective);
    if let Ok(mut state) = built {
        state.run_parallel();
    }
    log
}

fn row(case: &str, optimiser: &str, seed: u64, grid_w: f64, log: &Log) {
    let (reached, n, t, best) = log.summary(TARGET * grid_w);
    let (rn, rt) = reached.map_or(("".to_string(), "".to_string()), |(k, s)| {
        (k.to_string(), format!("{s:.3}"))
    });
    println!("{case},{optimiser},{seed},{rn},{rt},{n},{t:.3},{best:.6e},{grid_w:.6e}");
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let seeds: u64 = match std::env::args().nth(1) {
        Some(s) => s.parse()?,
        None => 15,
    };
    let settings = SearchSettings::default();
    println!(
        "case,optimiser,seed,evals_to_target,wall_s_to_target,evals,wall_s,best_feasible_w,grid_best_w"
    );
    for (name, p) in cases()? {
        let grid = p.grid(0, 0, 1, GRID_N, &[0.5, 0.5]);
        let grid_w = grid
            .iter()
            .filter(|e| e.feasible())
            .map(Evaluated::power_w)
            .fold(f64::NAN, f64::max);
        if !grid_w.is_finite() {
            return Err(format!("{name}: no feasible grid point").into());
        }
        let budget = settings.budget(1, p.ranges.len());
        for seed in 0..seeds {
            let log = Log::new();
            let s = SearchSettings {
                seed: seed as u32,
                ..settings
            };
            search(
                p.ranges.len(),
                |u: &[f64]| {
                    let e = p.evaluate(0, u);
                    log.push(&e);
                    e
                },
                &s,
            )?;
            row(name, "sobol_nelder_mead", seed, grid_w, &log);
        }
        // CMA-ES ranks its population, so the score's scale does not change its steps: the
        // grid's best serves as the power scale.
        for seed in 0..seeds {
            let log = cmaes_run(&p, seed + 1, budget, grid_w);
            row(name, "cmaes", seed + 1, grid_w, &log);
        }
    }
    Ok(())
}
