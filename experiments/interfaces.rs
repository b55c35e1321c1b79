//! From the harvester to the battery: the example devices `data/examples/piezo_bridge.toml`
//! (a piezoelectric cantilever with a stop) and `data/examples/em_bridge.toml` (an
//! electromagnetic harvester with stops) behind each interface circuit. Writes the DC power
//! against the load for every interface, the DC power against frequency with each steady
//! state's stability, random ensembles, a charging curve and the energy ledger of each
//! interface, as Parquet, plots and the chapter's generated tables
//! (`book/src/generated/interfaces/`). The cost of a record behind an interface against the
//! resistive load is measured by the benchmark (`bench`, `experiments/bench/interfaces.rs`).

use endstop_experiments as common;

use anyhow::Result;
use common::io::frame::frame;
use common::io::md::Table;
use common::io::plot::{LegendPos, LinePlot, Series, Style, PALETTE};
use common::{fmt_sig, row, write_atomic, Experiment};
use endstop::device::{Device, Interface, Inversion, Rectifier};
use endstop::drive::noise::NoiseSpec;
use endstop::drive::Sine;
use endstop::progress::Silent;
use endstop::study::interface::charging::{charge, ChargeSettings};
use endstop::study::interface::record::noise_ensemble;
use endstop::study::interface::sweep::{frequency_sweep, load_sweep};
use endstop::study::interface::{IfSteady, SteadyMethod, SteadySettings};
use endstop::study::record::{RecordSpec, Scheme, DEFAULT_RTOL};
use endstop::study::stepped::linspace_step;

fn main() {
    common::run_main("interfaces", run);
}

/// The drive of the chapter's sine studies (g rms).
const ACCEL_RMS_G: f64 = 0.3;
/// Seed of the random ensembles.
const SEED: u64 = 33;

fn variants(d: &Device) -> Vec<(&'static str, Device)> {
    let Interface::FullBridge(r) = &d.interface else {
        return vec![("full_bridge", d.clone())];
    };
    let with = |i: Interface| {
        let mut x = d.clone();
        x.interface = i;
        x
    };
    let q = Inversion::QualityFactor(3.0);
    let mut v = vec![("full_bridge", d.clone())];
    if matches!(d.transducer, endstop::device::Transducer::Piezoelectric(_)) {
        v.push(("parallel_sshi", with(Interface::ParallelSshi(r.clone(), q))));
        v.push(("series_sshi", with(Interface::SeriesSshi(r.clone(), q))));
        v.push((
            "sece",
            with(Interface::Sece {
                storage_capacitance_f: r.storage_capacitance_f,
                load: r.load.clone(),
                efficiency: 0.8,
            }),
        ));
    }
    v
}

fn resonance_hz(d: &Device) -> f64 {
    d.suspension_omega_rad_s() / (2.0 * std::f64::consts::PI)
}

fn run() -> Result<()> {
    let mut exp = Experiment::start("interfaces");
    exp.seed = Some(SEED);
    let piezo = common::load_device("examples/piezo_bridge")?;
    let em = common::load_device("examples/em_bridge")?;
    let resistive = common::load_device("examples/piezo_cantilever")?;
    for d in [&piezo, &em, &resistive] {
        let set = d.device.params.clone();
        exp.uses(d, &set);
    }
    let settings = SteadySettings::default();
    let book = exp.book_dir.clone();

    // DC power against the load at resonance, every interface, and the resistive load.
    let loads: Vec<f64> = (0..13)
        .map(|i| 10f64.powf(3.0 + 0.333_333 * i as f64))
        .collect();
    let f0 = resonance_hz(&piezo.device);
    let sine = Sine::from_rms_g(ACCEL_RMS_G, f0);
    let mut rows = Vec::new();
    let mut series = Vec::new();
    let mut missing: Vec<String> = Vec::new();
    let mut best = Table::new([
        "interface",
        "best load (ohm)",
        "largest DC power (uW)",
        "V_DC there (V)",
        "stops struck",
    ]);
    for (k, (name, d)) in variants(&piezo.device).into_iter().enumerate() {
        eprintln!("[interfaces] load sweep, {name}");
        let found: Vec<(f64, IfSteady)> = loads
            .iter()
            .zip(load_sweep(&d, &loads, sine, &settings, &Silent))
            .filter_map(|(r, s)| match s {
                Ok(s) => Some((*r, s)),
                Err(e) => {
                    missing.push(format!("{name} at {} ohm ({e})", fmt_sig(*r, 3)));
                    None
                }
            })
            .collect();
        for (r, s) in &found {
            rows.push(row!["interface" => name, "load_ohm" => *r, "p_dc_w" => s.p_dc_w, "vdc_v" => s.vdc_v, "contact" => s.contact, "stable" => s.is_stable()]);
        }
        let Some((rbest, s)) = found
            .iter()
            .max_by(|a, b| a.1.p_dc_w.total_cmp(&b.1.p_dc_w))
        else {
            continue;
        };
        best.row([
            name.to_string(),
            fmt_sig(*rbest, 3),
            fmt_sig(s.p_dc_w * 1e6, 4),
            fmt_sig(s.vdc_v, 4),
            s.contact.to_string(),
        ]);
        series.push(Series::new(
            name,
            found.iter().map(|(r, s)| (*r, s.p_dc_w * 1e6)).collect(),
            PALETTE[k],
            Style::LinePoints,
        ));
    }
    // The resistive load: the same cantilever's average load power.
    let mut res_pts = Vec::new();
    for &r in &loads {
        let d = resistive
            .device
            .with_param("transducer.load_resistance_ohm", r)?;
        let st = endstop::study::sweep::SweepSettings::for_device(&d, vec![f0], 0.1).run(
            &d,
            ACCEL_RMS_G,
            &Silent,
        )?;
        let m = st.measurements().next().expect("one frequency");
        rows.push(row!["interface" => "resistive", "load_ohm" => r, "p_dc_w" => m.p1_w, "vdc_v" => m.v1_rms_v, "contact" => m.contact_fraction > 0.0, "stable" => true]);
        res_pts.push((r, m.p1_w * 1e6));
    }
    let (ri, rp) = res_pts
        .iter()
        .enumerate()
        .max_by(|a, b| a.1 .1.total_cmp(&b.1 .1))
        .map(|(i, p)| (i, p.1))
        .expect("loads");
    best.row([
        "resistive (AC, for reference)".into(),
        fmt_sig(loads[ri], 3),
        fmt_sig(rp, 4),
        "-".into(),
        "-".into(),
    ]);
    series.push(Series::new(
        "resistive (AC)",
        res_pts,
        PALETTE[5],
        Style::Dashed,
    ));
    exp.write_parquet("power_vs_load", &mut frame(rows)?, &piezo.device.params)?;
    exp.write_extra_plot(
        "interfaces_load",
        &LinePlot::new(
            &format!(
                "Piezoelectric cantilever at {} Hz, {ACCEL_RMS_G} g rms",
                fmt_sig(f0, 4)
            ),
            "DC load [ohm]",
            "DC power [uW]",
            series,
        )
        .log(true, false)
        .legend(LegendPos::UpperRight),
    )?;
    let mut md = best.render();
    if !missing.is_empty() {
        md.push_str(&format!(
            "\nNo period-one steady state (shooting did not converge; the response there may be \
             of a longer period or not periodic): {}.\n",
            missing.join("; ")
        ));
    }
    write_atomic(&book.join("power_vs_load.md"), md.as_bytes())?;

    // DC power against frequency with stability, for both examples.
    let mut missing_f: Vec<String> = Vec::new();
    let mut by_map: Vec<String> = Vec::new();
    let mut rows = Vec::new();
    let mut plots = Vec::new();
    for (dev, from, to) in [(&piezo, 110.0, 130.0), (&em, 44.0, 56.0)] {
        let d = &dev.device;
        let freqs = linspace_step(from, to, 0.5);
        eprintln!("[interfaces] frequency sweep, {}", d.name);
        let states: Vec<IfSteady> = freqs
            .iter()
            .zip(frequency_sweep(d, &freqs, ACCEL_RMS_G, &settings, &Silent))
            .filter_map(|(f, s)| match s {
                Ok(s) => Some(s),
                Err(e) => {
                    missing_f.push(format!("{} at {} Hz ({e})", d.name, fmt_sig(*f, 4)));
                    None
                }
            })
            .collect();
        for s in &states {
            rows.push(row!["device" => d.name.clone(), "freq_hz" => s.freq_hz, "p_dc_w" => s.p_dc_w, "vdc_v" => s.vdc_v, "x_max_m" => s.x_peak_m, "contact" => s.contact, "stable" => s.is_stable(), "max_multiplier" => s.max_multiplier, "method" => s.method.label(), "ledger_rel_residual" => s.ledger.relative_residual()]);
            if let SteadyMethod::PeriodMap { periods } = s.method {
                by_map.push(format!(
                    "{} at {} Hz ({periods} periods)",
                    d.name,
                    fmt_sig(s.freq_hz, 4)
                ));
            }
        }
        let pts = |stable: bool| {
            states
                .iter()
                .filter(|s| s.is_stable() == stable)
                .map(|s| (s.freq_hz, s.p_dc_w * 1e6))
                .collect::<Vec<_>>()
        };
        plots.push(
            LinePlot::new(
                &format!("{}: DC power, up-sweep", d.name),
                "frequency [Hz]",
                "DC power [uW]",
                vec![
                    Series::new("stable", pts(true), PALETTE[0], Style::LinePoints),
                    Series::new("unstable", pts(false), PALETTE[1], Style::Points),
                ],
            )
            .legend(LegendPos::UpperLeft),
        );
    }
    exp.write_parquet("power_vs_frequency", &mut frame(rows)?, "hypothetical")?;
    for (i, p) in plots.iter().enumerate() {
        exp.write_extra_plot(&format!("interfaces_frequency_{i}"), p)?;
    }
    write_atomic(
        &book.join("frequency_missing.md"),
        {
            let mut md = if missing_f.is_empty() {
                "A period-one steady state was found at every frequency.\n".to_string()
            } else {
                format!("No period-one steady state at: {}.\n", missing_f.join("; "))
            };
            if !by_map.is_empty() {
                md.push_str(&format!(
                    "\nNewton's method did not converge, and the period map iterated from the \
                     transient's end did, at: {}.\n",
                    by_map.join("; ")
                ));
            }
            md
        }
        .as_bytes(),
    )?;

    // The energy ledger over one steady period, per interface.
    let mut t = Table::new([
        "device",
        "interface",
        "drive (uJ)",
        "damping",
        "contact",
        "coil",
        "diodes",
        "switch",
        "DC load",
        "stored change",
        "relative residual",
    ]);
    for (dev, f) in [(&piezo, f0), (&em, resonance_hz(&em.device))] {
        for (name, d) in variants(&dev.device) {
            let s = endstop::study::interface::steady_state(
                &d,
                Sine::from_rms_g(ACCEL_RMS_G, f),
                &endstop::physics::harvester::State::zeros(),
                &settings,
            );
            let s = match s {
                Ok(s) => s,
                Err(e) => {
                    t.row([
                        d.name.clone(),
                        name.into(),
                        format!("no period-one steady state: {e}"),
                        "".into(),
                        "".into(),
                        "".into(),
                        "".into(),
                        "".into(),
                        "".into(),
                        "".into(),
                        "".into(),
                    ]);
                    continue;
                }
            };
            let l = s.ledger;
            let u = |x: f64| fmt_sig(x * 1e6, 4);
            t.row([
                d.name.clone(),
                name.into(),
                u(l.excitation),
                u(l.mech_damping),
                u(l.contact),
                u(l.coil),
                u(l.diode),
                u(l.switching),
                u(l.dc_load),
                u(l.stored_change),
                format!("{:.1e}", l.relative_residual()),
            ]);
        }
    }
    write_atomic(&book.join("ledger.md"), t.render().as_bytes())?;

    // Charging an open storage from 0 V, drive ramped over 20 periods.
    let mut open = piezo.device.clone();
    if let Interface::FullBridge(r) = &mut open.interface {
        *r = Rectifier {
            load: endstop::device::DcLoad::Open,
            ..r.clone()
        };
    }
    let cs = ChargeSettings {
        start_v: 0.0,
        target_v: 5.0,
        ramp_s: 20.0 / f0,
        t_max_s: 60.0,
        sample_s: 1e-3,
        block_s: 0.5,
        rtol: 1e-8,
    };
    let run = common::with_progress(100, "charging (% of 5 V)", |p| {
        charge(&open, Sine::from_rms_g(ACCEL_RMS_G, f0), &cs, p)
    })?;
    exp.number("charge_time_to_5v_s", run.time_to_target_s);
    exp.write_parquet(
        "charging",
        &mut frame(
            run.t_s
                .iter()
                .zip(&run.vs_v)
                .map(|(&t, &v)| row!["t_s" => t, "vs_v" => v]),
        )?,
        "hypothetical",
    )?;
    exp.write_extra_plot(
        "interfaces_charging",
        &LinePlot::new(
            "Charging 10 uF from 0 V, full bridge",
            "time [s]",
            "V_s [V]",
            vec![Series::new(
                "V_s",
                run.t_s
                    .iter()
                    .copied()
                    .zip(run.vs_v.iter().copied())
                    .collect(),
                PALETTE[0],
                Style::Line,
            )],
        )
        .legend(LegendPos::LowerRight),
    )?;
    write_atomic(&book.join("charging.md"), format!("With the drive ramped up over 20 periods from rest at phase zero, the 10 uF storage of `piezo_bridge.toml` (load removed) reaches 5 V after **{} s** at {} Hz, {ACCEL_RMS_G} g rms.\n", fmt_sig(run.time_to_target_s, 4), fmt_sig(f0, 4)).as_bytes())?;

    // Random ensembles (the cost of a record against the resistive load is the benchmark's).
    let spec = |secs: f64| RecordSpec {
        noise: NoiseSpec {
            duration_s: secs,
            ..endstop::paper::setups::paper_noise(1e-4)
        },
        transient_s: 1.0,
        rtol: DEFAULT_RTOL,
        scheme: Scheme::Exponential,
    };
    let mut t = Table::new([
        "interface",
        "records",
        "mean DC power (uW)",
        "mean efficiency",
        "largest relative ledger residual",
    ]);
    let mut rows = Vec::new();
    for (name, d) in variants(&piezo.device) {
        eprintln!("[interfaces] ensemble, {name}");
        let ens = noise_ensemble(&d, &spec(2.0), SEED, 8)?;
        let n = ens.len() as f64;
        for (k, r) in ens.iter().enumerate() {
            rows.push(row!["interface" => name, "stream" => k, "p_dc_w" => r.p_dc_w, "p_drive_w" => r.p_drive_w, "vdc_v" => r.vdc_v]);
        }
        t.row([
            name.into(),
            ens.len().to_string(),
            fmt_sig(ens.iter().map(|r| r.p_dc_w).sum::<f64>() / n * 1e6, 4),
            fmt_sig(ens.iter().map(|r| r.efficiency()).sum::<f64>() / n, 3),
            format!(
                "{:.1e}",
                ens.iter()
                    .map(|r| r.ledger.relative_residual().abs())
                    .fold(0.0, f64::max)
            ),
        ]);
    }
    exp.write_parquet("ensembles", &mut frame(rows)?, "hypothetical")?;
    write_atomic(&book.join("ensembles.md"), t.render().as_bytes())?;

    exp.write_numbers_md("The interface circuits' chapter data.\n")?;
    exp.finish()
}
