//! The bistable example's power and rate of bottom-to-bottom passages against the noise level,
//! read from the summaries of its random-vibration jobs ([`NOISE_LEVEL_JOBS`]) after they
//! have run: a table and a plot for the "Nonlinear springs" chapter, each level with its 95 %
//! interval across records. Nothing is simulated here.

use std::path::Path;

use anyhow::{bail, Context, Result};
use serde::Deserialize;

use crate::io::md::Table;
use crate::io::plot::{error_bars, LinePlot, Series, Style, PALETTE};
use crate::pipeline::jobs::{job, Job};
use crate::{fmt_sig, write_atomic};

/// The jobs of the bistable example at increasing noise levels.
pub const NOISE_LEVEL_JOBS: [&str; 3] = [
    "own_device_springs_bistable_random_low",
    "own_device_springs_bistable_random",
    "own_device_springs_bistable_random_high",
];

/// The file stem of the curve in the book's `generated/own_device/`.
pub const STEM: &str = "springs_bistable_noise";

/// One level's numbers, as its job's `summary.json` gives them.
#[derive(Debug, Clone, PartialEq)]
pub struct Level {
    /// The job.
    pub job: &'static str,
    /// Two-sided acceleration PSD (g^2/Hz), from the job's `--psd`.
    pub psd_g2_per_hz: f64,
    /// Mean power of the loads (W) and its 95 % half-width across records.
    pub power_w: (f64, f64),
    /// The linear device's power without stops (W).
    pub linear_power_w: f64,
    /// Bottom-to-bottom passages per second and the 95 % half-width across records.
    pub rate_per_s: (f64, f64),
}

#[derive(Deserialize)]
struct Summary {
    numbers: std::collections::BTreeMap<String, f64>,
}

/// The value of a job's `--psd`.
fn psd_of(job: &Job) -> Result<f64> {
    let i = job
        .args
        .iter()
        .position(|a| *a == "--psd")
        .with_context(|| format!("job {} has no --psd", job.name))?;
    let v = job
        .args
        .get(i + 1)
        .with_context(|| format!("job {}: --psd without a value", job.name))?;
    v.parse()
        .with_context(|| format!("job {}: --psd {v} is not a number", job.name))
}

/// The levels from the jobs' summaries under `results` (one directory per job); an error names
/// the job whose summary is missing or lacks a number.
pub fn levels(results: &Path) -> Result<Vec<Level>> {
    NOISE_LEVEL_JOBS
        .iter()
        .map(|&name| {
            let j = job(name).with_context(|| format!("no job {name}"))?;
            let path = results.join(name).join("summary.json");
            let text = std::fs::read_to_string(&path)
                .with_context(|| format!("reading {} (has {name} run?)", path.display()))?;
            let s: Summary = serde_json::from_str(&text)
                .with_context(|| format!("parsing {}", path.display()))?;
            let n = |k: &str| {
                s.numbers
                    .get(k)
                    .copied()
                    .with_context(|| format!("{} has no number `{k}`", path.display()))
            };
            Ok(Level {
                job: name,
                psd_g2_per_hz: psd_of(j)?,
                power_w: (n("power_w")?, n("power_ci95_w")?),
                linear_power_w: n("linear_power_w")?,
                rate_per_s: (
                    n("transition_rate_per_s")?,
                    n("transition_rate_ci95_per_s")?,
                ),
            })
        })
        .collect()
}

/// The table of the levels (Markdown).
pub fn table(levels: &[Level]) -> String {
    let mut t = Table::new([
        "Sa (g²/Hz)",
        "power (uW)",
        "± 95 % (uW)",
        "linear theory without stops (uW)",
        "bottom-to-bottom passages per s",
        "± 95 %",
    ]);
    for l in levels {
        t.row([
            format!("{:e}", l.psd_g2_per_hz),
            fmt_sig(l.power_w.0 * 1e6, 4),
            fmt_sig(l.power_w.1 * 1e6, 2),
            fmt_sig(l.linear_power_w * 1e6, 4),
            fmt_sig(l.rate_per_s.0, 4),
            fmt_sig(l.rate_per_s.1, 2),
        ]);
    }
    t.render()
}

/// The two panels: power (with the linear theory) and the passage rate against the level,
/// on logarithmic axes, each point with its 95 % interval.
pub fn figure(levels: &[Level]) -> Result<crate::io::plot::Panels> {
    if levels.is_empty() {
        bail!("no noise level to plot");
    }
    let sa: Vec<f64> = levels.iter().map(|l| l.psd_g2_per_hz).collect();
    let xs = (sa[0] / 1.5, sa[sa.len() - 1] * 1.5);
    let panel = |title: &str, y: &str, pts: Vec<(f64, f64, f64)>, extra: Vec<Series>| {
        let lo = pts.iter().map(|p| p.1 - p.2).fold(f64::MAX, f64::min);
        let hi = pts.iter().map(|p| p.1 + p.2).fold(0.0, f64::max);
        let mut series = vec![Series::new(
            "ensemble (bars: 95 %)",
            pts.iter().map(|p| (p.0, p.1)).collect(),
            PALETTE[0],
            Style::LinePoints,
        )];
        series.extend(error_bars(pts, PALETTE[0]));
        series.extend(extra);
        LinePlot::new(title, "two-sided acceleration PSD Sa [g^2/Hz]", y, series)
            .log(true, true)
            .x(xs.0, xs.1)
            .y((lo / 2.0).max(hi * 1e-4), hi * 2.0)
    };
    let power = panel(
        "Power against the noise level: bistable_stops_em",
        "power of the load [uW]",
        levels
            .iter()
            .map(|l| (l.psd_g2_per_hz, l.power_w.0 * 1e6, l.power_w.1 * 1e6))
            .collect(),
        vec![Series::new(
            "linear theory without stops",
            levels
                .iter()
                .map(|l| (l.psd_g2_per_hz, l.linear_power_w * 1e6))
                .collect(),
            PALETTE[1],
            Style::Dashed,
        )],
    );
    let rate = panel(
        "Bottom-to-bottom passages",
        "passages per second",
        levels
            .iter()
            .map(|l| (l.psd_g2_per_hz, l.rate_per_s.0, l.rate_per_s.1))
            .collect(),
        Vec::new(),
    );
    Ok(crate::io::plot::Panels::row(vec![power, rate]))
}

/// Writes the table (`<STEM>.md`), the plot (`<STEM>.svg`, `.png`) and its caption
/// (`<STEM>.figure.md`) into `dst` from the summaries under `results`; where a level has not
/// run, a note in their place says so (the book's includes never go missing).
pub fn publish(results: &Path, dst: &Path) -> Result<()> {
    let caption = dst.join(format!("{STEM}.figure.md"));
    let numbers = dst.join(format!("{STEM}.md"));
    let levels = match levels(results) {
        Ok(l) => l,
        Err(e) => {
            let note = format!("*Not available in this build: {e:#}.*\n");
            write_atomic(&numbers, note.as_bytes())?;
            write_atomic(&caption, b"*(no plot: a noise level has not run)*\n")?;
            return Ok(());
        }
    };
    let (svg, png) = crate::io::plot::render(&figure(&levels)?)?;
    write_atomic(&dst.join(format!("{STEM}.svg")), svg.as_bytes())?;
    write_atomic(&dst.join(format!("{STEM}.png")), &png)?;
    let jobs: Vec<String> = levels.iter().map(|l| format!("`{}`", l.job)).collect();
    write_atomic(
        &caption,
        format!(
            "![Power and bottom-to-bottom passages against the noise level](generated/own_device/{STEM}.svg)\n\n\
             *Made by `reproduce` ([`experiments/src/pipeline/noise_curve.rs`](../../experiments/src/pipeline/noise_curve.rs)) \
             from the summaries of the jobs {}.*\n",
            jobs.join(", ")
        )
        .as_bytes(),
    )?;
    write_atomic(&numbers, table(&levels).as_bytes())
}
