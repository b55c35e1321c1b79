//! Times chosen fits of the recovery family (`endstop::fit::family`) on one thread and prints
//! each one's processor and wall time and fitted values: the harness that finds where a fit's time goes
//! (run it under `perf record` for the split between the design's stepped sweeps, the
//! identification of the branches and the Levenberg-Marquardt refinement). `bench --fits`
//! times every fit as the benchmark of record.
//!
//! Usage: `cargo run --release --example fit_cost -- 13 17 21` (case numbers from 1; none:
//! every case).

use endstop::fit::family::recovery_family;
use endstop::fit::{fit, model_curve, model_values, FitSettings};

/// Processor time of this process so far (s; user and system, from `/proc/self/stat`), or NaN
/// where it cannot be read.
fn cpu_s() -> f64 {
    let ticks = std::fs::read_to_string("/proc/self/stat")
        .ok()
        .and_then(|s| {
            // The fields after the command name in parentheses; utime and stime are 14 and 15.
            let rest = s.rsplit_once(')')?.1.to_string();
            let f: Vec<&str> = rest.split_whitespace().collect();
            Some(f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?)
        });
    // Clock ticks of 10 ms (the kernel's USER_HZ of 100).
    ticks.map_or(f64::NAN, |t| t / 100.0)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let chosen: Vec<usize> = std::env::args()
        .skip(1)
        .map(|a| a.parse())
        .collect::<Result<_, _>>()?;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    for (i, c) in recovery_family().iter().enumerate() {
        if !chosen.is_empty() && !chosen.contains(&(i + 1)) {
            continue;
        }
        let (data, start) = (c.data()?, c.start_device()?);
        // One plain stepped sweep of each data set at the start (what the design pays per
        // start) and one with the fit's criteria (what the stepped-sweep model pays per
        // evaluation).
        let c0 = cpu_s();
        pool.install(|| {
            data.iter()
                .try_for_each(|d| model_curve(&start, 1.0, d).map(|_| ()))
        })?;
        let plain = cpu_s() - c0;
        let c0 = cpu_s();
        pool.install(|| {
            data.iter()
                .try_for_each(|d| model_values(&start, 1.0, d).map(|_| ()))
        })?;
        let tight = cpu_s() - c0;
        println!(
            "{}: processor time of a plain sweep {plain:.2} s, of the fit's sweep {tight:.2} s",
            c.name
        );
        let (t, c0) = (std::time::Instant::now(), cpu_s());
        let r = pool.install(|| fit(&start, &data, &c.free, &FitSettings::default()))?;
        let (secs, cpu) = (t.elapsed().as_secs_f64(), cpu_s() - c0);
        println!(
            "{}: processor {cpu:.2} s (wall {secs:.2} s), chi2/dof {:.4}, {} evaluations, {} iterations, {} of {} starts \
             refined, model {}",
            c.name,
            r.reduced_chi2,
            r.evaluations,
            r.iterations,
            r.starts_refined(),
            r.starts.len(),
            r.model
        );
        for w in &r.warnings {
            if let endstop::fit::FitWarning::SteppedSweepModel { why } = w {
                println!("  stepped-sweep model: {why}");
            }
        }
        println!(
            "  design sweeps stopped early: {} of {} starts",
            r.starts.iter().filter(|s| s.design_cut).count(),
            r.starts.len()
        );
        for (p, t) in r.params.iter().zip(&c.truth) {
            println!(
                "  {}: {:.6e} ({:.6e} .. {:.6e}), truth {t:e}",
                p.path, p.value, p.interval.0, p.interval.1
            );
        }
    }
    Ok(())
}
