//! The general model on devices of every kind: the analytic Jacobian against central
//! differences of the right-hand side for every transducer and contact law, the free-flight
//! split `L y + N(y)` against the right-hand side, and the energy audit closing on each.

use endstop::device::Device;
use endstop::drive::{Excitation, Sine};
use endstop::model::{
    Books, Contact, Driven, FlightSplit, FlightVisitor, Mode, Model, NoFlight, Remainder,
};
use endstop::ode::Dopri5;
use endstop::physics::contact::Side;
use endstop::physics::harvester::Harvester;
use endstop::physics::transducer::State;
use nalgebra::Matrix4;

const MECH: &str =
    "[mechanics]\nmass_kg = 1e-3\nstiffness_n_per_m = 400.0\ndamping_n_s_per_m = 4e-3\n";

fn device(stops: &str, transducer: &str) -> Device {
    let text = format!(
        "name = \"t\"\nparams = \"test\"\ndescription = \"test\"\n{MECH}{stops}\n{transducer}\n"
    );
    Device::from_toml_str(&text, "test.toml").unwrap()
}

const TRANSDUCERS: [&str; 6] = [
    "[transducer]\nkind = \"none\"",
    "[transducer]\nkind = \"piezoelectric\"\ncoupling_n_per_v = 2e-4\ncapacitance_f = 1e-8\nload_resistance_ohm = 2e5",
    "[transducer]\nkind = \"electromagnetic\"\ntransduction_n_per_a = 2.0\ncoil_resistance_ohm = 50.0\ncoil_inductance_h = 5e-3\nload_resistance_ohm = 200.0",
    "[transducer]\nkind = \"electromagnetic\"\ntransduction_n_per_a = 2.0\ncoil_resistance_ohm = 50.0\ncoil_inductance_h = 0.0\nload_resistance_ohm = 200.0",
    "[transducer]\nkind = \"gap_closing_pair\"\nc0_f = 2e-11\nelectrode_gap_m = 2e-3\ncp_f = 5e-12\nload_resistance_ohm = 1e7\nload_capacitance_f = 1e-12\nbias_v = 50.0",
    "[transducer]\nkind = \"area_overlap_pair\"\nc0_f = 2e-11\ncp_f = 5e-12\nfinger_overlap_m = 2e-3\nload_resistance_ohm = 1e7\nload_capacitance_f = 1e-12\nbias_v = 50.0",
];

const STOPS: [&str; 5] = [
    "[stops.upper]\ngap_m = 1e-3\nlaw = \"linear\"\nstiffness_n_per_m = 1e5\ndamping_n_s_per_m = 0.3",
    "[stops.upper]\ngap_m = 1e-3\nlaw = \"hertz_point\"\nstiffness_n_per_m1p5 = 1e9\ndamping_n_s_per_m = 0.2",
    "[stops.upper]\ngap_m = 1e-3\nlaw = \"hunt_crossley\"\nstiffness_n_per_m_pow_n = 1e9\nexponent = 1.5\ndamping_s_per_m = 0.5",
    "[stops.upper]\ngap_m = 1e-3\nlaw = \"hertz_line\"\ncontact_length_m = 1e-3\nbump_radius_m = 1e-3\nyoungs_modulus_pa = 1.6e11\npoisson_ratio = 0.22\ndamping_n_s_per_m = 0.1",
    "[stops.upper]\ngap_m = 1e-3\nlaw = \"restitution\"\ncoefficient = 0.6",
];

/// Central differences of the right-hand side, scaled by the state scales, against the
/// analytic Jacobian: each entry to 1e-6 of its row's largest (steps of 1e-5 of each scale:
/// truncation ~1e-10 of the row, rounding ~1e-11).
fn check_jacobian(h: &Harvester<4>, a: f64, mode: Mode, y: &State, what: &str) {
    let sc = h.scales();
    let j = h.jacobian(mode, y);
    let mut fd = Matrix4::zeros();
    for c in 0..4 {
        let e = 1e-5 * sc[c];
        let (mut yp, mut ym) = (*y, *y);
        yp[c] += e;
        ym[c] -= e;
        let col = (h.rhs(mode, &yp, a) - h.rhs(mode, &ym, a)) * (sc[c] / (2.0 * e));
        fd.set_column(c, &col);
    }
    for r in 0..4 {
        let row_max = (0..4).map(|c| fd[(r, c)].abs()).fold(0.0, f64::max);
        for c in 0..4 {
            let an = j[(r, c)] * sc[c];
            assert!(
                (fd[(r, c)] - an).abs() <= 1e-6 * row_max + 1e-300,
                "{what} {mode:?} d f{r}/d y{c}: {an} vs {}",
                fd[(r, c)]
            );
        }
    }
}

#[test]
fn the_jacobian_matches_central_differences_on_every_device() {
    for t in TRANSDUCERS {
        for s in STOPS {
            let d = device(s, t);
            let h = Harvester::<4>::new(&d).unwrap();
            // The base acceleration of 1 g rms at 100 Hz at t = 0.1 s.
            let a = Sine::from_rms_g(1.0, 100.0).accel(0.1);
            let sc = h.scales();
            let mut y = State::new(0.3 * sc[0], 0.4 * sc[1], 0.0, 0.0);
            for i in 2..4 {
                if !h.unused().contains(&i) {
                    y[i] = 0.3 * sc[i];
                }
            }
            let what = format!(
                "{} / {}",
                d.transducer.key(),
                d.stops.upper.as_ref().unwrap().law.key()
            );
            check_jacobian(&h, a, Mode::FREE, &y, &what);
            // 2 % of the gap into the stop, moving in (the differences' steps are then 1/2000
            // of the penetration, so the power laws' truncation stays below 1e-6).
            let mut yc = y;
            yc[0] = h.gap(Side::Upper) * 1.02;
            if matches!(
                d.stops.upper.as_ref().unwrap().law,
                endstop::device::StopLaw::Restitution { .. }
            ) {
                yc[0] = h.gap(Side::Upper);
                yc[1] = 0.0;
                check_jacobian(&h, a, upper(Contact::Resting), &yc, &what);
            } else {
                check_jacobian(&h, a, upper(Contact::Pressed), &yc, &what);
            }
        }
    }
}

/// The mode in which the upper stop (the harvester's contact 0, `Side::BOTH` order) is in
/// the state `c` and the other apart.
fn upper(c: Contact) -> Mode {
    assert_eq!(Side::BOTH[0], Side::Upper);
    Mode::FREE.with_contact(0, c)
}

/// A model's free-flight split (`L`, whether the remainder vanishes) and `L y + R(y)` at `y`.
struct SplitAt(State);

impl FlightVisitor<4> for SplitAt {
    type Output = Result<(FlightSplit<4>, State), NoFlight>;

    fn visit<R: Remainder<4>>(self, split: FlightSplit<4>, remainder: R) -> Self::Output {
        let at = split.l * self.0 + remainder.remainder(&self.0);
        Ok((split, at))
    }

    fn refused(self, why: NoFlight) -> Self::Output {
        Err(why)
    }
}

/// The free-flight split `L y + c a + R(y)`, at a = 0, equals the right-hand side off the
/// stops to 1e-12 of its terms on every transducer; its remainder vanishes except for a
/// capacitor pair. The device has a stop on each side, so that a pair's free flight is
/// bounded and the model offers its split.
#[test]
fn the_free_flight_split_equals_the_right_hand_side() {
    let lower = STOPS[0].replace("stops.upper", "stops.lower");
    for t in TRANSDUCERS {
        let d = device(&format!("{}\n{lower}", STOPS[0]), t);
        let h = Harvester::<4>::new(&d).unwrap();
        let sc = h.scales();
        let y = State::new(0.7 * sc[0], -0.5 * sc[1], 0.2 * sc[2], -0.4 * sc[3]);
        let mut y = y;
        for &i in h.unused() {
            y[i] = 0.0;
        }
        let (ff, split) = h
            .flight(1e-5, SplitAt(y))
            .unwrap_or_else(|e| panic!("{}: no split: {e:?}", d.transducer.key()));
        let l = ff.l;
        let f = h.rhs(Mode::FREE, &y, 0.0);
        for i in 0..4 {
            let tol = 1e-12 * (f[i].abs() + (l.row(i) * y)[0].abs()) + 1e-300;
            assert!(
                (split[i] - f[i]).abs() <= tol,
                "{}: component {i}: {} vs {}",
                d.transducer.key(),
                split[i],
                f[i]
            );
        }
        assert_eq!(
            ff.linear,
            !matches!(
                d.transducer,
                endstop::device::Transducer::AreaOverlapPair(_)
                    | endstop::device::Transducer::GapClosingPair(_)
            )
        );
    }
}

/// The energy audit (the work of every force integrated beside the state) closes on a driven
/// impacting run of every device: the balance's residual is below 1e-6 of the sum of its
/// terms at rtol 1e-9.
#[test]
fn the_energy_balance_closes_on_every_device() {
    for t in TRANSDUCERS {
        for s in STOPS {
            let d = device(s, t);
            // Near resonance (100 Hz suspension), hard enough to hit the 1 mm stop.
            let h = Harvester::<4>::new(&d).unwrap();
            let sine = Sine::from_rms_g(3.0, 95.0);
            let mut books = Books::new(&h, sine);
            let mut ode = Dopri5::new(0.0, State::zeros(), Mode::FREE, h.solver_options(1e-9));
            ode.integrate_observed(&Driven::new(&h, sine), 0.2, &mut books)
                .unwrap();
            let what = format!(
                "{} / {}",
                d.transducer.key(),
                d.stops.upper.as_ref().unwrap().law.key()
            );
            let ledger = books.ledger();
            assert!(
                ledger.relative_residual().abs() < 1e-6,
                "{what}: {ledger:?} residual {}",
                ledger.relative_residual()
            );
            assert!(
                ode.stats().events > 0,
                "{what}: the run should reach the stop"
            );
        }
    }
}

/// The exact integration of sine-driven runs (`study::flow`) against Dormand-Prince everywhere
/// on a driven impacting run of every device (3 g at 95 Hz from rest, 0.1 s, about ten
/// impacts): with a linear transducer the free flight (and a linear stop's contact) is exact
/// and the other contacts go to Dormand-Prince at rtol 1e-11; a capacitor pair goes to
/// Dormand-Prince throughout, bit for bit. Dormand-Prince at rtol 1e-12 is the reference:
/// the final states agree within 1e-6 of the scales, the impacts in number (measured: within
/// a few 1e-9 where the run is exact).
#[test]
fn the_exact_sine_flow_matches_dormand_prince_on_every_device() {
    use endstop::study::flow::{SineFlow, SineScheme};
    for t in TRANSDUCERS {
        for s in STOPS {
            let d = device(s, t);
            let h = Harvester::<4>::new(&d).unwrap();
            let what = format!(
                "{} / {}",
                d.transducer.key(),
                d.stops.upper.as_ref().unwrap().law.key()
            );
            let sine = Sine::from_rms_g(3.0, 95.0);
            let run = |scheme, rtol| {
                let opts = h.solver_options(rtol);
                let mut flow =
                    SineFlow::with(&h, sine, 0.0, h.rest_state(), Mode::FREE, opts, scheme);
                let exact = flow.is_exact();
                flow.integrate(0.1, |_, _| {}).unwrap();
                (flow.y(), flow.stats().events, exact)
            };
            let (ye, ne, exact) = run(SineScheme::Exact, 1e-11);
            let (yd, nd, _) = run(SineScheme::Dopri5, 1e-12);
            assert_eq!(exact, h.free_flight_is_linear(), "{what}");
            assert!(nd > 0, "{what}: the run should reach the stop");
            assert_eq!(ne, nd, "{what}: events");
            let diff = (ye - yd).component_div(&h.scales()).amax();
            assert!(diff < 1e-8, "{what}: final states differ by {diff:e}");
            if !exact {
                let (yb, _, _) = run(SineScheme::Exact, 1e-12);
                assert_eq!(yb, yd, "{what}: a pair goes to Dormand-Prince bit for bit");
            }
        }
    }
}

/// A coil whose time constant L/(Rc + R) = 0.2 us is fifty times shorter than the 10 us
/// sample interval keeps a record on the exponential path (its free flight is linear, so the
/// step is exact at any step length), and the record's power agrees with Dormand-Prince
/// everywhere at rtol 1e-10 within 1e-8 on an impact-free record (measured: 5e-10, the
/// reference's own error).
#[test]
fn a_coil_faster_than_the_sample_rate_keeps_the_exponential_record() {
    use endstop::study::record::{simulate_record, FreeFlightPath, Scheme};
    let coil = "[transducer]\nkind = \"electromagnetic\"\ntransduction_n_per_a = 2.0\ncoil_resistance_ohm = 50.0\ncoil_inductance_h = 5e-5\nload_resistance_ohm = 200.0";
    let d = device(STOPS[2], coil);
    let mut spec = endstop::paper::setups::paper_record(&d, 1e-6);
    spec.transient_s = 0.02;
    spec.noise.duration_s = 0.2;
    let fast = simulate_record(&d, &spec, 7, 3).unwrap();
    assert_eq!(fast.summary.free_flight, FreeFlightPath::Exponential);
    assert_eq!(fast.summary.impacts, 0);
    // Every sample interval: the free flight is linear, so its step needs no remainder
    // history.
    assert_eq!(
        fast.summary.exponential_steps as usize + 1,
        spec.transient_samples() + spec.analysed_samples()
    );
    spec.scheme = Scheme::Dopri5;
    spec.rtol = 1e-10;
    let reference = simulate_record(&d, &spec, 7, 3).unwrap();
    let (a, b) = (fast.summary.p_total_w(), reference.summary.p_total_w());
    assert!((a / b - 1.0).abs() < 1e-8, "{a:e} vs {b:e}");
}

/// A nonlinear suspension makes no mode affine: the sine flow of the hardening and bistable
/// examples goes to Dormand-Prince throughout, bit for bit the run of that scheme (the exact
/// scheme once propagated their linearisation at rest as if it were the dynamics).
#[test]
fn a_nonlinear_suspension_keeps_the_sine_flow_on_dormand_prince() {
    use endstop::study::flow::{SineFlow, SineScheme};
    for file in ["hardening_em.toml", "bistable_stops_em.toml"] {
        let path = format!("{}/data/examples/{file}", env!("CARGO_MANIFEST_DIR"));
        let text = std::fs::read_to_string(&path).unwrap();
        let d = Device::from_toml_str(&text, &path).unwrap();
        let h = Harvester::<4>::new(&d).unwrap();
        let sine = Sine::from_rms_g(0.5, 40.0);
        let run = |scheme| {
            let opts = h.solver_options(1e-8);
            let mut flow = SineFlow::with(&h, sine, 0.0, h.rest_state(), Mode::FREE, opts, scheme);
            let exact = flow.is_exact();
            flow.integrate(0.2, |_, _| {}).unwrap();
            (flow.y(), exact)
        };
        let (ye, exact) = run(SineScheme::Exact);
        let (yd, _) = run(SineScheme::Dopri5);
        assert!(!exact, "{file}: a nonlinear suspension is not affine");
        assert_eq!(ye, yd, "{file}");
    }
}
