//! Tests of the SPICE netlist export (`endstop::spice`). Everything here runs without ngspice
//! except `ngspice_agrees_with_our_integrator`, which prints a skip message and returns when
//! `ngspice` is not on PATH.

use endstop::device::StiffnessModel;
use endstop::drive::Sine;
use endstop::model::{Mode, Model};
use endstop::paper::setups::{comb, endstop, stiffness_model, with_endstop};
use endstop::physics::harvester::Harvester;
use endstop::physics::hertz::HertzLine;
use endstop::physics::transducer::State;
use endstop::spice::*;
use endstop::study::steady::steady_state;
use endstop::study::steady::SettleSettings;
use std::collections::BTreeMap;
use std::process::Command;

use crate::common;
use common::{prototype1 as p1, prototype2 as p2};

fn options(
    initial: InitialCondition,
    solver: SolverSettings,
    wrdata: Option<&str>,
) -> SpiceOptions {
    SpiceOptions {
        title: "test".into(),
        initial,
        solver,
        transient: Transient {
            stop_s: 0.01,
            step_s: 1e-5,
            save_from_s: 0.0,
            wrdata_file: wrdata.map(str::to_string),
        },
        hertz_newton_steps: HERTZ_NEWTON_STEPS,
    }
}

/// `.param name = value` lines of a netlist.
fn params(net: &str) -> BTreeMap<String, f64> {
    net.lines()
        .filter_map(|l| l.strip_prefix(".param "))
        .map(|l| {
            let body = l.split('$').next().unwrap();
            let (k, v) = body.split_once('=').unwrap();
            (k.trim().to_string(), v.trim().parse::<f64>().unwrap())
        })
        .collect()
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * b.abs().max(1e-300)
}

#[test]
fn netlist_is_well_formed() {
    for dev in [
        p1(),
        with_endstop(&p1(), StiffnessModel::Linear, 2.0),
        p2(),
        with_endstop(&p2(), StiffnessModel::Hertz, 0.34),
    ] {
        let drive = SpiceDrive {
            accel_rms_g: 5.5,
            freq_hz: 1200.0,
        };
        let net = netlist(
            &dev,
            &drive,
            &options(
                InitialCondition::rest(),
                SolverSettings::ngspice_defaults(),
                Some("out.dat"),
            ),
        );
        let lines: Vec<&str> = net.lines().collect();
        assert!(lines[0].starts_with("* test"), "title line: {}", lines[0]);
        assert_eq!(*lines.last().unwrap(), ".end");
        assert_eq!(lines.iter().filter(|l| **l == ".end").count(), 1);
        // Every element appears exactly once.
        for name in [
            "Cm", "Rb", "Gk", "Cx", "Gx", "Ia", "Bfe", "Bim", "Vbias", "C1", "Vs1", "B1", "RL1",
            "CL1", "C2", "Vs2", "B2", "RL2", "CL2",
        ] {
            let n = lines
                .iter()
                .filter(|l| l.split_whitespace().next() == Some(name))
                .count();
            assert_eq!(n, 1, "element {name} appears {n} times in\n{net}");
        }
        // Balanced brackets on every line, no non-finite numbers, no ddt.
        for l in &lines {
            let count = |c: char| l.chars().filter(|&x| x == c).count();
            assert_eq!(count('('), count(')'), "unbalanced () in `{l}`");
            assert_eq!(count('{'), count('}'), "unbalanced {{}} in `{l}`");
            let lower = l.to_ascii_lowercase();
            assert!(!lower.contains("nan") && !lower.contains("inf "), "`{l}`");
        }
        assert!(!net.contains("ddt("), "the transducers must not use ddt");
        assert!(net.contains(".ic V(xpos)=0 V(vel)=0 V(n1)=0 V(n2)=0"));
        assert!(net.contains("V(s1)=") && net.contains("V(s2)="));
        assert!(net.contains("\n.control\n") && net.contains("\nquit\n.endc\n"));
        assert!(net.contains("wrdata out.dat v(n1) v(n2) v(xpos) v(vel)"));
        match stiffness_model(&dev) {
            StiffnessModel::Hertz => assert!(net.contains(".func hzf(d)")),
            StiffnessModel::Linear => {
                assert!(net.contains(".func fk(dl) {kim*dl}") && !net.contains("hzf"))
            }
        }
    }
}

#[test]
fn parameters_carry_the_unit_scaling() {
    let dev = p1().with_bias(30.0);
    let drive = SpiceDrive {
        accel_rms_g: 7.0,
        freq_hz: 1350.0,
    };
    let net = netlist(
        &dev,
        &drive,
        &options(
            InitialCondition::rest(),
            SolverSettings::ngspice_defaults(),
            None,
        ),
    );
    let p = params(&net);
    let m = dev.mechanics.mass_kg;
    assert_eq!(p["mass"], m);
    assert_eq!(p["bdamp"], dev.mechanics.damping_n_s_per_m);
    assert_eq!(p["km"], dev.mechanics.stiffness_n_per_m);
    assert!(close(p["x0"], 10.0, 1e-15), "x0 in um: {}", p["x0"]);
    assert!(close(p["xmax"], 7.0, 1e-15), "xmax in um: {}", p["xmax"]);
    assert_eq!(p["c0"], 1.6e-12);
    assert_eq!(p["cp"], 17.3e-12);
    assert_eq!(p["rl"], 4.9e6);
    assert_eq!(p["cl"], 4.0e-12);
    assert_eq!(p["vb"], 30.0);
    assert_eq!(p["bim"], 1.5);
    assert_eq!(p["freq"], 1350.0);
    // Peak inertial force in mN.
    let famp = m * std::f64::consts::SQRT_2 * 7.0 * endstop::G * 1e3;
    assert!(close(p["famp"], famp, 1e-14), "{} vs {famp}", p["famp"]);
    // Hertz scales in mN and um.
    let h = HertzLine::of_device(&dev).unwrap();
    assert!(close(p["hf0"], h.force_scale_n() * 1e3, 1e-14));
    assert!(close(p["hd0"], h.delta_scale_m() * 1e6, 1e-14));
    assert!(
        close(p["hd0"], 120.0, 1e-12),
        "delta0 of prototype 1 is 120 um"
    );
    // Linear law: k_im in mN/um = 1e-3 N/m.
    let lin = with_endstop(&dev, StiffnessModel::Linear, 2.0);
    let p = params(&netlist(
        &lin,
        &drive,
        &options(
            InitialCondition::rest(),
            SolverSettings::ngspice_defaults(),
            None,
        ),
    ));
    assert!(close(
        p["kim"],
        endstop::paper::setups::hertz_stop(&lin).linear_stiffness_n_per_m() * 1e-3,
        1e-14
    ));
    assert_eq!(p["bim"], 2.0);
}

#[test]
fn initial_condition_and_settings_are_written_in_netlist_units() {
    let dev = p1();
    let y = State::new(-6.3e-6, 0.022, 1.0e-12, -2.0e-12);
    let ic = InitialCondition::from_state(&dev, &y);
    let model = Harvester::<4>::new(&dev).unwrap();
    let mut v = vec![0.0; model.layout().outputs.len()];
    model.outputs(Mode::FREE, &y, &mut v);
    let (v1, v2) = (
        v[model.layout().output("v1").unwrap()],
        v[model.layout().output("v2").unwrap()],
    );
    assert_eq!(ic.v1_v, v1);
    assert_eq!(ic.v2_v, v2);
    let solver = SolverSettings {
        reltol: Some(1e-6),
        abstol: Some(1e-15),
        vntol: Some(1e-9),
        chgtol: Some(1e-20),
        trtol: Some(7.0),
        method: Method::Gear { maxord: 2 },
        max_step_s: Some(1e-6),
    };
    let net = netlist(
        &dev,
        &SpiceDrive {
            accel_rms_g: 1.0,
            freq_hz: 1000.0,
        },
        &options(ic, solver, None),
    );
    let icl = net.lines().find(|l| l.starts_with(".ic ")).unwrap();
    let get = |key: &str| -> f64 {
        let tok = icl
            .split_whitespace()
            .find(|t| t.starts_with(&format!("{key}=")))
            .unwrap();
        tok.split_once('=').unwrap().1.parse().unwrap()
    };
    assert!(close(get("V(xpos)"), -6.3, 1e-14), "x in um");
    assert!(close(get("V(vel)"), 22.0, 1e-14), "v in mm/s");
    assert_eq!(get("V(n1)"), v1);
    assert_eq!(get("V(n2)"), v2);
    assert_eq!(get("V(bias)"), comb(&dev).bias_v);
    assert_eq!(get("V(s1)"), comb(&dev).bias_v);
    assert!(net.contains(
        ".options reltol=1e-6 abstol=1e-15 vntol=1e-9 chgtol=1e-20 trtol=7 method=gear maxord=2"
    ));
    assert!(net.contains("\n.tran 1e-5 0.01 0 1e-6 uic\n"), "{net}");
    assert!(
        !net.contains(".control"),
        "no control block without a wrdata file"
    );
    // Defaults write no tolerance and no max step.
    let net = netlist(
        &dev,
        &SpiceDrive {
            accel_rms_g: 1.0,
            freq_hz: 1000.0,
        },
        &options(ic, SolverSettings::ngspice_defaults(), None),
    );
    assert!(net.contains("\n.options method=trap\n"));
    assert!(net.contains("\n.tran 1e-5 0.01 0 uic\n"));
}

#[test]
fn tension_free_variant_clips_the_bracket() {
    let mut dev = p2();
    dev = dev.with_tension_free(true);
    let net = netlist(
        &dev,
        &SpiceDrive {
            accel_rms_g: 0.31,
            freq_hz: 700.0,
        },
        &options(
            InitialCondition::rest(),
            SolverSettings::ngspice_defaults(),
            None,
        ),
    );
    let bim = net.lines().find(|l| l.starts_with("Bim ")).unwrap();
    assert!(
        bim.contains("max(fk(V(xpos)-xmax) + bim*V(vel), 0)"),
        "{bim}"
    );
    assert!(
        bim.contains("min(-fk(-V(xpos)-xmax) + bim*V(vel), 0)"),
        "{bim}"
    );
    dev = dev.with_tension_free(false);
    let net = netlist(
        &dev,
        &SpiceDrive {
            accel_rms_g: 0.31,
            freq_hz: 700.0,
        },
        &options(
            InitialCondition::rest(),
            SolverSettings::ngspice_defaults(),
            None,
        ),
    );
    let bim = net.lines().find(|l| l.starts_with("Bim ")).unwrap();
    assert!(!bim.contains("max(") && !bim.contains("min("), "{bim}");
}

/// Largest relative error of the closed-form Hertz inverse against the library's Lambert W
/// inverse, over delta/delta0 log-spaced in [d_lo, d_hi].
fn hertz_max_rel_error(h: &HertzLine, steps: usize, d_lo: f64, d_hi: f64) -> f64 {
    let n = 2000;
    (0..=n)
        .map(|i| {
            let d = d_lo * (d_hi / d_lo).powf(i as f64 / n as f64);
            let delta = d * h.delta_scale_m();
            let exact = h.force_of_delta(delta);
            let approx = hertz_force_closed_form(h, delta, steps);
            ((approx - exact) / exact).abs()
        })
        .fold(0.0, f64::max)
}

#[test]
fn hertz_closed_form_matches_the_lambert_w_inverse() {
    for dev in [p1(), p2()] {
        let h = HertzLine::of_device(&dev).unwrap();
        let errs: Vec<f64> = (0..=5)
            .map(|k| hertz_max_rel_error(&h, k, 1e-12, 0.5))
            .collect();
        println!(
            "{}: max relative error of the closed-form Hertz inverse on 1e-12 < d < 0.5, \
             by Newton steps 0..5: {}",
            dev.name,
            errs.iter()
                .map(|e| format!("{e:.1e}"))
                .collect::<Vec<_>>()
                .join(", ")
        );
        // Quadratic convergence: each step at least squares the error (up to rounding).
        for k in 1..4 {
            assert!(errs[k] < errs[k - 1], "{errs:?}");
        }
        assert!(errs[HERTZ_NEWTON_STEPS] < 1e-11, "{errs:?}");
        // The penetrations that matter (0 to 1 um) to rounding.
        let d_hi = 1e-6 / h.delta_scale_m();
        let e = hertz_max_rel_error(&h, HERTZ_NEWTON_STEPS, 1e-15, d_hi);
        println!("{}: up to 1 um penetration: {e:.1e}", dev.name);
        assert!(e < 1e-13, "{e}");
    }
    let h = HertzLine::of_device(&p1()).unwrap();
    assert_eq!(hertz_force_closed_form(&h, 0.0, 4), 0.0);
    assert_eq!(hertz_force_closed_form(&h, -1e-9, 4), 0.0);
}

#[test]
fn wrdata_parser_and_window_measures() {
    // A sine of amplitude 2 sampled unevenly over two periods, plus a column that is a
    // triangle wave between -1 and 1.
    let period = 1e-3;
    let mut text = String::from(" time v(n1) v(xpos)\n");
    let n = 4000;
    for i in 0..=n {
        let u = (i as f64 / n as f64).powf(1.02);
        let t = 2.0 * period * u;
        let s = 2.0 * (2.0 * std::f64::consts::PI * t / period).sin();
        let ph = (t / period).fract();
        let tri = if ph < 0.5 {
            4.0 * ph - 1.0
        } else {
            3.0 - 4.0 * ph
        };
        text.push_str(&format!("{t:.17e} {s:.17e} {tri:.17e}\n"));
    }
    let w = parse_wrdata(&text).unwrap();
    assert_eq!(w.names, vec!["time", "v(n1)", "v(xpos)"]);
    assert_eq!(w.len(), n + 1);
    let rms = w.rms("V(N1)", 0.5 * period, 1.5 * period).unwrap();
    assert!(close(rms, 2f64.sqrt(), 1e-5), "{rms}");
    assert!(close(
        w.max_abs("v(n1)", 0.0, 2.0 * period).unwrap(),
        2.0,
        1e-5
    ));
    // |triangle| > 0.5 half of the time.
    let f = w.fraction_above("v(xpos)", 0.5, 0.0, period).unwrap();
    assert!(close(f, 0.5, 1e-3), "{f}");
    assert!(matches!(w.column("v(n9)"), Err(SpiceError::NoColumn(_))));
    assert!(matches!(
        w.rms("v(n1)", 0.0, 3.0 * period),
        Err(SpiceError::Window { .. })
    ));
    assert!(matches!(parse_wrdata(""), Err(SpiceError::Empty)));
    assert!(matches!(
        parse_wrdata(" time v(n1)\n1 2\n3\n"),
        Err(SpiceError::BadLine { line: 3, .. })
    ));
}

/// Runs ngspice on a netlist in a fresh temporary directory and returns the waveforms.
fn run_ngspice(tag: &str, make: impl Fn(&str) -> String) -> Waveforms {
    let dir = std::env::temp_dir().join(format!("endstop-test-spice-{}-{tag}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let dat = dir.join("out.dat");
    let cir = dir.join("case.cir");
    std::fs::write(&cir, make(&dat.display().to_string())).unwrap();
    let out = Command::new("ngspice")
        .arg("-b")
        .arg(&cir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "ngspice failed:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let w = parse_wrdata(&std::fs::read_to_string(&dat).unwrap()).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    w
}

/// ngspice on the exported netlist against our integrator, over the same span from the same
/// initial state, with the documented settings of the `crosscheck` experiment (short spans, so
/// that the test takes seconds): prototype 1 without impacts, and with impacts on both stops.
///
/// It needs ngspice, so it is ignored by default; CI installs ngspice and runs it with
/// `cargo test --release --test all -- spice:: --ignored`. Run without ngspice, it fails
/// with a message saying so.
#[test]
#[ignore = "needs ngspice (apt-get install ngspice); run with --ignored"]
fn ngspice_agrees_with_our_integrator() {
    assert!(
        Command::new("ngspice").arg("-v").output().is_ok(),
        "ngspice is not on PATH: install it (apt-get install ngspice) to run this test"
    );
    let p1 = p1().with_bias(30.0);
    let cases = [
        (
            "free",
            with_endstop(&p1, StiffnessModel::Hertz, 1.5),
            4.1,
            1000.0,
            1e-4,
        ),
        (
            "impacting",
            with_endstop(&p1, StiffnessModel::Linear, 2.0),
            7.0,
            1300.0,
            1e-3,
        ),
    ];
    for (tag, dev, a, f, tol) in cases {
        let period = 1.0 / f;
        let model = Harvester::<4>::new(&dev).unwrap();
        // Exactly 3 settling blocks and 1 measured block of 5 periods each.
        let cfg = SettleSettings {
            rtol: 1e-8,
            block_periods: 5,
            settle_blocks: 3,
            rel_change_tol: 0.0,
            max_blocks: 1,
        };
        let (m, _, _, _) = steady_state(
            &model,
            Sine::from_rms_g(a, f),
            model.rest_state(),
            Mode::FREE,
            a,
            &cfg,
        )
        .unwrap();
        let block = 5.0 * period;
        let (t0, t1) = (3.0 * block, 4.0 * block);
        let solver = SolverSettings::documented(period);
        let w = run_ngspice(tag, |dat| {
            netlist(
                &dev,
                &SpiceDrive {
                    accel_rms_g: a,
                    freq_hz: f,
                },
                &SpiceOptions {
                    title: format!("test {tag}"),
                    initial: InitialCondition::rest(),
                    solver,
                    transient: Transient {
                        stop_s: t1,
                        step_s: period / 100.0,
                        save_from_s: t0 - period,
                        wrdata_file: Some(dat.to_string()),
                    },
                    hertz_newton_steps: HERTZ_NEWTON_STEPS,
                },
            )
        });
        let v1 = w.rms("v(n1)", t0, t1).unwrap();
        let v2 = w.rms("v(n2)", t0, t1).unwrap();
        let cf = w
            .fraction_above("v(xpos)", endstop(&dev).gap_m * 1e6, t0, t1)
            .unwrap();
        let r1 = (v1 - m.v1_rms_v) / m.v1_rms_v;
        let r2 = (v2 - m.v2_rms_v) / m.v2_rms_v;
        println!(
            "{tag}: ours V1 {:.7} V2 {:.7} contact {:.4}; ngspice V1 {v1:.7} V2 {v2:.7} \
             contact {cf:.4}; relative differences {r1:.1e} {r2:.1e}",
            m.v1_rms_v, m.v2_rms_v, m.contact_fraction
        );
        assert!(r1.abs() < tol && r2.abs() < tol, "{tag}: {r1:e} {r2:e}");
        assert_eq!(cf > 0.0, m.contact_fraction > 0.0, "{tag}: contact differs");
    }
}
