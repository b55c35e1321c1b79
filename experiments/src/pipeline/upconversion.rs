//! The up-conversion chapter's comparison, read from its jobs' outputs after they have run:
//! the two-mass up-converter (`data/examples/upconverter.toml`) against one mass of the same
//! total mass, element and stroke tuned to the driver's 20 Hz (`data/upconversion/direct.toml`)
//! and against its generator alone (`data/upconversion/generator_alone.toml`), each swept at
//! two levels, and the charging of the first two behind the same full bridge. A table, a plot
//! of the power against frequency at both levels, and the sentences that compare them, every
//! number from the runs. Nothing is simulated here.

use std::path::Path;

use anyhow::{bail, Context, Result};
use polars::prelude::*;
use serde::Deserialize;

use crate::io::md::Table;
use crate::io::plot::{LinePlot, Panels, Series, Style, PALETTE};
use crate::{fmt_sig, write_atomic};

/// The file stem of the comparison in the book's `generated/own_device/`.
pub const STEM: &str = "upconversion_compare";

/// The devices compared, as `(job stem, label)`: the job of a sweep is
/// `own_device_upconversion_<stem>_<level>`.
pub const DEVICES: [(&str, &str); 3] = [
    ("upconverter", "up-converter (two masses)"),
    ("direct", "one mass at 20 Hz"),
    ("generator", "generator alone"),
];

/// The two levels, as `(job suffix, RMS acceleration in g)`; the values are the jobs' own
/// `--accel-rms-g` (checked when read).
pub const LEVELS: [(&str, f64); 2] = [("low", 0.05), ("high", 0.2)];

/// The charging jobs, one per device behind a bridge (the generator alone is not charged).
pub const CHARGES: [(&str, &str); 2] = [
    (
        "own_device_upconversion_charge_upconverter",
        "up-converter (two masses)",
    ),
    ("own_device_upconversion_charge_direct", "one mass at 20 Hz"),
];

#[derive(Deserialize)]
struct Summary {
    numbers: std::collections::BTreeMap<String, f64>,
}

/// One device's sweep at one level.
#[derive(Debug, Clone)]
pub struct Swept {
    /// The device's label.
    pub label: &'static str,
    /// The RMS acceleration (g).
    pub accel_rms_g: f64,
    /// The largest power of the load (W) and its frequency (Hz).
    pub peak: (f64, f64),
    /// The half-power band's edges (Hz), each `None` where it lies beyond the sweep.
    pub band_hz: (Option<f64>, Option<f64>),
    /// The power against frequency, `(Hz, W)`.
    pub curve: Vec<(f64, f64)>,
}

/// A job's summary numbers; an error names the job that has not run.
fn numbers(results: &Path, job: &str) -> Result<std::collections::BTreeMap<String, f64>> {
    let path = results.join(job).join("summary.json");
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("reading {} (has {job} run?)", path.display()))?;
    let s: Summary =
        serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))?;
    Ok(s.numbers)
}

/// Every device's sweep at every level, from the jobs' summaries and Parquet under `results`.
pub fn sweeps(results: &Path) -> Result<Vec<Swept>> {
    let mut out = Vec::new();
    for (suffix, g) in LEVELS {
        for (stem, label) in DEVICES {
            let job = format!("own_device_upconversion_{stem}_{suffix}");
            let n = numbers(results, &job)?;
            let get = |k: &str| {
                n.get(k)
                    .copied()
                    .with_context(|| format!("{job}'s summary has no number `{k}`"))
            };
            let path = results.join(&job).join("sweep.parquet");
            let f = std::fs::File::open(&path)
                .with_context(|| format!("opening {}", path.display()))?;
            let df = ParquetReader::new(f)
                .finish()
                .with_context(|| format!("reading {}", path.display()))?;
            let col = |c: &str| -> Result<Vec<f64>> {
                Ok(df
                    .column(c)?
                    .f64()?
                    .into_iter()
                    .map(|v| v.unwrap_or(f64::NAN))
                    .collect())
            };
            let (f, p, a) = (col("freq_hz")?, col("p1_w")?, col("accel_rms_g")?);
            if a.iter().any(|&x| (x - g).abs() > 1e-12 * g) {
                bail!("{job} ran at another level than the chapter's {g} g");
            }
            out.push(Swept {
                label,
                accel_rms_g: g,
                peak: (get("power_max_w")?, get("half_power_peak_hz")?),
                band_hz: (
                    n.get("half_power_lower_hz").copied(),
                    n.get("half_power_upper_hz").copied(),
                ),
                curve: f.into_iter().zip(p).collect(),
            });
        }
    }
    Ok(out)
}

/// One device's charging run, with the conditions the run states in its summary.
#[derive(Debug, Clone, PartialEq)]
pub struct Charged {
    /// The device's label.
    pub label: &'static str,
    /// The time to the target (s).
    pub time_s: f64,
    /// The storage capacitance (F).
    pub storage_capacitance_f: f64,
    /// The start and target voltages (V).
    pub volts: (f64, f64),
    /// The drive's frequency (Hz) and RMS acceleration (g).
    pub drive: (f64, f64),
}

/// The charging runs; an error names the job that has not run or a number it lacks.
pub fn charges(results: &Path) -> Result<Vec<Charged>> {
    CHARGES
        .iter()
        .map(|&(job, label)| {
            let n = numbers(results, job)?;
            let get = |key: &str| {
                n.get(key)
                    .copied()
                    .with_context(|| format!("{job}'s summary has no `{key}`"))
            };
            let time_s = n
                .get("time_to_target_s")
                .copied()
                .with_context(|| format!("{job} did not reach its target"))?;
            Ok(Charged {
                label,
                time_s,
                storage_capacitance_f: get("storage_capacitance_f")?,
                volts: (get("start_v")?, get("target_v")?),
                drive: (get("freq_hz")?, get("accel_rms_g")?),
            })
        })
        .collect()
}

/// A ratio in words: three significant digits, in powers of ten from 10^4 on.
fn ratio_words(r: f64) -> String {
    if r.abs() >= 1e4 {
        format!("{r:.2e}")
    } else {
        fmt_sig(r, 3)
    }
}

/// A run's condition in words: four significant digits without trailing zeros (4e-6 F in
/// microfarads reads "4", not "4.000").
fn plain(x: f64) -> String {
    let s = fmt_sig(x, 4);
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// A band's edges in words.
fn band_words(band: (Option<f64>, Option<f64>)) -> String {
    let edge = |e: Option<f64>, beyond: &str| e.map_or(beyond.to_string(), |f| fmt_sig(f, 4));
    let width = match band {
        (Some(a), Some(b)) => format!("{} Hz wide", fmt_sig(b - a, 3)),
        _ => "beyond the sweep".to_string(),
    };
    format!(
        "{width} ({} to {} Hz)",
        edge(band.0, "below 10"),
        edge(band.1, "above 40")
    )
}

/// The table and the sentences that compare the devices (Markdown).
pub fn comparison(sweeps: &[Swept], charges: &[Charged]) -> String {
    let mut t = Table::new([
        "device",
        "level (g rms)",
        "largest power (uW)",
        "at (Hz)",
        "half-power band",
    ]);
    for s in sweeps {
        t.row([
            s.label.to_string(),
            fmt_sig(s.accel_rms_g, 2),
            fmt_sig(s.peak.0 * 1e6, 4),
            fmt_sig(s.peak.1, 4),
            band_words(s.band_hz),
        ]);
    }
    let mut md = t.render();
    md.push('\n');
    for (suffix, g) in LEVELS {
        let of = |label: &str| {
            sweeps
                .iter()
                .find(|s| s.label == label && s.accel_rms_g == g)
                .map(|s| s.peak.0)
        };
        if let (Some(up), Some(direct), Some(alone)) =
            (of(DEVICES[0].1), of(DEVICES[1].1), of(DEVICES[2].1))
        {
            let winner = if up > direct {
                "the up-converter delivers more"
            } else {
                "the single mass delivers more"
            };
            md.push_str(&format!(
                "- At {} g ({suffix} level) the up-converter's largest power is {} times its \
                 generator's alone and {} times the single mass's: {winner}.\n",
                fmt_sig(g, 2),
                ratio_words(up / alone),
                ratio_words(up / direct),
            ));
        }
    }
    for c in charges {
        md.push_str(&format!(
            "- Behind the full bridge, the {} charges {} uF from {} to {} V in {} s at {} Hz \
             and {} g.\n",
            c.label,
            plain(c.storage_capacitance_f * 1e6),
            plain(c.volts.0),
            plain(c.volts.1),
            fmt_sig(c.time_s, 3),
            plain(c.drive.0),
            plain(c.drive.1),
        ));
    }
    md
}

/// Power against frequency at each level (logarithmic power: the generator alone delivers
/// orders of magnitude less).
pub fn figure(sweeps: &[Swept]) -> Result<Panels> {
    if sweeps.is_empty() {
        bail!("no sweep to plot");
    }
    let positive = || {
        sweeps
            .iter()
            .flat_map(|s| s.curve.iter().map(|c| c.1 * 1e6))
            .filter(|p| *p > 0.0 && p.is_finite())
    };
    let lo = positive().fold(f64::INFINITY, f64::min);
    let hi = positive().fold(0.0, f64::max);
    if !(lo.is_finite() && hi > 0.0) {
        bail!("no positive power to plot");
    }
    let plots = LEVELS
        .iter()
        .map(|&(_, g)| {
            let series: Vec<Series> = sweeps
                .iter()
                .filter(|s| s.accel_rms_g == g)
                .enumerate()
                .map(|(i, s)| {
                    let pts = s
                        .curve
                        .iter()
                        .filter(|(_, p)| *p > 0.0)
                        .map(|&(f, p)| (f, p * 1e6))
                        .collect();
                    Series::new(s.label, pts, PALETTE[i], Style::LinePoints)
                })
                .collect();
            LinePlot::new(
                &format!("Up-sweeps at {} g rms", fmt_sig(g, 2)),
                "drive frequency [Hz]",
                "power of the load [uW]",
                series,
            )
            .log(false, true)
            .x(10.0, 40.0)
            // Every point inside (the generator's own response lies decades below the
            // impacts'), and a free decade and a half above the peaks for the legend.
            .y(lo / 3.0, hi * 30.0)
        })
        .collect();
    Ok(Panels::row(plots))
}

/// Writes the comparison (`<STEM>.md`), its plot (`<STEM>.svg`, `.png`) and caption
/// (`<STEM>.figure.md`) into `dst` from the jobs' outputs under `results`; where a job has
/// not run, a note in their place says so (the book's includes never go missing).
pub fn publish(results: &Path, dst: &Path) -> Result<()> {
    let caption = dst.join(format!("{STEM}.figure.md"));
    let numbers = dst.join(format!("{STEM}.md"));
    let (sweeps, charges) = match sweeps(results).and_then(|s| Ok((s, charges(results)?))) {
        Ok(v) => v,
        Err(e) => {
            let note = format!("*Not available in this build: {e:#}.*\n");
            write_atomic(&numbers, note.as_bytes())?;
            write_atomic(&caption, b"*(no plot: an up-conversion job has not run)*\n")?;
            return Ok(());
        }
    };
    let (svg, png) = crate::io::plot::render(&figure(&sweeps)?)?;
    write_atomic(&dst.join(format!("{STEM}.svg")), svg.as_bytes())?;
    write_atomic(&dst.join(format!("{STEM}.png")), &png)?;
    write_atomic(
        &caption,
        format!(
            "![Power against frequency: the up-converter, one mass at 20 Hz and the generator alone](generated/own_device/{STEM}.svg)\n\n\
             *Left: at {} g rms; right: at {} g rms. Made by `reproduce` \
             ([`experiments/src/pipeline/upconversion.rs`](../../experiments/src/pipeline/upconversion.rs)) \
             from the sweeps `own_device_upconversion_*`.*\n",
            fmt_sig(LEVELS[0].1, 2),
            fmt_sig(LEVELS[1].1, 2),
        )
        .as_bytes(),
    )?;
    write_atomic(&numbers, comparison(&sweeps, &charges).as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn swept(label: &'static str, g: f64, peak_w: f64) -> Swept {
        Swept {
            label,
            accel_rms_g: g,
            peak: (peak_w, 20.0),
            band_hz: (Some(19.0), None),
            curve: vec![(19.0, 0.5 * peak_w), (20.0, peak_w)],
        }
    }

    /// The verdict follows the ratio, and a band edge beyond the sweep is said so.
    #[test]
    fn the_verdict_follows_the_powers() {
        let [up, direct, alone] = DEVICES.map(|d| d.1);
        let (lo, hi) = (LEVELS[0].1, LEVELS[1].1);
        let s = [
            swept(up, lo, 2e-6),
            swept(direct, lo, 8e-6),
            swept(alone, lo, 1e-12),
            swept(up, hi, 9e-6),
            swept(direct, hi, 3e-6),
            swept(alone, hi, 1e-9),
        ];
        let charged = Charged {
            label: up,
            time_s: 1.5,
            storage_capacitance_f: 4e-6,
            volts: (0.0, 0.5),
            drive: (20.0, 0.2),
        };
        let md = comparison(&s, &[charged]);
        assert!(md.contains("2.00e6 times its generator's alone and 0.250 times the single mass's: the single mass delivers more"), "{md}");
        assert!(
            md.contains("3.00 times the single mass's: the up-converter delivers more"),
            "{md}"
        );
        assert!(
            md.contains("beyond the sweep (19.00 to above 40 Hz)"),
            "{md}"
        );
        assert!(
            md.contains("charges 4 uF from 0 to 0.5 V in 1.50 s at 20 Hz and 0.2 g"),
            "{md}"
        );
    }

    /// Without the jobs' outputs the chapter's includes hold a note naming the missing job.
    #[test]
    fn missing_jobs_leave_a_note() {
        let dir = std::env::temp_dir().join(format!("upconversion-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        publish(&dir.join("no-results"), &dir).unwrap();
        let note = std::fs::read_to_string(dir.join(format!("{STEM}.md"))).unwrap();
        assert!(
            note.contains("own_device_upconversion_upconverter_low"),
            "{note}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
