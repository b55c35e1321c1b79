//! The main table's cases: the paper's 10 s records, a steady impacting sine's share of steps
//! in contact, the bistable example against its linear twin and, in the whole benchmark, the
//! Figure 8 sweeps and Figure 13's whole curve by continuation and by sweeps.

use anyhow::Result;
use endstop::device::Device;
use endstop::drive::Sine;
use endstop::model::{Mode, Model};
use endstop::ode::Stats;
use endstop::paper::setups::paper_record;
use endstop::physics::harvester::Harvester;
use endstop::progress::Silent;
use endstop::study::flow::SineFlow;
use endstop::study::record::simulate_record;
use endstop_experiments as common;

use common::{fmt_sig, Experiment};

use crate::timing::{timed, Row, Times};
use crate::SEED;

/// A paper record: its label, the key its summary numbers start with, the device as simulated
/// and the level (g^2/Hz).
pub type RecordCase = (&'static str, &'static str, Device, f64);

/// The paper's 10 s records: prototype 1 at 2.85e-2 (calibrated and published sets) and
/// prototype 2 at 1.69e-3.
pub fn records(cal: &Device, p1: &Device, p2: &Device) -> [RecordCase; 3] {
    [
        (
            "P1 calibrated, 10 s record, Sa = 2.85e-2",
            "p1_record_calibrated",
            cal.clone(),
            2.85e-2,
        ),
        (
            "P1 published, 10 s record, Sa = 2.85e-2",
            "p1_record_published",
            p1.clone(),
            2.85e-2,
        ),
        (
            "P2 published, 10 s record, Sa = 1.69e-3",
            "p2_record",
            p2.clone(),
            1.69e-3,
        ),
    ]
}

/// The main table's rows (the sweeps and the continuation not with `quick`), with their
/// summary numbers.
pub fn rows(
    exp: &mut Experiment,
    records: &[RecordCase; 3],
    cal: &Device,
    p1: &Device,
    p2: &Device,
    repeats: usize,
    quick: bool,
) -> Result<Vec<Row>> {
    let mut rows = Vec::new();

    for (case, key, dev, sa) in records.iter().cloned() {
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
    let h = Harvester::<4>::new(cal)?;
    let sine = Sine::from_rms_g(5.5, 1300.0);
    let t_end = 200.0 / 1300.0;
    let ((contact_steps, free_steps, stats), times) = timed(repeats, || {
        let mut ode = SineFlow::new(&h, sine, 0.0, h.rest_state(), Mode::FREE, 1e-8);
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
        rows.extend(fig08_rows(exp, p1, repeats)?);
        rows.extend(response_rows(p2, repeats)?);
    }
    Ok(rows)
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
