//! The example devices of `data/examples/`, each timed on what its file's header runs: a 10 s
//! record at the header's level, one periodic orbit by shooting, and the whole response over
//! the header's range (up- and down-sweeps and the continued orbits, as `endstop response`
//! computes them); beside them the ratio to a fixed-step RK4 at equal accuracy and, where the
//! device exports to SPICE, to ngspice on the same steady sine.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use endstop::device::Device;
use endstop::drive::Sine;
use endstop::model::{Mode, Model};
use endstop::ode::Stats;
use endstop::paper::setups::paper_record;
use endstop::progress::Silent;
use endstop::study::continuation::frequency_branch;
use endstop::study::flow::SineFlow;
use endstop::study::orbit::{Forcing, Parameter, Shooter, ShootingOptions};
use endstop::study::record::{simulate_record, RecordSpec, Scheme};
use endstop::study::rk4_record::simulate_rk4_record;
use endstop::study::steady::{settle_settings, steady_state};
use endstop::study::stepped::linspace_step;
use endstop::study::sweep::{SweepSettings, REFINE_TOL_HZ};
use endstop_experiments as common;

use common::{fmt_sig, load_device_file};

/// One example device and the runs of its file's header.
pub struct Example {
    /// File under `data/examples/`.
    pub file: &'static str,
    /// The level of the header's `random` run (g^2/Hz).
    pub psd_g2_per_hz: f64,
    /// The range of the header's `response` (or `sweep`) run: from, to, step (Hz), RMS g.
    pub range: (f64, f64, f64, f64),
}

/// Every example device with its header's runs, but those behind an interface circuit:
/// `piezo_bridge`'s records are timed against the resistive load in `bench/interfaces.rs`,
/// and `em_bridge` is not timed.
pub const EXAMPLES: [Example; 6] = [
    Example {
        file: "piezo_cantilever.toml",
        psd_g2_per_hz: 1e-4,
        range: (100.0, 140.0, 0.5, 0.3),
    },
    Example {
        file: "em_asymmetric.toml",
        psd_g2_per_hz: 1e-4,
        range: (40.0, 60.0, 0.25, 0.2),
    },
    Example {
        file: "rigid_restitution.toml",
        psd_g2_per_hz: 1e-4,
        range: (550.0, 750.0, 2.0, 0.3),
    },
    Example {
        file: "my_harvester.toml",
        psd_g2_per_hz: 1e-3,
        range: (500.0, 900.0, 2.0, 0.3),
    },
    Example {
        file: "hardening_em.toml",
        psd_g2_per_hz: 1e-4,
        range: (80.0, 140.0, 1.0, 0.1),
    },
    Example {
        file: "bistable_stops_em.toml",
        psd_g2_per_hz: 3e-4,
        range: (20.0, 70.0, 1.0, 0.5),
    },
];

/// RK4 steps per sample interval tried for equal accuracy.
const RK4_SUBSTEPS: [usize; 6] = [1, 2, 4, 8, 16, 32];

/// Seed of the records.
const SEED: u64 = 2012;

/// The measured costs of one example device.
pub struct Costs {
    /// The device's name.
    pub name: String,
    /// Its transducer's key and its stops, for the table.
    pub what: String,
    /// Median processor time of a 10 s record (s), with the runs' spread (min, max).
    pub record: (f64, f64, f64),
    /// The record's free-flight path (exponential, or Dormand-Prince and why).
    pub record_path: String,
    /// Impacts in the record.
    pub impacts: u64,
    /// Median processor time of one periodic orbit by shooting (s).
    pub orbit: f64,
    /// Newton iterations of that orbit.
    pub orbit_iterations: usize,
    /// Processor time of the whole response over the header's range (s), its counters and the
    /// orbits on its continued branch (not measured with `--quick`).
    pub response: Option<f64>,
    /// Counters of the response.
    pub response_stats: Stats,
    /// Orbits on the continued branch.
    pub orbits: usize,
    /// A steady sine at the middle of the range from the settled state, 50 periods: the
    /// share of its steps taken by Dormand-Prince (in the modes that are not affine), and
    /// its processor time (s).
    pub steady: (f64, f64),
    /// RK4 at equal accuracy: (steps per sample, our time / RK4's time) or why not.
    pub rk4: Result<(usize, f64), String>,
    /// Our time over ngspice's on the same steady sine, where the device exports.
    pub ngspice: Option<Result<f64, String>>,
}

/// Processor time of `f` (s): this process's user and system time (the timed work runs on one
/// thread, and the machine is shared, so processor time is steadier than wall time).
pub(crate) fn cpu<T>(f: impl FnOnce() -> Result<T>) -> Result<(T, f64)> {
    let t0 = common::cpu_time_s().unwrap_or(0.0);
    let wall = Instant::now();
    let out = f()?;
    let t = match common::cpu_time_s() {
        Some(t1) => t1 - t0,
        None => wall.elapsed().as_secs_f64(),
    };
    Ok((out, t))
}

/// The median of `v` with its smallest and largest value.
pub(crate) fn median(mut v: Vec<f64>) -> (f64, f64, f64) {
    v.sort_by(f64::total_cmp);
    (v[v.len() / 2], v[0], v[v.len() - 1])
}

/// Times every example device (`repeats` runs of the record and the orbit, one of the
/// response), on the calling thread.
pub fn measure(root: &Path, repeats: usize, quick: bool) -> Result<Vec<Costs>> {
    EXAMPLES
        .iter()
        .map(|ex| {
            let path = root.join("data/examples").join(ex.file);
            let loaded = load_device_file(&path)?;
            measure_one(ex, &loaded.device, repeats, quick)
                .with_context(|| format!("benchmark of {}", ex.file))
        })
        .collect()
}

fn measure_one(ex: &Example, device: &Device, repeats: usize, quick: bool) -> Result<Costs> {
    let spec = paper_record(device, ex.psd_g2_per_hz);
    let mut record_times = Vec::new();
    let mut last = None;
    for _ in 0..repeats {
        let (rec, t) = cpu(|| Ok(simulate_record(device, &spec, SEED, 0)?))?;
        record_times.push(t);
        last = Some(rec.summary);
    }
    let summary = last.context("at least one repeat")?;
    let record_path = match summary.free_flight {
        endstop::study::record::FreeFlightPath::Exponential => "exponential".to_string(),
        endstop::study::record::FreeFlightPath::Affine => "exact affine steps".to_string(),
        endstop::study::record::FreeFlightPath::Dopri5(why) => format!("Dormand-Prince: {why}"),
    };

    let (from, to, step, g) = ex.range;
    let f_mid = 0.5 * (from + to);
    let (orbit, iterations, steady) = endstop::with_harvester!(device, |model| {
        orbit_and_steady(&model, device, f_mid, g, repeats)
    })?;

    let (response, response_stats, orbits) = if quick {
        (None, Stats::default(), 0)
    } else {
        let settings =
            SweepSettings::for_device(device, linspace_step(from, to, step), REFINE_TOL_HZ);
        let ((stats, orbits), t) = cpu(|| {
            let up = settings.run(device, g, &Silent)?;
            let down = settings.run_down(device, g, &Silent)?;
            let branch = frequency_branch(device, g, from, to, step, &Silent)?;
            let mut s = up.total_stats();
            s += down.total_stats();
            s += branch.stats;
            Ok((s, branch.points.len()))
        })?;
        (Some(t), stats, orbits)
    };

    let rk4 = if quick {
        Err("not measured (--quick)".to_string())
    } else {
        rk4_ratio(device, ex.psd_g2_per_hz)?
    };
    let ngspice =
        (!quick && endstop::spice::supports(device)).then(|| ngspice_ratio(device, f_mid, g));
    Ok(Costs {
        name: device.name.clone(),
        what: describe(device),
        record: median(record_times),
        record_path,
        impacts: summary.impacts,
        orbit,
        orbit_iterations: iterations,
        response,
        response_stats,
        orbits,
        steady,
        rk4,
        ngspice,
    })
}

/// The median time of `repeats` shootings of the orbit at `f_mid` from the settled state, the
/// shooting's iterations, and the share of the steps of 50 periods on the orbit that go to
/// Dormand-Prince with the time of those periods.
fn orbit_and_steady<M: Model<N>, const N: usize>(
    model: &M,
    device: &Device,
    f_mid: f64,
    g: f64,
    repeats: usize,
) -> Result<(f64, usize, (f64, f64))> {
    let sine = Sine::from_rms_g(g, f_mid);
    let cfg = settle_settings(device, f_mid);
    let (_, settled, mode, _) = steady_state(model, sine, model.rest_state(), Mode::FREE, g, &cfg)?;
    let shooter = Shooter::new(model, ShootingOptions::default());
    let forcing = Forcing {
        freq_hz: f_mid,
        accel_rms_g: g,
    };
    let mut orbit_times = Vec::new();
    let mut iterations = 0;
    for _ in 0..repeats {
        let mut stats = Stats::default();
        let (orbit, t) =
            cpu(|| Ok(shooter.solve(&forcing, Parameter::Frequency, 0.0, settled, &mut stats)?))?;
        orbit_times.push(t);
        iterations = orbit.iterations;
    }
    let steady = cpu(|| {
        let mut flow = SineFlow::new(model, sine, 0.0, settled, mode, 1e-8);
        let (mut dopri, mut all) = (0u64, 0u64);
        let exact = flow.is_exact();
        flow.integrate(50.0 / f_mid, |_, m| {
            all += 1;
            // An exact step is shown only in an affine mode: free flight and linear contacts.
            if !exact || (m.in_contact() && !linear_contact(device)) {
                dopri += 1;
            }
        })?;
        Ok(dopri as f64 / all.max(1) as f64)
    })?;
    Ok((median(orbit_times).0, iterations, steady))
}

/// True when every stop of the device is a linear spring with a viscous damper (its contact
/// is affine, integrated exactly with a linear transducer).
fn linear_contact(device: &Device) -> bool {
    use endstop::device::StopLaw;
    [&device.stops.upper, &device.stops.lower]
        .into_iter()
        .flatten()
        .all(|s| matches!(s.law, StopLaw::Linear { .. }))
}

/// The transducer and the stops' laws, in a few words.
fn describe(device: &Device) -> String {
    let side = |s: Option<&endstop::device::Stop>| s.map_or("none", |s| s.law.key());
    format!(
        "{}; stops: {} above, {} below",
        device.transducer.key(),
        side(device.stops.upper.as_ref()),
        side(device.stops.lower.as_ref())
    )
}

/// Periods of the ngspice comparison.
const NGSPICE_PERIODS: f64 = 200.0;

/// Our processor time over ngspice's on [`NGSPICE_PERIODS`] periods of the sine `g` at
/// `freq_hz` from rest (the cross-check's documented settings), or why it could not run.
fn ngspice_ratio(device: &Device, freq_hz: f64, g: f64) -> Result<f64, String> {
    use endstop::spice::{
        netlist, parse_wrdata, InitialCondition, SolverSettings, SpiceDrive, SpiceOptions,
        Transient, HERTZ_NEWTON_STEPS,
    };
    use endstop::study::flow::SineFlow;
    let run = || -> Result<f64> {
        common::ngspice::version()?;
        let period = 1.0 / freq_hz;
        let t_end = NGSPICE_PERIODS * period;
        let sine = Sine::from_rms_g(g, freq_hz);
        let (_, ours) = endstop::with_harvester!(device, |model| {
            cpu(|| {
                let mut flow =
                    SineFlow::new(&model, sine, 0.0, model.rest_state(), Mode::FREE, 1e-8);
                flow.advance(t_end)?;
                Ok(())
            })
        })?;
        let tmp = common::ngspice::TempDir(
            std::env::temp_dir().join(format!("endstop-bench-{}", std::process::id())),
        );
        std::fs::create_dir_all(&tmp.0)?;
        let (cir, dat) = (tmp.0.join("bench.cir"), tmp.0.join("bench.dat"));
        let opts = SpiceOptions {
            title: format!("endstop bench: {}", device.name),
            initial: InitialCondition::rest(),
            solver: SolverSettings::documented(period),
            transient: Transient {
                stop_s: t_end,
                step_s: period / 100.0,
                save_from_s: t_end - 10.0 * period,
                wrdata_file: Some("bench.dat".into()),
            },
            hertz_newton_steps: HERTZ_NEWTON_STEPS,
        };
        let drive = SpiceDrive {
            accel_rms_g: g,
            freq_hz,
        };
        std::fs::write(&cir, netlist(device, &drive, &opts))?;
        let before = common::children_cpu_time_s();
        let (text, wall) = common::ngspice::run(&cir, &dat)?;
        let spice = common::children_cpu_time_s()
            .zip(before)
            .map_or(wall, |(a, b)| a - b);
        parse_wrdata(&text)?;
        Ok(ours / spice)
    };
    run().map_err(|e| format!("not run: {e}"))
}

/// RK4 at equal accuracy: the fewest steps per sample of [`RK4_SUBSTEPS`] whose impact-free
/// 1 s record is as close to Dormand-Prince at rtol 1e-11 as ours (or as the reference's own
/// reproducibility, its distance from rtol 1e-10, where ours is closer), then our time over
/// RK4's on the 10 s record at the header's level (medians of 3 alternated runs).
fn rk4_ratio(device: &Device, psd: f64) -> Result<Result<(usize, f64), String>> {
    // An impact-free level: the header's, divided by 10 until a 1 s record has no impact.
    let mut level = psd;
    let short = |level: f64| {
        let mut s = paper_record(device, level);
        s.noise.duration_s = 1.0;
        s
    };
    loop {
        let r = simulate_record(device, &short(level), SEED, 0)?;
        if r.summary.impacts == 0 {
            break;
        }
        level /= 10.0;
        if level < psd * 1e-6 {
            return Ok(Err("no impact-free level found".into()));
        }
    }
    let spec = short(level);
    let reference = |rtol: f64| -> Result<f64> {
        let s = RecordSpec {
            scheme: Scheme::Dopri5,
            rtol,
            ..spec
        };
        Ok(simulate_record(device, &s, SEED, 0)?.summary.p_total_w())
    };
    let (p11, p10) = (reference(1e-11)?, reference(1e-10)?);
    let ours = simulate_record(device, &spec, SEED, 0)?.summary.p_total_w();
    let target = (ours / p11 - 1.0).abs().max((p10 / p11 - 1.0).abs());
    let mut pick = None;
    for n in RK4_SUBSTEPS {
        match simulate_rk4_record(device, &spec, SEED, 0, n) {
            Ok(r) if (r.p_total_w / p11 - 1.0).abs() <= target => {
                pick = Some(n);
                break;
            }
            _ => {}
        }
    }
    let Some(n) = pick else {
        return Ok(Err(format!(
            "RK4 misses {target:.1e} with up to {} steps per sample",
            RK4_SUBSTEPS[RK4_SUBSTEPS.len() - 1]
        )));
    };
    let full = paper_record(device, psd);
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for _ in 0..3 {
        a.push(cpu(|| Ok(simulate_record(device, &full, SEED, 0)?))?.1);
        match cpu(|| Ok(simulate_rk4_record(device, &full, SEED, 0, n)?)) {
            Ok((_, t)) => b.push(t),
            Err(e) => return Ok(Err(format!("RK4 with {n} steps per sample fails: {e}"))),
        }
    }
    Ok(Ok((n, median(a).0 / median(b).0)))
}

/// The tables of the example devices (Markdown).
pub fn table(costs: &[Costs], repeats: usize, quick: bool) -> String {
    let mut md = format!(
        "Processor time (user and system) of each run on one thread, median of {repeats} \
         run(s) for the record and the orbit{}. The record is 10 s long at the level of the \
         device file's header (its pre-roll of five ring-up times added); the orbit is one \
         periodic orbit by shooting at the middle of the header's range, from a settled state; \
         the response is what `endstop response` computes over the header's range (up- and \
         down-sweeps with their refinements, and the continued orbits){}.\n\n\
         | device | record (s) | record's free flight | impacts | orbit (s) | Newton iterations | response (s) | orbits | response steps | events |\n\
         |---|---|---|---|---|---|---|---|---|---|\n",
        if quick { "" } else { ", one run for the response" },
        if quick {
            " (measured by `just bench`, not by `bench --quick`)"
        } else {
            ""
        },
    );
    let or_dash = |v: Option<String>| v.unwrap_or_else(|| "-".into());
    for c in costs {
        md.push_str(&format!(
            "| `{}` ({}) | {} ({}-{}) | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            c.name,
            c.what,
            fmt_sig(c.record.0, 3),
            fmt_sig(c.record.1, 3),
            fmt_sig(c.record.2, 3),
            c.record_path,
            c.impacts,
            fmt_sig(c.orbit, 3),
            c.orbit_iterations,
            or_dash(c.response.map(|r| fmt_sig(r, 3))),
            or_dash(c.response.map(|_| c.orbits.to_string())),
            or_dash(c.response.map(|_| c.response_stats.steps().to_string())),
            or_dash(c.response.map(|_| c.response_stats.events.to_string())),
        ));
    }
    md.push_str(
        "\n**Where a steady sine's time goes.** 50 periods at the middle of each header's range \
         from the settled state: the share of the steps taken by Dormand-Prince (in the modes \
         that are not affine: contacts with a nonlinear law, and every mode of a capacitor \
         pair; the rest are exact steps, see `study::flow`) and the processor time.\n\n\
         | device | Dormand-Prince steps | 50 periods (s) |\n|---|---|---|\n",
    );
    for c in costs {
        md.push_str(&format!(
            "| `{}` | {} % | {} |\n",
            c.name,
            fmt_sig(100.0 * c.steady.0, 3),
            fmt_sig(c.steady.1, 3)
        ));
    }
    if quick {
        return md;
    }
    md.push_str(
        "\n**Against a fixed-step RK4 and ngspice.** RK4 (`study::rk4_record`) takes the fewest \
         steps per 10 us sample (of 1, 2, 4, ..., 32) at which an impact-free 1 s record's \
         power is as close to Dormand-Prince at rtol 1e-11 as ours is (or as Dormand-Prince at \
         rtol 1e-10 is, where ours is closer); the ratio is our processor time over RK4's on \
         the 10 s record above (medians of 3 alternated runs). ngspice runs the device's netlist \
         (`spice::netlist`, devices of the paper's topology only) over 200 periods of a sine at \
         the middle of the range from rest at the cross-check's documented settings; the ratio \
         is our processor time over ngspice's on the same span.\n\n\
         | device | RK4 steps per sample | ours / RK4 | ours / ngspice |\n|---|---|---|---|\n",
    );
    for c in costs {
        let (n, r) = match &c.rk4 {
            Ok((n, r)) => (n.to_string(), fmt_sig(*r, 3)),
            Err(e) => ("-".into(), e.clone()),
        };
        let s = match &c.ngspice {
            None => "does not export".to_string(),
            Some(Ok(r)) => fmt_sig(*r, 3),
            Some(Err(e)) => e.clone(),
        };
        md.push_str(&format!("| `{}` | {n} | {r} | {s} |\n", c.name));
    }
    md
}
