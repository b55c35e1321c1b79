//! Regression snapshots of our own sine-sweep numbers (Figures 8, 9 and 13, the calibration
//! and the b_im fits): not checks against the paper (see `paper.rs`), but a record of what the
//! reproduction computes today, so that any change shows in review. Stored in
//! `tests/snapshots/`; after a deliberate change, review the new numbers and accept them with
//! `INSTA_UPDATE=always cargo test --release --test all -- sweep_figures::` (or `cargo insta review`).
//!
//! Rounding, chosen from the convergence study (every sweep repeated with half the step and
//! half the tolerances) so that a legitimate numerical change inside the convergence limits
//! does not flip a digit except by landing on a rounding boundary:
//!
//! * frequencies to 1 Hz (transitions moved by at most 0.05 %, under 0.8 Hz at 1600 Hz);
//! * onsets in g to 0.01 g (they moved by less than 0.001 g);
//! * powers and their ratios to 3 significant digits (powers at 5.5 g moved by less than
//!   0.01 %, RMS voltages anywhere by at most 0.4 %), RMS voltages to 2;
//! * the fitted gap to 0.01 um (the calibration stops within 0.25 Hz of its target, about
//!   0.005 um of gap) and the fitted b_im to 2 significant digits (the fit stops within
//!   0.5 Hz of the jump, about 0.01 N s/m).

use std::fmt::Write;

use endstop::paper::claims::{Answer, Value};
use endstop::paper::figures::fig08::{Fig08, Fig8Curve};
use endstop::paper::figures::fig09::{Fig09, Fig9Bias, PowerReading};
use endstop::paper::figures::fig13::{Fig13, Fig13Curve};
use endstop::paper::Figure;
use endstop::study::sweep::BranchEnd;

use super::common::{calibration, claims as claims_file};
use super::{fig08_run, fig09_run, fig13_run};

/// `x` with `n` significant digits.
fn sig(x: f64, n: usize) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let mag = x.abs().log10().floor() as i32;
    let decimals = (n as i32 - 1 - mag).max(0) as usize;
    format!("{x:.decimals$}")
}

fn hz(x: Option<f64>) -> String {
    x.map_or("none".into(), |v| format!("{v:.0} Hz"))
}

fn end(e: Option<BranchEnd>) -> String {
    e.map_or("none".into(), |e| {
        format!("{:.0} Hz ({})", e.transition.value(), e.kind.label())
    })
}

/// A claim value rounded by its unit.
fn claim_line(out: &mut String, v: &Value) {
    let unit = &claims_file()
        .get(&v.claim, &v.quantity)
        .expect("a known claim")
        .unit;
    let ours = match (v.ours, unit.as_str()) {
        (Answer::YesNo(yes), _) => if yes { "yes" } else { "no" }.to_string(),
        (Answer::Number(x), "Hz") => format!("{x:.0} Hz"),
        (Answer::Number(x), "g") => format!("{x:.2} g"),
        (Answer::Number(x), "") => sig(x, 3),
        (Answer::Number(x), u) => format!("{} {u}", sig(x, 3)),
    };
    writeln!(out, "{} {} {}: {ours}", v.set, v.claim, v.quantity).unwrap();
}

fn snapshot(name: &str, text: &str) {
    insta::with_settings!({
        snapshot_path => "../snapshots",
        prepend_module_to_snapshot => false,
        omit_expression => true,
    }, {
        insta::assert_snapshot!(name, text);
    });
}

#[test]
fn calibration_numbers() {
    let c = &calibration().record;
    let mut s = String::new();
    writeln!(s, "published gap: {:.2} um", c.published_gap_m * 1e6).unwrap();
    writeln!(s, "fitted gap: {:.2} um", c.fitted_gap_m * 1e6).unwrap();
    writeln!(s, "achieved onset: {:.0} Hz", c.achieved_onset_hz).unwrap();
    writeln!(s, "evaluations: {}", c.evaluations).unwrap();
    snapshot("sweep_calibration", &s);
}

#[test]
fn figure8_numbers() {
    let run = fig08_run();
    let mut s = String::new();
    for v in Fig08::claims(run, claims_file()).unwrap() {
        claim_line(&mut s, &v);
    }
    for r in &run.sets {
        for c in Fig8Curve::ALL {
            let rep = &r.sweeps.curve(c).report;
            writeln!(
                s,
                "{} {}: onset {}, branch end {}, max V1 {} V",
                r.set.label(),
                c.spec().label(),
                hz(rep.onset.map(|t| t.value())),
                end(rep.branch_end()),
                sig(rep.max_v1_rms_v(), 2)
            )
            .unwrap();
        }
        for f in &r.fits {
            writeln!(
                s,
                "{} b_im fit {:?}: {} N s/m, at b_im = 0 the branch ends at {}",
                r.set.label(),
                f.stiffness,
                f.bim_n_s_per_m.map_or("none".into(), |b| sig(b, 2)),
                end(f.at_zero)
            )
            .unwrap();
        }
    }
    snapshot("sweep_fig08", &s);
}

#[test]
fn figure9_numbers() {
    let run = fig09_run();
    let mut s = String::new();
    for v in Fig09::claims(run, claims_file()).unwrap() {
        claim_line(&mut s, &v);
    }
    for r in &run.sets {
        for b in Fig9Bias::ALL {
            let rep = &r.curve(b).report;
            let m = rep.at_stop();
            writeln!(
                s,
                "{} {} V: onset {}, at 5.5 g P one load {} nW, P both loads {} nW, V1 {} V",
                r.set.label(),
                b.volts(),
                rep.onset
                    .map_or("none".into(), |t| format!("{:.2} g", t.value())),
                sig(PowerReading::OneLoad.of(m) * 1e9, 3),
                sig(PowerReading::BothLoads.of(m) * 1e9, 3),
                sig(m.v1_rms_v, 2)
            )
            .unwrap();
        }
    }
    snapshot("sweep_fig09", &s);
}

#[test]
fn figure13_numbers() {
    let run = fig13_run();
    let mut s = String::new();
    for v in Fig13::claims(run, claims_file()).unwrap() {
        claim_line(&mut s, &v);
    }
    for c in Fig13Curve::ALL {
        let rep = &run.sweeps.curve(c).report;
        writeln!(
            s,
            "{}: onset {}, jump {}, loss of contact {}, max V1 {} V",
            c.spec().label(),
            hz(rep.onset.map(|t| t.value())),
            hz(rep.jump.map(|t| t.value())),
            hz(rep.contact_lost.map(|t| t.value())),
            sig(rep.max_v1_rms_v(), 2)
        )
        .unwrap();
    }
    snapshot("sweep_fig13", &s);
}
