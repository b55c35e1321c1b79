//! The designer's figures of merit that `endstop sweep` and `endstop random` write (from
//! `endstop::design::merit`) against closed forms of a linear velocity-damped resonant
//! generator: a 10 g magnet on a 50 Hz spring in a coil with neither resistance nor inductance,
//! so that the load is a pure damper `c_e = Phi^2 / R` beside the mechanical damping `b`
//! (here `b = c_e`, quality factor 10), with stops 0.3 mm away that it never reaches at
//! 0.1 g rms. Under a base acceleration of amplitude `A` its velocity amplitude is
//! `m A / |c + i (m w - k / w)|` with `c = b + c_e`, so
//!
//! * the load's power `c_e |v|^2 / 2` is half its peak where `|m w - k / w| = c`, whose two
//!   roots differ by `c / m` exactly: the half-power band is `c / (2 pi m)` Hz wide
//!   (`2 zeta f0`);
//! * at resonance the load takes `c_e (m A / c)^2 / 2`, and the effectiveness, that power over
//!   the displacement-limited bound `m A Z_l w0 / 2` with `Z_l` the stop gap, is
//!   `c_e m A / (c^2 Z_l w0)`.

use std::path::{Path, PathBuf};
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_endstop");

/// The generator: mass (kg), resonance (Hz), transduction (N/A), gap (m), drive (g rms).
const M_KG: f64 = 10e-3;
const F0_HZ: f64 = 50.0;
const PHI_N_PER_A: f64 = 5.0;
const GAP_M: f64 = 3e-4;
const ACCEL_RMS_G: f64 = 0.1;
const Q: f64 = 10.0;

/// The total damping `m w0 / Q` (N s/m); half of it mechanical, half the load's.
fn c_total() -> f64 {
    M_KG * 2.0 * std::f64::consts::PI * F0_HZ / Q
}

/// Writes the generator's device file into `dir`.
fn device(dir: &Path) -> PathBuf {
    let w0 = 2.0 * std::f64::consts::PI * F0_HZ;
    let (b, c_e) = (0.5 * c_total(), 0.5 * c_total());
    let stop = format!(
        "gap_m = {GAP_M:e}\nlaw = \"hertz_point\"\nstiffness_n_per_m1p5 = 1e7\n\
         damping_n_s_per_m = 0.0\n"
    );
    let text = format!(
        "name = \"vdrg\"\nparams = \"hypothetical\"\n\
         description = \"a linear velocity-damped resonant generator\"\n\
         [mechanics]\nmass_kg = {M_KG:e}\nstiffness_n_per_m = {:e}\ndamping_n_s_per_m = {b:e}\n\
         [stops.upper]\n{stop}[stops.lower]\n{stop}\
         [transducer]\nkind = \"electromagnetic\"\ntransduction_n_per_a = {PHI_N_PER_A:e}\n\
         coil_resistance_ohm = 0.0\ncoil_inductance_h = 0.0\nload_resistance_ohm = {:e}\n",
        M_KG * w0 * w0,
        PHI_N_PER_A * PHI_N_PER_A / c_e
    );
    std::fs::create_dir_all(dir).unwrap();
    let path = dir.join("vdrg.toml");
    std::fs::write(&path, text).unwrap();
    path
}

fn tmp(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("endstop-merit-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn run(args: &[&str], dir: &Path) -> serde_json::Value {
    let out = dir.join("out");
    let o = Command::new(BIN)
        .args(args)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(out.join("summary.json")).unwrap();
    serde_json::from_str::<serde_json::Value>(&text).unwrap()["numbers"].clone()
}

/// The effectiveness at resonance, `c_e m A / (c^2 Z_l w0)` (module docs).
fn effectiveness_closed_form() -> f64 {
    let a = ACCEL_RMS_G * endstop::G * std::f64::consts::SQRT_2;
    let w0 = 2.0 * std::f64::consts::PI * F0_HZ;
    0.5 * c_total() * M_KG * a / (c_total() * c_total() * GAP_M * w0)
}

/// `endstop sweep`'s half-power band and effectiveness against the closed forms.
///
/// The sweep steps 1/40 of the band (0.125 Hz from 40 to 60 Hz, 50 Hz on the grid, so the peak
/// is a grid point). Tolerances: each steady state settles through blocks of at least 64
/// periods, over which the transient decays by `e^(-c T / (2 m))`, below 1e-8, and is
/// integrated to rtol 1e-8, so the powers are good to about 1e-8 and the effectiveness at the
/// peak is held to 1e-6. The band's edges are read by straight lines between steps `h` apart:
/// for the Lorentzian `1 / (1 + x^2)` (`x = 2 (f - f0) / w`, `w` the width) the chord's error
/// at the half-power point, `h_x^2 |P''| / 8` with `h_x = 2 h / w` and `P'' = 1/2`, over the
/// slope `|P'| = 1/2` moves each edge by at most `(h / w)^2 w / 4`: the width by
/// `(h / w)^2 / 2` relative, 3.1e-4 here. The curve in `f` departs from the Lorentzian by
/// terms of order `1 / Q` (10 %); the tolerance doubles the bound to `(h / w)^2`, 6.25e-4.
#[test]
fn sweep_reports_the_half_power_band_and_effectiveness_of_a_resonant_generator() {
    let dir = tmp("sweep");
    let dev = device(&dir);
    let width_hz = c_total() / (2.0 * std::f64::consts::PI * M_KG);
    let step_hz = 0.125;
    assert!(
        (width_hz / step_hz - 40.0).abs() < 1e-9,
        "the step is 1/40 of the band"
    );
    let n = run(
        &[
            "sweep",
            "--device",
            dev.to_str().unwrap(),
            "--from",
            "40",
            "--to",
            "60",
            "--step",
            "0.125",
            "--accel-rms-g",
            &ACCEL_RMS_G.to_string(),
        ],
        &dir,
    );
    let got = n["half_power_width_hz"].as_f64().expect("a width");
    let tol = (step_hz / width_hz).powi(2);
    eprintln!(
        "half-power width {got} Hz vs c / (2 pi m) = {width_hz} Hz: relative {:.3e} (tol {tol:.3e})",
        got / width_hz - 1.0
    );
    assert!((got / width_hz - 1.0).abs() < tol);
    assert_eq!(n["half_power_peak_hz"].as_f64(), Some(F0_HZ));
    let eff = n["effectiveness"].as_f64().expect("an effectiveness");
    let want = effectiveness_closed_form();
    eprintln!(
        "effectiveness {eff} vs c_e m A / (c^2 Z_l w0) = {want}: relative {:.3e}",
        eff / want - 1.0
    );
    assert!((eff / want - 1.0).abs() < 1e-6);
    assert_eq!(n["effectiveness_limit_m"].as_f64(), Some(GAP_M));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `endstop random --sine-g` at the resonance: the effectiveness of the record's power against
/// the closed form.
///
/// Tolerance: the pre-roll of five ring-up times `2 m / b` is ten decay times of the velocity's
/// transient (`b = c / 2`), which leaves `e^(-10)` = 4.5e-5 of the amplitude at the record's
/// start, decaying within 0.064 s of the 4 s record (the shortest the analysis band's 32
/// periods of 12.5 Hz allow after the pre-roll): its share of the mean power is below
/// 2 x 4.5e-5 x 0.064 / 4 = 1.5e-6. The record holds 200 whole periods (to one sample of the
/// pre-roll's rounding, 1/400 000 of the record), the drive is sampled 2000 times a period
/// (its linear interpolation changes the fundamental's amplitude by `(pi / 2000)^2 / 6`,
/// 4e-7), and the integrator's rtol is 1e-8: 1e-4 holds their sum with a margin of ten.
#[test]
fn random_reports_the_effectiveness_of_a_sine_drive() {
    let dir = tmp("random");
    let dev = device(&dir);
    let peak_g = ACCEL_RMS_G * std::f64::consts::SQRT_2;
    let n = run(
        &[
            "random",
            "--device",
            dev.to_str().unwrap(),
            "--sine-g",
            &peak_g.to_string(),
            "--freq-hz",
            &F0_HZ.to_string(),
            "--duration-s",
            "4",
        ],
        &dir,
    );
    let eff = n["effectiveness"].as_f64().expect("an effectiveness");
    let want = effectiveness_closed_form();
    eprintln!(
        "effectiveness {eff} vs c_e m A / (c^2 Z_l w0) = {want}: relative {:.3e}",
        eff / want - 1.0
    );
    assert!((eff / want - 1.0).abs() < 1e-4);
    let _ = std::fs::remove_dir_all(&dir);
}
