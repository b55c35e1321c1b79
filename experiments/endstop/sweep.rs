//! `endstop sweep`: a stepped-sine up-sweep on a device file, with the impact onset and the
//! end of the impacting branch refined, and the step's effect on that end; the half-power band,
//! the harvester effectiveness of its power and its normalised power density ([`crate::merit`]).

use anyhow::Result;

use crate::merit;
use crate::shared::{describe, implausible_drive, mass_peaks_md, start, step_effect, RangeArgs};
use endstop::study::mass_peaks::MassPeaks;
use endstop_experiments::io::plot::{LegendPos, LinePlot, Series, Style, PALETTE};
use endstop_experiments::reports::sweep_io;
use endstop_experiments::{self as common, fmt_sig};

/// Runs `endstop sweep`.
pub(crate) fn sweep(a: RangeArgs) -> Result<()> {
    a.check()?;
    let (mut exp, loaded, device) = start("endstop-sweep", &a.device, a.bias_v, a.out.clone())?;
    let protocol = a.protocol(&device);
    let settings = a.sweep_settings(&device, &protocol);
    let report = common::with_progress(settings.freqs_hz.len(), "sweep", |tick| {
        settings.run_with(&device, a.accel_rms_g, protocol.approach, tick)
    })?;

    let steps = &report.sweep.steps;
    let col = |f: &dyn Fn(&endstop::study::steady::Measurement) -> f64| -> Vec<f64> {
        steps.iter().map(|s| f(&s.measurement)).collect()
    };
    let masses = sweep_io::mass_columns(&device)?;
    let rows: Vec<_> = sweep_io::sweep_rows(
        &format!("{} g rms up-sweep", a.accel_rms_g),
        &device,
        report.measurements(),
        report.extended_from,
    )
    .into_iter()
    .zip(report.measurements())
    .map(|(mut row, m)| {
        row.extend(sweep_io::mass_cells(&masses, &m.mass_peaks));
        row
    })
    .collect();
    let mut df = common::io::frame::frame(rows)?;
    exp.write_parquet("sweep", &mut df, &device.params)?;

    let mut md = format!(
        "Up-sweep of `{}` ({} set; {}) from {} to {} Hz at {} g rms: {}.\n\n",
        loaded.file,
        device.params,
        describe(&device),
        a.from,
        a.to,
        a.accel_rms_g,
        protocol.words(),
    );
    // The model's first two named outputs (`v1`, `v2` across a transducer's loads; `vs`, the
    // storage voltage, and `v_element` behind a circuit).
    let names: Vec<String> = endstop::with_harvester!(&device, |h| {
        use endstop::model::Model;
        Ok::<_, anyhow::Error>(h.layout().outputs.iter().map(|s| s.name.clone()).collect())
    })?;
    let name = |i: usize| names.get(i).map_or("?", String::as_str);
    exp.number("step_hz", protocol.step_hz);
    let vmax = col(&|m| m.v1_rms_v).into_iter().fold(0.0, f64::max);
    let pmax = col(&|m| m.p_total_w()).into_iter().fold(0.0, f64::max);
    exp.number("v1_rms_max_v", vmax);
    exp.number("power_max_w", pmax);
    md.push_str(&format!(
        "- largest {}: {} V; largest power of the loads: {} uW\n",
        match name(0) {
            "v1" => "RMS voltage of load 1".to_string(),
            other => format!("RMS of `{other}`"),
        },
        fmt_sig(vmax, 4),
        fmt_sig(pmax * 1e6, 4)
    ));
    let x_peak = col(&|m| m.x_peak_m).into_iter().fold(0.0, f64::max);
    if let Some(w) = implausible_drive(&device, a.accel_rms_g, x_peak) {
        md.push_str(&w);
    }
    let peaks = steps
        .iter()
        .fold(MassPeaks::none(), |p, s| p.max(&s.measurement.mass_peaks));
    md.push_str(&mass_peaks_md(&mut exp, &masses, &peaks, "over the sweep"));
    match report.onset {
        Some(t) => {
            exp.number("impact_onset_hz", t.value());
            md.push_str(&format!(
                "- impacts begin at {} Hz (bracket {}-{} Hz)\n",
                fmt_sig(t.value(), 5),
                fmt_sig(t.before, 5),
                fmt_sig(t.after, 5)
            ));
        }
        None if report.contact_at_start => md.push_str("- in contact from the first step\n"),
        None => md.push_str("- no impact in this range\n"),
    }
    if let Some(end) = report.branch_end() {
        exp.number("branch_end_hz", end.transition.value());
        md.push_str(&format!(
            "- the impacting branch ends at {} Hz ({})\n",
            fmt_sig(end.transition.value(), 5),
            end.kind.label()
        ));
        let quarter = settings
            .up_end_with_step_divided(&device, a.accel_rms_g, protocol.approach, &report, 4.0)?
            .map(|e| e.transition.value());
        if let Some(q) = quarter {
            exp.number("branch_end_quarter_step_hz", q);
        }
        md.push_str(&step_effect(
            "the end of the impacting branch",
            end.transition.value(),
            quarter,
        ));
    }
    // The designer's figures of merit over the whole sweep (its frequencies increase): the
    // half-power band, and the effectiveness at the band's peak.
    let freqs_hz = col(&|m| m.freq_hz);
    let power_w = col(&|m| m.p_total_w());
    if let Some((line, band)) = merit::half_power(&mut exp, &freqs_hz, &power_w) {
        md.push_str(&line);
        md.push_str(&merit::effectiveness(
            &mut exp,
            &device,
            band.peak_w,
            a.accel_rms_g,
            band.peak_hz,
        ));
        md.push_str(&merit::power_density(
            &mut exp,
            &device,
            band.peak_w,
            a.accel_rms_g,
        ));
    }
    exp.write_numbers_md(&md)?;
    print!("{md}");

    let pts = |f: &dyn Fn(&endstop::study::steady::Measurement) -> f64| -> Vec<(f64, f64)> {
        steps
            .iter()
            .map(|s| (s.measurement.freq_hz, f(&s.measurement)))
            .collect()
    };
    // Two loads: a transducer's own (its outputs are `v1`, `v2`) with both electrodes loaded.
    let two_loads = name(0) == "v1" && device.transducer.loads() == 2;
    let mut series = vec![Series::new(
        &match name(0) {
            "v1" if two_loads => "V1 (one load)".to_string(),
            "v1" => "V (the load)".to_string(),
            other => other.to_string(),
        },
        pts(&|m| m.v1_rms_v),
        PALETTE[0],
        Style::LinePoints,
    )];
    if two_loads {
        series.push(Series::new(
            "V2 - V1",
            pts(&|m| m.vdiff_rms_v),
            PALETTE[1],
            Style::Dashed,
        ));
    }
    let plot = LinePlot::new(
        &format!("Up-sweep at {} g rms: {}", a.accel_rms_g, device.name),
        "frequency [Hz]",
        "RMS output voltage [V]",
        series,
    )
    .legend(LegendPos::UpperLeft);
    exp.write_plot(&plot)?;
    exp.finish()
}
