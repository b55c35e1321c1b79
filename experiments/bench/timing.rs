//! The benchmark's clock: repeated runs of a case with their sorted wall and processor times,
//! and the row of the main table that holds them.

use std::time::Instant;

use anyhow::Result;
use endstop::ode::Stats;
use endstop_experiments as common;

use common::fmt_sig;

/// The wall and processor times of `repeats` runs of `f`, each sorted, with the last result.
pub fn timed<T>(repeats: usize, mut f: impl FnMut() -> Result<T>) -> Result<(T, Times)> {
    let (mut wall, mut cpu) = (Vec::new(), Vec::new());
    let mut last = None;
    for _ in 0..repeats.max(1) {
        let (t, c) = (Instant::now(), common::cpu_time_s());
        last = Some(f()?);
        wall.push(t.elapsed().as_secs_f64());
        cpu.push(common::cpu_time_s().zip(c).map_or(f64::NAN, |(b, a)| b - a));
    }
    wall.sort_by(f64::total_cmp);
    cpu.sort_by(f64::total_cmp);
    Ok((last.expect("at least one run"), Times { wall, cpu }))
}

/// Three significant digits, or a dash where there is no number (a run without its
/// processor time).
pub fn sig_or_dash(x: f64) -> String {
    if x.is_finite() {
        fmt_sig(x, 3)
    } else {
        "-".to_string()
    }
}

/// Sorted wall and processor times of repeated runs (s).
pub struct Times {
    /// Wall times, fastest first.
    pub wall: Vec<f64>,
    /// Processor times (user and system, every thread), smallest first.
    pub cpu: Vec<f64>,
}

impl Times {
    /// The median wall time.
    pub fn median_wall(&self) -> f64 {
        self.wall[self.wall.len() / 2]
    }
    /// The median processor time.
    pub fn median_cpu(&self) -> f64 {
        self.cpu[self.cpu.len() / 2]
    }
    /// The fastest wall time.
    pub fn fastest_wall(&self) -> f64 {
        self.wall[0]
    }
}

/// One timed case of the main table.
pub struct Row {
    /// What ran.
    pub case: String,
    /// Its runs' times.
    pub times: Times,
    /// Simulated time of one run (s; a frequency span in Hz where the note says so).
    pub simulated_s: f64,
    /// The integrator's counters of one run.
    pub stats: Stats,
    /// What else the table says of it.
    pub note: String,
}
