//! The `endstop` tool on a device of several masses (the up-converter example): each study's
//! Parquet and numbers carry every mass's peak displacement and speed under the mass's name,
//! beside the one-mass columns of the output contract.

use std::path::PathBuf;

use crate::cli_common::{read_parquet, run};

/// The per-mass columns of the up-converter (its masses are `driver` and `generator`).
const MASS_COLUMNS: [&str; 4] = [
    "x_generator_peak_m",
    "v_generator_peak_m_per_s",
    "x_driver_peak_m",
    "v_driver_peak_m_per_s",
];

fn upconverter() -> String {
    format!(
        "{}/../data/examples/upconverter.toml",
        env!("CARGO_MANIFEST_DIR")
    )
}

fn tmp(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("endstop-climass-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// Every per-mass column of `df` is there and positive, and the transducer mass's peak is the
/// one-mass `x_peak_m` (`x_col`) of the same row: the first mass of the state is the
/// transducer's, measured at the same samples.
fn assert_mass_columns(df: &polars::prelude::DataFrame, x_col: Option<&str>) {
    for c in MASS_COLUMNS {
        let col = df.column(c).unwrap_or_else(|_| panic!("no column {c}"));
        let v = col.f64().unwrap().clone();
        assert!(v.into_iter().all(|v| v.unwrap() > 0.0), "{c}");
    }
    if let Some(x) = x_col {
        let a = df.column(x).unwrap().f64().unwrap().clone();
        let b = df.column(MASS_COLUMNS[0]).unwrap().f64().unwrap().clone();
        for (a, b) in a.into_iter().zip(&b) {
            assert_eq!(a, b);
        }
    }
}

#[test]
fn a_two_mass_sweep_and_record_carry_each_mass_peaks() {
    let out = tmp("sweep");
    let o = run(&[
        "sweep",
        "--device",
        &upconverter(),
        "--from",
        "16",
        "--to",
        "20",
        "--step",
        "2",
        "--accel-rms-g",
        "0.5",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let df = read_parquet(&out.join("sweep.parquet"));
    // The one-mass contract's columns stay.
    for c in [
        "freq_hz",
        "v1_rms_v",
        "p1_w",
        "x_peak_m",
        "contact_fraction",
    ] {
        assert!(df.column(c).is_ok(), "{c}");
    }
    assert_mass_columns(&df, Some("x_peak_m"));
    let md = std::fs::read_to_string(out.join("numbers.md")).unwrap();
    assert!(
        md.contains("largest displacement and speed of each mass over the sweep")
            && md.contains("`driver`")
            && md.contains("`generator`"),
        "{md}"
    );
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    for c in MASS_COLUMNS {
        assert!(summary.contains(c), "{c} not in summary.json");
    }

    let rec = tmp("record");
    let o = run(&[
        "random",
        "--device",
        &upconverter(),
        "--sine-g",
        "0.7",
        "--freq-hz",
        "18",
        "--duration-s",
        "3",
        "--sample-rate-hz",
        "5000",
        "--out",
        rec.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let df = read_parquet(&rec.join("records.parquet"));
    assert_mass_columns(&df, None);
    let md = std::fs::read_to_string(rec.join("numbers.md")).unwrap();
    assert!(
        md.contains("largest displacement and speed of each mass over the analysed record"),
        "{md}"
    );
    // The one-mass linear theory does not describe two masses: no number is given for it.
    assert!(
        md.contains("linear theory without stops under the same spectrum: not computed for a device of several masses"),
        "{md}"
    );
    let summary = std::fs::read_to_string(rec.join("summary.json")).unwrap();
    assert!(!summary.contains("linear_power_w"), "{summary}");
    let psd = read_parquet(&rec.join("output_psd.parquet"));
    let linear = psd
        .column("linear_psd_uw_per_hz")
        .unwrap()
        .f64()
        .unwrap()
        .clone();
    assert!(
        !linear.is_empty() && linear.into_iter().all(|v| v.is_none_or(f64::is_nan)),
        "linear theory written for two masses"
    );
    let _ = std::fs::remove_dir_all(out);
    let _ = std::fs::remove_dir_all(rec);
}

/// The linear two-mass chain of the library's tests (`tests/masses.rs`: masses `a` 1 g and `b`
/// 0.2 g, springs 40 N/m to the frame from `a`, 10 N/m from `b`, 30 N/m between them; dampers
/// 2e-3 N s/m from `a`, 5e-4 N s/m between them; no transducer, no stops).
const LINEAR_CHAIN: &str = r#"
name = "pair"
params = "test"
description = "a linear two-mass chain"
[[masses]]
name = "a"
mass_kg = 1e-3
[[masses]]
name = "b"
mass_kg = 2e-4
[[springs]]
masses = [0]
stiffness_n_per_m = 40.0
[[springs]]
masses = [1]
stiffness_n_per_m = 10.0
[[springs]]
masses = [0, 1]
stiffness_n_per_m = 30.0
[[dampers]]
masses = [0]
damping_n_s_per_m = 2e-3
[[dampers]]
masses = [1, 0]
damping_n_s_per_m = 5e-4
[transducer]
kind = "none"
"#;

/// A complex number `(re, im)`, for the closed form below.
type C = (f64, f64);

fn mul(a: C, b: C) -> C {
    (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0)
}

fn div(a: C, b: C) -> C {
    let d = b.0 * b.0 + b.1 * b.1;
    ((a.0 * b.0 + a.1 * b.1) / d, (a.1 * b.0 - a.0 * b.1) / d)
}

fn sub(a: C, b: C) -> C {
    (a.0 - b.0, a.1 - b.1)
}

/// The closed-form steady state of the linear chain `M x'' + C x' + K x = M 1 A sin(w t)`:
/// the complex amplitudes `X = (K - w^2 M + i w C)^-1 M 1 A` of masses `a` and `b` (Cramer's
/// rule on the 2 x 2 system), with `x(t) = Im(X e^{i w t})` (the formula of
/// `tests/masses.rs::closed_form`).
fn linear_chain_response(w: f64, amplitude: f64) -> [C; 2] {
    let (k1, k2, k12, c1, c12, m1, m2) = (40.0, 10.0, 30.0, 2e-3, 5e-4, 1e-3, 2e-4);
    let d11 = (k1 + k12 - w * w * m1, w * (c1 + c12));
    let d12 = (-k12, -w * c12);
    let d22 = (k2 + k12 - w * w * m2, w * c12);
    let (f1, f2) = ((m1 * amplitude, 0.0), (m2 * amplitude, 0.0));
    let det = sub(mul(d11, d22), mul(d12, d12));
    [
        div(sub(mul(f1, d22), mul(d12, f2)), det),
        div(sub(mul(d11, f2), mul(d12, f1)), det),
    ]
}

fn column(df: &polars::prelude::DataFrame, name: &str) -> Vec<f64> {
    let c = df
        .column(name)
        .unwrap_or_else(|_| panic!("no column {name}"));
    c.f64().unwrap().into_iter().map(Option::unwrap).collect()
}

fn number(summary: &str, key: &str) -> f64 {
    let v: serde_json::Value = serde_json::from_str(summary).unwrap();
    let n = v
        .get("numbers")
        .and_then(|n| n.get(key))
        .or_else(|| v.get(key));
    n.and_then(serde_json::Value::as_f64)
        .unwrap_or_else(|| panic!("no number {key} in {summary}"))
}

#[test]
fn basins_of_a_linear_chain_on_a_mixed_slice_are_one_attractor_the_closed_form() {
    let dir = tmp("basins-linear");
    std::fs::create_dir_all(&dir).unwrap();
    let dev = dir.join("pair.toml");
    std::fs::write(&dev, LINEAR_CHAIN).unwrap();
    let out = dir.join("out");
    // 70 Hz, between the chain's modes, where the masses' amplitudes differ by 37 %.
    let (f_hz, g_rms) = (70.0, 0.5);
    let o = run(&[
        "basins",
        "--device",
        dev.to_str().unwrap(),
        "--freq",
        "70",
        "--accel-rms-g",
        "0.5",
        "--cells",
        "3",
        "--seeds-per-side",
        "2",
        "--x-range=-1e-3,1e-3",
        "--slice",
        "x:b,v:a",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // A damped linear system has one periodic orbit, reached from every initial state.
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert_eq!(number(&summary, "attractors"), 1.0);
    assert_eq!(number(&summary, "unsettled_share"), 0.0);
    assert_eq!(number(&summary, "share_orbit"), 1.0);
    // The grid's columns name the masses of the slice; the positions span the range asked.
    let cells = read_parquet(&out.join("basins.parquet"));
    let x0 = column(&cells, "x0_b_m");
    assert_eq!(x0.iter().copied().fold(f64::INFINITY, f64::min), -1e-3);
    assert_eq!(x0.iter().copied().fold(f64::NEG_INFINITY, f64::max), 1e-3);
    assert!(cells.column("v0_a_m_per_s").is_ok());
    let md = std::fs::read_to_string(out.join("numbers.md")).unwrap();
    assert!(md.contains("x of `b`") && md.contains("v of `a`"), "{md}");
    // The device's line lists every mass, spring, damper and stop (none here), not the
    // one-mass stops.
    assert!(
        md.contains(
            "masses `a` 1.000 g, `b` 0.2000 g; springs `a`-frame 40.00 N/m, `b`-frame 10.00 N/m, \
             `a`-`b` 30.00 N/m; dampers `a`-frame 0.002000 N s/m, `b`-`a` 0.0005000 N s/m; \
             stops none"
        ),
        "{md}"
    );
    // The attractor's state at drive phase zero, each mass under its name, is the closed
    // form's `x = Im X`, `v = w Re X`. The orbit is converged to a scaled residual of 5e-10
    // with an integration error near 15 rtol = 1.5e-9 of the state's scales (the shooting
    // defaults); 1e-6 of each mass's amplitude leaves more than two decades, while the masses'
    // amplitudes differ by 37 %: a column under the wrong mass's name fails.
    let w = std::f64::consts::TAU * f_hz;
    let amplitude = std::f64::consts::SQRT_2 * g_rms * endstop::G;
    let x = linear_chain_response(w, amplitude);
    let att = read_parquet(&out.join("attractors.parquet"));
    for (name, xk) in ["a", "b"].iter().zip(x) {
        let scale = xk.0.hypot(xk.1);
        let got_x = column(&att, &format!("x_phase0_{name}_m"))[0];
        let got_v = column(&att, &format!("v_phase0_{name}_m_per_s"))[0];
        assert!(
            (got_x - xk.1).abs() < 1e-6 * scale,
            "{name}: x {got_x} vs {}",
            xk.1
        );
        assert!(
            (got_v - w * xk.0).abs() < 1e-6 * w * scale,
            "{name}: v {got_v} vs {}",
            w * xk.0
        );
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn basins_refuse_a_slice_that_names_no_mass_and_a_slice_of_one_mass() {
    let dir = tmp("basins-bad-slice");
    let out = dir.join("out");
    let args = |device: &str, slice: &str| -> std::process::Output {
        run(&[
            "basins",
            "--device",
            device,
            "--freq",
            "18",
            "--accel-rms-g",
            "0.5",
            "--x-range=-1e-3,1e-3",
            "--slice",
            slice,
            "--out",
            out.to_str().unwrap(),
        ])
    };
    let o = args(&upconverter(), "x:driver,v:nobody");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("no mass is named `nobody`") && err.contains("driver, generator")
            || err.contains("generator, driver"),
        "{err}"
    );
    let o = args(&upconverter(), "driver");
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("x:MASS,v:MASS"));
    let one = format!(
        "{}/../data/examples/piezo_cantilever.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let o = args(&one, "x:tip,v:tip");
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("has one mass"));
    assert!(!out.exists(), "a refused run wrote {}", out.display());
}

/// `data/examples/piezo_bridge.toml` as a file of two masses: its mass `tip` (suspension,
/// stop, transducer and bridge unchanged) and a mass `spare` on its own spring and damper,
/// joined to nothing.
fn piezo_bridge_with_a_spare_mass() -> String {
    let text = std::fs::read_to_string(format!(
        "{}/../data/examples/piezo_bridge.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let head = &text[..text.find("[mechanics]").unwrap()];
    let tail = &text[text.find("[transducer]").unwrap()..];
    let masses = r#"transducer_mass = 0
[[masses]]
name = "tip"
mass_kg = 5e-3
[[masses]]
name = "spare"
mass_kg = 1e-3
[[springs]]
masses = [0]
stiffness_n_per_m = 2842.0
[[springs]]
masses = [1]
stiffness_n_per_m = 100.0
[[dampers]]
masses = [0]
damping_n_s_per_m = 0.0754
[[dampers]]
masses = [1]
damping_n_s_per_m = 1e-3
[[stops]]
masses = [0]
side = "upper"
gap_m = 0.1e-3
law = "linear"
stiffness_n_per_m = 28420.0
damping_n_s_per_m = 0.5
"#;
    // The mass-file keys must come before the first table of the one-mass file's head.
    format!("{head}{masses}\n{tail}")
}

#[test]
fn charge_through_a_mass_file_with_a_spare_mass_takes_the_one_mass_time() {
    let dir = tmp("charge");
    std::fs::create_dir_all(&dir).unwrap();
    let two = dir.join("two.toml");
    std::fs::write(&two, piezo_bridge_with_a_spare_mass()).unwrap();
    let one = format!(
        "{}/../data/examples/piezo_bridge.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let time = |device: &str, tag: &str| {
        let out = dir.join(tag);
        let o = run(&[
            "charge",
            "--device",
            device,
            "--freq-hz",
            "120",
            "--accel-rms-g",
            "0.3",
            "--target-v",
            "2",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        number(
            &std::fs::read_to_string(out.join("summary.json")).unwrap(),
            "time_to_target_s",
        )
    };
    let t1 = time(&one, "one");
    let t2 = time(two.to_str().unwrap(), "two");
    // The spare mass is joined to nothing: the tip, its port and its storage obey the one-mass
    // equations, and only the integrator's steps differ (the spare mass's components enter the
    // error norm). Each run holds rtol 1e-8 per step over some 40 drive periods to the target
    // (0.33 s at 120 Hz), so their times differ by about 40 x 1e-8 = 4e-7 at most; 1e-6.
    assert!((t2 / t1 - 1.0).abs() < 1e-6, "{t1} vs {t2}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
#[ignore = "slow: about 80 s (a fit of 5 points over 9 starts)"]
fn fit_on_a_mass_file_runs_on_the_stepped_sweep_and_says_why() {
    use endstop::device::Device;
    use endstop::fit::{model_values, Direction, Point, Quantity, SweepData};
    let dir = tmp("fit");
    std::fs::create_dir_all(&dir).unwrap();
    let start = Device::from_toml_str(
        &std::fs::read_to_string(upconverter()).unwrap(),
        "upconverter",
    )
    .unwrap();
    // The truth: the driver-generator stop's gap at 0.6 mm (the file's start: 0.5 mm).
    let truth = start.with_param("stops.0.gap_m", 0.6e-3).unwrap();
    let freqs = [16.0, 17.0, 18.0, 19.0, 20.0];
    let template = SweepData {
        label: "t".into(),
        direction: Direction::Up,
        accel_rms_g: 0.5,
        quantity: Quantity::V1RmsV,
        points: freqs
            .iter()
            .map(|&f| Point {
                freq_hz: f,
                value: 0.0,
                sigma: None,
            })
            .collect(),
        grid_hz: None,
        features: vec![],
    };
    let v = model_values(&truth, 1.0, &template).unwrap();
    let mut csv = "# accel_rms_g = 0.5\nfreq_hz,v1_rms_v,sigma_v\n".to_string();
    for (f, x) in freqs.iter().zip(&v) {
        csv.push_str(&format!("{f},{x},{}\n", 0.02 * x));
    }
    std::fs::write(dir.join("up.csv"), csv).unwrap();
    let out = dir.join("out");
    let o = run(&[
        "fit",
        "--device",
        &upconverter(),
        "--up-sweep",
        dir.join("up.csv").to_str().unwrap(),
        "--free",
        "stops.0.gap_m=0.3e-3..0.9e-3",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let fitted = std::fs::read_to_string(out.join("fitted.toml")).unwrap();
    let dev = Device::from_toml_str(&fitted, "fitted.toml").unwrap();
    assert!(dev.masses.is_some(), "the fitted file lost its masses");
    let gap = dev.param("stops.0.gap_m").unwrap();
    assert!((0.3e-3..=0.9e-3).contains(&gap), "gap {gap:e}");
    // The branch model follows one mass's orbits: a file of several masses is fitted on the
    // stepped sweep, and the report says why. How near the truth the fit lands is not
    // asserted: the stepped sweep's misfit jumps, and its refinement can stop in a local
    // minimum.
    let md = std::fs::read_to_string(out.join("numbers.md")).unwrap();
    assert!(
        md.contains("stepped-sweep model")
            && md.contains("device `upconverter` has 2 masses: a model of one mass cannot take it"),
        "{md}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn random_on_the_upconverter_normalises_by_the_total_mass() {
    let out = tmp("random-noise");
    let o = run(&[
        "random",
        "--device",
        &upconverter(),
        "--psd",
        "1e-3",
        "--records",
        "1",
        "--duration-s",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    // The white noise puts M Sa / 2 into the device, M the total mass (5.5 g: every mass is
    // driven by the frame), so the efficiency is 2P/(M Sa); one record, so the mean of the
    // ratios is the ratio of the means, to rounding (1e-12). With the driver's 5 g the ratio
    // is off by 10 %, with the generator's 0.5 g by a factor 11.
    let (p, eff) = (number(&summary, "power_w"), number(&summary, "efficiency"));
    let sa_si = 1e-3 * endstop::G * endstop::G;
    let want = 2.0 * p / (5.5e-3 * sa_si);
    assert!((eff / want - 1.0).abs() < 1e-12, "{eff} vs {want}");
    let md = std::fs::read_to_string(out.join("numbers.md")).unwrap();
    assert!(
        md.contains("(m = 5.500 g, the total mass, every mass driven by the frame"),
        "{md}"
    );
    // The device's line names the stop between the two masses.
    assert!(
        md.contains("`piezoelectric` transducer, one load (v2 is zero) on `generator`")
            && md.contains("stops `driver`-`generator` upper `restitution` at 500.0 um"),
        "{md}"
    );
    let _ = std::fs::remove_dir_all(out);
}
