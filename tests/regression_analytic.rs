//! Snapshot regression suite of our own analytic numbers (Figure 5 and Table 3): the values
//! the scorecard shows for F5-a, F5-b, T3-a, T3-b and eq 21, and the readings shown beside
//! them, pinned with `insta` under `tests/snapshots/`. The verdicts are asserted in
//! `tests/foundation.rs`.
//!
//! Rounding: 6 significant digits. Table 3 is closed-form arithmetic (exact to about 1e-15),
//! and Figure 5's least-squares coefficients are quadratures converged to better than 1e-6
//! (10 times more samples move them by less than that, `tests/foundation.rs`), so a sixth
//! digit flips only when a formula or an input changes.

use std::fmt::Write;

use endstop::paper::figures::fig05::{self, Fig05};
use endstop::paper::figures::table3::Table3;
use endstop::paper::qm::QmReading;
use endstop::paper::Figure;

use crate::common;
use common::{claims, prototypes};

/// `x` with 6 significant digits, in scientific notation.
fn sig6(x: f64) -> String {
    format!("{x:.5e}")
}

fn snapshot(name: &str, text: &str) {
    insta::with_settings!({ prepend_module_to_snapshot => false }, {
        insta::assert_snapshot!(format!("analytic_{name}"), text);
    });
}

#[test]
fn regression_fig05_contact_law_and_eq19() {
    let run = Fig05::run(&prototypes(), &|| {}).unwrap();
    let mut s = String::new();
    for v in Fig05::claims(&run, claims()).unwrap() {
        writeln!(s, "{} {}: {}", v.claim, v.quantity, sig6(v.ours.to_f64())).unwrap();
    }
    for p in &run.prototypes {
        for (label, c) in fig05::FIT_READINGS {
            writeln!(s, "{} {label}: {}", p.label, sig6(c(&p.fits))).unwrap();
        }
        writeln!(s, "{} k_im: {} N/m", p.label, sig6(p.k_im_n_per_m)).unwrap();
    }
    snapshot("fig05", &s);
}

#[test]
fn regression_table3_coupling() {
    let run = Table3::run(&prototypes(), &|| {}).unwrap();
    let mut s = String::new();
    for v in Table3::claims(&run, claims()).unwrap() {
        writeln!(s, "{} {}: {}", v.claim, v.quantity, sig6(v.ours.to_f64())).unwrap();
    }
    for p in &run.prototypes {
        for r in QmReading::ALL {
            writeln!(
                s,
                "{} Qm {}: {}, eq 21 efficiency {}",
                p.label,
                r.label(),
                sig6(p.qm(r)),
                sig6(p.efficiency(r))
            )
            .unwrap();
        }
        writeln!(
            s,
            "{}: k2 with eq 10's C0 {}, k2 without CL {}",
            p.label,
            sig6(p.k2_c0_geometry),
            sig6(p.k2_without_cl)
        )
        .unwrap();
    }
    writeln!(
        s,
        "bias for the abstract's k2 of prototype 1: {} V",
        sig6(run.bias_for_abstract_k2_p1_v)
    )
    .unwrap();
    snapshot("table3", &s);
}
