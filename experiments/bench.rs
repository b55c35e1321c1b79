//! `bench`: how fast the model runs, on fixed cases. Speed is measured here, never
//! asserted by a test.
//!
//! Usage: `cargo run --release --bin bench [-- --quick | --interfaces]` (`just bench` runs the
//! whole benchmark; `reproduce` runs `--quick`, which keeps its last phase short;
//! `--interfaces` measures the records behind an interface circuit alone and prints their
//! table, writing nothing).
//!
//! * a 10 s prototype-1 record at Sa = 2.85e-2 g^2/Hz (heavy impacts; calibrated set, whose
//!   stops are closer, and published set), and a 10 s prototype-2 record at 1.69e-3;
//! * a steady impacting sine of prototype 1 (calibrated, 5.5 g at 1300 Hz): the share of
//!   integrator steps spent in contact;
//! * every example device of `data/examples/` (`bench/examples.rs`): its 10 s record, one
//!   periodic orbit and (not with `--quick`) its whole response over its file's range, with
//!   the ratio to a fixed-step RK4 at equal accuracy and to ngspice where it exports;
//! * the bistable example's 10 s record beside its linear twin's, paired;
//! * not with `--quick`: a full Figure 8 sweep (every curve of the published set, one thread
//!   and all threads), Figure 13's whole curve by continuation and by sweeps, the paper
//!   records against RK4, and the untimed accuracy tables (`bench/accuracy.rs`;
//!   `tests/record_accuracy.rs` asserts what they show).
//!
//! Each timed case runs [`REPEATS`] times (once with `--quick`); the tables give the median
//! processor time (user and system, of every thread) beside the median and fastest wall time:
//! on a machine shared with other work the processor time is the steadier of the two. Results
//! go to `data/results/bench/` and the book's Performance page.

use endstop_experiments as common;

use std::time::Instant;

use anyhow::{bail, Result};
use common::{fmt_sig, Experiment};
use endstop::drive::Sine;
use endstop::ode::Stats;
use endstop::paper::setups::paper_record;
use endstop::physics::contact::Mode;
use endstop::physics::harvester::Harvester;
use endstop::progress::Silent;
use endstop::study::flow::SineFlow;
use endstop::study::record::{simulate_record, RecordError};
use endstop::study::rk4_record::{
    simulate_rk4_record, RK4_STEPS_AT_OUR_ACCURACY, RK4_STEPS_AT_TARGET,
};
use polars::prelude::*;

#[path = "bench/accuracy.rs"]
mod accuracy;
#[path = "bench/examples.rs"]
mod examples;
#[path = "bench/interfaces.rs"]
mod interfaces;

/// Runs of each timed case (one with `--quick`).
pub const REPEATS: usize = 5;
/// Runs of each scheme in the side-by-side comparison with RK4.
const RK4_REPEATS: usize = 3;
/// Seed of every record.
pub const SEED: u64 = 2012;
/// The accuracy asked of a record: its power within this of a tight-tolerance run, and its
/// energy balance closed to this, relatively (`tests/record_accuracy.rs`).
const ACCURACY_TARGET: f64 = 1e-6;

fn main() {
    common::run_main("bench", run);
}

/// The wall and processor times of `repeats` runs of `f`, each sorted, with the last result.
fn timed<T>(repeats: usize, mut f: impl FnMut() -> Result<T>) -> Result<(T, Times)> {
    let (mut wall, mut cpu) = (Vec::new(), Vec::new());
    let mut last = None;
    for _ in 0..repeats.max(1) {
        let (t, c) = (Instant::now(), common::cpu_time_s());
        last = Some(f()?);
        wall.push(t.elapsed().as_secs_f64());
        cpu.push(common::cpu_time_s().zip(c).map_or(f64::NAN, |(b, a)| b - a));
    }
    wall.sort_by(f64::total_cmp);
    cpu.sort_by(f64::total_cmp);
    Ok((last.expect("at least one run"), Times { wall, cpu }))
}

/// Three significant digits, or a dash where there is no number (a run without its
/// processor time).
fn sig_or_dash(x: f64) -> String {
    if x.is_finite() {
        fmt_sig(x, 3)
    } else {
        "-".to_string()
    }
}

/// Sorted wall and processor times of repeated runs (s).
struct Times {
    wall: Vec<f64>,
    cpu: Vec<f64>,
}

impl Times {
    fn median_wall(&self) -> f64 {
        self.wall[self.wall.len() / 2]
    }
    fn median_cpu(&self) -> f64 {
        self.cpu[self.cpu.len() / 2]
    }
    fn fastest_wall(&self) -> f64 {
        self.wall[0]
    }
}

struct Row {
    case: String,
    times: Times,
    simulated_s: f64,
    /// The integrator's counters of one run.
    stats: Stats,
    note: String,
}

fn run() -> Result<()> {
    let mut quick = false;
    for a in std::env::args().skip(1) {
        match a.as_str() {
            "--quick" => quick = true,
            "--interfaces" => {
                print!(
                    "{}",
                    interfaces::table(&interfaces::measure(REPEATS)?, REPEATS)
                );
                return Ok(());
            }
            other => bail!("unknown argument `{other}`; usage: bench [--quick | --interfaces]"),
        }
    }
    let repeats = if quick { 1 } else { REPEATS };
    let mut exp = Experiment::start("bench");
    exp.seed = Some(SEED);
    let p1 = exp.load_published("prototype1")?;
    let p2 = exp.load_published("prototype2")?;
    let cal = common::calibrated_prototype1(&p1)?.0.device;
    let mut rows = Vec::new();

    // (case, the key its summary numbers start with, device, Sa).
    let records = [
        (
            "P1 calibrated, 10 s record, Sa = 2.85e-2",
            "p1_record_calibrated",
            cal.clone(),
            2.85e-2,
        ),
        (
            "P1 published, 10 s record, Sa = 2.85e-2",
            "p1_record_published",
            p1.device.clone(),
            2.85e-2,
        ),
        (
            "P2 published, 10 s record, Sa = 1.69e-3",
            "p2_record",
            p2.device.clone(),
            1.69e-3,
        ),
    ];
    for (case, key, dev, sa) in records.clone() {
        let spec = paper_record(&dev, sa);
        let (rec, times) = timed(repeats, || Ok(simulate_record(&dev, &spec, SEED, 0)?))?;
        let sim = spec.transient_s + spec.noise.duration_s;
        let s = rec.summary;
        exp.number(&format!("{key}_median_s"), times.median_cpu());
        rows.push(Row {
            case: case.to_string(),
            times,
            simulated_s: sim,
            stats: s.stats,
            note: format!(
                "{} impacts, {} % of time in contact",
                s.impacts,
                fmt_sig(100.0 * s.contact_fraction, 3)
            ),
        });
    }
    // Steady impacting sine: how much of the work is spent in contact.
    let h = Harvester::new(&cal, Sine::from_rms_g(5.5, 1300.0));
    let t_end = 200.0 / 1300.0;
    let ((contact_steps, free_steps, stats), times) = timed(repeats, || {
        let mut ode = SineFlow::new(&h, 0.0, h.rest_state(), Mode::Free, 1e-8);
        let (mut c, mut f) = (0u64, 0u64);
        ode.integrate(t_end, |_, m| if m.in_contact() { c += 1 } else { f += 1 })?;
        Ok((c, f, ode.stats()))
    })?;
    let share = contact_steps as f64 / (contact_steps + free_steps) as f64;
    rows.push(Row {
        case: "P1 calibrated, sine 5.5 g at 1300 Hz, 200 periods".into(),
        times,
        simulated_s: t_end,
        stats,
        note: format!(
            "{} % of accepted steps are in contact",
            fmt_sig(100.0 * share, 3)
        ),
    });
    exp.number("contact_step_share_sine_p1", share);

    // A bistable example against its linear twin of the same well frequency, paired (wall
    // times: the pairs alternate in this process).
    let bistable = common::load_device("examples/bistable_stops_em")?;
    exp.uses(&bistable, "hypothetical");
    let pc = common::reports::springs_io::paired_record_cost(&bistable.device, 3e-4, repeats)?;
    exp.number("bistable_record_cost_ratio_median", pc.ratios[repeats / 2]);
    for (case, t, path) in [
        (
            "bistable_stops_em, 10 s record, Sa = 3e-4",
            &pc.nonlinear_s,
            &pc.paths.0,
        ),
        (
            "its linear twin (same well frequency), Sa = 3e-4",
            &pc.linear_s,
            &pc.paths.1,
        ),
    ] {
        rows.push(Row {
            case: case.to_string(),
            times: Times {
                wall: t.clone(),
                cpu: vec![f64::NAN; t.len()],
            },
            simulated_s: paper_record(&bistable.device, 3e-4).transient_s + 10.0,
            stats: pc.summary.stats,
            note: format!(
                "paired runs, wall times only, median cost ratio bistable/linear {} (range {} \
                 to {}); free flight: {path}",
                fmt_sig(pc.ratios[repeats / 2], 3),
                fmt_sig(pc.ratios[0], 3),
                fmt_sig(pc.ratios[repeats - 1], 3)
            ),
        });
    }

    if !quick {
        rows.extend(fig08_rows(&mut exp, &p1.device, repeats)?);
        rows.extend(response_rows(&p2.device, repeats)?);
    }

    let mut md = format!(
        "Machine: {} logical cores (RAYON_NUM_THREADS unset unless stated). Each case ran \
         {repeats} time(s){}. Processor time is user plus system time of every thread.\n\n\
         | case | median processor time (s) | median wall (s) | fastest wall (s) | simulated s per processor s | steps per simulated s | rejected steps (after an event) | RHS evals per simulated s | events | notes |\n|---|---|---|---|---|---|---|---|---|---|\n",
        std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1),
        if quick {
            " (`bench --quick`, as `reproduce` runs it; `just bench` adds the sweeps, the \
             continuation, the comparisons with RK4 and ngspice and the accuracy tables)"
        } else {
            ""
        }
    );
    for r in &rows {
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} ({}) | {} | {} | {} |\n",
            r.case,
            sig_or_dash(r.times.median_cpu()),
            fmt_sig(r.times.median_wall(), 3),
            fmt_sig(r.times.fastest_wall(), 3),
            sig_or_dash(r.simulated_s / r.times.median_cpu()),
            fmt_sig(r.stats.steps() as f64 / r.simulated_s, 3),
            r.stats.rejected,
            r.stats.rejected_after_event,
            fmt_sig(r.stats.rhs_evals as f64 / r.simulated_s, 3),
            r.stats.events,
            r.note
        ));
    }
    exp.write_numbers_md(&md)?;
    print!("{md}");
    // The comparison with RK4 and the accuracy tables: only the whole benchmark measures
    // them. `--quick` keeps the last whole run's tables (they name their commit), or says
    // how to make them where there are none.
    let full_md = common::book_generated_root().join("bench").join("full.md");
    if !quick {
        let md = format!(
            "*Measured by the whole benchmark (`just bench`) at commit `{}`.*\n{}",
            common::git_commit(),
            paper_rk4_and_accuracy(&mut exp, &records, &p1, &p2)?
        );
        common::write_atomic(&full_md, md.as_bytes())?;
        print!("{md}");
    } else if !full_md.exists() {
        common::write_atomic(
            &full_md,
            b"*Not measured in this build: `just bench` (the whole benchmark, about a minute \
              on 2 cores) writes the comparison with RK4 and the accuracy tables here; \
              `reproduce` runs `bench --quick`.*\n",
        )?;
    }
    // Records behind an interface circuit against the resistive load: only the whole
    // benchmark measures them, in alternated rounds.
    let interfaces_md = common::book_generated_root()
        .join("bench")
        .join("interfaces.md");
    if !quick {
        let costs = interfaces::measure(repeats)?;
        for c in &costs.interfaces {
            let key = c.name.split(' ').next().unwrap_or(c.name);
            exp.number(
                &format!("interface_record_cost_ratio_median_{key}"),
                c.ratios.0,
            );
        }
        let md = interfaces::table(&costs, repeats);
        common::write_atomic(&interfaces_md, md.as_bytes())?;
        print!("{md}");
    } else if !interfaces_md.exists() {
        common::write_atomic(
            &interfaces_md,
            b"*Not measured in this build: `just bench` (the whole benchmark) writes the \
              paired cost of records behind an interface here; `reproduce` runs `bench \
              --quick`.*\n",
        )?;
    }

    // Every example device.
    let costs = examples::measure(&common::root(), repeats, quick)?;
    let examples_md = examples::table(&costs, repeats, quick);
    for c in &costs {
        exp.number(&format!("{}_record_s", c.name), c.record.0);
        exp.number(&format!("{}_orbit_s", c.name), c.orbit);
        if let Some(r) = c.response {
            exp.number(&format!("{}_response_s", c.name), r);
        }
    }
    common::write_atomic(
        &common::book_generated_root()
            .join("bench")
            .join("examples.md"),
        examples_md.as_bytes(),
    )?;
    print!("{examples_md}");

    let mut df = df!(
        "case" => rows.iter().map(|r| r.case.clone()).collect::<Vec<_>>(),
        "median_cpu_s" => rows.iter().map(|r| r.times.median_cpu()).collect::<Vec<_>>(),
        "median_wall_s" => rows.iter().map(|r| r.times.median_wall()).collect::<Vec<_>>(),
        "min_wall_s" => rows.iter().map(|r| r.times.fastest_wall()).collect::<Vec<_>>(),
        "simulated_s" => rows.iter().map(|r| r.simulated_s).collect::<Vec<_>>(),
        "steps" => rows.iter().map(|r| r.stats.steps()).collect::<Vec<_>>(),
        "rejected_steps" => rows.iter().map(|r| r.stats.rejected).collect::<Vec<_>>(),
        "rejected_after_event" => rows.iter().map(|r| r.stats.rejected_after_event).collect::<Vec<_>>(),
        "rhs_evals" => rows.iter().map(|r| r.stats.rhs_evals).collect::<Vec<_>>(),
        "events" => rows.iter().map(|r| r.stats.events).collect::<Vec<_>>(),
        "params" => vec!["published+calibrated"; rows.len()],
    )?;
    exp.write_parquet("bench", &mut df, "published+calibrated")?;
    let mut df = df!(
        "device" => costs.iter().map(|c| c.name.clone()).collect::<Vec<_>>(),
        "record_cpu_s" => costs.iter().map(|c| c.record.0).collect::<Vec<_>>(),
        "orbit_cpu_s" => costs.iter().map(|c| c.orbit).collect::<Vec<_>>(),
        "response_cpu_s" => costs.iter().map(|c| c.response).collect::<Vec<_>>(),
        "params" => vec!["example"; costs.len()],
    )?;
    exp.write_parquet("examples", &mut df, "example")?;
    exp.finish()
}

/// The paper records against RK4 and the untimed accuracy tables (Markdown), with their
/// summary numbers.
fn paper_rk4_and_accuracy(
    exp: &mut Experiment,
    records: &[(&str, &str, endstop::device::Device, f64); 3],
    p1: &common::LoadedDevice,
    p2: &common::LoadedDevice,
) -> Result<String> {
    // The RK4 yardstick at the target accuracy and at our measured accuracy.
    // (RK4 steps per sample, the end of its summary key).
    let picks = [
        (RK4_STEPS_AT_TARGET, "target"),
        (RK4_STEPS_AT_OUR_ACCURACY, "equal"),
    ];
    let accuracy_md = accuracy::rk4_accuracy(&p1.device, &p2.device)?;
    let mut ratios = Vec::new();
    for (case, key, dev, sa) in records.iter().cloned() {
        for (substeps, pick) in picks {
            let spec = paper_record(&dev, sa);
            let mut ours = Vec::new();
            let mut rk4 = Vec::new();
            // RK4 with too few steps through a stiff contact diverges: the failure is
            // reported instead of a time.
            let mut failure = None;
            // Side by side, alternating, so that a change of the machine's speed hits both.
            for _ in 0..RK4_REPEATS {
                ours.push(
                    timed(1, || Ok(simulate_record(&dev, &spec, SEED, 0)?))?
                        .1
                        .cpu[0],
                );
                if failure.is_none() {
                    match timed(1, || {
                        Ok(simulate_rk4_record(&dev, &spec, SEED, 0, substeps)?)
                    }) {
                        Ok((_, t)) => rk4.push(t.cpu[0]),
                        Err(e) => {
                            failure = Some(match e.downcast_ref::<RecordError>() {
                                Some(b) => divergence(b),
                                None => e.to_string(),
                            })
                        }
                    }
                }
            }
            ours.sort_by(f64::total_cmp);
            rk4.sort_by(f64::total_cmp);
            let a = ours[RK4_REPEATS / 2];
            let b = match failure {
                None => Ok(rk4[RK4_REPEATS / 2]),
                Some(e) => Err(e),
            };
            ratios.push((case, format!("{key}_over_rk4_{pick}"), substeps, a, b));
        }
    }
    let mut md = format!(
        "\n**Against a fixed-step RK4 at equal accuracy.** The yardstick \
         (`study::rk4_record`) is the classical RK4, driven by the same Runge-Kutta engine as \
         Dormand-Prince, with a fixed number of steps per 10 us sample interval and contacts \
         located by the Illinois root finder on shortened RK4 steps. \
         Accuracy: the power of impact-free 1 s records against Dormand-Prince everywhere at \
         rtol 1e-10 (relative error):\n\n{accuracy_md}\n\
         RK4 meets the {ACCURACY_TARGET:e} target with {} step(s) per sample, and reaches our accuracy (below \
         1e-8, where the reference's own error is of the same size) with {} (the fewest of 1, 2, \
         4 and 8; `tests/record_accuracy.rs` asserts both). With impacts, too few steps per \
         sample diverge in the contacts (a prototype 1 contact at 2.85e-2 lasts about half a \
         sample interval); the table then gives the integrator's error instead of a time. \
         Median processor times of {RK4_REPEATS} runs of each, alternating in the same process:\n\n\
         | case | RK4 steps per sample | ours (s) | RK4 (s) | ours / RK4 |\n|---|---|---|---|---|\n",
        RK4_STEPS_AT_TARGET,
        RK4_STEPS_AT_OUR_ACCURACY
    );
    for (case, _, substeps, a, b) in &ratios {
        let (rk4, ratio) = match b {
            Ok(b) => (fmt_sig(*b, 3), fmt_sig(a / b, 3)),
            Err(e) => (e.clone(), "-".to_string()),
        };
        md.push_str(&format!(
            "| {case} | {substeps} | {} | {rk4} | {ratio} |\n",
            fmt_sig(*a, 3),
        ));
    }
    for (substeps, pick) in picks {
        exp.number(&format!("rk4_substeps_{pick}"), substeps as f64);
    }
    // Ratios of the timed pairs only (a diverged RK4 run has none).
    for (_, key, _, a, b) in &ratios {
        if let Ok(b) = b {
            exp.number(key, a / b);
        }
    }
    let (impact_md, impact) = accuracy::impact_accuracy(&p1.device, &p2.device)?;
    md.push_str(&format!(
        "\n**A record's power with impacts.** One 10 s record (stream 0) of each figure's \
         setup, by our scheme (rtol {:e} in and near contacts) and by Dormand-Prince \
         everywhere:\n\n{impact_md}\n",
        endstop::study::record::DEFAULT_RTOL
    ));
    for (key, rel) in impact {
        exp.number(&key, rel);
    }
    let (ledger_md, ledger) = accuracy::energy_balance(&p1.device, &p2.device)?;
    md.push_str(&format!(
        "\n**The energy balance of a record.** The same records and two impact-free ones, \
         with the work of every force booked interval by interval on each scheme's own \
         interpolant (`study::record_ledger`); the residual is relative to the sum of the \
         terms' magnitudes:\n\n{ledger_md}\n"
    ));
    for (key, r) in ledger {
        exp.number(&format!("energy_residual_{key}"), r);
    }
    Ok(md)
}

/// A full Figure 8 sweep (every curve of the published set), on one thread and on all, with
/// its summary numbers (the processor time on one thread, the wall time on all).
fn fig08_rows(
    exp: &mut Experiment,
    p1: &endstop::device::Device,
    repeats: usize,
) -> Result<Vec<Row>> {
    let settings = endstop::paper::figures::fig08::sweep_settings(p1);
    let curves = endstop::paper::figures::fig08::Fig8Curve::ALL
        .map(endstop::paper::figures::fig08::Fig8Curve::spec);
    let mut rows = Vec::new();
    for (label, threads) in [("1 thread", 1usize), ("all threads", 0)] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()?;
        let (res, times) = timed(repeats, || {
            pool.install(|| {
                Ok(endstop::paper::curves::run_curves(
                    p1,
                    &curves,
                    &settings,
                    &|| {},
                )?)
            })
        })?;
        let (mut stats, mut periods) = (Stats::default(), 0.0);
        for c in &res {
            stats += c.report.sweep.stats;
            for s in &c.report.sweep.steps {
                periods += (s.measurement.blocks + settings.cfg.settle_blocks) as f64
                    * settings.cfg.block_periods as f64
                    / s.measurement.freq_hz;
            }
        }
        if threads == 1 {
            exp.number("fig08_sweeps_1thread_median_s", times.median_cpu());
        } else {
            exp.number("fig08_sweeps_all_threads_median_s", times.median_wall());
        }
        rows.push(Row {
            case: format!(
                "Figure 8 sweeps, published set, {} curves, {label}",
                curves.len()
            ),
            times,
            simulated_s: periods,
            stats,
            note: "coarse sweeps only (refinements excluded from the counts)".into(),
        });
    }
    Ok(rows)
}

/// A failed RK4 record as a table cell: where its state left the admissible range, or the
/// error's text.
fn divergence(e: &RecordError) -> String {
    use endstop::ode::SolverError;
    match e {
        RecordError::Solver(SolverError::NonFinite { t, .. }) => {
            format!("diverges (non-finite state at t = {t:.3e} s)")
        }
        RecordError::Solver(SolverError::InvalidState { t, .. }) => {
            format!("diverges (inadmissible state at t = {t:.3e} s)")
        }
        other => format!("fails ({other})"),
    }
}

/// The whole Figure 13 curve (prototype 2, 0.31 g, linear law): the continuation of the
/// periodic orbits with their stability over 600-850 Hz, beside the stepped up- and
/// down-sweeps of the same curve, each on one thread.
fn response_rows(p2: &endstop::device::Device, repeats: usize) -> Result<Vec<Row>> {
    use endstop::paper::response::{continuation, setups, Case};
    let setup = setups(p2, p2, p2)
        .into_iter()
        .find(|s| s.case == Case::Fig13P2)
        .expect("the Figure 13 case");
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let span = setup.continuation.stop - setup.continuation.start;
    let (branch, times) = timed(repeats, || pool.install(|| Ok(continuation(&setup)?)))?;
    let mut rows = vec![Row {
        case: "Figure 13 whole curve by continuation (both branches, multipliers), 1 thread".into(),
        times,
        simulated_s: span,
        stats: branch.stats,
        note: format!(
            "{} orbits, {} events; 'simulated s' is the frequency span in Hz",
            branch.points.len(),
            branch.events.len()
        ),
    }];
    for (dir, down) in [("up", false), ("down", true)] {
        let (stats, times) = timed(repeats, || {
            pool.install(|| {
                Ok(if down {
                    setup
                        .sweep
                        .run_down(&setup.device, setup.accel_rms_g, &Silent)?
                        .total_stats()
                } else {
                    setup
                        .sweep
                        .run(&setup.device, setup.accel_rms_g, &Silent)?
                        .total_stats()
                })
            })
        })?;
        rows.push(Row {
            case: format!("Figure 13 stepped {dir}-sweep of the same curve, 1 thread"),
            times,
            simulated_s: span,
            stats,
            note: "with refinements; 'simulated s' is the frequency span in Hz".into(),
        });
    }
    Ok(rows)
}
