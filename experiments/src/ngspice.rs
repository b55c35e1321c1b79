//! Running ngspice in batch mode: its version, and one run of a netlist with the waveform
//! file it writes (the cross-check and the benchmark).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anyhow::{bail, Context, Result};

/// `ngspice -v`'s first non-empty line, or an error telling how to install it.
pub fn version() -> Result<String> {
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
