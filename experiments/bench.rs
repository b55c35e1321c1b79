//! `bench`: how fast the model runs, on fixed cases. Speed is measured here, never
//! asserted by a test.
//!
//! * a 10 s prototype-1 record at Sa = 2.85e-2 g^2/Hz (heavy impacts; calibrated set, whose
//!   stops are closer, and published set);
//! * a 10 s prototype-2 record at Sa = 1.69e-3 g^2/Hz;
//! * a full Figure 8 sweep (every curve of the published set, one thread and all threads);
//! * a steady impacting sine of prototype 1 (calibrated, 5.5 g at 1300 Hz): the share of
//!   integrator steps and right-hand-side evaluations spent in contact.
//!
//! Each case runs `REPEATS` times; the table gives the median and the fastest wall time.
//! Beside them, the accuracy tables of the Performance page (untimed runs of the library;
//! `tests/record_accuracy.rs` asserts what they show). Results go to `data/results/bench/` and
//! the book's Performance page.

use endstop_experiments as common;

use std::time::Instant;

use anyhow::Result;
use common::{fmt_sig, Experiment};
use endstop::drive::Sine;
use endstop::ode::{Dopri5, Stats};
use endstop::paper::setups::paper_record;
use endstop::physics::contact::Mode;
use endstop::physics::harvester::Harvester;
use endstop::study::record::simulate_record;
use endstop::study::record::RecordSpec;
use endstop::study::rk4_record::{
    simulate_rk4_record, RK4_STEPS_AT_OUR_ACCURACY, RK4_STEPS_AT_TARGET,
};
use polars::prelude::*;
use rayon::prelude::*;

const REPEATS: usize = 5;
/// Runs of each scheme in the side-by-side comparison with RK4.
const RK4_REPEATS: usize = 3;
const SEED: u64 = 2012;
/// The accuracy asked of a record: its power within this of a tight-tolerance run, and its
/// energy balance closed to this, relatively (`tests/record_accuracy.rs`).
const ACCURACY_TARGET: f64 = 1e-6;

fn main() {
    common::run_main("bench", run);
}

fn timed<T>(mut f: impl FnMut() -> Result<T>) -> Result<(T, Vec<f64>)> {
    let mut times = Vec::with_capacity(REPEATS);
    let mut last = None;
    for _ in 0..REPEATS {
        let t = Instant::now();
        last = Some(f()?);
        times.push(t.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    Ok((last.expect("REPEATS > 0"), times))
}

struct Row {
    case: String,
    median_s: f64,
    min_s: f64,
    simulated_s: f64,
    /// The integrator's counters of one run.
    stats: Stats,
    note: String,
}

fn run() -> Result<()> {
    let mut exp = Experiment::start("bench");
    exp.seed = Some(SEED);
    let p1 = exp.load_published("prototype1")?;
    let p2 = exp.load_published("prototype2")?;
    let cal = common::calibrated_prototype1(&p1)?.0.device;
    let mut rows = Vec::new();

    let records = [
        (
            "P1 calibrated, 10 s record, Sa = 2.85e-2",
            cal.clone(),
            2.85e-2,
        ),
        (
            "P1 published, 10 s record, Sa = 2.85e-2",
            p1.device.clone(),
            2.85e-2,
        ),
        (
            "P2 published, 10 s record, Sa = 1.69e-3",
            p2.device.clone(),
            1.69e-3,
        ),
    ];
    // The RK4 yardstick at the target accuracy and at our measured accuracy.
    let picks = [RK4_STEPS_AT_TARGET, RK4_STEPS_AT_OUR_ACCURACY];
    let accuracy_md = rk4_accuracy(&p1.device, &p2.device)?;
    let mut ratios = Vec::new();
    for (case, dev, sa) in records.clone() {
        for substeps in picks {
            let spec = paper_record(&dev, sa);
            let mut ours = Vec::new();
            let mut rk4 = Vec::new();
            // RK4 with too few steps through a stiff contact diverges: the failure is
            // reported instead of a time.
            let mut failure = None;
            // Side by side, alternating, so that a change of the machine's speed hits both.
            for _ in 0..RK4_REPEATS {
                let t = Instant::now();
                simulate_record(&dev, &spec, SEED, 0)?;
                ours.push(t.elapsed().as_secs_f64());
                if failure.is_none() {
                    let t = Instant::now();
                    match simulate_rk4_record(&dev, &spec, SEED, 0, substeps) {
                        Ok(_) => rk4.push(t.elapsed().as_secs_f64()),
                        Err(e) => failure = Some(divergence(&e)),
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
            ratios.push((case, substeps, a, b));
        }
    }
    // A bistable example against its linear twin of the same well frequency, paired.
    let bistable = common::load_device("examples/bistable_stops_em")?;
    exp.uses(&bistable, "hypothetical");
    let pc = common::springs_io::paired_record_cost(&bistable.device, 3e-4, REPEATS)?;
    exp.number("bistable_record_cost_ratio_median", pc.ratios[REPEATS / 2]);
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
            median_s: t[REPEATS / 2],
            min_s: t[0],
            simulated_s: endstop::paper::setups::paper_record(&bistable.device, 3e-4).transient_s
                + 10.0,
            stats: pc.summary.stats,
            note: format!(
                "paired runs, median cost ratio bistable/linear {} (range {} to {}); free \
                 flight: {path}",
                fmt_sig(pc.ratios[REPEATS / 2], 3),
                fmt_sig(pc.ratios[0], 3),
                fmt_sig(pc.ratios[REPEATS - 1], 3)
            ),
        });
    }
    for (case, dev, sa) in records {
        let spec = paper_record(&dev, sa);
        let (rec, times) = timed(|| Ok(simulate_record(&dev, &spec, SEED, 0)?))?;
        let sim = spec.transient_s + spec.noise.duration_s;
        let s = rec.summary;
        rows.push(Row {
            case: case.to_string(),
            median_s: times[REPEATS / 2],
            min_s: times[0],
            simulated_s: sim,
            stats: s.stats,
            note: format!(
                "{} impacts, {} % of time in contact",
                s.impacts,
                fmt_sig(100.0 * s.contact_fraction, 3)
            ),
        });
    }

    // A full Figure 8 sweep: every curve of the published set.
    let settings = endstop::paper::figures::fig08::sweep_settings(&p1.device);
    let curves = endstop::paper::figures::fig08::Fig8Curve::ALL
        .map(endstop::paper::figures::fig08::Fig8Curve::spec);
    for (label, threads) in [("1 thread", 1usize), ("all threads", 0)] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()?;
        let (res, times) = timed(|| {
            pool.install(|| {
                Ok(endstop::paper::curves::run_curves(
                    &p1.device,
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
        rows.push(Row {
            case: format!(
                "Figure 8 sweeps, published set, {} curves, {label}",
                curves.len()
            ),
            median_s: times[REPEATS / 2],
            min_s: times[0],
            simulated_s: periods,
            stats,
            note: "coarse sweeps only (refinements excluded from the counts)".into(),
        });
    }

    // Steady impacting sine: how much of the work is spent in contact.
    let h = Harvester::new(&cal, Sine::from_rms_g(5.5, 1300.0));
    let t_end = 200.0 / 1300.0;
    let ((contact_steps, free_steps, stats), times) = timed(|| {
        let mut ode = Dopri5::new(0.0, h.rest_state(), Mode::Free, h.solver_options(1e-8));
        let (mut c, mut f) = (0u64, 0u64);
        ode.integrate(
            &h,
            t_end,
            |_, m| {
                if m.in_contact() {
                    c += 1
                } else {
                    f += 1
                }
            },
        )?;
        Ok((c, f, ode.stats()))
    })?;
    let share = contact_steps as f64 / (contact_steps + free_steps) as f64;
    rows.push(Row {
        case: "P1 calibrated, sine 5.5 g at 1300 Hz, 200 periods".into(),
        median_s: times[REPEATS / 2],
        min_s: times[0],
        simulated_s: t_end,
        stats,
        note: format!(
            "{} % of accepted steps are in contact",
            fmt_sig(100.0 * share, 3)
        ),
    });
    exp.number("contact_step_share_sine_p1", share);

    rows.extend(response_rows(&p2.device)?);

    let mut md = format!(
        "Machine: {} logical cores (RAYON_NUM_THREADS unset unless stated). Each case ran {REPEATS} times.\n\n\
         | case | median wall (s) | fastest (s) | simulated s per wall s | steps per simulated s | rejected steps (after an event) | RHS evals per simulated s | events | notes |\n|---|---|---|---|---|---|---|---|---|\n",
        std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1)
    );
    for r in &rows {
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} ({}) | {} | {} | {} |\n",
            r.case,
            fmt_sig(r.median_s, 3),
            fmt_sig(r.min_s, 3),
            fmt_sig(r.simulated_s / r.median_s, 3),
            fmt_sig(r.stats.steps() as f64 / r.simulated_s, 3),
            r.stats.rejected,
            r.stats.rejected_after_event,
            fmt_sig(r.stats.rhs_evals as f64 / r.simulated_s, 3),
            r.stats.events,
            r.note
        ));
    }
    exp.number("p1_record_calibrated_median_s", rows[0].median_s);
    exp.number("p1_record_published_median_s", rows[1].median_s);
    exp.number("p2_record_median_s", rows[2].median_s);
    exp.number("fig08_sweeps_1thread_median_s", rows[3].median_s);
    exp.number("fig08_sweeps_all_threads_median_s", rows[4].median_s);
    md.push_str(&format!(
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
         Medians of {RK4_REPEATS} runs of each, alternating in the same process:\n\n\
         | case | RK4 steps per sample | ours (s) | RK4 (s) | ours / RK4 |\n|---|---|---|---|---|\n",
        picks[0],
        picks[1]
    ));
    for (case, substeps, a, b) in &ratios {
        let (rk4, ratio) = match b {
            Ok(b) => (fmt_sig(*b, 3), fmt_sig(a / b, 3)),
            Err(e) => (e.clone(), "-".to_string()),
        };
        md.push_str(&format!(
            "| {case} | {substeps} | {} | {rk4} | {ratio} |\n",
            fmt_sig(*a, 3),
        ));
    }
    exp.number("rk4_substeps_target", picks[0] as f64);
    exp.number("rk4_substeps_equal", picks[1] as f64);
    // Ratios of the timed pairs only (a diverged RK4 run has none).
    for ((_, _, a, b), key) in ratios.iter().zip([
        "p1_record_calibrated_over_rk4_target",
        "p1_record_calibrated_over_rk4_equal",
        "p1_record_published_over_rk4_target",
        "p1_record_published_over_rk4_equal",
        "p2_record_over_rk4_target",
        "p2_record_over_rk4_equal",
    ]) {
        if let Ok(b) = b {
            exp.number(key, a / b);
        }
    }
    let (impact_md, impact) = impact_accuracy(&p1.device, &p2.device)?;
    md.push_str(&format!(
        "\n**A record's power with impacts.** One 10 s record (stream 0) of each figure's \
         setup, by our scheme (rtol {:e} in and near contacts) and by Dormand-Prince \
         everywhere:\n\n{impact_md}\n",
        endstop::study::record::DEFAULT_RTOL
    ));
    exp.number("p1_impacting_record_rel_dev_ours", impact[0].0);
    exp.number("p1_impacting_record_rel_dev_rtol1e-9", impact[0].1);
    exp.number("p2_impacting_record_rel_dev_ours", impact[1].0);
    exp.number("p2_impacting_record_rel_dev_rtol1e-9", impact[1].1);
    let (ledger_md, ledger) = energy_balance(&p1.device, &p2.device)?;
    md.push_str(&format!(
        "\n**The energy balance of a record.** The same records and two impact-free ones, \
         with the work of every force booked interval by interval on each scheme's own \
         interpolant (`study::record_ledger`); the residual is relative to the sum of the \
         terms' magnitudes:\n\n{ledger_md}\n"
    ));
    for (key, r) in ledger {
        exp.number(&format!("energy_residual_{key}"), r);
    }
    exp.write_numbers_md(&md)?;
    print!("{md}");
    let mut df = df!(
        "case" => rows.iter().map(|r| r.case.clone()).collect::<Vec<_>>(),
        "median_wall_s" => rows.iter().map(|r| r.median_s).collect::<Vec<_>>(),
        "min_wall_s" => rows.iter().map(|r| r.min_s).collect::<Vec<_>>(),
        "simulated_s" => rows.iter().map(|r| r.simulated_s).collect::<Vec<_>>(),
        "steps" => rows.iter().map(|r| r.stats.steps()).collect::<Vec<_>>(),
        "rejected_steps" => rows.iter().map(|r| r.stats.rejected).collect::<Vec<_>>(),
        "rejected_after_event" => rows.iter().map(|r| r.stats.rejected_after_event).collect::<Vec<_>>(),
        "rhs_evals" => rows.iter().map(|r| r.stats.rhs_evals).collect::<Vec<_>>(),
        "events" => rows.iter().map(|r| r.stats.events).collect::<Vec<_>>(),
        "params" => vec!["published+calibrated"; rows.len()],
    )?;
    exp.write_parquet("bench", &mut df, "published+calibrated")?;
    exp.finish()
}

/// A failed RK4 record as a table cell: where its state left the admissible range, or the
/// error's text.
fn divergence(e: &endstop::study::record::BroadbandError) -> String {
    use endstop::ode::SolverError;
    use endstop::study::record::BroadbandError;
    match e {
        BroadbandError::Solver(SolverError::NonFinite { t, .. }) => {
            format!("diverges (non-finite state at t = {t:.3e} s)")
        }
        BroadbandError::Solver(SolverError::InvalidState { t, .. }) => {
            format!("diverges (inadmissible state at t = {t:.3e} s)")
        }
        other => format!("fails ({other})"),
    }
}

/// A record of the accuracy tables: its label, its key in summary numbers, the device as
/// simulated and the level (g^2/Hz).
type AccuracyCase = (&'static str, &'static str, endstop::device::Device, f64);

/// The impact-free records of the accuracy tables (the linear regime of Figures 14 and 11).
fn impact_free_cases(
    p1: &endstop::device::Device,
    p2: &endstop::device::Device,
) -> [AccuracyCase; 2] {
    use endstop::paper::setups::{prototype1_setup, prototype2_setup};
    [
        ("P2, Sa = 1e-4", "p2_1e-4", prototype2_setup(p2), 1e-4),
        (
            "P1, Sa = 4.42e-6",
            "p1_4.42e-6",
            prototype1_setup(p1),
            4.42e-6,
        ),
    ]
}

/// The impacting records of the accuracy tables: prototype 1 at 2.85e-2 (Figure 12's setup)
/// and prototype 2 at 1.69e-3 (Figures 14 and 15's).
fn impacting_cases(
    p1: &endstop::device::Device,
    p2: &endstop::device::Device,
) -> [AccuracyCase; 2] {
    use endstop::paper::setups::{prototype1_setup, prototype2_setup};
    [
        (
            "P1, Sa = 2.85e-2",
            "p1_2.85e-2",
            prototype1_setup(p1),
            2.85e-2,
        ),
        (
            "P2, Sa = 1.69e-3",
            "p2_1.69e-3",
            prototype2_setup(p2),
            1.69e-3,
        ),
    ]
}

/// `f(case, run)` for every case and run, on every core at once (for the accuracy tables:
/// nothing here is timed), returned case by case in order.
fn untimed_grid<T: Send>(
    cases: usize,
    runs: usize,
    f: impl Fn(usize, usize) -> Result<T> + Sync,
) -> Result<Vec<Vec<T>>> {
    let all = (0..cases * runs)
        .into_par_iter()
        .map(|k| f(k / runs, k % runs))
        .collect::<Result<Vec<T>>>()?;
    let mut all = all.into_iter();
    Ok((0..cases)
        .map(|_| all.by_ref().take(runs).collect())
        .collect())
}

/// The power of impact-free 1 s records of both prototypes by our scheme and by RK4 with 1,
/// 2, 4 and 8 steps per sample interval, relative to Dormand-Prince at rtol 1e-10, as a
/// Markdown table.
fn rk4_accuracy(p1: &endstop::device::Device, p2: &endstop::device::Device) -> Result<String> {
    use endstop::study::record::Scheme;
    let cases = impact_free_cases(p1, p2);
    const SUBSTEPS: [usize; 4] = [1, 2, 4, 8];
    // Run 0 is ours, 1 the reference, then RK4 with each number of substeps.
    let powers = untimed_grid(cases.len(), 2 + SUBSTEPS.len(), |c, r| {
        let (_, _, dev, sa) = &cases[c];
        let mut spec = paper_record(dev, *sa);
        spec.noise.duration_s = 1.0;
        Ok(match r {
            0 => simulate_record(dev, &spec, SEED, 0)?.summary.p_total_w(),
            1 => {
                let mut tight = spec;
                tight.scheme = Scheme::Dopri5;
                tight.rtol = 1e-10;
                simulate_record(dev, &tight, SEED, 0)?.summary.p_total_w()
            }
            _ => simulate_rk4_record(dev, &spec, SEED, 0, SUBSTEPS[r - 2])?.p_total_w,
        })
    })?;
    let mut md = String::from("| record | ours | RK4, 1 step | RK4, 2 steps | RK4, 4 steps | RK4, 8 steps |\n|---|---|---|---|---|---|\n");
    for ((label, _, _, _), p) in cases.iter().zip(&powers) {
        let reference = p[1];
        let mut row = format!("| {label} | {:.1e} |", (p[0] / reference - 1.0).abs());
        for rk4 in &p[2..] {
            row.push_str(&format!(" {:.1e} |", (rk4 / reference - 1.0).abs()));
        }
        md.push_str(&row);
        md.push('\n');
    }
    Ok(md)
}

/// A record's power with impacts, ours against Dormand-Prince everywhere at rtol 1e-7, 1e-9
/// and 1e-10, one 10 s record of each of [`impacting_cases`]. Returns the Markdown table and,
/// per case, our relative deviation from rtol 1e-10 and that of rtol 1e-9 (the reference's
/// own reproducibility).
fn impact_accuracy(
    p1: &endstop::device::Device,
    p2: &endstop::device::Device,
) -> Result<(String, Vec<(f64, f64)>)> {
    use endstop::study::record::Scheme;
    let cases = impacting_cases(p1, p2);
    let runs = [
        ("ours", Scheme::Exponential, None),
        ("Dormand-Prince, rtol 1e-7", Scheme::Dopri5, Some(1e-7)),
        ("Dormand-Prince, rtol 1e-9", Scheme::Dopri5, Some(1e-9)),
        ("Dormand-Prince, rtol 1e-10", Scheme::Dopri5, Some(1e-10)),
    ];
    let mut md = String::from(
        "| record | run | mean power (W) | relative to rtol 1e-10 | impacts |\n|---|---|---|---|---|\n",
    );
    let summaries = untimed_grid(cases.len(), runs.len(), |c, r| {
        let (_, _, dev, sa) = &cases[c];
        let base = paper_record(dev, *sa);
        let (_, scheme, rtol) = runs[r];
        let spec = RecordSpec {
            scheme,
            rtol: rtol.unwrap_or(base.rtol),
            ..base
        };
        Ok(simulate_record(dev, &spec, SEED, 0)?.summary)
    })?;
    let mut out = Vec::new();
    for ((label, _, _, _), case) in cases.iter().zip(&summaries) {
        let got: Vec<_> = runs
            .iter()
            .zip(case)
            .map(|((name, _, _), s)| (*name, s.p_total_w(), s.impacts))
            .collect();
        let reference = got[runs.len() - 1].1;
        let rel = |p: f64| p / reference - 1.0;
        for (name, p, impacts) in &got {
            md.push_str(&format!(
                "| {label} | {name} | {p:.6e} | {:+.1e} | {impacts} |\n",
                rel(*p)
            ));
        }
        out.push((rel(got[0].1), rel(got[2].1)));
    }
    Ok((md, out))
}

/// The energy balance of one 10 s record (stream 0) per case, by our scheme at the default
/// tolerance and at rtol 1e-9 and by Dormand-Prince everywhere at the default: the records
/// of [`impact_free_cases`] (10 s long here) and of [`impacting_cases`]. Returns the Markdown
/// table and (key, our relative residual) per record.
fn energy_balance(
    p1: &endstop::device::Device,
    p2: &endstop::device::Device,
) -> Result<(String, Vec<(String, f64)>)> {
    use endstop::study::record::{Scheme, DEFAULT_RTOL};
    use endstop::study::record_ledger::record_ledger;
    let [free_a, free_b] = impact_free_cases(p1, p2);
    let [hit_a, hit_b] = impacting_cases(p1, p2);
    let cases = [free_a, free_b, hit_a, hit_b];
    let runs = [
        ("ours", Scheme::Exponential, DEFAULT_RTOL),
        ("ours, rtol 1e-9", Scheme::Exponential, 1e-9),
        ("Dormand-Prince everywhere", Scheme::Dopri5, DEFAULT_RTOL),
    ];
    let mut md = String::from(
        "| record | run | relative residual | residual (J) | work of the drive (J) | impacts |\n\
         |---|---|---|---|---|---|\n",
    );
    let books = untimed_grid(cases.len(), runs.len(), |c, r| {
        let (_, _, dev, sa) = &cases[c];
        let (_, scheme, rtol) = runs[r];
        let spec = RecordSpec {
            scheme,
            rtol,
            ..paper_record(dev, *sa)
        };
        let (rec, l) = record_ledger(dev, &spec, SEED, 0)?;
        Ok((rec.summary.impacts, l))
    })?;
    let mut out = Vec::new();
    for ((label, key, _, _), case) in cases.iter().zip(&books) {
        for (run, ((name, _, _), (impacts, l))) in runs.iter().zip(case).enumerate() {
            let r = l.relative_residual();
            md.push_str(&format!(
                "| {label} | {name} | {r:+.1e} | {:+.1e} | {:.3e} | {} |\n",
                l.residual(),
                l.excitation,
                impacts
            ));
            if run == 0 {
                out.push((key.to_string(), r));
            }
        }
    }
    Ok((md, out))
}

/// The whole Figure 13 curve (prototype 2, 0.31 g, linear law): the continuation of the
/// periodic orbits with their stability over 600-850 Hz, beside the stepped up- and
/// down-sweeps of the same curve, each on one thread.
fn response_rows(p2: &endstop::device::Device) -> Result<Vec<Row>> {
    use endstop::paper::response::{continuation, setups, Case};
    let setup = setups(p2, p2, p2)
        .into_iter()
        .find(|s| s.case == Case::Fig13P2)
        .expect("the Figure 13 case");
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let span = setup.continuation.stop - setup.continuation.start;
    let (branch, times) = timed(|| pool.install(|| Ok(continuation(&setup)?)))?;
    let mut rows = vec![Row {
        case: "Figure 13 whole curve by continuation (both branches, multipliers), 1 thread".into(),
        median_s: times[REPEATS / 2],
        min_s: times[0],
        simulated_s: span,
        stats: branch.stats,
        note: format!(
            "{} orbits, {} events; 'simulated s' is the frequency span in Hz",
            branch.points.len(),
            branch.events.len()
        ),
    }];
    for (dir, down) in [("up", false), ("down", true)] {
        let (stats, times) = timed(|| {
            pool.install(|| {
                Ok(if down {
                    setup
                        .sweep
                        .run_down(&setup.device, setup.accel_rms_g, |_| {})?
                        .total_stats()
                } else {
                    setup
                        .sweep
                        .run(&setup.device, setup.accel_rms_g, |_| {})?
                        .total_stats()
                })
            })
        })?;
        rows.push(Row {
            case: format!("Figure 13 stepped {dir}-sweep of the same curve, 1 thread"),
            median_s: times[REPEATS / 2],
            min_s: times[0],
            simulated_s: span,
            stats,
            note: "with refinements; 'simulated s' is the frequency span in Hz".into(),
        });
    }
    Ok(rows)
}
