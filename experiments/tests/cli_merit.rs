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
//!   `c_e m A / (c^2 Z_l w0)`, and the normalised power density, that power over the volume `V`
//!   and the RMS acceleration squared (Beeby et al. 2007), `c_e (m A / c)^2 / (2 V a_rms^2)`;
//! * under white noise of two-sided density `Sa` (per Hz) the relative velocity's mean square
//!   is `m Sa / (2 c)` (the classical `pi S0 / (2 zeta w0)` for a density `S0 = Sa / (2 pi)`
//!   per rad/s, with `2 zeta w0 = c / m`), so the load takes `c_e m Sa / (2 c)`: its power
//!   per unit density is `m c_e / (2 c)`, a quarter of the mass here.

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

/// The device's volume in the file that gives one (m^3): 2 cm^3.
const VOLUME_M3: f64 = 2e-6;

/// Writes the generator's device file into `dir`, with `[size] volume_m3 = VOLUME_M3` when
/// `sized`.
fn device(dir: &Path, sized: bool) -> PathBuf {
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
    ) + &if sized {
        format!("[size]\nvolume_m3 = {VOLUME_M3:e}\n")
    } else {
        String::new()
    };
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

/// Runs the command; returns the numbers of `summary.json` and the text of `numbers.md`.
fn run_md(args: &[&str], dir: &Path) -> (serde_json::Value, String) {
    let out = dir.join("out");
    let o = Command::new(BIN)
        .args(args)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(out.join("summary.json")).unwrap();
    let md = std::fs::read_to_string(out.join("numbers.md")).unwrap();
    let numbers = serde_json::from_str::<serde_json::Value>(&text).unwrap()["numbers"].clone();
    (numbers, md)
}

fn run(args: &[&str], dir: &Path) -> serde_json::Value {
    run_md(args, dir).0
}

/// The effectiveness at resonance, `c_e m A / (c^2 Z_l w0)` (module docs).
fn effectiveness_closed_form() -> f64 {
    let a = ACCEL_RMS_G * endstop::G * std::f64::consts::SQRT_2;
    let w0 = 2.0 * std::f64::consts::PI * F0_HZ;
    0.5 * c_total() * M_KG * a / (c_total() * c_total() * GAP_M * w0)
}

/// The normalised power density at resonance, `c_e (m A / c)^2 / (2 V a_rms^2)` (module docs).
fn power_density_closed_form() -> f64 {
    let a_rms = ACCEL_RMS_G * endstop::G;
    let a = a_rms * std::f64::consts::SQRT_2;
    let p = 0.5 * (0.5 * c_total()) * (M_KG * a / c_total()).powi(2);
    p / (VOLUME_M3 * a_rms * a_rms)
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
    let dev = device(&dir, true);
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
    // The power density is the peak power's over a constant: the effectiveness's tolerance.
    let npd = n["normalised_power_density_kg_s_per_m3"]
        .as_f64()
        .expect("a power density");
    let want = power_density_closed_form();
    eprintln!(
        "power density {npd} vs c_e (m A / c)^2 / (2 V a_rms^2) = {want}: relative {:.3e}",
        npd / want - 1.0
    );
    assert!((npd / want - 1.0).abs() < 1e-6);
    assert_eq!(n["volume_m3"].as_f64(), Some(VOLUME_M3));
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
    let dev = device(&dir, false);
    let peak_g = ACCEL_RMS_G * std::f64::consts::SQRT_2;
    let (n, md) = run_md(
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
    // Without a volume: no power density, and the numbers say what it needs.
    assert!(n.get("normalised_power_density_kg_s_per_m3").is_none());
    assert!(n.get("volume_m3").is_none());
    assert!(
        md.contains("normalised power density: needs the device volume"),
        "{md}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `endstop random --psd` (white noise) on the generator: the power per unit density against
/// `m c_e / (2 c)` and the normalised power density against the same mean power over `V` and
/// the noise's mean square `2 B Sa` (module docs).
///
/// Tolerance: the ensemble's mean has the standard error `ci95 / t` (Student's t at 95 % for
/// 7 degrees of freedom, 2.365, as the command's interval is); four of them leave a false
/// failure at a fixed seed below 1 %. The noise is band-limited at `B` = 10 kHz: the response
/// above the band, `|H_v|^2 ~ 1 / w^2` there, holds `4 zeta w0 / (pi w_B)` = 3.2e-4 of the
/// power, a bias added to the bound. The stops 0.3 mm away are 15 RMS displacements
/// (`sqrt(Sa / (4 zeta w0^3))` = 20 um): never reached (asserted).
#[test]
fn random_reports_the_power_per_unit_density_of_white_noise() {
    let dir = tmp("noise");
    let dev = device(&dir, true);
    let psd_g2_per_hz = 2.5e-5;
    let records = 8;
    let n = run(
        &[
            "random",
            "--device",
            dev.to_str().unwrap(),
            "--psd",
            &psd_g2_per_hz.to_string(),
            "--records",
            &records.to_string(),
            "--duration-s",
            "2",
        ],
        &dir,
    );
    assert_eq!(
        n["contact_fraction"].as_f64(),
        Some(0.0),
        "linear throughout"
    );
    let sa_si = psd_g2_per_hz * endstop::G * endstop::G;
    let c_e = 0.5 * c_total();
    let want = M_KG * c_e / (2.0 * c_total());
    let got = n["power_per_sa_kg"]
        .as_f64()
        .expect("a power per unit density");
    let p = n["power_w"].as_f64().unwrap();
    let se = n["power_ci95_w"].as_f64().unwrap() / 2.365 / sa_si;
    let w0 = 2.0 * std::f64::consts::PI * F0_HZ;
    let zeta = c_total() / (2.0 * M_KG * w0);
    let bias = 4.0 * zeta * w0 / (std::f64::consts::PI * 2.0 * std::f64::consts::PI * 10e3);
    let tol = 4.0 * se + bias * want;
    eprintln!(
        "P/Sa {got} kg vs m c_e / (2 c) = {want} kg: difference {:.3e} (tol {tol:.3e}, se {se:.3e})",
        got - want
    );
    assert!((got - want).abs() < tol);
    // The same mean power, by hand, over V and the mean square 2 B Sa.
    assert!((got / (p / sa_si) - 1.0).abs() < 1e-12);
    let npd = n["normalised_power_density_kg_s_per_m3"]
        .as_f64()
        .expect("a power density");
    let by_hand = p / (VOLUME_M3 * 2.0 * 10e3 * sa_si);
    assert!((npd / by_hand - 1.0).abs() < 1e-12, "{npd} vs {by_hand}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `endstop design --psd`: the answer under noise, confirmed on fresh records, and its power
/// density at the noise's RMS acceleration `sqrt(2 B Sa)`.
///
/// What is asserted is what the command writes, not the optimum (the library's test
/// `design_noise` checks that against the closed form): the confirmation's interval is
/// positive and finite; the fresh records' mean lies within two of its 95 % intervals of the
/// search's value: both estimate the same power from 4 records, so the interval is 3.18
/// standard errors (Student's t, 3 degrees of freedom) and two of them 4.5 standard errors of
/// the difference of two independent estimates (the search's value is also biased up by its
/// choice, little on the flat optimum the load's range spans); and the power density is the
/// search's power over `V` and the mean square to rounding (1e-12).
#[test]
fn design_under_noise_confirms_its_answer() {
    let dir = tmp("design-noise");
    let dev = device(&dir, true);
    let (psd, band_hz) = (2.5e-5, 1e3);
    let (n, md) = run_md(
        &[
            "design",
            "--device",
            dev.to_str().unwrap(),
            "--range",
            "load.resistance_ohm=50..500",
            "--psd",
            &psd.to_string(),
            "--noise-band-hz",
            &band_hz.to_string(),
            "--records",
            "4",
            "--duration-s",
            "1",
            "--samples",
            "4",
            "--map-points",
            "0",
        ],
        &dir,
    );
    let p = n["power_w"].as_f64().expect("a power");
    let c = n["power_confirmed_w"].as_f64().expect("a confirmed power");
    let ci = n["power_confirmed_ci95_w"].as_f64().expect("an interval");
    eprintln!("search {p:.5e} W, fresh records {c:.5e} +- {ci:.2e} W");
    assert!(ci.is_finite() && ci > 0.0);
    assert!((c - p).abs() < 2.0 * ci);
    assert!(md.contains("fresh records"), "{md}");
    let sa_si = psd * endstop::G * endstop::G;
    let npd = n["normalised_power_density_kg_s_per_m3"]
        .as_f64()
        .expect("a power density");
    let by_hand = p / (VOLUME_M3 * 2.0 * band_hz * sa_si);
    assert!((npd / by_hand - 1.0).abs() < 1e-12, "{npd} vs {by_hand}");
    assert!(
        n.get("effectiveness").is_none(),
        "no sine bound under noise"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
