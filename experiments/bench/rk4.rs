//! The paper records against a fixed-step RK4 at equal accuracy, timed side by side, and the
//! untimed accuracy tables beside them (`bench/accuracy.rs`): what only the whole benchmark
//! measures.

use anyhow::Result;
use endstop::paper::setups::paper_record;
use endstop::study::record::{simulate_record, RecordError};
use endstop::study::rk4_record::{
    simulate_rk4_record, RK4_STEPS_AT_OUR_ACCURACY, RK4_STEPS_AT_TARGET,
};
use endstop_experiments as common;

use common::{fmt_sig, Experiment};

use crate::accuracy;
use crate::cases::RecordCase;
use crate::timing::timed;
use crate::SEED;

/// Runs of each scheme in the side-by-side comparison with RK4.
const RK4_REPEATS: usize = 3;
/// The accuracy asked of a record: its power within this of a tight-tolerance run, and its
/// energy balance closed to this, relatively (`tests/record_accuracy.rs`).
const ACCURACY_TARGET: f64 = 1e-6;

/// The paper records against RK4 and the untimed accuracy tables (Markdown), with their
/// summary numbers.
pub fn paper_rk4_and_accuracy(
    exp: &mut Experiment,
    records: &[RecordCase; 3],
    p1: &common::LoadedDevice,
    p2: &common::LoadedDevice,
) -> Result<String> {
    // The RK4 yardstick at the target accuracy and at our measured accuracy.
    // (RK4 steps per sample, the end of its summary key).
    let picks = [
        (RK4_STEPS_AT_TARGET, "target"),
        (RK4_STEPS_AT_OUR_ACCURACY, "equal"),
    ];
    let accuracy_md = accuracy::rk4_accuracy(&p1.device, &p2.device)?;
    let mut ratios = Vec::new();
    for (case, key, dev, sa) in records.iter().cloned() {
        for (substeps, pick) in picks {
            let spec = paper_record(&dev, sa);
            let mut ours = Vec::new();
            let mut rk4 = Vec::new();
            // RK4 with too few steps through a stiff contact diverges: the failure is
            // reported instead of a time.
            let mut failure = None;
            // Side by side, alternating, so that a change of the machine's speed hits both.
            for _ in 0..RK4_REPEATS {
                ours.push(
                    timed(1, || Ok(simulate_record(&dev, &spec, SEED, 0)?))?
                        .1
                        .cpu[0],
                );
                if failure.is_none() {
                    match timed(1, || {
                        Ok(simulate_rk4_record(&dev, &spec, SEED, 0, substeps)?)
                    }) {
                        Ok((_, t)) => rk4.push(t.cpu[0]),
                        Err(e) => {
                            failure = Some(match e.downcast_ref::<RecordError>() {
                                Some(b) => divergence(b),
                                None => e.to_string(),
                            })
                        }
                    }
                }
            }
            ours.sort_by(f64::total_cmp);
            rk4.sort_by(f64::total_cmp);
            let a = ours[RK4_REPEATS / 2];
            let b = match failure {
                None => Ok(rk4[RK4_REPEATS / 2]),
                Some(e) => Err(e),
            };
            ratios.push((case, format!("{key}_over_rk4_{pick}"), substeps, a, b));
        }
    }
    let mut md = format!(
        "\n**Against a fixed-step RK4 at equal accuracy.** The yardstick \
         (`study::rk4_record`) is the classical RK4, driven by the same Runge-Kutta engine as \
         Dormand-Prince, with a fixed number of steps per 10 us sample interval and contacts \
         located by the Illinois root finder on shortened RK4 steps. \
         Accuracy: the power of impact-free 1 s records against Dormand-Prince everywhere at \
         rtol 1e-10 (relative error):\n\n{accuracy_md}\n\
         RK4 meets the {ACCURACY_TARGET:e} target with {} step(s) per sample, and reaches our accuracy (below \
         1e-8, where the reference's own error is of the same size) with {} (the fewest of 1, 2, \
         4 and 8; `tests/record_accuracy.rs` asserts both). With impacts, too few steps per \
         sample diverge in the contacts (a prototype 1 contact at 2.85e-2 lasts about half a \
         sample interval); the table then gives the integrator's error instead of a time. \
         Median processor times of {RK4_REPEATS} runs of each, alternating in the same process:\n\n\
         | case | RK4 steps per sample | ours (s) | RK4 (s) | ours / RK4 |\n|---|---|---|---|---|\n",
        RK4_STEPS_AT_TARGET,
        RK4_STEPS_AT_OUR_ACCURACY
    );
    for (case, _, substeps, a, b) in &ratios {
        let (rk4, ratio) = match b {
            Ok(b) => (fmt_sig(*b, 3), fmt_sig(a / b, 3)),
            Err(e) => (e.clone(), "-".to_string()),
        };
        md.push_str(&format!(
            "| {case} | {substeps} | {} | {rk4} | {ratio} |\n",
            fmt_sig(*a, 3),
        ));
    }
    for (substeps, pick) in picks {
        exp.number(&format!("rk4_substeps_{pick}"), substeps as f64);
    }
    // Ratios of the timed pairs only (a diverged RK4 run has none).
    for (_, key, _, a, b) in &ratios {
        if let Ok(b) = b {
            exp.number(key, a / b);
        }
    }
    let (impact_md, impact) = accuracy::impact_accuracy(&p1.device, &p2.device)?;
    md.push_str(&format!(
        "\n**A record's power with impacts.** One 10 s record (stream 0) of each figure's \
         setup, by our scheme (rtol {:e} in and near contacts) and by Dormand-Prince \
         everywhere:\n\n{impact_md}\n",
        endstop::study::record::DEFAULT_RTOL
    ));
    for (key, rel) in impact {
        exp.number(&key, rel);
    }
    let (ledger_md, ledger) = accuracy::energy_balance(&p1.device, &p2.device)?;
    md.push_str(&format!(
        "\n**The energy balance of a record.** The same records and two impact-free ones, \
         with the work of every force booked interval by interval on each scheme's own \
         interpolant (`study::record_ledger`); the residual is relative to the sum of the \
         terms' magnitudes:\n\n{ledger_md}\n"
    ));
    for (key, r) in ledger {
        exp.number(&format!("energy_residual_{key}"), r);
    }
    Ok(md)
}

/// A failed RK4 record as a table cell: where its state left the admissible range, or the
/// error's text.
fn divergence(e: &RecordError) -> String {
    use endstop::ode::SolverError;
    match e {
        RecordError::Solver(SolverError::NonFinite { t, .. }) => {
            format!("diverges (non-finite state at t = {t:.3e} s)")
        }
        RecordError::Solver(SolverError::InvalidState { t, .. }) => {
            format!("diverges (inadmissible state at t = {t:.3e} s)")
        }
        other => format!("fails ({other})"),
    }
}
