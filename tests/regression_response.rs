//! Regression of the whole response curve of Figure 13 (prototype 2, 0.31 g, linear law):
//! the events of the continued branch and the Floquet multipliers at 714 Hz, pinned as a
//! snapshot. Frequencies are rounded to 0.01 Hz (events are located to 1e-4 Hz and move by far
//! less than that when the integrator tolerance is halved); multipliers' moduli to 3
//! significant digits (the monodromy is accurate to about 1e-7 absolute, so even the
//! smallest moduli, near 1e-3, keep three digits).

use endstop::ode::Stats;
use endstop::paper::response::{continuation, setups, Case};
use endstop::physics::harvester::Harvester;
use endstop::study::orbit::Shooter;

use crate::common;

#[test]
fn figure13_whole_curve_events_and_multipliers() {
    let p2 = common::prototype2();
    let s = setups(&p2, &p2, &p2)
        .into_iter()
        .find(|s| s.case == Case::Fig13P2)
        .unwrap();
    let b = continuation(&s).unwrap();
    let mut out = String::from("event | frequency (Hz) | stable before | stable after\n");
    for e in &b.events {
        out.push_str(&format!(
            "{} | {:.2} | {} | {}\n",
            e.label(),
            e.param,
            e.stable_before,
            e.stable_after
        ));
    }
    let h = Harvester::<4>::new(&s.device).unwrap();
    let shooter = Shooter::new(&h, s.continuation.shooting);
    let mut stats = Stats::default();
    out.push_str("\norbit at 714 Hz | impacting | stable | |mu| (largest first)\n");
    for o in b.orbits_at(&shooter, 714.0, &mut stats).unwrap() {
        let mu: Vec<String> = o
            .multipliers
            .iter()
            .map(|m| format!("{:.2e}", m.norm()))
            .collect();
        out.push_str(&format!(
            "{:.4} V | {} | {} | {}\n",
            o.summary.v1_rms_v,
            o.is_impacting(),
            o.is_stable(),
            mu.join(", ")
        ));
    }
    insta::assert_snapshot!(out);
}
