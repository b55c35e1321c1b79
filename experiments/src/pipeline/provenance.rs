//! The provenance page: each experiment's parameter files, seed, commit, wall and processor
//! time, with the processor time's sum, the floor it puts on the wall time, and the last
//! `reproduce` run's totals.

use anyhow::Result;

use crate::pipeline::jobs::{Job, JOBS};
use crate::pipeline::schedule::LAST_RUN;
use crate::pipeline::scorecard::{read_json, SummaryIn};

/// The jobs that simulate the random-vibration ensembles (the provenance line compares their
/// processor time with a minute of the machine's cores).
const ENSEMBLE_JOBS: [&str; 4] = ["fig11", "fig12", "fig14", "fig15"];

/// The provenance table: experiment, parameter files, seed, commit, wall and CPU time; under
/// it, the CPU sum with the floor it puts on the wall time, and the last run's totals.
pub fn write_provenance() -> Result<()> {
    let mut md = String::from(
        "| experiment | parameter files (set) | seed | commit | wall time (s) | CPU time (s) |\n\
         |---|---|---|---|---|---|\n",
    );
    let (mut cpu_sum, mut cpu_jobs, mut cpu_ensembles) = (0.0, 0, 0.0);
    for (name, dir) in JOBS.iter().flat_map(Job::outputs) {
        let Some(s) = read_json::<SummaryIn>(&dir.join("summary.json")) else {
            md.push_str(&format!("| {name} | (no results) | | | | |\n"));
            continue;
        };
        let timing: Option<serde_json::Value> = read_json(&dir.join("timing.json"));
        let seconds = |key: &str| timing.as_ref().and_then(|v| v[key].as_f64());
        let wall = seconds("wall_time_s")
            .map(|t| format!("{t:.2}"))
            .unwrap_or_default();
        let cpu = seconds("cpu_time_s");
        if let Some(c) = cpu {
            cpu_sum += c;
            cpu_jobs += 1;
            if ENSEMBLE_JOBS.contains(&name) {
                cpu_ensembles += c;
            }
        }
        let params: Vec<String> = s
            .params
            .iter()
            .map(|(f, l)| format!("`{f}` ({l})"))
            .collect();
        md.push_str(&format!(
            "| {name} | {} | {} | `{}` | {wall} | {} |\n",
            params.join(", "),
            s.seed.map(|x| x.to_string()).unwrap_or_else(|| "-".into()),
            s.commit,
            cpu.map(|c| format!("{c:.1}")).unwrap_or_default(),
        ));
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    if cpu_jobs > 0 {
        md.push_str(&format!(
            "\nThe CPU times (user and system, ngspice's included) add up to {cpu_sum:.0} s over \
             {cpu_jobs} experiments: on this machine's {cores} cores no schedule of them can take \
             less than {:.0} s of wall time.",
            cpu_sum / cores as f64
        ));
        // What a minute of wall time allows, against the random-vibration ensembles alone.
        let minute = 60.0 * cores as f64;
        md.push_str(&format!(
            " A minute on {cores} cores is {minute:.0} s of CPU time; the random-vibration \
             ensembles ({}) took {cpu_ensembles:.0} s of CPU time, {} of it.",
            ENSEMBLE_JOBS.join(", "),
            if cpu_ensembles > minute {
                "more than all".to_string()
            } else {
                format!("{:.0} %", 100.0 * cpu_ensembles / minute)
            }
        ));
    }
    if let Some(v) = read_json::<serde_json::Value>(&crate::results_root().join(LAST_RUN)) {
        let (wall, cpu) = (v["wall_time_s"].as_f64(), v["cpu_time_s"].as_f64());
        let n = v["experiments"].as_array().map_or(0, |a| a.len());
        if let Some(wall) = wall {
            md.push_str(&format!(
                " The last `reproduce{}` ran {n} experiments in {wall:.0} s of wall time{}.",
                if v["force"].as_bool() == Some(true) {
                    " --force"
                } else {
                    ""
                },
                cpu.map(|c| format!(
                    " and {c:.0} s of CPU time ({:.2} cores busy on average)",
                    c / wall
                ))
                .unwrap_or_default()
            ));
        }
    }
    md.push('\n');
    crate::write_atomic(
        &crate::book_generated_root().join("provenance.md"),
        md.as_bytes(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::jobs::experiment_names;

    #[test]
    fn the_ensemble_jobs_are_experiments() {
        for name in ENSEMBLE_JOBS {
            assert!(
                experiment_names().contains(&name),
                "{name} is not an experiment"
            );
        }
    }
}
