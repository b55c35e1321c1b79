//! The time a run spends in each of its phases (reading, resampling, integrating, spectra,
//! output), measured by the run itself and reported on stderr and in `timing.json` (beside the
//! run's wall time; `summary.json` stays free of wall-clock content so that it is
//! byte-identical between runs).
//!
//! A run calls [`TimeSplit::lap`] at the end of each phase: the time since the previous lap is
//! added to that phase, so that the phases add up to the time since [`TimeSplit::start`]. Each
//! phase gets its wall time ([`Instant`]) and the processor time of the process's own threads
//! ([`crate::own_cpu_time_s`], user and system): on a shared machine the wall time includes
//! waiting for a processor, which the processor time does not. Child processes (the
//! provenance's `git`) run beside the phases and are counted once, in a phase of their own
//! ([`TimeSplit::children`]), whichever phase they end in.
//!
//! Each phase also gets the process's minor page faults ([`crate::own_memory`]): the fresh
//! pages it touched, which the kernel zeroes first (for a short run a large share of its
//! processor time), and the peak resident set at the phase's end.

use std::time::Instant;

use crate::Experiment;

/// One phase's seconds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Phase {
    /// The phase's name.
    pub name: &'static str,
    /// Wall time (s).
    pub wall_s: f64,
    /// Processor time, user and system (s); None where it cannot be read.
    pub cpu_s: Option<f64>,
    /// Minor page faults of the process's own threads; None where they cannot be read.
    pub minor_faults: Option<u64>,
    /// The process's peak resident set at the phase's last end (bytes); None where it cannot
    /// be read.
    pub peak_rss_bytes: Option<u64>,
}

/// The seconds spent in each phase so far, in the order the phases first ended.
#[derive(Debug, Clone)]
pub struct TimeSplit {
    last: Instant,
    last_cpu: Option<f64>,
    last_memory: Option<crate::Memory>,
    /// The child processes' processor time at the start (s).
    children_start: Option<f64>,
    phases: Vec<Phase>,
}

impl TimeSplit {
    /// Starts the clocks.
    pub fn start() -> Self {
        Self {
            last: Instant::now(),
            last_cpu: crate::own_cpu_time_s(),
            last_memory: crate::own_memory(),
            children_start: crate::children_cpu_time_s(),
            phases: Vec::new(),
        }
    }

    /// Ends a stretch of `phase`: adds the time since the previous lap (or the start) to it.
    pub fn lap(&mut self, phase: &'static str) {
        let (now, cpu, memory) = (Instant::now(), crate::own_cpu_time_s(), crate::own_memory());
        let wall_s = now.duration_since(self.last).as_secs_f64();
        let cpu_s = cpu.zip(self.last_cpu).map(|(c, c0)| c - c0);
        let used = memory.zip(self.last_memory).map(|(m, m0)| crate::Memory {
            minor_faults: m.minor_faults.saturating_sub(m0.minor_faults),
            peak_rss_bytes: m.peak_rss_bytes,
        });
        (self.last, self.last_cpu, self.last_memory) = (now, cpu, memory);
        self.add(phase, wall_s, cpu_s);
        self.add_memory(phase, used);
    }

    /// Adds `used`'s page faults to `phase` (which has ended at least once) and sets its peak.
    fn add_memory(&mut self, phase: &'static str, used: Option<crate::Memory>) {
        if let Some(p) = self.phases.iter_mut().find(|p| p.name == phase) {
            let faults = used.map(|u| u.minor_faults);
            p.minor_faults = match p.minor_faults {
                Some(f) => faults.map(|g| f + g),
                None => faults,
            };
            p.peak_rss_bytes = used.map(|u| u.peak_rss_bytes);
        }
    }

    /// Adds the processor time of the child processes waited for since the start as the
    /// phase `phase`, of no wall time of its own (they ran beside the other phases).
    pub fn children(&mut self, phase: &'static str) {
        let cpu_s = crate::children_cpu_time_s()
            .zip(self.children_start)
            .map(|(c, c0)| c - c0);
        self.add(phase, 0.0, cpu_s);
    }

    fn add(&mut self, name: &'static str, wall_s: f64, cpu_s: Option<f64>) {
        match self.phases.iter_mut().find(|p| p.name == name) {
            Some(p) => {
                p.wall_s += wall_s;
                p.cpu_s = p.cpu_s.zip(cpu_s).map(|(a, b)| a + b);
            }
            None => self.phases.push(Phase {
                name,
                wall_s,
                cpu_s,
                minor_faults: None,
                peak_rss_bytes: None,
            }),
        }
    }

    /// The phases, in the order they first ended.
    pub fn phases(&self) -> &[Phase] {
        &self.phases
    }

    /// The sums over the phases: wall and processor time (s).
    pub fn total(&self) -> (f64, Option<f64>) {
        let wall = self.phases.iter().map(|p| p.wall_s).sum();
        let cpu = self.phases.iter().map(|p| p.cpu_s).sum();
        (wall, cpu)
    }

    /// One line: each phase's processor time and share of the total (wall time where the
    /// processor time cannot be read), then the totals.
    pub fn line(&self) -> String {
        let (wall, cpu) = self.total();
        let (total, what) = match cpu {
            Some(c) => (c, "processor"),
            None => (wall, "wall"),
        };
        let parts: Vec<String> = self
            .phases
            .iter()
            .map(|p| {
                let s = if cpu.is_some() {
                    p.cpu_s.unwrap_or(0.0)
                } else {
                    p.wall_s
                };
                let pct = if total > 0.0 { 100.0 * s / total } else { 0.0 };
                format!("{} {s:.3} s ({pct:.0} %)", p.name)
            })
            .collect();
        format!(
            "{what} time: {}; total {total:.3} s ({wall:.3} s wall)",
            parts.join(", ")
        )
    }

    /// Prints the split on stderr under `tag`, with the child processes' phase
    /// ([`TimeSplit::children`]), and records it in `exp`'s `timing.json` (`phases_wall_s`,
    /// `phases_cpu_s`, `phases_minor_faults` and `phases_peak_rss_bytes`, by phase; the child
    /// processes' memory is not counted).
    pub fn report(&self, tag: &str, exp: &mut Experiment) {
        let mut all = self.clone();
        all.children("child processes");
        eprintln!("[{tag}] time split, {}", all.line());
        let by_phase = |f: &dyn Fn(&Phase) -> serde_json::Value| {
            serde_json::Value::Object(
                all.phases
                    .iter()
                    .map(|p| (p.name.to_string(), f(p)))
                    .collect(),
            )
        };
        exp.timing("phases_wall_s", by_phase(&|p| serde_json::json!(p.wall_s)));
        exp.timing("phases_cpu_s", by_phase(&|p| serde_json::json!(p.cpu_s)));
        let own = || self.phases.iter();
        let memory = |f: &dyn Fn(&Phase) -> Option<u64>| {
            serde_json::Value::Object(
                own()
                    .map(|p| (p.name.to_string(), serde_json::json!(f(p))))
                    .collect(),
            )
        };
        exp.timing("phases_minor_faults", memory(&|p| p.minor_faults));
        exp.timing("phases_peak_rss_bytes", memory(&|p| p.peak_rss_bytes));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Laps of the same phase add up, the phases keep the order they first ended in, and the
    /// line gives each one's share of the processor time (or, without it, of the wall time).
    #[test]
    fn phases_add_up_in_order() {
        let mut t = TimeSplit::start();
        t.add("reading", 0.5, Some(0.25));
        t.add("integrating", 1.0, Some(0.5));
        t.add("reading", 0.5, Some(0.25));
        let names: Vec<&str> = t.phases().iter().map(|p| p.name).collect();
        assert_eq!(names, ["reading", "integrating"]);
        assert_eq!(t.total(), (2.0, Some(1.0)));
        assert_eq!(
            t.line(),
            "processor time: reading 0.500 s (50 %), integrating 0.500 s (50 %); total 1.000 s \
             (2.000 s wall)"
        );
        t.add("output", 2.0, None);
        assert_eq!(t.total(), (4.0, None));
        assert!(
            t.line().starts_with("wall time: reading 1.000 s (25 %)"),
            "{}",
            t.line()
        );
        t.lap("output");
        assert_eq!(t.phases().len(), 3);
    }

    /// The child processes' phase holds the processor time of a child waited for after the
    /// start, and no wall time (the child ran beside the other phases).
    #[test]
    fn child_processes_count_in_their_own_phase() {
        let mut t = TimeSplit::start();
        // `true` ends at once: its processor time is some microseconds, perhaps 0 at the
        // clock's resolution, never negative.
        let ran = std::process::Command::new("true").status();
        t.lap("work");
        t.children("child processes");
        let p = t.phases()[1];
        assert_eq!((p.name, p.wall_s), ("child processes", 0.0));
        if ran.is_ok() {
            assert!(p.cpu_s.is_none_or(|c| c >= 0.0), "{p:?}");
        }
    }

    /// A phase that touches fresh memory has page faults and a peak resident set at least that
    /// large (where `getrusage` gives them): 64 MiB written, far above what the test harness
    /// holds, so the bound does not depend on the rest of the process.
    #[test]
    fn memory_counts_the_fresh_pages_a_phase_touches() {
        const BYTES: usize = 64 << 20;
        let mut t = TimeSplit::start();
        let fresh = vec![1u8; BYTES];
        t.lap("touching");
        let p = t.phases()[0];
        if crate::own_memory().is_some() {
            assert!(p.minor_faults.is_some_and(|f| f >= 1), "{p:?}");
            assert!(p.peak_rss_bytes.is_some_and(|b| b >= BYTES as u64), "{p:?}");
        }
        assert_eq!(fresh.iter().map(|&b| usize::from(b)).sum::<usize>(), BYTES);
    }
}
