//! The cost of a fit (`bench --fits`): every case of the recovery family
//! (`endstop::fit::family`, asserted by `tests/fit_family.rs`) and the paper's Figure 8 fit
//! (`endstop fit --device data/prototype1.toml --up-sweep data/measured/fig08_paper.csv --free
//! stops.both.gap_m=4e-6..9.9e-6 --free stops.both.damping_n_s_per_m=0.1..20`), each fitted
//! with the default settings inside a thread pool of one thread, so that its processor time
//! and its wall time are those of one core. The table is printed, nothing written.

use anyhow::Result;
use endstop::device::ParamRange;
use endstop::fit::family::recovery_family;
use endstop::fit::{fit, Direction, FitReport, FitSettings};
use endstop_experiments as common;

use common::fmt_sig;
use common::reports::fit_csv::parse_sweep;

use crate::examples::{cpu, median};

/// One fit's runs.
pub struct FitCost {
    /// The case.
    pub name: String,
    /// Processor times (s): median, smallest, largest.
    pub cpu_s: (f64, f64, f64),
    /// Starts of the design and those refined, and the chi-square per degree of freedom, of
    /// the last run.
    pub note: String,
}

fn note(r: &FitReport) -> String {
    format!(
        "{} starts, {} refined; chi2/dof {}",
        r.starts.len(),
        r.starts_refined(),
        fmt_sig(r.reduced_chi2, 3)
    )
}

/// The Figure 8 fit's inputs, as `endstop fit` reads them.
fn fig08() -> Result<(
    endstop::device::Device,
    Vec<endstop::fit::SweepData>,
    Vec<ParamRange>,
)> {
    let device = common::load_device("prototype1")?.device;
    let file = "data/measured/fig08_paper.csv";
    let text = std::fs::read_to_string(common::root().join(file))?;
    let data = parse_sweep(&text, file, Direction::Up)?;
    let free = vec![
        ParamRange::auto("stops.both.gap_m", 4e-6, 9.9e-6),
        ParamRange::auto("stops.both.damping_n_s_per_m", 0.1, 20.0),
    ];
    Ok((device, vec![data], free))
}

/// Whether the fit `id` (a family case's number, `fig8` for Figure 8) is among
/// `only` (every fit when `only` is empty).
fn chosen(only: &[String], id: &str) -> bool {
    only.is_empty() || only.iter().any(|o| o == id)
}

/// A family case's id: the number its name starts with.
fn case_id(name: &str) -> &str {
    name.split_whitespace().next().unwrap_or_default()
}

/// Times every fit chosen by `only` (see [`chosen`]) `repeats` times, each on one thread.
pub fn measure(repeats: usize, only: &[String]) -> Result<Vec<FitCost>> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let family = recovery_family();
    let known = |id: &str| id == "fig8" || family.iter().any(|c| case_id(c.name) == id);
    if let Some(unknown) = only.iter().find(|id| !known(id)) {
        anyhow::bail!(
            "--fit-only {unknown}: no such fit (a recovery-family case's number, 1 to {}, or fig8)",
            family.len()
        );
    }
    let mut cases = Vec::new();
    if chosen(only, "fig8") {
        let (device, data, free) = fig08()?;
        cases.push((
            "Figure 8 (prototype 1, kink and jump)".to_string(),
            device,
            data,
            free,
        ));
    }
    for c in family {
        if !chosen(only, case_id(c.name)) {
            continue;
        }
        cases.push((
            c.name.to_string(),
            c.start_device()?,
            c.data()?,
            c.free.clone(),
        ));
    }
    cases
        .into_iter()
        .map(|(name, device, data, free)| {
            let mut times = Vec::new();
            let mut last = String::new();
            for _ in 0..repeats.max(1) {
                let (r, t) = pool
                    .install(|| cpu(|| Ok(fit(&device, &data, &free, &FitSettings::default())?)))?;
                times.push(t);
                last = note(&r);
            }
            eprintln!("{name}: {times:.2?} s");
            Ok(FitCost {
                name,
                cpu_s: median(times),
                note: last,
            })
        })
        .collect()
}

/// The table of `costs` over `repeats` runs.
pub fn table(costs: &[FitCost], repeats: usize) -> String {
    let mut md = format!(
        "Processor time of each fit on one thread (a pool of one), median of {repeats} runs \
         with the smallest and largest, at commit `{}`.\n\n\
         | fit | median processor time (s) | range (s) | outcome |\n|---|---|---|---|\n",
        common::git_commit()
    );
    for c in costs {
        md.push_str(&format!(
            "| {} | {} | {} to {} | {} |\n",
            c.name,
            fmt_sig(c.cpu_s.0, 3),
            fmt_sig(c.cpu_s.1, 3),
            fmt_sig(c.cpu_s.2, 3),
            c.note
        ));
    }
    md
}
