//! Running ngspice in batch mode: its version, one run of a netlist with the waveform file it
//! writes (the cross-check and the benchmark), and the recording of what a program read off
//! its runs ([`Runner`]): `reproduce` takes ngspice's numbers from the recording, so that it
//! needs neither ngspice nor its minute of runs, and CI runs ngspice again
//! (`--fresh-ngspice`) and fails if the recording no longer holds what ngspice writes.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

/// `ngspice -v`'s first non-empty line, or an error telling how to install it.
pub fn version() -> Result<String> {
    let out = match Command::new("ngspice").arg("-v").output() {
        Ok(o) => o,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => bail!(
            "ngspice is not installed (no `ngspice` on PATH); install with: apt-get install ngspice"
        ),
        Err(e) => return Err(e).context("cannot run `ngspice -v`"),
    };
    if !out.status.success() {
        bail!(
            "`ngspice -v` failed ({}): {}",
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        );
    }
    let text = String::from_utf8_lossy(&out.stdout);
    Ok(text
        .lines()
        .map(|l| l.trim_matches(|c: char| c == '*' || c.is_whitespace()))
        .find(|l| l.starts_with("ngspice"))
        .map(|l| l.split(" : ").next().unwrap_or(l).trim().to_string())
        .unwrap_or_else(|| "ngspice (unknown version)".to_string()))
}

/// Runs `ngspice -b cir` and returns the text of the waveform file `dat` it writes, with the
/// wall time of the run (s).
pub fn run(cir: &Path, dat: &Path) -> Result<(String, f64)> {
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
    Ok((text, wall_s))
}

/// Removes the temporary directory when dropped.
pub struct TempDir(pub PathBuf);

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Where a program takes ngspice's numbers from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    /// The recording where it holds the same netlist; ngspice (if installed) for the others.
    Recorded,
    /// ngspice for every netlist, each checked against the recording where it holds the same
    /// netlist (ngspice is deterministic: the same version writes the same bytes).
    Fresh,
    /// ngspice for every netlist, and the recording rewritten from its runs.
    Record,
}

impl Source {
    /// The source named by the program's arguments: `--fresh-ngspice` or `--record-ngspice`
    /// (neither: [`Source::Recorded`]). Any other argument is an error.
    pub fn from_args(program: &str) -> Result<Self> {
        let args: Vec<String> = std::env::args().skip(1).collect();
        match args
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>()
            .as_slice()
        {
            [] => Ok(Source::Recorded),
            ["--fresh-ngspice"] => Ok(Source::Fresh),
            ["--record-ngspice"] => Ok(Source::Record),
            other => bail!(
                "{program}: unknown arguments {other:?}; takes none (ngspice's recorded numbers), \
                 --fresh-ngspice (run ngspice and check the recording) or --record-ngspice \
                 (run ngspice and rewrite the recording)"
            ),
        }
    }
}

/// ngspice's numbers for a set of netlists, as the program that ran it reduced them, with
/// where they came from: a peer tool's output is stored, never retyped.
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
pub struct Recording {
    /// What the file holds.
    pub about: String,
    /// `ngspice -v`'s version line.
    pub ngspice: String,
    /// The command that wrote the file.
    pub command: String,
    /// The commit it was written at.
    pub commit: String,
    /// The runs by netlist name.
    pub runs: BTreeMap<String, RecordedRun>,
}

/// One recorded ngspice run.
#[derive(Debug, Clone, Default, Serialize, Deserialize, PartialEq)]
pub struct RecordedRun {
    /// SHA-256 of the netlist's text (the recording answers only that netlist).
    pub netlist_sha256: String,
    /// Wall time of the run where it was recorded (s), process start and output included.
    pub wall_s: f64,
    /// The numbers the program read off the waveforms, by name.
    pub values: BTreeMap<String, f64>,
    /// A waveform the program plots, (time, value) pairs (empty when it plots none).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub series: Vec<(f64, f64)>,
}

/// What a program reads off ngspice's waveform text: named numbers and a series to plot.
pub type Reduced = (BTreeMap<String, f64>, Vec<(f64, f64)>);

/// One netlist's numbers and where they came from.
#[derive(Debug, Clone, PartialEq)]
pub struct Reading {
    /// The run's numbers and series.
    pub run: RecordedRun,
    /// True when they come from the recording, not from a run of ngspice here.
    pub recorded: bool,
}

/// Relative difference above which a fresh run disagrees with the recording: the recording
/// holds the numbers in their shortest round-trip form (serde_json with `float_roundtrip`),
/// so an identical run agrees exactly; the margin admits only the last bits of a platform's
/// libm in the reduction.
const RECORDING_REL_TOL: f64 = 1e-12;

/// Runs netlists through ngspice or takes their numbers from a recording ([`Source`]).
pub struct Runner {
    source: Source,
    path: PathBuf,
    recording: Recording,
    written: Recording,
    tmp: TempDir,
    mismatches: Vec<String>,
    /// Netlists neither recorded nor runnable (no ngspice).
    missing: Vec<String>,
    fresh: usize,
}

impl Runner {
    /// A runner over the recording at `path` (relative to the repository root); `about` and
    /// `command` describe a recording this runner writes.
    pub fn new(source: Source, path: &str, about: &str, command: &str) -> Result<Self> {
        let path = crate::root().join(path);
        let recording: Recording = match std::fs::read_to_string(&path) {
            Ok(text) => serde_json::from_str(&text)
                .with_context(|| format!("{}: not a recording of ngspice runs", path.display()))?,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound && source != Source::Recorded => {
                Recording::default()
            }
            Err(e) => {
                return Err(e).with_context(|| {
                    format!(
                        "cannot read ngspice's recorded numbers {} (write them with \
                         `{command}` where ngspice is installed)",
                        path.display()
                    )
                })
            }
        };
        let tmp = TempDir(std::env::temp_dir().join(format!(
            "endstop-ngspice-{}-{}",
            std::process::id(),
            path.file_stem().and_then(|s| s.to_str()).unwrap_or("run")
        )));
        std::fs::create_dir_all(&tmp.0)
            .with_context(|| format!("cannot create {}", tmp.0.display()))?;
        let written = Recording {
            about: about.to_string(),
            ngspice: String::new(),
            command: command.to_string(),
            commit: crate::git_commit(),
            runs: BTreeMap::new(),
        };
        Ok(Self {
            source,
            path,
            recording,
            written,
            tmp,
            mismatches: Vec::new(),
            missing: Vec::new(),
            fresh: 0,
        })
    }

    /// The ngspice whose numbers the page shows: the recording's, or the installed one's
    /// when any run was fresh.
    pub fn version(&self) -> Result<String> {
        if self.source == Source::Recorded && self.fresh == 0 {
            Ok(format!(
                "{}, its runs recorded in `{}` by `{}` at commit {}",
                self.recording.ngspice,
                self.path
                    .strip_prefix(crate::root())
                    .unwrap_or(&self.path)
                    .display(),
                self.recording.command,
                short(&self.recording.commit),
            ))
        } else {
            version()
        }
    }

    /// The numbers of the netlist `netlist` (which writes its waveforms to `dat_name` in its
    /// own directory) stored as `name`: from the recording when it holds this netlist and
    /// the source is [`Source::Recorded`], else from a run of ngspice reduced by `reduce`.
    pub fn run(
        &mut self,
        name: &str,
        netlist: &str,
        dat_name: &str,
        reduce: impl FnOnce(&str) -> Result<Reduced>,
    ) -> Result<Reading> {
        let sha = format!("{:x}", Sha256::digest(netlist.as_bytes()));
        let recorded = self
            .recording
            .runs
            .get(name)
            .filter(|r| r.netlist_sha256 == sha);
        if self.source == Source::Recorded {
            if let Some(r) = recorded {
                return Ok(Reading {
                    run: r.clone(),
                    recorded: true,
                });
            }
            if version().is_err() {
                self.missing.push(name.to_string());
                bail!(
                    "{name}: {} holds no ngspice run of this netlist (it changed since the \
                     recording) and ngspice is not installed; rerun `{}` where it is",
                    self.path.display(),
                    self.recording.command
                );
            }
        }
        let cir = self.tmp.0.join(format!("{name}.cir"));
        std::fs::write(&cir, netlist).with_context(|| format!("cannot write {}", cir.display()))?;
        let (text, wall_s) = run(&cir, &self.tmp.0.join(dat_name))?;
        let (values, series) = reduce(&text)?;
        let fresh = RecordedRun {
            netlist_sha256: sha,
            wall_s,
            values,
            series,
        };
        self.fresh += 1;
        if self.source == Source::Fresh {
            match recorded {
                Some(r) => {
                    if let Some(why) = disagreement(r, &fresh) {
                        self.mismatches.push(format!("{name}: {why}"));
                    }
                }
                None => self.mismatches.push(format!(
                    "{name}: the recording holds no run of this netlist"
                )),
            }
        }
        self.written.runs.insert(name.to_string(), fresh.clone());
        Ok(Reading {
            run: fresh,
            recorded: false,
        })
    }

    /// Ends the runs: writes the recording ([`Source::Record`]), or fails when a fresh run
    /// disagreed with it ([`Source::Fresh`]) or a netlist had neither a recording nor
    /// ngspice to run it ([`Source::Recorded`]).
    pub fn finish(mut self) -> Result<()> {
        match self.source {
            Source::Recorded if self.missing.is_empty() => Ok(()),
            Source::Recorded => bail!(
                "{} holds no ngspice run of {} netlist(s) and ngspice is not installed: {} \
                 (rerun `{}` where it is)",
                self.path.display(),
                self.missing.len(),
                self.missing.join(", "),
                self.recording.command
            ),
            Source::Fresh if self.mismatches.is_empty() => {
                eprintln!(
                    "[ngspice] {} fresh runs agree with {}",
                    self.fresh,
                    self.path.display()
                );
                Ok(())
            }
            Source::Fresh => bail!(
                "ngspice's runs differ from {} (rewrite it with `{}` if the change is \
                 intended):\n  {}",
                self.path.display(),
                self.written.command,
                self.mismatches.join("\n  ")
            ),
            Source::Record => {
                self.written.ngspice = version()?;
                let text = serde_json::to_string_pretty(&self.written)?;
                crate::write_atomic(&self.path, format!("{text}\n").as_bytes())?;
                eprintln!(
                    "[ngspice] recorded {} runs in {}",
                    self.fresh,
                    self.path.display()
                );
                Ok(())
            }
        }
    }
}

/// Why a fresh run disagrees with the recorded one (None when it agrees); wall times differ
/// by nature and are not compared.
fn disagreement(recorded: &RecordedRun, fresh: &RecordedRun) -> Option<String> {
    let close = |a: f64, b: f64| {
        a == b
            || (a.is_nan() && b.is_nan())
            || (a - b).abs() <= RECORDING_REL_TOL * a.abs().max(b.abs())
    };
    if recorded.values.keys().ne(fresh.values.keys()) {
        return Some("different quantities".into());
    }
    for (k, a) in &recorded.values {
        let b = fresh.values[k];
        if !close(*a, b) {
            return Some(format!("{k}: recorded {a:e}, ngspice now {b:e}"));
        }
    }
    if recorded.series.len() != fresh.series.len()
        || recorded
            .series
            .iter()
            .zip(&fresh.series)
            .any(|(a, b)| !close(a.0, b.0) || !close(a.1, b.1))
    {
        return Some("the plotted waveform differs".into());
    }
    None
}

fn short(commit: &str) -> &str {
    &commit[..commit.len().min(10)]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(v1: f64) -> RecordedRun {
        RecordedRun {
            netlist_sha256: "ab".into(),
            wall_s: 1.0,
            values: BTreeMap::from([("v1_rms_v".to_string(), v1)]),
            series: vec![(0.0, v1)],
        }
    }

    #[test]
    fn a_run_agrees_with_its_recording_and_not_with_a_changed_number() {
        let recorded = run(0.220445379);
        let mut again = run(0.220445379);
        again.wall_s = 2.0;
        assert_eq!(
            disagreement(&recorded, &again),
            None,
            "wall times are not compared"
        );
        let changed = run(0.220445379 * (1.0 + 1e-9));
        assert!(disagreement(&recorded, &changed).is_some_and(|w| w.starts_with("v1_rms_v")));
        let mut other = run(0.220445379);
        other.values.insert("v2_rms_v".into(), 0.1);
        assert_eq!(
            disagreement(&recorded, &other).as_deref(),
            Some("different quantities")
        );
    }

    #[test]
    fn a_recorded_number_reads_back_bit_for_bit() {
        // serde_json parses floats exactly only with `float_roundtrip`; without it this
        // number reads back one unit in the last place off.
        let x = 0.22044537924619706_f64;
        let text = serde_json::to_string(&run(x)).unwrap();
        let back: RecordedRun = serde_json::from_str(&text).unwrap();
        assert_eq!(back.values["v1_rms_v"].to_bits(), x.to_bits());
    }
}
