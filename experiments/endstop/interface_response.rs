//! `endstop response` on a device with an interface circuit: the DC up- and down-sweeps (each
//! point a steady state found by shooting from the previous one) and the steady state continued
//! in frequency through its folds ([`continue_frequency`]), each point with its stability from
//! the Floquet multipliers of the exact monodromy.

use anyhow::Result;
use endstop::study::interface::continuation::{
    continue_frequency, IfBranch, IfBranchEnd, IfContinuationSettings,
};
use endstop::study::interface::sweep::frequency_sweep;
use endstop::study::interface::{IfSteady, SteadyMethod, SteadySettings};
use endstop::study::stepped::linspace_step;

use crate::shared::{start, Protocol, RangeArgs};
use endstop_experiments::fmt_sig;
use endstop_experiments::io::frame::frame;
use endstop_experiments::io::plot::{LegendPos, LinePlot, Series, Style, PALETTE};
use endstop_experiments::reports::branch_io::{stability_segments, stability_series};
use endstop_experiments::row;

/// The sweeps and the continued branch of a device with an interface over `a`'s range.
pub fn response(a: &RangeArgs) -> Result<()> {
    let (mut exp, loaded, device) = start("endstop-response", &a.device, a.bias_v, a.out.clone())?;
    let protocol = a.protocol(&device);
    let up_freqs = linspace_step(a.from, a.to, protocol.step_hz);
    let down_freqs: Vec<f64> = up_freqs.iter().rev().copied().collect();
    let settings = SteadySettings::default();
    let (up, down) = endstop_experiments::with_progress(2 * up_freqs.len(), "sweeps", |tick| {
        rayon::join(
            || frequency_sweep(&device, &up_freqs, a.accel_rms_g, &settings, tick),
            || frequency_sweep(&device, &down_freqs, a.accel_rms_g, &settings, tick),
        )
    });
    let mut failed = Vec::new();
    let mut keep = |dir: &str, freqs: &[f64], rs: Vec<Result<IfSteady, _>>| -> Vec<IfSteady> {
        let mut out = Vec::new();
        for (f, r) in freqs.iter().zip(rs) {
            match r {
                Ok(s) => out.push(s),
                Err(e) => failed.push(format!("{dir} at {} Hz: {e}", fmt_sig(*f, 5))),
            }
        }
        out
    };
    let up = keep("up-sweep", &up_freqs, up);
    let down = keep("down-sweep", &down_freqs, down);

    eprintln!(
        "[endstop-response] continuing the steady state from {} Hz",
        a.from
    );
    let mut cont = IfContinuationSettings::new(a.from, a.to, a.accel_rms_g);
    cont.max_freq_step_hz = protocol.max_step_hz;
    cont.ds_max = protocol.max_step_hz / cont.freq_scale_hz;
    let branch = endstop_experiments::with_progress(100, "continuation (% of the range)", |p| {
        continue_frequency(&device, &cont, p)
    })?;

    let mut rows = Vec::new();
    for (dir, states) in [("up", &up), ("down", &down)] {
        for s in states.iter() {
            rows.push(row![
                "direction" => dir,
                "freq_hz" => s.freq_hz,
                "vdc_v" => s.vdc_v,
                "p_dc_w" => s.p_dc_w,
                "x_max_m" => s.x_peak_m,
                "contact" => s.contact,
                "stable" => s.is_stable(),
                "max_multiplier" => s.max_multiplier,
                "method" => s.method.label(),
            ]);
        }
    }
    exp.write_parquet("sweeps", &mut frame(rows)?, &device.params)?;
    let segments = stability_segments(branch.points.iter().map(|p| p.is_stable()));
    let rows = branch
        .points
        .iter()
        .zip(&segments)
        .map(|(p, &seg)| {
            row![
                "freq_hz" => p.steady.freq_hz,
                "vdc_v" => p.steady.vdc_v,
                "p_dc_w" => p.steady.p_dc_w,
                "x_max_m" => p.steady.x_peak_m,
                "contact" => p.steady.contact,
                "stable" => p.is_stable(),
                "max_multiplier" => p.steady.max_multiplier,
                "branch" => seg,
                "tangent_freq" => p.tangent_freq,
                "residual" => p.steady.residual,
            ]
        })
        .collect::<Vec<_>>();
    exp.write_parquet("continuation", &mut frame(rows)?, &device.params)?;

    let md = words(
        a,
        &loaded.file,
        &device,
        &protocol,
        &branch,
        &up,
        &down,
        &failed,
    );
    exp.number("step_hz", protocol.step_hz);
    exp.number("continuation_points", branch.points.len() as f64);
    let unstable = branch.points.iter().filter(|p| !p.is_stable()).count();
    exp.number("continuation_unstable_points", unstable as f64);
    for (i, (f, _)) in branch.folds.iter().enumerate() {
        exp.number(&format!("fold_{i}_hz"), *f);
    }
    for (name, states) in [("up", &up), ("down", &down)] {
        if let Some(best) = states.iter().max_by(|a, b| a.p_dc_w.total_cmp(&b.p_dc_w)) {
            exp.number(&format!("{name}_p_dc_max_w"), best.p_dc_w);
            exp.number(&format!("{name}_p_dc_max_freq_hz"), best.freq_hz);
        }
    }
    if let Some(best) = branch
        .points
        .iter()
        .max_by(|a, b| a.steady.p_dc_w.total_cmp(&b.steady.p_dc_w))
    {
        exp.number("continuation_p_dc_max_w", best.steady.p_dc_w);
        exp.number("continuation_p_dc_max_freq_hz", best.steady.freq_hz);
    }
    exp.write_numbers_md(&md)?;
    print!("{md}");
    exp.write_plot(&figure(a, &device, &branch, &up, &down))?;
    exp.finish()
}

/// Of the two points around the fold at `f` (Hz) before point `k`, the one nearer in frequency.
fn near_fold(branch: &IfBranch, f: f64, k: usize) -> &IfSteady {
    [k.saturating_sub(1), k]
        .into_iter()
        .map(|i| &branch.points[i].steady)
        .min_by(|a, b| (a.freq_hz - f).abs().total_cmp(&(b.freq_hz - f).abs()))
        .expect("two indices")
}

/// The numbers of the run, as Markdown.
#[allow(clippy::too_many_arguments)]
fn words(
    a: &RangeArgs,
    file: &str,
    device: &endstop::device::Device,
    protocol: &Protocol,
    branch: &IfBranch,
    up: &[IfSteady],
    down: &[IfSteady],
    failed: &[String],
) -> String {
    let residual = branch
        .points
        .iter()
        .map(|p| p.steady.residual)
        .fold(0.0, f64::max);
    let mut md = format!(
        "Whole response of `{}` ({} interface) from {} to {} Hz at {} g rms: up- and \
         down-sweeps in steps of {} Hz, each point the periodic steady state found by shooting \
         (Newton's method on the period map after {} periods) from the previous one; the steady state continued in frequency by \
         pseudo-arclength ({} points, frequency steps of at most {} Hz, largest scaled residual \
         {:.1e}, {} Newton iterations, {} rejected steps), its stability from the Floquet \
         multipliers of the monodromy with saltation matrices.\n\n",
        file,
        device.interface.key(),
        a.from,
        a.to,
        a.accel_rms_g,
        fmt_sig(protocol.step_hz, 3),
        SteadySettings::default().transient_periods,
        branch.points.len(),
        fmt_sig(protocol.max_step_hz, 3),
        residual,
        branch.newton_iterations,
        branch.rejected_steps,
    );
    for (name, states) in [("up-sweep", up), ("down-sweep", down)] {
        if let Some(b) = states.iter().max_by(|a, b| a.p_dc_w.total_cmp(&b.p_dc_w)) {
            md.push_str(&format!(
                "- {name}: largest DC power {} uW at {} Hz (V_DC = {} V)\n",
                fmt_sig(b.p_dc_w * 1e6, 4),
                fmt_sig(b.freq_hz, 5),
                fmt_sig(b.vdc_v, 4)
            ));
        }
    }
    for (i, &(f, k)) in branch.folds.iter().enumerate() {
        let p = near_fold(branch, f, k);
        md.push_str(&format!(
            "- fold {}: {} Hz (P_DC {} uW, V_DC {} V at the nearer point of the two around it)\n",
            i + 1,
            fmt_sig(f, 6),
            fmt_sig(p.p_dc_w * 1e6, 4),
            fmt_sig(p.vdc_v, 4)
        ));
    }
    if branch.folds.is_empty() {
        md.push_str("- no fold in this range\n");
    }
    let unstable: Vec<f64> = branch
        .points
        .iter()
        .filter(|p| !p.is_stable())
        .map(|p| p.steady.freq_hz)
        .collect();
    if let (Some(lo), Some(hi)) = (
        unstable.iter().copied().reduce(f64::min),
        unstable.iter().copied().reduce(f64::max),
    ) {
        md.push_str(&format!(
            "- unstable steady states: {} of {} points, between {} and {} Hz\n",
            unstable.len(),
            branch.points.len(),
            fmt_sig(lo, 5),
            fmt_sig(hi, 5)
        ));
    } else {
        md.push_str("- every continued steady state is stable\n");
    }
    match branch.end {
        IfBranchEnd::Reached => {}
        IfBranchEnd::Stalled(f) => md.push_str(&format!(
            "- the continuation stalled at {} Hz (its step fell below the minimum)\n",
            fmt_sig(f, 6)
        )),
        IfBranchEnd::MaxPoints => md.push_str("- the continuation ran out of points\n"),
    }
    let by_map = up
        .iter()
        .chain(down)
        .filter(|s| s.method != SteadyMethod::Newton)
        .count();
    if by_map > 0 {
        md.push_str(&format!(
            "- {by_map} of the sweeps' {} steady states found by iterating the period map \
             (Newton's method did not converge there)\n",
            up.len() + down.len()
        ));
    }
    for f in failed {
        md.push_str(&format!("- no period-one steady state: {f}\n"));
    }
    md
}

/// DC power against frequency: the continued branch solid where stable and dashed where not (neighbouring stretches share their end point), the sweeps' points, and the folds.
fn figure(
    a: &RangeArgs,
    device: &endstop::device::Device,
    branch: &IfBranch,
    up: &[IfSteady],
    down: &[IfSteady],
) -> LinePlot {
    let uw = |s: &IfSteady| (s.freq_hz, s.p_dc_w * 1e6);
    let mut series = stability_series(
        branch
            .points
            .iter()
            .map(|p| (p.steady.freq_hz, p.steady.p_dc_w * 1e6, p.is_stable())),
        ["continued, stable", "continued, unstable"],
    );
    series.push(Series::new(
        "down-sweep",
        down.iter().map(uw).collect(),
        PALETTE[2],
        Style::Circles,
    ));
    series.push(Series::new(
        "up-sweep",
        up.iter().map(uw).collect(),
        PALETTE[1],
        Style::Points,
    ));
    let folds: Vec<(f64, f64)> = branch
        .folds
        .iter()
        .map(|&(f, k)| (f, near_fold(branch, f, k).p_dc_w * 1e6))
        .collect();
    if !folds.is_empty() {
        series.push(Series::new("folds", folds, PALETTE[3], Style::Triangles));
    }
    LinePlot::new(
        &format!(
            "Whole response at {} g rms, {} interface: {} (solid stable, dashed unstable)",
            a.accel_rms_g,
            device.interface.key(),
            device.name
        ),
        "frequency [Hz]",
        "DC power [uW]",
        series,
    )
    .x(a.from, a.to)
    .legend(LegendPos::UpperRight)
}
