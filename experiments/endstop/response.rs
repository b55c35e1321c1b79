//! `endstop response`: the whole frequency response of a device: up- and down-sweeps (with the
//! step's effect on where they leave the branches), optionally swept sines at a stated rate,
//! and every branch of periodic orbits with its stability and the bifurcations between them.

use anyhow::Result;
use clap::Parser;
use common::io::frame::frame;
use common::io::md::Table;
use common::io::plot::Panels;
use common::reports::branch_io::{diagram_figure, diagram_rows, diagram_words};
use common::{fmt_sig, row, Experiment};
use endstop::device::Device;
use endstop::study::chirp::{ChirpReport, ChirpSweep};
use endstop::study::continuation::impacting::DiagramSettings;
use endstop::study::continuation::{
    diagram_with_step, ContinuationSettings, Diagram, DiagramEventKind,
};
use endstop::study::orbit::Forcing;
use endstop::study::stepped::Approach;
use endstop::study::sweep::{DownSweepReport, SweepReport, SweepSettings};
use endstop_experiments as common;

use crate::shared::{
    describe, implausible_drive, mass_peaks_md, start, step_effect, Protocol, RangeArgs,
};
use common::reports::sweep_io::{mass_cells, mass_columns};
use endstop::study::mass_peaks::MassPeaks;

/// The arguments of `endstop response`.
#[derive(Parser, Debug)]
pub(crate) struct ResponseArgs {
    #[command(flatten)]
    range: RangeArgs,
    /// Also sweep the drive continuously at this rate (Hz/s), up and down, at a continuous
    /// phase (a swept sine, as a lab measures).
    #[arg(long, allow_hyphen_values = true)]
    sweep_rate: Option<f64>,
    /// Also find where the down-sweep leaves the lower branch with 4, 2, 1, 1/2 and 1/4 times
    /// the step, each taken at once and by a ramp (its convergence as the step shrinks).
    #[arg(long)]
    step_study: bool,
}

/// Step multiples of the step study.
const STUDY_FACTORS: [f64; 5] = [4.0, 2.0, 1.0, 0.5, 0.25];

pub(crate) fn response(args: ResponseArgs) -> Result<()> {
    let a = &args.range;
    a.check()?;
    if let Some(r) = args.sweep_rate {
        if !(r.is_finite() && r > 0.0) {
            anyhow::bail!("--sweep-rate must be a finite positive rate in Hz/s, not {r}");
        }
    }
    let (mut exp, loaded, device) = start("endstop-response", &a.device, a.bias_v, a.out.clone())?;
    let protocol = a.protocol(&device);
    let settings = a.sweep_settings(&device, &protocol);
    let freqs = &settings.freqs_hz;
    let approach = protocol.approach;
    // Three pieces of work share nothing: the up-sweep and the down-sweep, each followed by
    // its branch's end found again at a quarter of the step, and the continuation. Each runs
    // on a thread of its own, so that the processors share themselves among all three and
    // the run's wall time is about half their sum on two cores (a pool of two would run the
    // continuation and then one sweep on the same thread).
    let (sweeps, diagram) = std::thread::scope(|s| {
        let diagram = s.spawn(|| continue_orbits(&device, a, &protocol));
        let sweeps = common::with_progress(2 * freqs.len(), "sweeps", |tick| {
            std::thread::scope(|s| {
                let down = s.spawn(|| -> Result<_> {
                    let down = settings.run_down_with(&device, a.accel_rms_g, approach, tick)?;
                    let quarter = settings
                        .down_end_with_step_divided(&device, a.accel_rms_g, approach, &down, 4.0)?
                        .map(|e| e.1.value());
                    Ok((down, quarter))
                });
                let up = || -> Result<_> {
                    let up = settings.run_with(&device, a.accel_rms_g, approach, tick)?;
                    let quarter = settings
                        .up_end_with_step_divided(&device, a.accel_rms_g, approach, &up, 4.0)?
                        .map(|e| e.transition.value());
                    Ok((up, quarter))
                };
                (up(), joined(down))
            })
        });
        (sweeps, joined(diagram))
    });
    let ((up, up_quarter_hz), (down, down_quarter_hz)) = (sweeps.0?, sweeps.1?);
    let diagram = diagram?;
    let chirps = match args.sweep_rate {
        Some(rate) => Some(swept_sines(&settings, &device, a, rate)?),
        None => None,
    };
    write_parquet(&exp, &device, &diagram, &up, &down, chirps.as_ref())?;
    let found = Found {
        up: &up,
        down: &down,
        up_quarter_hz,
        down_quarter_hz,
        chirps: chirps.as_ref(),
        diagram: &diagram,
    };
    let mut md = summary_md(&mut exp, &loaded.file, &device, a, &protocol, &found)?;
    if args.step_study {
        eprintln!("[endstop-response] the down-sweep's end against its step");
        md.push_str(&step_study(
            &settings,
            &device,
            a.accel_rms_g,
            &protocol,
            &down,
            &diagram,
            &mut exp,
        )?);
    }
    exp.write_numbers_md(&md)?;
    print!("{md}");
    exp.write_plot(&response_plot(&device, a, &diagram, &up, &down))?;
    exp.finish()
}

/// What the sweeps, the swept sines and the continuation found.
struct Found<'a> {
    up: &'a SweepReport,
    down: &'a DownSweepReport,
    /// Where the up-sweep leaves its branch with a quarter of the step (Hz).
    up_quarter_hz: Option<f64>,
    /// Where the down-sweep leaves its branch with a quarter of the step (Hz).
    down_quarter_hz: Option<f64>,
    chirps: Option<&'a (ChirpReport, ChirpReport)>,
    diagram: &'a Diagram,
}

/// The value of a scoped thread, its panic carried on.
fn joined<T>(h: std::thread::ScopedJoinHandle<'_, T>) -> T {
    h.join().unwrap_or_else(|p| std::panic::resume_unwind(p))
}

/// The swept sines up and down at `rate` (Hz/s).
fn swept_sines(
    settings: &SweepSettings,
    device: &Device,
    a: &RangeArgs,
    rate: f64,
) -> Result<(ChirpReport, ChirpReport)> {
    eprintln!("[endstop-response] swept sines at {rate} Hz/s");
    let sweep = |from: f64, to: f64| ChirpSweep {
        from_hz: from,
        to_hz: to,
        rate_hz_per_s: rate,
        window_cycles: 4,
        cfg: settings.cfg.clone(),
    };
    let (u, d) = rayon::join(
        || sweep(a.from, a.to).run(device, a.accel_rms_g),
        || sweep(a.to, a.from).run(device, a.accel_rms_g),
    );
    Ok((u?, d?))
}

/// Every branch of periodic orbits from the range's lower end, with its events; where a
/// branch ends at a grazing that adds a strike, resumed in the sweeps' steps after transients.
fn continue_orbits(device: &Device, a: &RangeArgs, protocol: &Protocol) -> Result<Diagram> {
    eprintln!(
        "[endstop-response] continuing the periodic orbits from {} Hz",
        a.from
    );
    let start_drive = Forcing {
        freq_hz: a.from,
        accel_rms_g: a.accel_rms_g,
    };
    let cont = ContinuationSettings::frequency(a.from, a.to, protocol.max_step_hz);
    Ok(common::with_progress(1, "continuation", |branch| {
        diagram_with_step(
            device,
            start_drive,
            &cont,
            &DiagramSettings::default(),
            protocol.step_hz,
            branch,
        )
    })?)
}

/// The continuation and the sweeps (stepped and swept) as Parquet.
fn write_parquet(
    exp: &Experiment,
    device: &Device,
    diagram: &Diagram,
    up: &SweepReport,
    down: &DownSweepReport,
    chirps: Option<&(ChirpReport, ChirpReport)>,
) -> Result<()> {
    let masses = mass_columns(device)?;
    let rows: Vec<_> = diagram_rows(&device.name, diagram)
        .into_iter()
        .zip(diagram.branches.iter().flat_map(|b| &b.points))
        .map(|(mut row, p)| {
            row.extend(mass_cells(&masses, &p.summary.mass_peaks));
            row
        })
        .collect();
    exp.write_parquet("continuation", &mut frame(rows)?, &device.params)?;
    let mut rows = Vec::new();
    for (dir, ms) in [
        ("up", up.measurements().collect::<Vec<_>>()),
        ("down", down.measurements().collect()),
    ] {
        for m in ms {
            let mut row = row![
                "direction" => dir,
                "freq_hz" => m.freq_hz,
                "v1_rms_v" => m.v1_rms_v,
                "x_max_m" => m.x_peak_m,
                "contact_fraction" => m.contact_fraction,
            ];
            row.extend(mass_cells(&masses, &m.mass_peaks));
            rows.push(row);
        }
    }
    if let Some((u, d)) = chirps {
        for (dir, r) in [("swept up", u), ("swept down", d)] {
            for w in &r.windows {
                let mut row = row![
                    "direction" => dir,
                    "freq_hz" => w.freq_hz,
                    "v1_rms_v" => w.v1_rms_v,
                    "x_max_m" => w.x_peak_m,
                    "contact_fraction" => if w.contact { 1.0 } else { 0.0 },
                ];
                row.extend(mass_cells(&masses, &w.mass_peaks));
                rows.push(row);
            }
        }
    }
    exp.write_parquet("sweeps", &mut frame(rows)?, &device.params)?;
    Ok(())
}

/// The summary's words and numbers: the run, where the sweeps leave their branches (with the
/// step's effect), the swept sines and the continuation's events.
fn summary_md(
    exp: &mut Experiment,
    file: &str,
    device: &Device,
    a: &RangeArgs,
    protocol: &Protocol,
    found: &Found<'_>,
) -> Result<String> {
    let Found {
        up,
        down,
        up_quarter_hz,
        down_quarter_hz,
        chirps,
        diagram,
    } = *found;
    let points: usize = diagram.branches.iter().map(|b| b.points.len()).sum();
    let residual = diagram
        .branches
        .iter()
        .flat_map(|b| &b.points)
        .map(|p| p.residual)
        .fold(0.0, f64::max);
    let mut md = format!(
        "Whole response of `{}` ({} set; {}) from {} to {} Hz at {} g rms: sweeps in {} \
         (transitions refined to 0.1 Hz); periodic orbits continued in frequency ({} {}, \
         {} points, largest residual {:.1e}).\n\n",
        file,
        device.params,
        describe(device),
        a.from,
        a.to,
        a.accel_rms_g,
        protocol.words(),
        diagram.branches.len(),
        if diagram.branches.len() == 1 {
            "branch"
        } else {
            "branches"
        },
        points,
        residual
    );
    let x_peak = up
        .measurements()
        .chain(down.measurements())
        .map(|m| m.x_peak_m)
        .fold(0.0, f64::max);
    if let Some(w) = implausible_drive(device, a.accel_rms_g, x_peak) {
        md.push_str(&w);
    }
    let peaks = up
        .measurements()
        .chain(down.measurements())
        .fold(MassPeaks::none(), |p, m| p.max(&m.mass_peaks));
    md.push_str(&mass_peaks_md(
        exp,
        &mass_columns(device)?,
        &peaks,
        "over the up- and down-sweeps",
    ));
    exp.number("step_hz", protocol.step_hz);
    if let Some(e) = up.branch_end() {
        let v = e.transition.value();
        exp.number("up_branch_end_hz", v);
        md.push_str(&format!(
            "- the up-sweep leaves the impacting branch at {} Hz ({})\n",
            fmt_sig(v, 6),
            e.kind.label()
        ));
        let q = up_quarter_hz;
        if let Some(q) = q {
            exp.number("up_branch_end_quarter_step_hz", q);
        }
        md.push_str(&step_effect(
            "the point where the up-sweep leaves the branch",
            v,
            q,
        ));
    }
    if let Some((kind, t)) = down.branch_end() {
        exp.number("down_branch_end_hz", t.value());
        md.push_str(&format!(
            "- the down-sweep leaves the lower branch at {} Hz ({})\n",
            fmt_sig(t.value(), 6),
            kind.label()
        ));
        let q = down_quarter_hz;
        if let Some(q) = q {
            exp.number("down_branch_end_quarter_step_hz", q);
        }
        md.push_str(&step_effect(
            "the point where the down-sweep leaves the branch",
            t.value(),
            q,
        ));
    }
    if let Some((u, d)) = chirps {
        md.push_str(&chirp_words(u, d));
        if let Some(f) = u.last_contact_hz {
            exp.number("swept_up_last_contact_hz", f);
        }
        if let Some(f) = d.first_contact_hz {
            exp.number("swept_down_first_contact_hz", f);
        }
    }
    for (i, e) in diagram.events.iter().enumerate() {
        exp.number(&format!("event_{i}_hz"), e.param);
    }
    md.push_str(&diagram_words(diagram));
    Ok(md)
}

/// The stepped sweeps over the continued branches.
fn response_plot(
    device: &Device,
    a: &RangeArgs,
    diagram: &Diagram,
    up: &SweepReport,
    down: &DownSweepReport,
) -> Panels {
    let steps = |ms: Vec<&endstop::study::steady::Measurement>| -> Vec<(f64, f64)> {
        ms.into_iter().map(|m| (m.freq_hz, m.v1_rms_v)).collect()
    };
    diagram_figure(
        &format!(
            "Whole response at {} g rms: {} (orbits: solid stable, dashed unstable)",
            a.accel_rms_g, device.name
        ),
        diagram,
        steps(up.measurements().collect()),
        steps(down.measurements().collect()),
        (a.from, a.to),
    )
}

/// Where the swept sines start and stop touching the stops.
fn chirp_words(up: &ChirpReport, down: &ChirpReport) -> String {
    let hz = |v: Option<f64>| v.map_or("nowhere".to_string(), |f| format!("{} Hz", fmt_sig(f, 6)));
    format!(
        "- swept up at {} Hz/s (windows of {} cycles), the response last touches a stop at \
         {}; swept down, it first touches one at {}\n",
        fmt_sig(up.sweep.rate_hz_per_s, 3),
        up.sweep.window_cycles,
        hz(up.last_contact_hz),
        hz(down.first_contact_hz)
    )
}

/// The down-sweep's end at several steps, taken at once and by the ramp, against the nearest
/// fold or grazing of the continued orbits: a table, with its numbers in the summary.
fn step_study(
    settings: &endstop::study::sweep::SweepSettings,
    device: &endstop::device::Device,
    accel_rms_g: f64,
    protocol: &Protocol,
    down: &endstop::study::sweep::DownSweepReport,
    d: &Diagram,
    exp: &mut common::Experiment,
) -> Result<String> {
    let ramp = match protocol.approach {
        Approach::Ramp { .. } => protocol.approach,
        Approach::Jump => Approach::Ramp {
            rate_per_s: endstop::study::chirp::default_ramp_rate_hz_per_s(device)
                .unwrap_or(protocol.step_hz),
        },
    };
    let ends: Vec<f64> = d
        .events
        .iter()
        .filter(|e| matches!(e.kind, DiagramEventKind::Fold | DiagramEventKind::Grazing))
        .map(|e| e.param)
        .collect();
    let nearest = |f: f64| {
        ends.iter()
            .copied()
            .min_by(|a, b| (a - f).abs().total_cmp(&(b - f).abs()))
    };
    let mut t = Table::new([
        "step (Hz)",
        "leaves the lower branch, steps at once (Hz)",
        "the same, steps by ramps (Hz)",
        "nearest fold or grazing (Hz)",
        "ramped - that (Hz)",
    ]);
    for (i, factor) in STUDY_FACTORS.iter().enumerate() {
        let step = protocol.step_hz * factor;
        let mut cells = vec![fmt_sig(step, 3)];
        let mut ramped = None;
        for (j, approach) in [Approach::Jump, ramp].into_iter().enumerate() {
            let end = settings
                .down_end_with_step_divided(device, accel_rms_g, approach, down, 1.0 / factor)?
                .map(|e| e.1.value());
            if let Some(v) = end {
                exp.number(
                    &format!("step_study_{i}_{}_hz", ["at_once", "ramped"][j]),
                    v,
                );
            }
            if j == 1 {
                ramped = end;
            }
            cells.push(end.map_or("-".into(), |v| format!("{v:.3}")));
        }
        let near = ramped.and_then(nearest);
        cells.push(near.map_or("-".into(), |v| format!("{v:.3}")));
        cells.push(
            ramped
                .zip(near)
                .map_or("-".into(), |(a, b)| format!("{:+.3}", a - b)),
        );
        let cells: [String; 5] = cells.try_into().expect("five cells");
        t.row(cells);
    }
    Ok(format!(
        "\n### Where the down-sweep leaves the lower branch, against the step\n\n\
         The down-sweep rerun from three steps above its end to two below it, at multiples of \
         the step, each step taken at once or reached by a ramp; brackets of {} Hz.\n\n{}",
        settings.refine_tol_hz,
        t.render()
    ))
}
