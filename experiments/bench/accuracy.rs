//! The untimed accuracy tables of the benchmark (`just bench` only): a record's power by our
//! scheme and by RK4 against Dormand-Prince at a tight tolerance, with impacts, and the energy
//! balance of records. `tests/record_accuracy.rs` asserts what they show.

use anyhow::Result;
use endstop::paper::setups::paper_record;
use endstop::study::record::{simulate_record, RecordSpec};
use endstop::study::rk4_record::simulate_rk4_record;
use rayon::prelude::*;

use crate::SEED;

/// A record of the accuracy tables: its label, its key in summary numbers, the device as
/// simulated and the level (g^2/Hz).
type AccuracyCase = (&'static str, &'static str, endstop::device::Device, f64);

/// The impact-free records of the accuracy tables (the linear regime of Figures 14 and 11).
fn impact_free_cases(
    p1: &endstop::device::Device,
    p2: &endstop::device::Device,
) -> [AccuracyCase; 2] {
    use endstop::paper::setups::{prototype1_setup, prototype2_setup};
    [
        ("P2, Sa = 1e-4", "p2_1e-4", prototype2_setup(p2), 1e-4),
        (
            "P1, Sa = 4.42e-6",
            "p1_4.42e-6",
            prototype1_setup(p1),
            4.42e-6,
        ),
    ]
}

/// The impacting records of the accuracy tables: prototype 1 at 2.85e-2 (Figure 12's setup)
/// and prototype 2 at 1.69e-3 (Figures 14 and 15's).
fn impacting_cases(
    p1: &endstop::device::Device,
    p2: &endstop::device::Device,
) -> [AccuracyCase; 2] {
    use endstop::paper::setups::{prototype1_setup, prototype2_setup};
    [
        (
            "P1, Sa = 2.85e-2",
            "p1_2.85e-2",
            prototype1_setup(p1),
            2.85e-2,
        ),
        (
            "P2, Sa = 1.69e-3",
            "p2_1.69e-3",
            prototype2_setup(p2),
            1.69e-3,
        ),
    ]
}

/// `f(case, run)` for every case and run, on every core at once (for the accuracy tables:
/// nothing here is timed), returned case by case in order.
fn untimed_grid<T: Send>(
    cases: usize,
    runs: usize,
    f: impl Fn(usize, usize) -> Result<T> + Sync,
) -> Result<Vec<Vec<T>>> {
    let all = (0..cases * runs)
        .into_par_iter()
        .map(|k| f(k / runs, k % runs))
        .collect::<Result<Vec<T>>>()?;
    let mut all = all.into_iter();
    Ok((0..cases)
        .map(|_| all.by_ref().take(runs).collect())
        .collect())
}

/// The power of impact-free 1 s records of both prototypes by our scheme and by RK4 with 1,
/// 2, 4 and 8 steps per sample interval, relative to Dormand-Prince at rtol 1e-10, as a
/// Markdown table.
pub fn rk4_accuracy(p1: &endstop::device::Device, p2: &endstop::device::Device) -> Result<String> {
    use endstop::study::record::Scheme;
    let cases = impact_free_cases(p1, p2);
    const SUBSTEPS: [usize; 4] = [1, 2, 4, 8];
    // The runs of a case: ours, the reference, then RK4 with each number of substeps.
    const OURS: usize = 0;
    const REFERENCE: usize = 1;
    const FIRST_RK4: usize = 2;
    let powers = untimed_grid(cases.len(), FIRST_RK4 + SUBSTEPS.len(), |c, r| {
        let (_, _, dev, sa) = &cases[c];
        let mut spec = paper_record(dev, *sa);
        spec.noise.duration_s = 1.0;
        Ok(match r {
            OURS => simulate_record(dev, &spec, SEED, 0)?.summary.p_total_w(),
            REFERENCE => {
                let mut tight = spec;
                tight.scheme = Scheme::Dopri5;
                tight.rtol = 1e-10;
                simulate_record(dev, &tight, SEED, 0)?.summary.p_total_w()
            }
            _ => simulate_rk4_record(dev, &spec, SEED, 0, SUBSTEPS[r - FIRST_RK4])?.p_total_w,
        })
    })?;
    let mut md = String::from("| record | ours | RK4, 1 step | RK4, 2 steps | RK4, 4 steps | RK4, 8 steps |\n|---|---|---|---|---|---|\n");
    for ((label, _, _, _), p) in cases.iter().zip(&powers) {
        let reference = p[REFERENCE];
        let mut row = format!("| {label} | {:.1e} |", (p[OURS] / reference - 1.0).abs());
        for rk4 in &p[FIRST_RK4..] {
            row.push_str(&format!(" {:.1e} |", (rk4 / reference - 1.0).abs()));
        }
        md.push_str(&row);
        md.push('\n');
    }
    Ok(md)
}

/// A record's power with impacts, ours against Dormand-Prince everywhere at rtol 1e-7, 1e-9
/// and 1e-10, one 10 s record of each of [`impacting_cases`]. Returns the Markdown table and,
/// per case, our relative deviation from rtol 1e-10 and that of rtol 1e-9 (the reference's
/// own reproducibility), each under its summary key
/// (`p1_impacting_record_rel_dev_ours`, ..._rtol1e-9).
pub fn impact_accuracy(
    p1: &endstop::device::Device,
    p2: &endstop::device::Device,
) -> Result<(String, Vec<(String, f64)>)> {
    use endstop::study::record::Scheme;
    let cases = impacting_cases(p1, p2);
    // (label, scheme, rtol, the key of its summary number), the reference last.
    let runs = [
        ("ours", Scheme::Exponential, None, Some("ours")),
        (
            "Dormand-Prince, rtol 1e-7",
            Scheme::Dopri5,
            Some(1e-7),
            None,
        ),
        (
            "Dormand-Prince, rtol 1e-9",
            Scheme::Dopri5,
            Some(1e-9),
            Some("rtol1e-9"),
        ),
        (
            "Dormand-Prince, rtol 1e-10",
            Scheme::Dopri5,
            Some(1e-10),
            None,
        ),
    ];
    let mut md = String::from(
        "| record | run | mean power (W) | relative to rtol 1e-10 | impacts |\n|---|---|---|---|---|\n",
    );
    let summaries = untimed_grid(cases.len(), runs.len(), |c, r| {
        let (_, _, dev, sa) = &cases[c];
        let base = paper_record(dev, *sa);
        let (_, scheme, rtol, _) = runs[r];
        let spec = RecordSpec {
            scheme,
            rtol: rtol.unwrap_or(base.rtol),
            ..base
        };
        Ok(simulate_record(dev, &spec, SEED, 0)?.summary)
    })?;
    let mut out = Vec::new();
    for ((label, key, _, _), case) in cases.iter().zip(&summaries) {
        let reference = case.last().expect("a reference run").p_total_w();
        let rel = |p: f64| p / reference - 1.0;
        // The case key starts with its prototype (`p1_2.85e-2`).
        let prototype = key.split('_').next().unwrap_or(key);
        for ((name, _, _, number), s) in runs.iter().zip(case) {
            let (p, impacts) = (s.p_total_w(), s.impacts);
            md.push_str(&format!(
                "| {label} | {name} | {p:.6e} | {:+.1e} | {impacts} |\n",
                rel(p)
            ));
            if let Some(n) = number {
                out.push((format!("{prototype}_impacting_record_rel_dev_{n}"), rel(p)));
            }
        }
    }
    Ok((md, out))
}

/// The energy balance of one 10 s record (stream 0) per case, by our scheme at the default
/// tolerance and at rtol 1e-9 and by Dormand-Prince everywhere at the default: the records
/// of [`impact_free_cases`] (10 s long here) and of [`impacting_cases`]. Returns the Markdown
/// table and (key, our relative residual) per record.
pub fn energy_balance(
    p1: &endstop::device::Device,
    p2: &endstop::device::Device,
) -> Result<(String, Vec<(String, f64)>)> {
    use endstop::study::record::{Scheme, DEFAULT_RTOL};
    use endstop::study::record_ledger::record_ledger;
    let [free_a, free_b] = impact_free_cases(p1, p2);
    let [hit_a, hit_b] = impacting_cases(p1, p2);
    let cases = [free_a, free_b, hit_a, hit_b];
    let runs = [
        ("ours", Scheme::Exponential, DEFAULT_RTOL),
        ("ours, rtol 1e-9", Scheme::Exponential, 1e-9),
        ("Dormand-Prince everywhere", Scheme::Dopri5, DEFAULT_RTOL),
    ];
    let mut md = String::from(
        "| record | run | relative residual | residual (J) | work of the drive (J) | impacts |\n\
         |---|---|---|---|---|---|\n",
    );
    let books = untimed_grid(cases.len(), runs.len(), |c, r| {
        let (_, _, dev, sa) = &cases[c];
        let (_, scheme, rtol) = runs[r];
        let spec = RecordSpec {
            scheme,
            rtol,
            ..paper_record(dev, *sa)
        };
        let (rec, l) = record_ledger(dev, &spec, SEED, 0)?;
        Ok((rec.summary.impacts, l))
    })?;
    let mut out = Vec::new();
    for ((label, key, _, _), case) in cases.iter().zip(&books) {
        for (run, ((name, _, _), (impacts, l))) in runs.iter().zip(case).enumerate() {
            let r = l.relative_residual();
            md.push_str(&format!(
                "| {label} | {name} | {r:+.1e} | {:+.1e} | {:.3e} | {} |\n",
                l.residual(),
                l.excitation(),
                impacts
            ));
            if run == 0 {
                out.push((key.to_string(), r));
            }
        }
    }
    Ok((md, out))
}
