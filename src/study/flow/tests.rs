//! The exact scheme against Dormand-Prince at a tight tolerance and against closed forms.

use super::*;
use crate::device::Device;
use crate::physics::harvester::Harvester;
use crate::study::orbit::{Forcing, Parameter, Shooter, ShootingOptions};

type State = SVector<f64, 4>;

fn example(name: &str) -> Device {
    let text = match name {
        "piezo" => include_str!("../../../data/examples/piezo_cantilever.toml"),
        "em" => include_str!("../../../data/examples/em_asymmetric.toml"),
        _ => unreachable!(),
    };
    Device::from_toml_str(text, name).unwrap()
}

/// Runs `model` from rest over `periods` drive periods by `scheme` at `rtol`: the final
/// state, the events, and the integral of V1^2 over the run.
fn run(
    model: &Harvester<4>,
    sine: Sine,
    periods: f64,
    scheme: SineScheme,
    rtol: f64,
) -> (State, u64, f64) {
    let mut flow = SineFlow::with(
        model,
        sine,
        0.0,
        model.rest_state(),
        Mode::FREE,
        model.solver_options(rtol),
        scheme,
    );
    assert_eq!(flow.is_exact(), scheme == SineScheme::Exact);
    let mut v1sq = 0.0;
    flow.integrate(periods / sine.freq_hz, |st, mode| {
        v1sq += st.integrate(|y| {
            let mut out = [0.0; 4];
            model.outputs(mode, y, &mut out);
            out[0].powi(2)
        });
    })
    .unwrap();
    (flow.y(), flow.stats().events, v1sq)
}

/// The largest difference of two states relative to the model's scales.
fn scaled_diff(model: &Harvester<4>, a: &State, b: &State) -> f64 {
    (a - b).component_div(&model.scales()).amax()
}

#[test]
fn exact_through_linear_contacts_matches_dormand_prince() {
    // The piezoelectric example at 130 Hz, 0.5 g: impacts on its linear stop from the fifth
    // period on, every mode affine. Dormand-Prince at rtol 1e-12 is accurate to about 1e-10
    // of the scales over 40 periods, the events to about 1e-14 s: the two agree within 1e-8
    // (measured: a few 1e-10), with the same number of events.
    let model = Harvester::<4>::new(&example("piezo")).unwrap();
    let sine = Sine::from_rms_g(0.5, 130.0);
    let (ye, ne, ve) = run(&model, sine, 40.0, SineScheme::Exact, 1e-8);
    let (yd, nd, vd) = run(&model, sine, 40.0, SineScheme::Dopri5, 1e-12);
    assert!(ne > 40, "{ne} events: the run must impact");
    assert_eq!(ne, nd);
    let d = scaled_diff(&model, &ye, &yd);
    assert!(d < 1e-8, "final states differ by {d:e} of the scales");
    assert!((ve / vd - 1.0).abs() < 1e-8, "{ve} vs {vd}");
}

#[test]
fn exact_with_a_stiff_coil_and_nonlinear_contacts_matches_dormand_prince() {
    // The electromagnetic example at 50 Hz, 0.2 g: a coil with L/(Rc + R) = 1.25 us, exact in
    // free flight at 64 steps per period, and Hunt-Crossley impacts on the upper stop from
    // about the 20th period on, by Dormand-Prince. With Dormand-Prince at rtol 1e-11 in the
    // contacts the runs agree with Dormand-Prince everywhere at rtol 1e-11 within 1e-7 of the
    // scales (the contacts' own error; measured: about 1e-9).
    let model = Harvester::<4>::new(&example("em")).unwrap();
    let sine = Sine::from_rms_g(0.2, 50.0);
    let (ye, ne, ve) = run(&model, sine, 40.0, SineScheme::Exact, 1e-11);
    let (yd, nd, vd) = run(&model, sine, 40.0, SineScheme::Dopri5, 1e-11);
    assert!(ne >= 10, "{ne} events: the run must impact");
    assert_eq!(ne, nd);
    let d = scaled_diff(&model, &ye, &yd);
    assert!(d < 1e-7, "final states differ by {d:e} of the scales");
    assert!((ve / vd - 1.0).abs() < 1e-7, "{ve} vs {vd}");
}

/// A linear oscillator without transducer at 10 Hz, 100 Hz natural frequency, light damping,
/// started on its periodic solution (no homogeneous part): x(t) = X sin(w t + psi) exactly.
/// Returns the model with an upper stop at `gap_rel` times X, and (X, psi).
fn sine_on_a_stop(gap_rel: f64) -> (Harvester<4>, f64, f64) {
    let text = r#"
        name = "oscillator"
        params = "example"
        description = "A linear oscillator on a stop (test)"
        [mechanics]
        mass_kg = 1e-3
        stiffness_n_per_m = 394.78417604357435
        damping_n_s_per_m = 1e-3
        [stops.upper]
        gap_m = 1e-3
        law = "linear"
        stiffness_n_per_m = 4000.0
        damping_n_s_per_m = 0.0
        [transducer]
        kind = "none"
    "#;
    let dev = Device::from_toml_str(text, "oscillator").unwrap();
    let sine = Sine::from_rms_g(1.0, 10.0);
    // The forced response of m x'' + b x' + k x = m a: x = Im[A e^{i w t} / (k/m - w^2 + i w b/m)].
    let w = 2.0 * std::f64::consts::PI * 10.0;
    let (m, k, b) = (1e-3, 394.78417604357435, 1e-3);
    let den = nalgebra::Complex::new(k / m - w * w, w * b / m);
    let amp = sine.amplitude_m_s2 / den;
    let (x_amp, psi) = (amp.norm(), amp.arg());
    let mut dev = dev;
    dev.stops.upper.as_mut().unwrap().gap_m = gap_rel * x_amp;
    (Harvester::<4>::new(&dev).unwrap(), x_amp, psi)
}

/// The time of the first contact entry.
struct FirstImpact(Option<f64>);

impl Observer<State, Mode> for FirstImpact {
    fn step(&mut self, _: &Step<State>, _: Mode) {}

    fn switched(&mut self, t: f64, from: Mode, to: Mode) {
        if !from.in_contact() && to.in_contact() && self.0.is_none() {
            self.0 = Some(t);
        }
    }
}

#[test]
fn a_grazing_orbit_is_found_at_the_closed_form_time() {
    // x(t) = X sin(w t + psi): with the stop 1e-7 X below the crest, the mass reaches it at
    // w t = asin(gap / X) - psi (mod 2 pi), 45 us before the crest; with the stop 1e-7 X above
    // the crest it never does. Both within one period.
    let w = 2.0 * std::f64::consts::PI * 10.0;
    for (gap_rel, hits) in [(1.0 - 1e-7, true), (1.0 + 1e-7, false)] {
        let (model, x_amp, psi) = sine_on_a_stop(gap_rel);
        let sine = Sine::from_rms_g(1.0, 10.0);
        let affine = model.affine(Mode::FREE).unwrap();
        let am = AffineMode::of(Mode::FREE, affine, &sine, model.unused()).unwrap();
        let y0 = am.particular(0.0);
        assert!((y0[0] - x_amp * psi.sin()).abs() < 1e-12 * x_amp);
        let mut flow = SineFlow::new(&model, sine, 0.0, y0, Mode::FREE, 1e-8);
        let mut first = FirstImpact(None);
        flow.integrate_observed(0.1, &mut first).unwrap();
        let first = first.0;
        match (hits, first) {
            (true, Some(t)) => {
                let two_pi = 2.0 * std::f64::consts::PI;
                let want = ((gap_rel.asin() - psi).rem_euclid(two_pi)) / w;
                // The event time tolerance is 1e-14 s; asin near 1 loses half the digits of
                // gap/X (1e-16 relative): the closed form itself is good to about 1e-10 s.
                assert!(
                    (t - want).abs() < 1e-9,
                    "contact at {t} s, closed form {want} s"
                );
            }
            (false, None) => {}
            _ => panic!("gap {gap_rel} X: contact at {first:?}"),
        }
    }
}

#[test]
fn exact_variational_equations_match_finite_differences() {
    // A periodic orbit of the piezoelectric example with impacts (130 Hz, 0.5 g): the
    // monodromy of the exact variational equations (with the saltation at each impact) against
    // central differences of the period map, to 1e-5 of its largest entry (as for
    // Dormand-Prince's variational equations in the orbit tests: truncation falls as eps^2, and
    // the event times, located to 1e-14 s, put a floor of about 1e-14 s times the speed over
    // eps times the scale under the differences); a missing saltation term changes entries by
    // order one (measured: 1.5e-7 at both steps). And dP/df against a central difference in
    // f, to 1e-6.
    let model = Harvester::<4>::new(&example("piezo")).unwrap();
    let sine = Sine::from_rms_g(0.5, 130.0);
    let forcing = Forcing {
        freq_hz: 130.0,
        accel_rms_g: 0.5,
    };
    let shooter = Shooter::new(&model, ShootingOptions::default());
    let settled = run(&model, sine, 60.0, SineScheme::Exact, 1e-10).0;
    let mut stats = Stats::default();
    let orbit = shooter
        .solve(&forcing, Parameter::Frequency, 0.0, settled, &mut stats)
        .unwrap();
    assert!(orbit.summary.impacts > 0);
    let lin = shooter
        .linearise(
            &forcing,
            Parameter::Frequency,
            0.0,
            orbit.state_n(),
            &mut stats,
        )
        .unwrap();
    let exact = shooter.scaled_monodromy(&lin.monodromy);
    for eps in [3e-5, 1e-5] {
        let fd = shooter
            .monodromy_fd(&forcing, 0.0, orbit.state_n(), eps)
            .unwrap();
        let err = (exact - fd).amax() / fd.amax();
        assert!(err < 1e-5, "eps {eps:e}: monodromy differs by {err:e}");
    }
    // Steps of 1e-3 Hz: the truncation is of order df^2; below 1e-4 Hz the floor of the
    // event times shows (measured: 1.6e-7 at 1e-3 Hz, 3e-6 at 1e-4 Hz, 1e-5 at 1e-5 Hz).
    let df = 1e-3;
    let up = shooter
        .period_map(
            &forcing.with(Parameter::Frequency, 130.0 + df),
            0.0,
            orbit.state_n(),
        )
        .unwrap();
    let down = shooter
        .period_map(
            &forcing.with(Parameter::Frequency, 130.0 - df),
            0.0,
            orbit.state_n(),
        )
        .unwrap();
    let fd_dp = (up - down) / (2.0 * df);
    let err = (lin.dp - fd_dp).component_div(&model.scales()).amax()
        / fd_dp.component_div(&model.scales()).amax();
    assert!(err < 1e-6, "dP/df differs by {err:e}");
}

#[test]
fn a_transient_advanced_unseen_takes_the_same_steps_as_one_observed() {
    // Not building the dense output for an observer that sees nothing must leave the steps
    // alone: the same final state and mode bit for bit, the same counters, over a run that
    // impacts (events, partial steps) on the exact path.
    let model = Harvester::<4>::new(&example("piezo")).unwrap();
    let sine = Sine::from_rms_g(0.5, 130.0);
    let new = || SineFlow::new(&model, sine, 0.0, model.rest_state(), Mode::FREE, 1e-8);
    let (mut seen, mut unseen) = (new(), new());
    assert!(seen.is_exact());
    let t_end = 40.0 / sine.freq_hz;
    let mut shown = 0;
    seen.integrate(t_end, |_, _| shown += 1).unwrap();
    unseen.advance(t_end).unwrap();
    assert!(seen.stats().events > 40, "the run must impact");
    assert!(shown > 0);
    assert_eq!(seen.y(), unseen.y());
    assert_eq!(seen.mode(), unseen.mode());
    assert_eq!(seen.stats(), unseen.stats());
}
