//! Devices of several masses (`[[masses]]` files, `physics::harvester::masses::MassChain`):
//! loading and its named errors, the linear two-mass chain against its closed-form frequency
//! response and modal frequencies, energy and momentum over thousands of impacts between two
//! free masses, and a stepped sweep of the up-converter example.

use endstop::device::{Device, ParamError};
use endstop::drive::Sine;
use endstop::model::{Driven, Mode, Model};
use endstop::ode::Dopri5;
use endstop::physics::harvester::masses::{natural_frequencies_hz, MassChain};
use nalgebra::{Complex, Matrix2, SVector, Vector2};

const UPCONVERTER: &str = include_str!("../data/examples/upconverter.toml");

/// A two-mass file with the given tables after its masses (transducer none unless given).
pub(crate) fn two_masses(rest: &str) -> String {
    format!(
        r#"
name = "pair"
params = "test"
description = "two masses"
[[masses]]
name = "a"
mass_kg = 1e-3
[[masses]]
name = "b"
mass_kg = 2e-4
{rest}
"#
    )
}

pub(crate) const NO_TRANSDUCER: &str = "[transducer]\nkind = \"none\"\n";

fn load(text: &str) -> Result<Device, ParamError> {
    Device::from_toml_str(text, "pair.toml")
}

#[test]
fn the_upconverter_loads_and_reads_back_equal() {
    let d = Device::from_toml_str(UPCONVERTER, "upconverter.toml").unwrap();
    let m = d.masses.as_ref().unwrap();
    assert_eq!(m.bodies.len(), 2);
    assert_eq!(m.transducer_mass, 1);
    assert_eq!(m.stops[0].other, Some(1));
    let back = Device::from_toml_str(&d.to_toml_string(), "back.toml").unwrap();
    assert_eq!(back, d);
    // Parameters by path, arrays indexed by number.
    assert_eq!(d.param("masses.1.mass_kg").unwrap(), 0.5e-3);
    let heavier = d.with_param("masses.1.mass_kg", 1e-3).unwrap();
    assert_eq!(heavier.masses.unwrap().bodies[1].mass_kg, 1e-3);
    assert!(d.with_param("masses.1.mass_kg", -1.0).is_err());
}

#[test]
fn bad_multi_mass_files_get_named_errors() {
    let spring = "[[springs]]\nmasses = [0]\nstiffness_n_per_m = 10.0\n[[springs]]\nmasses = [1]\nstiffness_n_per_m = 10.0\n";
    let field = |text: String| load(&text).unwrap_err().field().map(str::to_string);
    // A mass's index that does not exist.
    let e = load(&two_masses(&format!(
        "{spring}[[dampers]]\nmasses = [2]\ndamping_n_s_per_m = 1e-3\n{NO_TRANSDUCER}"
    )))
    .unwrap_err();
    assert!(matches!(e, ParamError::OutOfRange { ref field, .. } if field == "dampers[0].masses"));
    // A stop between a mass and itself.
    let e = load(&two_masses(&format!(
        "{spring}[[stops]]\nmasses = [1, 1]\nside = \"upper\"\ngap_m = 1e-3\nlaw = \"restitution\"\ncoefficient = 0.5\n{NO_TRANSDUCER}"
    )))
    .unwrap_err();
    assert!(matches!(e, ParamError::Invalid { ref field, .. } if field == "stops[0].masses"));
    // A stop without its side.
    let text = two_masses(&format!(
        "{spring}[[stops]]\nmasses = [0, 1]\ngap_m = 1e-3\nlaw = \"restitution\"\ncoefficient = 0.5\n{NO_TRANSDUCER}"
    ));
    assert!(matches!(
        load(&text).unwrap_err(),
        ParamError::Missing { .. }
    ));
    assert_eq!(field(text).as_deref(), Some("stops[0].side"));
    // A stop's own keys are checked as a one-mass file's.
    let text = two_masses(&format!(
        "{spring}[[stops]]\nmasses = [0, 1]\nside = \"lower\"\ngap_m = 1e-3\nlaw = \"restitution\"\ncoefficient = 1.5\n{NO_TRANSDUCER}"
    ));
    assert_eq!(field(text).as_deref(), Some("stops[0].coefficient"));
    // A mass connected to nothing.
    let text = two_masses(&format!(
        "[[springs]]\nmasses = [0]\nstiffness_n_per_m = 10.0\n{NO_TRANSDUCER}"
    ));
    assert_eq!(field(text).as_deref(), Some("masses[1]"));
    // The transducer on a mass that does not exist.
    let text = format!(
        "transducer_mass = 3\n{}",
        two_masses(&format!("{spring}{NO_TRANSDUCER}"))
    );
    assert_eq!(field(text).as_deref(), Some("transducer_mass"));
    // A one-mass `[mechanics]` beside `[[masses]]`.
    let text = two_masses(&format!(
        "{spring}[mechanics]\nmass_kg = 1.0\nstiffness_n_per_m = 1.0\ndamping_n_s_per_m = 1.0\n{NO_TRANSDUCER}"
    ));
    assert_eq!(field(text).as_deref(), Some("mechanics"));
    // The one-mass assembly refuses a device of several masses rather than model one of them.
    let d = Device::from_toml_str(UPCONVERTER, "upconverter.toml").unwrap();
    assert!(
        matches!(
            endstop::physics::harvester::Harvester::<4>::new(&d),
            Err(endstop::physics::harvester::AssemblyError::SeveralMasses { masses: 2, .. })
        ),
        "the one-mass assembly must name the device's masses"
    );
}

/// The linear chain of the frequency-response check: mass a on a spring and damper to the
/// frame, mass b on a spring to the frame, a spring and a damper between them.
const K1: f64 = 40.0;
const K2: f64 = 10.0;
const K12: f64 = 30.0;
const C1: f64 = 2e-3;
const C12: f64 = 5e-4;
const M1: f64 = 1e-3;
const M2: f64 = 2e-4;

pub(crate) fn linear_chain() -> Device {
    load(&two_masses(&format!(
        "[[springs]]\nmasses = [0]\nstiffness_n_per_m = {K1}\n\
         [[springs]]\nmasses = [1]\nstiffness_n_per_m = {K2}\n\
         [[springs]]\nmasses = [0, 1]\nstiffness_n_per_m = {K12}\n\
         [[dampers]]\nmasses = [0]\ndamping_n_s_per_m = {C1}\n\
         [[dampers]]\nmasses = [1, 0]\ndamping_n_s_per_m = {C12}\n{NO_TRANSDUCER}"
    )))
    .unwrap()
}

/// The closed-form steady state of `M x'' + C x' + K x = M 1 A sin(w t)`: the complex
/// amplitudes `X = (K - w^2 M + i w C)^-1 M 1 A`, with `x(t) = Im(X e^{i w t})`.
pub(crate) fn closed_form(w: f64, amplitude: f64) -> [Complex<f64>; 2] {
    let i = Complex::new(0.0, 1.0);
    let d = Matrix2::new(
        Complex::from(K1 + K12 - w * w * M1) + i * w * (C1 + C12),
        Complex::from(-K12) - i * w * C12,
        Complex::from(-K12) - i * w * C12,
        Complex::from(K2 + K12 - w * w * M2) + i * w * C12,
    );
    let f = Vector2::new(Complex::from(M1 * amplitude), Complex::from(M2 * amplitude));
    let x = d.lu().solve(&f).unwrap();
    [x[0], x[1]]
}

#[test]
fn a_linear_two_mass_chain_follows_its_closed_form_response() {
    let d = linear_chain();
    let h = MassChain::<6>::new(&d).unwrap();
    let idx = h.layout().masses.clone();
    // The modal frequencies: the undamped chain's w^2 are the eigenvalues of M^-1 K,
    // (p + q)/2 -+ sqrt(((p - q)/2)^2 + K12^2 / (M1 M2)) with p = (K1 + K12)/M1,
    // q = (K2 + K12)/M2.
    let (p, q) = ((K1 + K12) / M1, (K2 + K12) / M2);
    let root = (0.25 * (p - q) * (p - q) + K12 * K12 / (M1 * M2)).sqrt();
    let modes = [(0.5 * (p + q) - root).sqrt(), (0.5 * (p + q) + root).sqrt()];
    // The model's slowest frequency is the first; its undamped Jacobian's eigenvalues are
    // -+ i w_k. Both are an eigenvalue solver's work on a 2x2 or 6x6 matrix whose entries are
    // within a few roundings of exact: 1e-12 relative leaves four decades to the eps of 1e-16.
    let w0 = h.omega_rad_s();
    assert!((w0 / modes[0] - 1.0).abs() < 1e-12, "{w0} vs {}", modes[0]);
    let undamped = load(&two_masses(&format!(
        "[[springs]]\nmasses = [0]\nstiffness_n_per_m = {K1}\n\
         [[springs]]\nmasses = [1]\nstiffness_n_per_m = {K2}\n\
         [[springs]]\nmasses = [0, 1]\nstiffness_n_per_m = {K12}\n{NO_TRANSDUCER}"
    )))
    .unwrap();
    let hu = MassChain::<6>::new(&undamped).unwrap();
    let j = hu.jacobian(Mode::FREE, &SVector::zeros());
    let mut found: Vec<f64> = j
        .complex_eigenvalues()
        .iter()
        .filter(|l| l.im > 0.0)
        .map(|l| l.im)
        .collect();
    found.sort_by(f64::total_cmp);
    assert_eq!(found.len(), 2);
    for (f, w) in found.iter().zip(&modes) {
        assert!((f / w - 1.0).abs() < 1e-12, "mode {f} vs {w}");
    }
    // The natural frequencies the studies report for a device of several masses: the same
    // closed form, within the same eigenvalue solver's 1e-12.
    let reported = natural_frequencies_hz(&undamped);
    assert_eq!(reported.len(), 2);
    for (f, w) in reported.iter().zip(&modes) {
        let w_hz = w / (2.0 * std::f64::consts::PI);
        assert!(
            (f / w_hz - 1.0).abs() < 1e-12,
            "reported {f} Hz vs {w_hz} Hz"
        );
    }
    // The forced response: started on the closed form's orbit, the model stays on it. Over
    // ten periods at rtol 1e-10 the adaptive integrator's global error is of the order of the
    // tolerance times the number of steps' error growth (a few hundred steps per period):
    // 1e-7 of the amplitude leaves two decades of room, while a stiffness or mass off by
    // 1e-6 would move the orbit by more than 1e-6 near a mode.
    let amplitude = 9.81;
    for f_hz in [
        10.0,
        0.98 * modes[0] / std::f64::consts::TAU,
        50.0,
        modes[1] / std::f64::consts::TAU,
        200.0,
    ] {
        let w = std::f64::consts::TAU * f_hz;
        let x = closed_form(w, amplitude);
        let mut y0 = SVector::<f64, 6>::zeros();
        for (k, &(ix, iv)) in idx.iter().enumerate() {
            y0[ix] = x[k].im;
            y0[iv] = (x[k] * Complex::new(0.0, w)).im;
        }
        let sine = Sine {
            amplitude_m_s2: amplitude,
            freq_hz: f_hz,
            phase_rad: 0.0,
        };
        let sys = Driven::new(&h, sine);
        let t_end = 10.0 / f_hz;
        let mut ode = Dopri5::new(0.0, y0, Mode::FREE, h.solver_options(1e-10));
        ode.integrate(&sys, t_end, |_, _| {}).unwrap();
        let phase = Complex::new(0.0, w * t_end).exp();
        for (k, &(ix, _)) in idx.iter().enumerate() {
            let exact = (x[k] * phase).im;
            let err = (ode.y()[ix] - exact).abs() / x[k].norm();
            assert!(
                err < 1e-7,
                "{f_hz} Hz, mass {k}: {} vs {exact} ({err:e})",
                ode.y()[ix]
            );
        }
    }
}

/// A ball of 1 g in a free box of 10 g: two rigid stops between them, restitution 1, no
/// spring, no damper, no drive.
fn ball_in_box() -> Device {
    let stop = |side: &str| {
        format!(
            "[[stops]]\nmasses = [1, 0]\nside = \"{side}\"\ngap_m = 1e-3\nlaw = \"restitution\"\ncoefficient = 1.0\n"
        )
    };
    load(&format!(
        r#"
name = "ball_in_box"
params = "test"
description = "a free ball in a free box"
[[masses]]
name = "box"
mass_kg = 1e-2
[[masses]]
name = "ball"
mass_kg = 1e-3
{}{}{NO_TRANSDUCER}"#,
        stop("upper"),
        stop("lower")
    ))
    .unwrap()
}

#[test]
fn impacts_between_two_free_masses_conserve_energy_and_momentum() {
    let d = ball_in_box();
    let h = MassChain::<6>::new(&d).unwrap();
    let idx = h.layout().masses.clone();
    let masses = [1e-2, 1e-3];
    let mut y0 = SVector::<f64, 6>::zeros();
    y0[idx[0].1] = -0.1;
    y0[idx[1].1] = 1.0;
    let energy = |y: &SVector<f64, 6>| -> f64 {
        (0..2)
            .map(|k| 0.5 * masses[k] * y[idx[k].1] * y[idx[k].1])
            .sum()
    };
    let momentum = |y: &SVector<f64, 6>| -> f64 { (0..2).map(|k| masses[k] * y[idx[k].1]).sum() };
    let scale_p: f64 = (0..2).map(|k| masses[k] * y0[idx[k].1].abs()).sum();
    let (e0, p0) = (energy(&y0), momentum(&y0));
    let sine = Sine {
        amplitude_m_s2: 0.0,
        freq_hz: 1.0,
        phase_rad: 0.0,
    };
    let sys = Driven::new(&h, sine);
    let mut ode = Dopri5::new(0.0, y0, Mode::FREE, h.solver_options(1e-10));
    let (mut worst_e, mut worst_p) = (0.0f64, 0.0f64);
    ode.integrate(&sys, 5.0, |st, _| {
        worst_e = worst_e.max((energy(&st.y1) - e0).abs() / e0);
        worst_p = worst_p.max((momentum(&st.y1) - p0).abs() / scale_p);
    })
    .unwrap();
    let impacts = ode.stats().events as f64;
    // The relative speed 1.1 m/s crosses the 2 mm of play about 550 times a second.
    assert!(impacts > 2000.0, "{impacts} impacts");
    // Between impacts nothing accelerates and the integrator keeps each velocity exactly; an
    // impact computes each new velocity in six roundings (the relative velocity, the
    // coefficient (1 + e) m / (m_i + m_j) in three, its product and the sum), each of at most
    // eps of the larger speed: per impact the momentum moves by at most 12 eps of sum m |v|
    // and the kinetic energy by 24 eps of itself. Summed over every impact without
    // cancellation: 32 eps per impact bounds both.
    let bound = 32.0 * impacts * f64::EPSILON;
    println!("{impacts} impacts: energy {worst_e:e}, momentum {worst_p:e}, bound {bound:e}");
    assert!(worst_e < bound, "energy drifts by {worst_e:e} > {bound:e}");
    assert!(
        worst_p < bound,
        "momentum drifts by {worst_p:e} > {bound:e}"
    );
}

#[test]
fn the_upconverter_sweeps_and_its_generator_is_plucked() {
    use endstop::study::sweep::SweepSettings;
    let d = Device::from_toml_str(UPCONVERTER, "upconverter.toml").unwrap();
    let freqs: Vec<f64> = (0..5).map(|i| 16.0 + 2.0 * i as f64).collect();
    let sweep = |d: &Device| {
        let s = SweepSettings::for_device(d, freqs.clone(), endstop::study::sweep::REFINE_TOL_HZ);
        s.run(d, 0.5, &endstop::progress::Silent).unwrap()
    };
    let with = sweep(&d);
    let alone = sweep(&d.without_stops());
    assert_eq!(with.sweep.steps.len(), 5);
    for (a, b) in with.sweep.steps.iter().zip(&alone.sweep.steps) {
        let (a, b) = (&a.measurement, &b.measurement);
        println!(
            "{} Hz: {:.3e} W plucked ({:.1} impacts a period), {:.3e} W without the stop",
            a.freq_hz,
            a.p_total_w(),
            a.impacts_per_period,
            b.p_total_w()
        );
        // Without the stop the generator follows the 20 Hz base quasi-statically, about
        // m a / k = 4.4e-6 m at 0.5 g rms; plucked, it rings at 200 Hz with the driver's
        // stroke beyond the 0.5 mm gap, tens of times further and ten times faster: its power
        // is above a hundred times the unplucked one wherever the driver reaches it.
        assert!(a.impacts_per_period >= 1.0, "{} Hz: not plucked", a.freq_hz);
        assert!(
            a.p_total_w() > 100.0 * b.p_total_w(),
            "{} Hz: {:e} W plucked, {:e} W alone",
            a.freq_hz,
            a.p_total_w(),
            b.p_total_w()
        );
    }
}

/// A ball dropped onto a table on a spring: the impacts between the two masses accumulate and
/// end with the ball resting on the table, the two moving as one body.
#[test]
fn impacts_that_accumulate_between_two_masses_end_at_rest() {
    let d = load(
        r#"
name = "ball_on_table"
params = "test"
description = "a ball dropped on a sprung table"
[[masses]]
name = "table"
mass_kg = 1e-2
[[masses]]
name = "ball"
mass_kg = 1e-3
[[springs]]
masses = [0]
stiffness_n_per_m = 100.0
[[dampers]]
masses = [0]
damping_n_s_per_m = 0.5
[[stops]]
masses = [0, 1]
side = "upper"
gap_m = 1e-3
law = "restitution"
coefficient = 0.5
[transducer]
kind = "none"
"#,
    )
    .unwrap();
    let h = MassChain::<6>::new(&d).unwrap();
    let idx = h.layout().masses.clone();
    // A base acceleration of -g: a sine of period 1e6 s a quarter-period in, which moves by
    // 2e-11 of itself over the run.
    let g = 9.81;
    let sine = Sine {
        amplitude_m_s2: -g,
        freq_hz: 1e-6,
        phase_rad: std::f64::consts::FRAC_PI_2,
    };
    let sys = Driven::new(&h, sine);
    let mut ode = Dopri5::new(0.0, SVector::zeros(), Mode::FREE, h.solver_options(1e-9));
    ode.integrate(&sys, 1.0, |_, _| {}).unwrap();
    let y = ode.y();
    println!(
        "{} events, mode {:?}, x_table {:e}",
        ode.stats().events,
        ode.mode(),
        y[idx[0].0]
    );
    assert_eq!(ode.mode().contact(0), endstop::model::Contact::Resting);
    // Resting, the two move together with the separation of the contact.
    assert_eq!(y[idx[0].1], y[idx[1].1]);
    assert!((y[idx[0].0] - y[idx[1].0] - 1e-3).abs() < 1e-15);
    // The table settles at the static sag of both masses, -(m_t + m_b) g / k: its ringing
    // (zeta = 0.25 at 100 rad/s) has decayed by exp(-25) after 1 s, so the integrator's 1e-9
    // and the resting shortcut's 1e-12 m bound the error: 1e-6 relative leaves room.
    let sag = -(1e-2 + 1e-3) * g / 100.0;
    assert!(
        (y[idx[0].0] / sag - 1.0).abs() < 1e-6,
        "{} vs {sag}",
        y[idx[0].0]
    );
}

/// `response` on a two-mass file: the continuation runs over the model without a fork (a smoke
/// check: the branch's accuracy is not yet compared with anything outside).
#[test]
fn response_continues_the_upconverter_branch() {
    let d = Device::from_toml_str(UPCONVERTER, "upconverter.toml").unwrap();
    let dg = endstop::study::continuation::frequency_diagram(
        &d,
        0.5,
        19.0,
        21.0,
        0.5,
        &endstop::progress::Silent,
    )
    .unwrap();
    let points: usize = dg.branches.iter().map(|b| b.points.len()).sum();
    println!(
        "{} branches, {} events, {points} points",
        dg.branches.len(),
        dg.events.len()
    );
    assert!(
        points >= 5,
        "{points} points over 2 Hz in steps of at most 0.5 Hz"
    );
}
