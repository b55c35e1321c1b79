//! The interfaces' steady states: the DC power against the load at resonance (with the
//! resistive load for reference), the DC power against frequency with each state's stability,
//! and the energy ledger over one steady period.

use anyhow::Result;
use endstop::drive::Sine;
use endstop::progress::Silent;
use endstop::study::periodic::{
    frequency_sweep, load_sweep, steady_state_from_rest, PeriodicState, SteadyMethod,
    SteadySettings,
};
use endstop::study::stepped::linspace_step;

use super::{resonance_hz, variants, ACCEL_RMS_G, SECE_EFFICIENCY, SSHI_Q};
use crate::io::frame::frame;
use crate::io::md::Table;
use crate::io::plot::{LegendPos, LinePlot, Series, Style, PALETTE};
use crate::{fmt_sig, row, write_atomic, Experiment, LoadedDevice};

/// The DC power against the load at resonance, every interface, and the resistive load.
pub(super) fn power_vs_load(
    exp: &mut Experiment,
    piezo: &LoadedDevice,
    resistive: &LoadedDevice,
    settings: &SteadySettings,
) -> Result<()> {
    let f0 = resonance_hz(&piezo.device);
    let loads: Vec<f64> = (0..13)
        .map(|i| 10f64.powf(3.0 + 0.333_333 * i as f64))
        .collect();
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
        let found: Vec<(f64, PeriodicState)> = loads
            .iter()
            .zip(load_sweep(&d, &loads, sine, settings, &Silent))
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
    let mut md = format!(
        "At the resonance, {} Hz, and {ACCEL_RMS_G} g rms; SSHI inverts with Q = {SSHI_Q}, SECE \
         extracts with an efficiency of {SECE_EFFICIENCY}.\n\n{}",
        fmt_sig(f0, 4),
        best.render()
    );
    if !missing.is_empty() {
        md.push_str(&format!(
            "\nNo period-one steady state (shooting did not converge; the response there may be \
             of a longer period or not periodic): {}.\n",
            missing.join("; ")
        ));
    }
    write_atomic(&exp.book_dir.join("power_vs_load.md"), md.as_bytes())?;

    Ok(())
}

/// The DC power against frequency with stability, for both examples behind every interface
/// they take ([`variants`]).
pub(super) fn power_vs_frequency(
    exp: &mut Experiment,
    piezo: &LoadedDevice,
    em: &LoadedDevice,
    settings: &SteadySettings,
) -> Result<()> {
    let mut missing_f: Vec<String> = Vec::new();
    let mut by_map: Vec<String> = Vec::new();
    // Steady states found, and how many of them are unstable.
    let (mut found, mut unstable_n) = (0usize, 0usize);
    let mut rows = Vec::new();
    let mut plots = Vec::new();
    for (dev, from, to) in [(piezo, 110.0, 130.0), (em, 44.0, 56.0)] {
        let freqs = linspace_step(from, to, 0.5);
        let mut series = Vec::new();
        for (k, (name, d)) in variants(&dev.device).into_iter().enumerate() {
            eprintln!("[interfaces] frequency sweep, {}, {name}", d.name);
            let states: Vec<PeriodicState> = freqs
                .iter()
                .zip(frequency_sweep(&d, &freqs, ACCEL_RMS_G, settings, &Silent)?)
                .filter_map(|(f, s)| match s {
                    Ok(s) => Some(s),
                    Err(e) => {
                        missing_f.push(format!(
                            "{}, {name} at {} Hz ({e})",
                            d.name,
                            fmt_sig(*f, 4)
                        ));
                        None
                    }
                })
                .collect();
            for s in &states {
                rows.push(row!["device" => d.name.clone(), "interface" => name, "freq_hz" => s.freq_hz, "p_dc_w" => s.p_dc_w, "vdc_v" => s.vdc_v, "x_max_m" => s.x_peak_m, "contact" => s.contact, "stable" => s.is_stable(), "max_multiplier" => s.max_multiplier, "method" => s.method.label(), "ledger_rel_residual" => s.ledger.relative_residual()]);
                if let SteadyMethod::PeriodMap { periods } = s.method {
                    by_map.push(format!(
                        "{}, {name} at {} Hz ({periods} periods)",
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
            let c = PALETTE[k % PALETTE.len()];
            series.push(Series::new(name, pts(true), c, Style::LinePoints));
            let unstable = pts(false);
            found += states.len();
            unstable_n += unstable.len();
            if !unstable.is_empty() {
                series.push(Series::new(
                    &format!("{name}, unstable"),
                    unstable,
                    c,
                    Style::Points,
                ));
            }
        }
        plots.push(
            LinePlot::new(
                &format!(
                    "{}: DC power against frequency, {ACCEL_RMS_G} g rms, up-sweep",
                    dev.device.name
                ),
                "frequency [Hz]",
                "DC power [uW]",
                series,
            )
            .legend(LegendPos::UpperLeft),
        );
    }
    exp.write_parquet("power_vs_frequency", &mut frame(rows)?, "hypothetical")?;
    for (i, p) in plots.iter().enumerate() {
        exp.write_extra_plot(&format!("interfaces_frequency_{i}"), p)?;
    }
    write_atomic(
        &exp.book_dir.join("frequency_missing.md"),
        {
            let mut md = if missing_f.is_empty() {
                "A period-one steady state was found at every frequency.\n".to_string()
            } else {
                format!("No period-one steady state at: {}.\n", missing_f.join("; "))
            };
            // The plots draw an unstable state as a cross of its interface's colour; say
            // what a reader sees when there is none.
            md.push_str(&if unstable_n == 0 {
                format!(
                    "All {found} steady states are stable (no Floquet multiplier outside the \
                     unit circle), so no cross for an unstable one appears.\n"
                )
            } else {
                format!(
                    "{unstable_n} of the {found} steady states are unstable (a Floquet \
                     multiplier outside the unit circle), drawn as crosses.\n"
                )
            });
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
    Ok(())
}

/// The energy ledger over one steady period, per interface, at each example's resonance.
pub(super) fn ledger(
    exp: &Experiment,
    piezo: &LoadedDevice,
    em: &LoadedDevice,
    settings: &SteadySettings,
) -> Result<()> {
    let f0 = resonance_hz(&piezo.device);
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
    for (dev, f) in [(piezo, f0), (em, resonance_hz(&em.device))] {
        for (name, d) in variants(&dev.device) {
            let s = steady_state_from_rest(&d, Sine::from_rms_g(ACCEL_RMS_G, f), settings);
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
            let l = &s.ledger;
            let u = |x: f64| fmt_sig(x * 1e6, 4);
            // The contact's net loss: the stop's damper, clips less re-engagements, impacts.
            let contact = l.get("stop_damping") + l.get("clip_losses")
                - l.get("reengagement_gains")
                + l.get("impact_losses");
            t.row([
                d.name.clone(),
                name.into(),
                u(l.get("drive")),
                u(l.get("mech_damping")),
                u(contact),
                u(l.get("element")),
                u(l.get("diodes")),
                u(l.get("switching")),
                u(l.get("dc_load")),
                u(l.stored_change_j),
                format!("{:.1e}", l.relative_residual()),
            ]);
        }
    }
    write_atomic(&exp.book_dir.join("ledger.md"), t.render().as_bytes())?;
    Ok(())
}
