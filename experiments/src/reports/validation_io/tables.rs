//! The validation chapter's generated tables: the checks of some groups as one table, the
//! random-vibration ensembles, the harmonic-balance convergence and the cost of each case.

use endstop::validation::nlvib;
use endstop::validation::random_law::{self, LawEnsemble};
use endstop::validation::{cases, Check, Measure, Verdict};

use super::Cost;
use crate::io::md::Table;

fn e(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else {
        format!("{x:.2e}")
    }
}

fn value(x: f64) -> String {
    if x == 0.0 || (x.fract() == 0.0 && x.abs() < 1e6) {
        format!("{x}")
    } else {
        format!("{x:.10e}")
    }
}

/// The verdict as the chapter's tables write it.
fn verdict_label(v: Verdict) -> &'static str {
    match v {
        Verdict::Open => "*open question*",
        Verdict::Reproduced => "within",
        Verdict::Deviates | Verdict::NotYet => "**not met**",
    }
}

pub(super) fn measure_label(m: Measure) -> &'static str {
    match m {
        Measure::Relative => "relative",
        Measure::RelativeToOurs => "relative to ours",
        Measure::Absolute => "absolute",
        Measure::NotAbove => "ours - theirs",
    }
}

/// The checks of some groups as one table.
pub(super) fn checks_table<'a>(checks: impl IntoIterator<Item = &'a Check>) -> String {
    let mut t = Table::new([
        "reference",
        "quantity",
        "theirs",
        "ours",
        "difference",
        "tolerance",
        "verdict",
    ]);
    for c in checks {
        t.row([
            c.source.clone(),
            c.quantity.clone(),
            value(c.compared.reference),
            value(c.compared.ours),
            format!(
                "{} ({})",
                e(c.difference()),
                measure_label(c.compared.measure)
            ),
            match &c.open {
                Some(why) => format!("{} (not applied: {why})", e(c.compared.tolerance)),
                None => format!("{}: {}", e(c.compared.tolerance), c.reason),
            },
            verdict_label(c.verdict()).to_string(),
        ]);
    }
    t.render()
}

pub(super) fn in_groups<'a>(
    checks: &'a [Check],
    prefix: &'a str,
) -> impl Iterator<Item = &'a Check> + 'a {
    checks.iter().filter(move |c| c.group.starts_with(prefix))
}

pub(super) fn random_md(ensembles: &[LawEnsemble], checks: &[Check]) -> String {
    let mut t = Table::new([
        "device",
        "impacts per s",
        "m Sa / 2 (W)",
        "band deficit (est.)",
        "less the deficit (W)",
        "drive (W, 95 %)",
        "dissipation (W, 95 %)",
        "mech. damper",
        "stops (damping)",
        "impact losses",
        "coil",
        "loads",
    ]);
    for ens in ensembles {
        let (d, s) = (ens.drive(), ens.dissipation());
        let share = |f: fn(&random_law::RecordPowers) -> f64| {
            format!("{:.1} %", 100.0 * ens.mean(f) / s.mean)
        };
        t.row([
            ens.device.clone(),
            format!("{:.1}", ens.mean(|r| r.impacts_per_s)),
            format!("{:.4e}", ens.law_w),
            format!("{:.2} %", 100.0 * ens.band_deficit),
            format!("{:.4e}", ens.band_law_w()),
            format!("{:.4e} +- {:.1e}", d.mean, d.ci95),
            format!("{:.4e} +- {:.1e}", s.mean, s.ci95),
            share(|r| r.mech_damping_w),
            share(|r| r.stop_w),
            share(|r| r.impact_losses_w),
            share(|r| r.internal_w),
            share(|r| r.loads_w),
        ]);
    }
    let spec_line = format!(
        "Each ensemble: {} records (noise streams 0 to {} of seed {}), each {} s analysed after \
         the device's pre-roll of five ring-up times, two-sided level Sa = {} g^2/Hz flat to \
         10 kHz, sampled at 100 kHz. The shares divide each dissipation by the total.\n\n",
        cases::RANDOM_RECORDS,
        cases::RANDOM_RECORDS - 1,
        cases::RANDOM_SEED,
        cases::RANDOM_RECORD_S,
        cases::RANDOM_PSD_G2_PER_HZ,
    );
    format!(
        "{spec_line}{}\n{}",
        t.render(),
        checks_table(in_groups(checks, "random vibration"))
    )
}

pub(super) fn nlvib_md(
    checks: &[Check],
    hb: &[nlvib::HbComparison],
    aft_floor: f64,
    fold_floor: f64,
    branch: &endstop::study::continuation::Branch,
    samples: &[nlvib::BranchSample],
) -> String {
    let mut t = Table::new([
        "H",
        "NLvib fold (rad/s)",
        "our fold (rad/s)",
        "fold difference (rad/s)",
        "points compared",
        "largest a1 difference (m)",
    ]);
    for c in hb {
        t.row([
            c.harmonics.to_string(),
            format!("{:.9}", c.fold_rad_s),
            format!("{:.9}", c.our_fold_rad_s),
            e(c.fold_difference()),
            c.amplitudes.len().to_string(),
            e(c.worst_amplitude_difference()),
        ]);
    }
    let unstable = samples.iter().filter(|s| !s.stable).count();
    let events: Vec<String> = branch
        .events
        .iter()
        .map(|ev| {
            format!(
                "{} at Omega = {:.9} rad/s",
                ev.label(),
                ev.param * 2.0 * std::f64::consts::PI
            )
        })
        .collect();
    format!(
        "Our branch: {} points, {} of them unstable; events in branch order: {}.\n\n\
         The floors: the AFT sampling floor (largest change of an H = 40 amplitude with four \
         times finer sampling) is {} m; the deepest micro turning point of the sampled contact \
         force below the fold is {} rad/s.\n\n{}\n{}",
        samples.len(),
        unstable,
        events.join("; "),
        e(aft_floor),
        e(fold_floor),
        t.render(),
        checks_table(in_groups(checks, "peer"))
    )
}

pub(super) fn cost_md(costs: &[Cost]) -> String {
    let mut t = Table::new(["device", "case", "wall time (s)"]);
    for c in costs {
        t.row([c.case.clone(), c.what.clone(), format!("{:.2}", c.wall_s)]);
    }
    format!(
        "Wall-clock seconds of each case in the run that generated this page (the random \
         ensembles run their records in parallel on the machine's cores).\n\n{}",
        t.render()
    )
}
