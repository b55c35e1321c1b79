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
//! Results go to `data/results/bench/` and the book's Performance page.

use endstop_experiments as common;

use std::time::Instant;

use anyhow::Result;
use common::{fmt_sig, Experiment};
use endstop::drive::Sine;
use endstop::ode::Dopri5;
use endstop::physics::contact::Mode;
use endstop::physics::harvester::Harvester;
use endstop::study::record::simulate_record;
use endstop::study::record::RecordSpec;
use polars::prelude::*;

const REPEATS: usize = 5;
const SEED: u64 = 2012;

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
    steps: u64,
    rhs_evals: u64,
    events: u64,
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
    for (case, dev, sa) in records {
        let spec = RecordSpec::paper(&dev, sa);
        let (rec, times) = timed(|| Ok(simulate_record(&dev, &spec, SEED, 0)?))?;
        let sim = spec.transient_s + spec.noise.duration_s;
        let s = rec.summary;
        rows.push(Row {
            case: case.to_string(),
            median_s: times[REPEATS / 2],
            min_s: times[0],
            simulated_s: sim,
            steps: s.stats.accepted + s.stats.rejected,
            rhs_evals: s.stats.rhs_evals,
            events: s.stats.events,
            note: format!(
                "{} impacts, {} % of time in contact",
                s.impacts,
                fmt_sig(100.0 * s.contact_fraction, 3)
            ),
        });
    }

    // A full Figure 8 sweep: every curve of the published set.
    let settings = endstop::paper::fig08::sweep_settings(&p1.device);
    let curves = endstop::paper::fig08::Fig8Curve::ALL.map(endstop::paper::fig08::Fig8Curve::spec);
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
        let (mut steps, mut evals, mut events, mut periods) = (0, 0, 0, 0.0);
        for c in &res {
            let st = &c.report.sweep.stats;
            steps += st.accepted + st.rejected;
            evals += st.rhs_evals;
            events += st.events;
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
            steps,
            rhs_evals: evals,
            events,
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
        steps: stats.accepted + stats.rejected,
        rhs_evals: stats.rhs_evals,
        events: stats.events,
        note: format!(
            "{} % of accepted steps are in contact",
            fmt_sig(100.0 * share, 3)
        ),
    });
    exp.number("contact_step_share_sine_p1", share);

    rows.extend(response_rows(&p2.device)?);

    let mut md = format!(
        "Machine: {} logical cores (RAYON_NUM_THREADS unset unless stated). Each case ran {REPEATS} times.\n\n\
         | case | median wall (s) | fastest (s) | simulated s per wall s | steps per simulated s | RHS evals per simulated s | events | notes |\n|---|---|---|---|---|---|---|---|\n",
        std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1)
    );
    for r in &rows {
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} |\n",
            r.case,
            fmt_sig(r.median_s, 3),
            fmt_sig(r.min_s, 3),
            fmt_sig(r.simulated_s / r.median_s, 3),
            fmt_sig(r.steps as f64 / r.simulated_s, 3),
            fmt_sig(r.rhs_evals as f64 / r.simulated_s, 3),
            r.events,
            r.note
        ));
    }
    exp.number("p1_record_calibrated_median_s", rows[0].median_s);
    exp.number("p1_record_published_median_s", rows[1].median_s);
    exp.number("p2_record_median_s", rows[2].median_s);
    exp.number("fig08_sweeps_1thread_median_s", rows[3].median_s);
    exp.number("fig08_sweeps_all_threads_median_s", rows[4].median_s);
    exp.write_numbers_md(&md)?;
    print!("{md}");
    let mut df = df!(
        "case" => rows.iter().map(|r| r.case.clone()).collect::<Vec<_>>(),
        "median_wall_s" => rows.iter().map(|r| r.median_s).collect::<Vec<_>>(),
        "min_wall_s" => rows.iter().map(|r| r.min_s).collect::<Vec<_>>(),
        "simulated_s" => rows.iter().map(|r| r.simulated_s).collect::<Vec<_>>(),
        "steps" => rows.iter().map(|r| r.steps).collect::<Vec<_>>(),
        "rhs_evals" => rows.iter().map(|r| r.rhs_evals).collect::<Vec<_>>(),
        "events" => rows.iter().map(|r| r.events).collect::<Vec<_>>(),
        "params" => vec!["published+calibrated"; rows.len()],
    )?;
    exp.write_parquet("bench", &mut df, "published+calibrated")?;
    exp.finish()
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
        steps: branch.stats.accepted + branch.stats.rejected,
        rhs_evals: branch.stats.rhs_evals,
        events: branch.stats.events,
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
            steps: stats.accepted + stats.rejected,
            rhs_evals: stats.rhs_evals,
            events: stats.events,
            note: "with refinements; 'simulated s' is the frequency span in Hz".into(),
        });
    }
    Ok(rows)
}
