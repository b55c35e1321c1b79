//! Cross-check with ngspice: the same model, exported as a SPICE netlist by `endstop::spice`
//! (the paper's Figure 6), simulated by ngspice in batch mode and compared with our integrator
//! (`study::steady::steady_state`) for the same drive, from the same initial state, over the
//! same time span, measured over the same window of whole periods.
//!
//! Cases: prototype 1 without impacts, prototype 1 on its impacting upper branch (Hertz and
//! linear end-stop laws), prototype 1 grazing the stops at Figure 8's 5.5 g, and prototype 2 on
//! its upper branch near the jump at 0.31 g. Each case runs under several ngspice settings, from
//! ngspice's defaults to the documented ones. The run fails (non-zero exit) if ngspice is not
//! installed or if the documented settings miss the acceptance tolerances (0.1 % without
//! impacts, 1 % with impacts).

use endstop::paper::setups::{comb, endstop, stiffness_model};
use endstop_experiments as common;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use common::plot::{LegendPos, LinePlot, Series, Style, PALETTE};
use common::{fmt_sig, write_atomic, Experiment};
use endstop::device::Device;
use endstop::device::StiffnessModel;
use endstop::drive::Sine;
use endstop::ode::Dopri5;
use endstop::physics::contact::Mode;
use endstop::physics::harvester::Harvester;
use endstop::physics::harvester::State;
use endstop::spice::netlist;
use endstop::spice::parse_wrdata;
use endstop::spice::InitialCondition;
use endstop::spice::Method;
use endstop::spice::SolverSettings;
use endstop::spice::SpiceDrive;
use endstop::spice::SpiceOptions;
use endstop::spice::Transient;
use endstop::spice::Waveforms;
use endstop::spice::HERTZ_NEWTON_STEPS;
use endstop::study::steady::steady_config;
use endstop::study::steady::steady_state;
use endstop::study::steady::Measurement;
use endstop::study::steady::SteadyConfig;
use endstop::study::stepped::linspace_step;
use endstop::study::stepped::SteppedDrive;
use polars::prelude::*;

fn main() {
    common::run_main("crosscheck", run);
}

/// Every comparison spans at least this many drive periods (long enough for ngspice's default
/// settings to fall off an upper branch, see the book chapter).
const MIN_SPAN_PERIODS: usize = 200;
/// Output step `tstep` of `.tran`: this many per period (ngspice's default max step is bounded
/// by it).
const OUTPUT_STEPS_PER_PERIOD: f64 = 100.0;
/// Steady-state criterion of our integrator: relative change of the RMS voltages between two
/// blocks (tighter than the sweeps' 1e-3, so that the comparison window is in steady state).
const REL_CHANGE_TOL: f64 = 1e-5;
/// Acceptance: relative difference of the RMS voltages with the documented settings.
const TOL_FREE: f64 = 1e-3;
/// Acceptance with impacts.
const TOL_IMPACTING: f64 = 1e-2;
/// The case whose netlist the book shows, and whose waveforms are plotted.
const BOOK_CASE: &str = "p1_impacting";

/// Where a case starts.
#[derive(Debug, Clone, Copy)]
enum Start {
    /// From rest.
    Rest,
    /// From the final state of an up-sweep (our continuation) from `from_hz` in steps of
    /// `step_hz` up to the case frequency: the upper branch.
    UpSweep { from_hz: f64, step_hz: f64 },
}

struct Case {
    key: &'static str,
    label: String,
    device: Device,
    accel_rms_g: f64,
    freq_hz: f64,
    start: Start,
    /// Impacts expected (selects the tolerance).
    impacting: bool,
}

#[derive(Clone, Copy)]
struct Setting {
    key: &'static str,
    label: &'static str,
    /// The documented settings, held to the acceptance tolerance.
    documented: bool,
    solver: fn(f64) -> SolverSettings,
}

/// ngspice's defaults (reltol 1e-3, abstol 1e-12, vntol 1e-6, chgtol 1e-14, trapezoidal; max
/// step bounded by the output step T/100).
fn s_defaults(_period: f64) -> SolverSettings {
    SolverSettings::ngspice_defaults()
}

/// Defaults with only the max step reduced to T/1000.
fn s_defaults_maxstep(period: f64) -> SolverSettings {
    SolverSettings {
        max_step_s: Some(period / endstop::spice::DOCUMENTED_STEPS_PER_PERIOD),
        ..SolverSettings::ngspice_defaults()
    }
}

/// The documented tolerances, with ngspice's default max step.
fn s_documented_no_maxstep(period: f64) -> SolverSettings {
    SolverSettings {
        max_step_s: None,
        ..s_documented(period)
    }
}

/// The documented settings (`SolverSettings::documented`).
fn s_documented(period: f64) -> SolverSettings {
    SolverSettings::documented(period)
}

/// The documented settings with Gear's method of order 2.
fn s_documented_gear(period: f64) -> SolverSettings {
    SolverSettings {
        method: Method::Gear { maxord: 2 },
        ..s_documented(period)
    }
}

const SETTINGS: [Setting; 5] = [
    Setting {
        key: "defaults",
        label: "ngspice defaults",
        documented: false,
        solver: s_defaults,
    },
    Setting {
        key: "defaults_maxstep",
        label: "defaults, max step T/1000",
        documented: false,
        solver: s_defaults_maxstep,
    },
    Setting {
        key: "documented_no_maxstep",
        label: "documented tolerances, default max step",
        documented: false,
        solver: s_documented_no_maxstep,
    },
    Setting {
        key: "documented",
        label: "documented (trapezoidal)",
        documented: true,
        solver: s_documented,
    },
    Setting {
        key: "documented_gear2",
        label: "documented, Gear order 2",
        documented: false,
        solver: s_documented_gear,
    },
];

/// One ngspice run, measured.
struct SpiceResult {
    v1: f64,
    v2: f64,
    x_peak_m: f64,
    contact_fraction: f64,
    points: usize,
    wall_s: f64,
    waveforms: Waveforms,
}

/// One row of the table.
struct Row {
    case: String,
    case_label: String,
    device: String,
    stiffness: String,
    bim: f64,
    bias_v: f64,
    accel_rms_g: f64,
    freq_hz: f64,
    start: String,
    setting: String,
    setting_label: String,
    documented: bool,
    settings_text: String,
    span_s: f64,
    window_s: f64,
    v1_ours: f64,
    v2_ours: f64,
    v1_spice: f64,
    v2_spice: f64,
    rel_diff_v1: f64,
    rel_diff_v2: f64,
    rel_diff: f64,
    x_peak_ours_m: f64,
    x_peak_spice_m: f64,
    cf_ours: f64,
    cf_spice: f64,
    v1_ours_from_rest: f64,
    ours_s: f64,
    ours_steps: u64,
    spice_s: f64,
    spice_points: usize,
    tolerance: f64,
    impacting: bool,
    status: String,
}

/// Removes the temporary directory when dropped.
struct TempDir(PathBuf);

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// `ngspice -v`'s first non-empty line, or an error telling how to install it.
fn ngspice_version() -> Result<String> {
    let out = match Command::new("ngspice").arg("-v").output() {
        Ok(o) => o,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => bail!(
            "ngspice is not installed (no `ngspice` on PATH); install with: apt-get install ngspice"
        ),
        Err(e) => return Err(e).context("cannot run `ngspice -v`"),
    };
    let text = String::from_utf8_lossy(&out.stdout);
    Ok(text
        .lines()
        .map(|l| l.trim_matches(|c: char| c == '*' || c.is_whitespace()))
        .find(|l| l.starts_with("ngspice"))
        .map(|l| l.split(" : ").next().unwrap_or(l).trim().to_string())
        .unwrap_or_else(|| "ngspice (unknown version)".to_string()))
}

fn settings_text(s: &SolverSettings, period: f64) -> String {
    let f = |v: Option<f64>, d: &str| v.map(|x| format!("{x:e}")).unwrap_or(format!("{d}*"));
    let method = match s.method {
        Method::Trapezoidal => "trap".to_string(),
        Method::Gear { maxord } => format!("gear{maxord}"),
    };
    let maxstep = match s.max_step_s {
        Some(h) => format!("T/{}", (period / h).round()),
        None => format!("T/{}*", OUTPUT_STEPS_PER_PERIOD),
    };
    format!(
        "reltol={} abstol={} vntol={} chgtol={} {method} maxstep={maxstep}",
        f(s.reltol, "1e-3"),
        f(s.abstol, "1e-12"),
        f(s.vntol, "1e-6"),
        f(s.chgtol, "1e-14"),
    )
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b) / b
}

fn run_ngspice(cir: &Path, dat: &Path, xmax_m: f64, t0: f64, t1: f64) -> Result<SpiceResult> {
    let started = Instant::now();
    let out = Command::new("ngspice")
        .arg("-b")
        .arg(cir)
        .current_dir(cir.parent().unwrap_or(Path::new(".")))
        .output()
        .context("cannot run ngspice")?;
    let wall_s = started.elapsed().as_secs_f64();
    let log = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let tail = || {
        log.lines()
            .filter(|l| !l.trim().is_empty())
            .rev()
            .take(6)
            .collect::<Vec<_>>()
            .into_iter()
            .rev()
            .collect::<Vec<_>>()
            .join(" | ")
    };
    if !out.status.success() {
        bail!("ngspice exited with {}: {}", out.status, tail());
    }
    let text = std::fs::read_to_string(dat)
        .with_context(|| format!("ngspice wrote no {} ({})", dat.display(), tail()))?;
    let w = parse_wrdata(&text).with_context(|| format!("reading {}", dat.display()))?;
    let xmax_um = xmax_m * 1e6;
    let res = SpiceResult {
        v1: w.rms("v(n1)", t0, t1)?,
        v2: w.rms("v(n2)", t0, t1)?,
        x_peak_m: w.max_abs("v(xpos)", t0, t1)? * 1e-6,
        contact_fraction: w.fraction_above("v(xpos)", xmax_um, t0, t1)?,
        points: w.time.iter().filter(|&&t| t >= t0 && t <= t1).count(),
        wall_s,
        waveforms: w,
    };
    if !(res.v1.is_finite() && res.v2.is_finite()) {
        bail!("ngspice returned non-finite voltages ({})", tail());
    }
    Ok(res)
}

/// Our model's V1 over the last period of [0, t_end] from (y0, mode0), sampled at `n` + 1
/// points, as (phase in periods, V1).
fn our_last_period(
    model: &Harvester<Sine>,
    y0: State,
    mode0: Mode,
    cfg: &SteadyConfig,
    t_end: f64,
    n: usize,
) -> Result<Vec<(f64, f64)>> {
    let period = model.excitation.period_s();
    let t_start = t_end - period;
    let times: Vec<f64> = (0..=n)
        .map(|i| t_start + period * i as f64 / n as f64)
        .collect();
    let mut pts = Vec::with_capacity(n + 1);
    let mut k = 0;
    let mut ode = Dopri5::new(0.0, y0, mode0, model.solver_options(cfg.rtol));
    ode.integrate(model, t_end, |st, _| {
        while k < times.len() && times[k] <= st.t1() {
            if times[k] >= st.t0 {
                let y = st.at(times[k]);
                pts.push(((times[k] - t_start) / period, model.electrical(&y).v[0]));
            }
            k += 1;
        }
    })?;
    Ok(pts)
}

fn cases(p1: &Device, p2: &Device) -> Vec<Case> {
    let p1_30 = p1.with_bias(30.0);
    let p2_10 = p2.with_bias(10.0);
    vec![
        Case {
            key: "p1_free",
            label: "P1, 30 V, 4.1 g, 1000 Hz, no impacts (Hertz, b_im = 1.5 N s/m)".into(),
            device: p1_30.with_endstop(StiffnessModel::Hertz, 1.5),
            accel_rms_g: 4.1,
            freq_hz: 1000.0,
            start: Start::Rest,
            impacting: false,
        },
        Case {
            key: "p1_impacting",
            label: "P1, 30 V, 7 g, 1350 Hz, upper branch (Hertz, b_im = 1.5 N s/m)".into(),
            device: p1_30.with_endstop(StiffnessModel::Hertz, 1.5),
            accel_rms_g: 7.0,
            freq_hz: 1350.0,
            start: Start::UpSweep {
                from_hz: 1100.0,
                step_hz: 10.0,
            },
            impacting: true,
        },
        Case {
            key: "p1_impacting_linear",
            label: "P1, 30 V, 7 g, 1350 Hz, upper branch (linear k_im, b_im = 2 N s/m)".into(),
            device: p1_30.with_endstop(StiffnessModel::Linear, 2.0),
            accel_rms_g: 7.0,
            freq_hz: 1350.0,
            start: Start::UpSweep {
                from_hz: 1100.0,
                step_hz: 10.0,
            },
            impacting: true,
        },
        Case {
            key: "p1_grazing",
            label: "P1, 30 V, 5.5 g, 1240 Hz, grazing (Hertz, b_im = 1.5 N s/m)".into(),
            device: p1_30.with_endstop(StiffnessModel::Hertz, 1.5),
            accel_rms_g: 5.5,
            freq_hz: 1240.0,
            start: Start::UpSweep {
                from_hz: 1100.0,
                step_hz: 10.0,
            },
            impacting: true,
        },
        Case {
            key: "p2_upper",
            label: "P2, 10 V, 0.31 g, 720 Hz, upper branch (linear k_im, b_im = 0.4 N s/m)".into(),
            device: p2_10.with_endstop(StiffnessModel::Linear, 0.4),
            accel_rms_g: 0.31,
            freq_hz: 720.0,
            start: Start::UpSweep {
                from_hz: 640.0,
                step_hz: 5.0,
            },
            impacting: true,
        },
    ]
}

fn run() -> Result<()> {
    let version = ngspice_version()?;
    let mut exp = Experiment::start("crosscheck");
    eprintln!("[crosscheck] using {version}");
    let p1 = exp.load_published("prototype1")?;
    let p2 = exp.load_published("prototype2")?;

    let tmp =
        TempDir(std::env::temp_dir().join(format!("endstop-crosscheck-{}", std::process::id())));
    std::fs::create_dir_all(&tmp.0)
        .with_context(|| format!("cannot create {}", tmp.0.display()))?;

    let mut rows: Vec<Row> = Vec::new();
    let mut plot_series: Vec<Series> = Vec::new();
    let mut failures: Vec<String> = Vec::new();
    for case in cases(&p1.device, &p2.device) {
        let f = case.freq_hz;
        let a = case.accel_rms_g;
        let period = 1.0 / f;
        let dev = &case.device;
        let model = Harvester::new(dev, Sine::from_rms_g(a, f));
        let mut cfg = steady_config(dev, f);
        cfg.rel_change_tol = REL_CHANGE_TOL;
        // The initial state: rest, or the end of our up-sweep at the case frequency.
        let (y0, mode0, start_label) = match case.start {
            Start::Rest => (model.rest_state(), Mode::Free, "rest".to_string()),
            Start::UpSweep { from_hz, step_hz } => {
                let c = SteppedDrive {
                    base: &model,
                    drive: move |ff: f64| (ff, a),
                    cfg: cfg.clone(),
                };
                let sweep = c.run(&linspace_step(from_hz, f, step_hz), |_| {})?;
                let last = sweep.steps.last().context("empty up-sweep")?;
                (
                    last.state,
                    last.mode,
                    format!("up-sweep {from_hz}-{f} Hz in {step_hz} Hz steps (ours)"),
                )
            }
        };
        // Ours over at least MIN_SPAN_PERIODS periods, measured over the last block.
        cfg.settle_blocks = MIN_SPAN_PERIODS.div_ceil(cfg.block_periods).max(1);
        let started = Instant::now();
        let (m, _, _, stats): (Measurement, _, _, _) = steady_state(&model, y0, mode0, a, &cfg)?;
        let ours_s = started.elapsed().as_secs_f64();
        if !m.converged {
            bail!("{}: our steady state did not converge", case.key);
        }
        let block_s = cfg.block_periods as f64 * period;
        let t_end = (cfg.settle_blocks + m.blocks) as f64 * block_s;
        let (t0, t1) = (t_end - block_s, t_end);
        // The lower branch for reference: ours from rest at the same drive.
        let v1_from_rest = if case.impacting {
            let cfg_rest = steady_config(dev, f);
            steady_state(&model, model.rest_state(), Mode::Free, a, &cfg_rest)?
                .0
                .v1_rms_v
        } else {
            m.v1_rms_v
        };
        eprintln!(
            "[crosscheck] {}: ours V1 = {:.6} V over {} periods in {:.3} s",
            case.key,
            m.v1_rms_v,
            (t_end / period).round(),
            ours_s
        );
        let drive = SpiceDrive {
            accel_rms_g: a,
            freq_hz: f,
        };
        let initial = InitialCondition::from_state(dev, &y0);
        let make_opts = |setting: &Setting, wrdata: String| SpiceOptions {
            title: format!("endstop crosscheck: {} [{}]", case.label, setting.label),
            initial,
            solver: (setting.solver)(period),
            transient: Transient {
                stop_s: t_end,
                step_s: period / OUTPUT_STEPS_PER_PERIOD,
                save_from_s: (t0 - period).max(0.0),
                wrdata_file: Some(wrdata),
            },
            hertz_newton_steps: HERTZ_NEWTON_STEPS,
        };
        for setting in &SETTINGS {
            let stem = format!("{}_{}", case.key, setting.key);
            let dat = tmp.0.join(format!("{stem}.dat"));
            let cir = tmp.0.join(format!("{stem}.cir"));
            let opts = make_opts(setting, dat.display().to_string());
            let text = netlist(dev, &drive, &opts);
            std::fs::write(&cir, &text)
                .with_context(|| format!("cannot write {}", cir.display()))?;
            if setting.documented {
                // The netlist as a user would run it (`ngspice -b <case>.cir`), writing
                // `<case>.dat` beside it.
                let portable = netlist(
                    dev,
                    &drive,
                    &make_opts(setting, format!("{}.dat", case.key)),
                );
                write_atomic(
                    &exp.dir.join(format!("netlists/{}.cir", case.key)),
                    portable.as_bytes(),
                )?;
                if case.key == BOOK_CASE {
                    write_atomic(
                        &exp.book_dir.join(format!("{BOOK_CASE}.cir")),
                        portable.as_bytes(),
                    )?;
                }
            }
            let tol = if case.impacting {
                TOL_IMPACTING
            } else {
                TOL_FREE
            };
            let solver = (setting.solver)(period);
            let mut row = Row {
                case: case.key.to_string(),
                case_label: case.label.clone(),
                device: dev.name.clone(),
                stiffness: format!("{:?}", stiffness_model(dev)).to_lowercase(),
                bim: endstop(dev).damping_n_s_per_m,
                bias_v: comb(dev).bias_v,
                accel_rms_g: a,
                freq_hz: f,
                start: start_label.clone(),
                setting: setting.key.to_string(),
                setting_label: setting.label.to_string(),
                documented: setting.documented,
                settings_text: settings_text(&solver, period),
                span_s: t_end,
                window_s: block_s,
                v1_ours: m.v1_rms_v,
                v2_ours: m.v2_rms_v,
                v1_spice: f64::NAN,
                v2_spice: f64::NAN,
                rel_diff_v1: f64::NAN,
                rel_diff_v2: f64::NAN,
                rel_diff: f64::NAN,
                x_peak_ours_m: m.x_peak_m,
                x_peak_spice_m: f64::NAN,
                cf_ours: m.contact_fraction,
                cf_spice: f64::NAN,
                v1_ours_from_rest: v1_from_rest,
                ours_s,
                ours_steps: stats.accepted,
                spice_s: f64::NAN,
                spice_points: 0,
                tolerance: tol,
                impacting: case.impacting,
                status: String::new(),
            };
            match run_ngspice(&cir, &dat, endstop(dev).gap_m, t0, t1) {
                Ok(r) => {
                    row.v1_spice = r.v1;
                    row.v2_spice = r.v2;
                    row.rel_diff_v1 = rel(r.v1, m.v1_rms_v);
                    row.rel_diff_v2 = rel(r.v2, m.v2_rms_v);
                    row.rel_diff = row.rel_diff_v1.abs().max(row.rel_diff_v2.abs());
                    row.x_peak_spice_m = r.x_peak_m;
                    row.cf_spice = r.contact_fraction;
                    row.spice_s = r.wall_s;
                    row.spice_points = r.points;
                    row.status = if row.rel_diff <= tol {
                        "within tolerance".into()
                    } else {
                        "outside tolerance".into()
                    };
                    if case.key == BOOK_CASE
                        && (setting.key == "documented" || setting.key == "defaults")
                    {
                        let w = &r.waveforms;
                        let v1 = w.column("v(n1)")?;
                        let pts: Vec<(f64, f64)> = w
                            .time
                            .iter()
                            .zip(v1)
                            .filter(|(t, _)| **t >= t1 - period && **t <= t1)
                            .map(|(t, v)| ((t - (t1 - period)) / period, *v))
                            .collect();
                        let (color, style) = if setting.documented {
                            (PALETTE[1], Style::Dashed)
                        } else {
                            (PALETTE[2], Style::Line)
                        };
                        let label = if setting.documented {
                            "ngspice, documented settings"
                        } else if r.contact_fraction == 0.0 && m.contact_fraction > 0.0 {
                            "ngspice, defaults (no impacts left: the lower branch)"
                        } else {
                            "ngspice, defaults"
                        };
                        plot_series.push(Series::new(label, pts, color, style));
                    }
                }
                Err(e) => {
                    row.status = format!("ngspice failed: {e:#}");
                }
            }
            eprintln!(
                "[crosscheck]   {:<24} V1 {:>10} V  rel diff {:>10}  ngspice {:.2} s  ({})",
                setting.key,
                fmt_sig(row.v1_spice, 7),
                fmt_sig(row.rel_diff, 2),
                row.spice_s,
                row.status
            );
            if setting.documented && row.status != "within tolerance" {
                failures.push(format!(
                    "{} [{}]: relative difference {} > tolerance {} ({})",
                    case.key, setting.key, row.rel_diff, tol, row.status
                ));
            }
            exp.number(
                &format!("rel_diff_{}_{}", case.key, setting.key),
                row.rel_diff,
            );
            exp.number(
                &format!("v1_rms_spice_{}_{}_v", case.key, setting.key),
                row.v1_spice,
            );
            rows.push(row);
        }
        exp.number(&format!("v1_rms_ours_{}_v", case.key), m.v1_rms_v);
        exp.number(
            &format!("v1_rms_ours_from_rest_{}_v", case.key),
            v1_from_rest,
        );
        if case.key == BOOK_CASE {
            let ours = our_last_period(&model, y0, mode0, &cfg, t_end, 400)?;
            plot_series.insert(
                0,
                Series::new(
                    "ours (Dormand-Prince, events)",
                    ours,
                    PALETTE[0],
                    Style::Line,
                ),
            );
        }
    }

    exp.write_numbers_md(&numbers_md(&rows, &version))?;
    let mut df = rows_df(&rows)?;
    exp.write_parquet("crosscheck", &mut df, "published")?;
    let (lo, hi) = plot_series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.1))
        .fold((f64::MAX, f64::MIN), |(a, b), y| (a.min(y), b.max(y)));
    let pad = 0.08 * (hi - lo).max(1e-9);
    let plot = LinePlot::new(
        "Cross-check: P1, 30 V, 7 g, 1350 Hz (Hertz), V1 over the last period",
        "time in the last period [periods]",
        "V1 [V]",
        plot_series,
    )
    .x(0.0, 1.0)
    .y(lo - pad, hi + 3.0 * pad)
    .legend(LegendPos::UpperRight);
    exp.write_plot(&plot)?;
    exp.finish()?;
    if !failures.is_empty() {
        bail!(
            "the documented ngspice settings miss the acceptance tolerance:\n  {}",
            failures.join("\n  ")
        );
    }
    Ok(())
}

fn numbers_md(rows: &[Row], version: &str) -> String {
    let mut md = format!(
        "Simulator: {version}. Relative difference = (ngspice - ours)/ours of the RMS voltage \
         over the comparison window, the larger of V1 and V2. Tolerance: {} % without impacts, \
         {} % with impacts, applied to the documented settings. Settings marked * \
         are ngspice's defaults; T is the drive period; the output step of `.tran` is \
         T/{OUTPUT_STEPS_PER_PERIOD}. The verdict applies the tolerance to every row; only the \
         documented settings (in bold) are required to meet it. Run times are wall-clock seconds on the machine that \
         generated this page (ngspice's include starting the process and writing its output).\n\n",
        TOL_FREE * 100.0,
        TOL_IMPACTING * 100.0,
    );
    let mut last_case = String::new();
    for r in rows {
        if r.case != last_case {
            last_case = r.case.clone();
            md.push_str(&format!(
                "\n**{}** (`{}`). Start: {}. Span {} periods, window {} periods. Ours: V1 = {} V, \
                 V2 = {} V, peak abs(x) = {} um, time in contact {} %, {} steps in {} s.{}\n\n\
                 | ngspice setting | V1 ngspice (V) | V2 ngspice (V) | rel. diff | peak abs(x) (um) | time in contact (%) | points in window | ngspice (s) | verdict |\n\
                 |---|---|---|---|---|---|---|---|---|\n",
                r.case_label,
                r.case,
                r.start,
                (r.span_s * r.freq_hz).round(),
                (r.window_s * r.freq_hz).round(),
                fmt_sig(r.v1_ours, 7),
                fmt_sig(r.v2_ours, 7),
                fmt_sig(r.x_peak_ours_m * 1e6, 6),
                fmt_sig(r.cf_ours * 100.0, 3),
                r.ours_steps,
                fmt_sig(r.ours_s, 2),
                if r.impacting {
                    format!(
                        " Ours from rest at the same drive (the lower branch where the drive is \
                         bistable): V1 = {} V.",
                        fmt_sig(r.v1_ours_from_rest, 4)
                    )
                } else {
                    String::new()
                },
            ));
        }
        let verdict = if r.documented {
            format!("**{}**", r.status)
        } else {
            r.status.clone()
        };
        md.push_str(&format!(
            "| {}: `{}` | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            r.setting_label,
            r.settings_text,
            fmt_sig(r.v1_spice, 7),
            fmt_sig(r.v2_spice, 7),
            sci(r.rel_diff),
            fmt_sig(r.x_peak_spice_m * 1e6, 6),
            fmt_sig(r.cf_spice * 100.0, 3),
            r.spice_points,
            fmt_sig(r.spice_s, 2),
            verdict,
        ));
    }
    // Speed: ngspice at the documented settings against ours over the same span, measured in
    // this run (ngspice's time includes starting the process and writing its output).
    let mut ratios: Vec<f64> = rows
        .iter()
        .filter(|r| r.documented && r.spice_s.is_finite() && r.ours_s > 0.0)
        .map(|r| r.spice_s / r.ours_s)
        .collect();
    ratios.sort_by(f64::total_cmp);
    if let (Some(lo), Some(hi)) = (ratios.first(), ratios.last()) {
        md.push_str(&format!(
            "\n**Speed.** Over the same span, ngspice at the documented settings took {} times \
             as long as ours (median of the {} cases; from {} to {}).\n",
            fmt_sig(ratios[ratios.len() / 2], 3),
            ratios.len(),
            fmt_sig(*lo, 3),
            fmt_sig(*hi, 3),
        ));
    }
    md
}

fn sci(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.1e}")
    } else {
        "-".into()
    }
}

fn rows_df(rows: &[Row]) -> Result<DataFrame> {
    let s = |f: fn(&Row) -> String| rows.iter().map(f).collect::<Vec<String>>();
    let x = |f: fn(&Row) -> f64| rows.iter().map(f).collect::<Vec<f64>>();
    Ok(df!(
        "case" => s(|r| r.case.clone()),
        "case_label" => s(|r| r.case_label.clone()),
        "device" => s(|r| r.device.clone()),
        "stiffness" => s(|r| r.stiffness.clone()),
        "bim_n_s_per_m" => x(|r| r.bim),
        "bias_v" => x(|r| r.bias_v),
        "accel_rms_g" => x(|r| r.accel_rms_g),
        "freq_hz" => x(|r| r.freq_hz),
        "start" => s(|r| r.start.clone()),
        "setting" => s(|r| r.setting.clone()),
        "setting_label" => s(|r| r.setting_label.clone()),
        "documented" => rows.iter().map(|r| r.documented).collect::<Vec<bool>>(),
        "ngspice_options" => s(|r| r.settings_text.clone()),
        "span_s" => x(|r| r.span_s),
        "window_s" => x(|r| r.window_s),
        "v1_rms_ours_v" => x(|r| r.v1_ours),
        "v2_rms_ours_v" => x(|r| r.v2_ours),
        "v1_rms_spice_v" => x(|r| r.v1_spice),
        "v2_rms_spice_v" => x(|r| r.v2_spice),
        "rel_diff_v1" => x(|r| r.rel_diff_v1),
        "rel_diff_v2" => x(|r| r.rel_diff_v2),
        "rel_diff" => x(|r| r.rel_diff),
        "x_peak_ours_m" => x(|r| r.x_peak_ours_m),
        "x_peak_spice_m" => x(|r| r.x_peak_spice_m),
        "contact_fraction_ours" => x(|r| r.cf_ours),
        "contact_fraction_spice" => x(|r| r.cf_spice),
        "v1_rms_ours_from_rest_v" => x(|r| r.v1_ours_from_rest),
        "ours_s" => x(|r| r.ours_s),
        "ours_steps" => rows.iter().map(|r| r.ours_steps).collect::<Vec<u64>>(),
        "spice_s" => x(|r| r.spice_s),
        "spice_points_in_window" => rows.iter().map(|r| r.spice_points as u64).collect::<Vec<u64>>(),
        "tolerance" => x(|r| r.tolerance),
        "status" => s(|r| r.status.clone()),
        "params" => s(|_| "published".to_string()),
    )?)
}
