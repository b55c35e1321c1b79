//! The cross-check's run (the comparison itself is `endstop::paper::crosscheck`):
//! for every case and ngspice setting, writes the netlist, takes ngspice's numbers for it (from
//! the recording `data/recorded/ngspice/crosscheck.json` where it holds that netlist, else from
//! a run of ngspice in batch mode; `--fresh-ngspice` runs ngspice for every netlist and checks
//! the recording, `--record-ngspice` rewrites it) and has the paper layer judge them against
//! our integrator; writes the table, the portable netlists, the plot and the book's numbers.
//! The run fails (non-zero exit) if a netlist has neither a recording nor ngspice to run it,
//! if a fresh run disagrees with the recording, or if the documented settings miss the
//! acceptance tolerances (0.1 % without impacts, 1 % with impacts).

use std::collections::BTreeMap;
use std::time::Instant;

use super::{numbers_md, rows_df, waveform_plot, Row};
use crate::io::plot::{Series, Style, PALETTE};
use crate::ngspice::{Reading, Reduced, Runner, Source};
use crate::{fmt_sig, write_atomic, Experiment};
use anyhow::{bail, Result};
use endstop::paper::crosscheck::{
    acceptance_failures, cases, prepare, Case, Difference, Ours, Prepared, Setting, SpiceRun,
    Verdict, BOOK_CASE, SETTINGS,
};
use endstop::paper::setups::{comb, endstop, stiffness_model, ParamSet};

/// Our side of a case as the rows report it.
struct OursRun<'a> {
    prepared: &'a Prepared,
    ours: &'a Ours,
    /// Wall time of our steady state (s).
    seconds: f64,
    /// V1 from rest at the same drive (V).
    v1_from_rest: f64,
}

/// The row of a setting before ngspice has run.
fn new_row(o: &OursRun, setting: Setting) -> Row {
    let case = &o.prepared.case;
    let dev = &case.device;
    let m = &o.ours.measurement;
    Row {
        case: case.key.to_string(),
        case_label: case.label.to_string(),
        device: dev.name.clone(),
        stiffness: format!("{:?}", stiffness_model(dev)).to_lowercase(),
        bim: endstop(dev).damping_n_s_per_m,
        bias_v: comb(dev).bias_v,
        accel_rms_g: case.accel_rms_g,
        freq_hz: case.freq_hz,
        start: o.prepared.start_label.clone(),
        setting: setting.key().to_string(),
        setting_kind: setting,
        setting_label: setting.label().to_string(),
        documented: setting.documented(),
        settings_text: setting.text(case.period_s()),
        span_s: o.ours.t_end_s,
        window_s: o.ours.window_length_s(),
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
        v1_ours_from_rest: o.v1_from_rest,
        ours_s: o.seconds,
        ours_steps: o.ours.stats.accepted,
        spice_s: f64::NAN,
        spice_recorded: false,
        spice_points: 0,
        tolerance: case.tolerance(),
        impacting: case.impacting,
        verdict: Verdict::NotYet,
        failure: Some("not run".into()),
    }
}

/// Fills in ngspice's run and the verdict.
fn judge(row: &mut Row, spice: &SpiceRun, ours: &Ours, reading: &Reading) {
    let d = Difference::of(&ours.measurement, spice);
    row.v1_spice = spice.v1_rms_v;
    row.v2_spice = spice.v2_rms_v;
    row.rel_diff_v1 = d.rel_v1;
    row.rel_diff_v2 = d.rel_v2;
    row.rel_diff = d.rel;
    row.x_peak_spice_m = spice.x_peak_m;
    row.cf_spice = spice.contact_fraction;
    row.spice_s = reading.run.wall_s;
    row.spice_recorded = reading.recorded;
    row.spice_points = spice.points;
    row.verdict = d.verdict(row.tolerance);
    row.failure = None;
}

/// Where ngspice's numbers for the cross-check are recorded.
const RECORDING: &str = "data/recorded/ngspice/crosscheck.json";

/// Runs the cross-check (`cargo run --release --bin crosscheck [-- --fresh-ngspice |
/// --record-ngspice]`): see the module docs.
pub fn run() -> Result<()> {
    let source = Source::from_args("crosscheck")?;
    let mut exp = Experiment::start("crosscheck");
    let p1 = exp.load_published("prototype1")?;
    let p2 = exp.load_published("prototype2")?;
    let mut spice = Runner::new(
        source,
        RECORDING,
        "ngspice's numbers for the cross-check: for each netlist (its name: case and \
         setting; the netlist itself is the one `crosscheck` writes, identified by its \
         SHA-256), the RMS voltages, peak displacement, time in contact and points over the \
         comparison window, or the storage's mean voltage and DC power of a bridge case, as \
         `crosscheck` reads them off the waveforms ngspice writes, and the wall time of the run",
        "cargo run --release --bin crosscheck -- --record-ngspice",
    )?;

    let mut rows: Vec<Row> = Vec::new();
    let mut plot_series: Vec<Series> = Vec::new();
    for case in cases(&p1.device, &p2.device) {
        let (case_rows, series) = run_case(&mut exp, &mut spice, &case)?;
        rows.extend(case_rows);
        plot_series.extend(series);
    }
    let keys: Vec<&str> = cases(&p1.device, &p2.device)
        .iter()
        .map(|c| c.key)
        .collect();
    let verdicts: Vec<(&str, Setting, Verdict)> = rows
        .iter()
        .map(|r| (r.case.as_str(), r.setting_kind, r.verdict))
        .collect();
    let failures = acceptance_failures(&keys, &verdicts);

    let (bridge_table, bridge_failures) = bridge_cases(&mut exp, &mut spice)?;
    write_atomic(&exp.book_dir.join("bridge.md"), bridge_table.as_bytes())?;
    let mut failures = failures;
    failures.extend(bridge_failures);

    let version = spice.version()?;
    eprintln!("[crosscheck] ngspice: {version}");
    spice.finish()?;
    exp.write_numbers_md(&numbers_md(&rows, &version))?;
    let mut df = rows_df(&rows)?;
    exp.write_parquet("crosscheck", &mut df, ParamSet::Published.label())?;
    exp.write_plot(&waveform_plot(plot_series))?;
    exp.finish()?;
    if !failures.is_empty() {
        bail!(
            "the documented ngspice settings miss the acceptance tolerance:\n  {}",
            failures.join("\n  ")
        );
    }
    Ok(())
}

/// Runs one case under every setting: its rows, and for the book's case the plot's series
/// (ours first, then ngspice's defaults and documented settings).
fn run_case(
    exp: &mut Experiment,
    spice: &mut Runner,
    case: &Case,
) -> Result<(Vec<Row>, Vec<Series>)> {
    let prepared = prepare(case)?;
    let started = Instant::now();
    let ours = prepared.ours()?;
    let seconds = started.elapsed().as_secs_f64();
    let v1_from_rest = prepared.v1_from_rest(&ours)?;
    let m = &ours.measurement;
    eprintln!(
        "[crosscheck] {}: ours V1 = {:.6} V over {} periods in {:.3} s",
        case.key,
        m.v1_rms_v,
        (ours.t_end_s * case.freq_hz).round(),
        seconds
    );
    let o = OursRun {
        prepared: &prepared,
        ours: &ours,
        seconds,
        v1_from_rest,
    };
    let mut rows = Vec::new();
    let mut series = Vec::new();
    for setting in SETTINGS {
        let (row, reading) = run_setting(exp, spice, &o, setting)?;
        eprintln!(
            "[crosscheck]   {:<24} V1 {:>10} V  rel diff {:>10}  ngspice {:.2} s  ({})",
            row.setting,
            fmt_sig(row.v1_spice, 7),
            fmt_sig(row.rel_diff, 2),
            row.spice_s,
            row.verdict_label()
        );
        exp.number(
            &format!("rel_diff_{}_{}", case.key, setting.key()),
            row.rel_diff,
        );
        exp.number(
            &format!("v1_rms_spice_{}_{}_v", case.key, setting.key()),
            row.v1_spice,
        );
        if let (Some((spice, reading)), true) = (reading, case.key == BOOK_CASE) {
            series.extend(spice_series(&o, setting, &spice, &reading));
        }
        rows.push(row);
    }
    exp.number(&format!("v1_rms_ours_{}_v", case.key), m.v1_rms_v);
    exp.number(
        &format!("v1_rms_ours_from_rest_{}_v", case.key),
        v1_from_rest,
    );
    if case.key == BOOK_CASE {
        let pts = prepared.last_period(&ours, 400)?;
        series.insert(
            0,
            Series::new(
                "ours (Dormand-Prince, events)",
                pts,
                PALETTE[0],
                Style::Line,
            ),
        );
    }
    Ok((rows, series))
}

/// Runs one setting of a case: writes, for the documented settings, the portable netlist a
/// user would run, takes ngspice's numbers for the setting's netlist and judges them.
fn run_setting(
    exp: &Experiment,
    spice: &mut Runner,
    o: &OursRun,
    setting: Setting,
) -> Result<(Row, Option<(SpiceRun, Reading)>)> {
    let case = &o.prepared.case;
    let stem = format!("{}_{}", case.key, setting.key());
    let text = o.prepared.netlist(o.ours, setting, format!("{stem}.dat"));
    if setting.documented() {
        // The netlist as a user would run it (`ngspice -b <case>.cir`), writing `<case>.dat`
        // beside it.
        let portable = o
            .prepared
            .netlist(o.ours, setting, format!("{}.dat", case.key));
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
    let mut row = new_row(o, setting);
    let gap = endstop(&case.device).gap_m;
    let plotted =
        case.key == BOOK_CASE && matches!(setting, Setting::Documented | Setting::Defaults);
    let (period, t1) = (case.period_s(), o.ours.window_s.1);
    let reading = spice.run(&stem, &text, &format!("{stem}.dat"), |text| {
        let (run, w) = SpiceRun::read_wrdata(text, gap, o.ours.window_s)?;
        let series = if plotted {
            w.time
                .iter()
                .zip(w.column("v(n1)")?)
                .filter(|(t, _)| **t >= t1 - period && **t <= t1)
                .map(|(t, v)| (*t, *v))
                .collect()
        } else {
            Vec::new()
        };
        Ok(reduce(&run, series))
    });
    match reading {
        Ok(reading) => {
            let run = spice_run(&reading)?;
            judge(&mut row, &run, o.ours, &reading);
            Ok((row, Some((run, reading))))
        }
        Err(e) => {
            row.verdict = Verdict::NotYet;
            row.failure = Some(format!("{e:#}"));
            Ok((row, None))
        }
    }
}

/// The numbers the cross-check reads off one ngspice run (what the recording keeps).
fn reduce(run: &SpiceRun, series: Vec<(f64, f64)>) -> Reduced {
    let values = BTreeMap::from([
        ("v1_rms_v".to_string(), run.v1_rms_v),
        ("v2_rms_v".to_string(), run.v2_rms_v),
        ("x_peak_m".to_string(), run.x_peak_m),
        ("contact_fraction".to_string(), run.contact_fraction),
        ("points_in_window".to_string(), run.points as f64),
    ]);
    (values, series)
}

/// The run [`reduce`] kept, as the paper layer judges it.
fn spice_run(reading: &Reading) -> Result<SpiceRun> {
    let v = |k: &str| {
        reading
            .run
            .values
            .get(k)
            .copied()
            .ok_or_else(|| anyhow::anyhow!("ngspice's numbers lack `{k}`"))
    };
    Ok(SpiceRun {
        v1_rms_v: v("v1_rms_v")?,
        v2_rms_v: v("v2_rms_v")?,
        x_peak_m: v("x_peak_m")?,
        contact_fraction: v("contact_fraction")?,
        points: v("points_in_window")? as usize,
    })
}

/// ngspice's V1 over the last period of the book's case, for the defaults and the documented
/// settings (none for the others).
fn spice_series(
    o: &OursRun,
    setting: Setting,
    spice: &SpiceRun,
    reading: &Reading,
) -> Option<Series> {
    let (color, style, label) = match setting {
        Setting::Documented => (PALETTE[1], Style::Dashed, "ngspice, documented settings"),
        Setting::Defaults => {
            let fell = spice.contact_fraction == 0.0 && o.ours.measurement.contact_fraction > 0.0;
            let label = if fell {
                "ngspice, defaults (no impacts left: the lower branch)"
            } else {
                "ngspice, defaults"
            };
            (PALETTE[2], Style::Line, label)
        }
        _ => return None,
    };
    let period = o.prepared.case.period_s();
    let t1 = o.ours.window_s.1;
    let pts: Vec<(f64, f64)> = reading
        .run
        .series
        .iter()
        .map(|(t, v)| ((t - (t1 - period)) / period, *v))
        .collect();
    Some(Series::new(label, pts, color, style))
}

/// The diode-bridge cases (`endstop::spice::bridge::BRIDGE_CASES`): ngspice from our steady
/// state's section for ten periods, the storage's mean voltage and the load's mean power over
/// the last one against ours. Returns the book's table and the cases outside tolerance.
fn bridge_cases(exp: &mut Experiment, spice: &mut Runner) -> Result<(String, Vec<String>)> {
    use endstop::drive::Sine;
    use endstop::num::compare::{Comparison, Measure};
    use endstop::spice::bridge::{
        bridge_netlist, bridge_solver, dc_means, BRIDGE_CASES, BRIDGE_PERIODS,
    };
    use endstop::study::periodic::{steady_state_from_rest, SteadySettings};

    let mut t = crate::io::md::Table::new([
        "device",
        "quantity",
        "ours",
        "ngspice",
        "relative difference",
        "tolerance",
    ]);
    let mut failures = Vec::new();
    for case in BRIDGE_CASES {
        let name = case
            .file
            .trim_start_matches("data/")
            .trim_end_matches(".toml");
        let loaded = crate::load_device(name)?;
        let set = loaded.device.params.clone();
        exp.uses(&loaded, &set);
        let d = loaded.device;
        let f = d.suspension_omega_rad_s() / (2.0 * std::f64::consts::PI);
        let sine = Sine::from_rms_g(case.accel_rms_g, f);
        let ours = steady_state_from_rest(&d, sine, &SteadySettings::default())?;
        let (t0, t1) = ((BRIDGE_PERIODS - 1.0) / f, BRIDGE_PERIODS / f);
        let dat_name = format!("{}.dat", d.name);
        let net = bridge_netlist(
            &d,
            sine.amplitude_m_s2,
            f,
            &endstop::study::periodic::state_of::<4>(&ours),
            t1,
            t0,
            &bridge_solver(f),
            &dat_name,
        )?;
        let r = match d.interface.load() {
            Some(endstop::device::DcLoad::Resistor { resistance_ohm }) => *resistance_ohm,
            _ => bail!("{name}: the bridge cross-check takes a resistor load"),
        };
        let reading = spice.run(&d.name, &net, &dat_name, |text| {
            let (v, p) = dc_means(&endstop::spice::parse_wrdata(text)?, r, t0, t1)?;
            let values = BTreeMap::from([("vdc_v".to_string(), v), ("p_dc_w".to_string(), p)]);
            Ok((values, Vec::new()))
        })?;
        let (v, p) = (reading.run.values["vdc_v"], reading.run.values["p_dc_w"]);
        for (q, o, s) in [
            ("mean V_s (V)", ours.vdc_v, v),
            ("mean DC power (W)", ours.p_dc_w, p),
        ] {
            let c = Comparison {
                ours: o,
                reference: s,
                measure: Measure::RelativeToOurs,
                tolerance: case.tolerance,
            };
            let rel = c.difference();
            if !c.within() {
                failures.push(format!(
                    "{name} {q}: relative difference {rel:e} > {}",
                    case.tolerance
                ));
            }
            t.row([
                format!(
                    "`{}`{}",
                    case.file,
                    if ours.contact {
                        " (strikes its stop)"
                    } else {
                        ""
                    }
                ),
                q.to_string(),
                fmt_sig(o, 6),
                fmt_sig(s, 6),
                format!("{rel:.1e}"),
                format!("{:.0e}: {}", case.tolerance, case.reason),
            ]);
        }
    }
    Ok((t.render(), failures))
}
