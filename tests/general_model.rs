//! The general model on devices of every kind: the analytic Jacobian against central
//! differences of the right-hand side for every transducer and contact law, the free-flight
//! split `L y + N(y)` against the right-hand side, and the energy audit closing on each.

use endstop::device::Device;
use endstop::drive::Sine;
use endstop::ode::{Dopri5, HybridSystem};

use endstop::physics::contact::{Mode, Side};
use endstop::physics::energy::{AuditState, EnergyAudit};
use endstop::physics::harvester::{Harvester, State};
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
fn check_jacobian(h: &Harvester<Sine>, mode: Mode, y: &State, what: &str) {
    let sc = h.scales();
    let j = h.jacobian(mode, y);
    let mut fd = Matrix4::zeros();
    for c in 0..4 {
        let e = 1e-5 * sc[c];
        let (mut yp, mut ym) = (*y, *y);
        yp[c] += e;
        ym[c] -= e;
        let col = (h.rhs(mode, 0.1, &yp) - h.rhs(mode, 0.1, &ym)) * (sc[c] / (2.0 * e));
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
            let h = Harvester::new(&d, Sine::from_rms_g(1.0, 100.0));
            let sc = h.scales();
            let live = h.active_states();
            let mut y = State::new(0.3 * sc[0], 0.4 * sc[1], 0.0, 0.0);
            for i in 2..live {
                y[i] = 0.3 * sc[i];
            }
            let what = format!(
                "{} / {}",
                d.transducer.key(),
                d.stops.upper.as_ref().unwrap().law.key()
            );
            check_jacobian(&h, Mode::Free, &y, &what);
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
                check_jacobian(&h, Mode::Stuck(Side::Upper), &yc, &what);
            } else {
                check_jacobian(&h, Mode::Contact(Side::Upper), &yc, &what);
            }
        }
    }
}

#[test]
fn the_free_flight_split_equals_the_right_hand_side() {
    for t in TRANSDUCERS {
        let d = device(STOPS[0], t);
        let h = Harvester::new(&d, Sine::from_rms_g(0.0, 100.0));
        let ff = h.free_flight();
        let (l, _) = ff.linear();
        let sc = h.scales();
        let y = State::new(0.7 * sc[0], -0.5 * sc[1], 0.2 * sc[2], -0.4 * sc[3]);
        let mut y = y;
        for i in h.active_states()..4 {
            y[i] = 0.0;
        }
        let split = l * y + ff.remainder(&y);
        let f = h.rhs(Mode::Free, 0.0, &y);
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
            ff.is_linear(),
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
            let h = Harvester::new(&d, Sine::from_rms_g(3.0, 95.0));
            let audit = EnergyAudit(h);
            let y0 = AuditState::zeros();
            let mut ode = Dopri5::new(0.0, y0, Mode::Free, audit.solver_options(1e-9));
            ode.integrate(&audit, 0.2, |_, _| {}).unwrap();
            let what = format!(
                "{} / {}",
                d.transducer.key(),
                d.stops.upper.as_ref().unwrap().law.key()
            );
            let ledger = audit.ledger(ode.mode(), &ode.y());
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
