//! Rigid stops with a coefficient of restitution: the impacts of a mass pressed onto the stop
//! accumulate in finite time (chattering), and the model ends the sequence by sticking to the
//! stop until the holding force changes sign. The accumulation time against its closed form,
//! and a low-frequency drive that presses the mass onto a one-sided stop every period: the run
//! never hangs, sticks and releases every period, and closes its energy balance.

use endstop::device::Device;
use endstop::drive::{Excitation, Sine};
use endstop::model::{Books, Contact, Driven, Mode, Model, SwitchKind};
use endstop::ode::{Dopri5, Observer, Step};
use endstop::physics::contact::Side;
use endstop::physics::harvester::stops::contact_of;
use endstop::physics::harvester::Harvester;
use endstop::physics::transducer::State;

fn rigid_device(e: f64, transducer: &str) -> Device {
    rigid_device_with(e, transducer, 40.0, 1e-3)
}

/// One rigid stop of restitution `e`, 1 mm above the mass, on a suspension of stiffness `km`
/// (N/m) and damping `b` (N s/m).
fn rigid_device_with(e: f64, transducer: &str, km: f64, b: f64) -> Device {
    let text = format!(
        "name = \"rigid\"\nparams = \"test\"\ndescription = \"one rigid stop\"\n\
         [mechanics]\nmass_kg = 1e-3\nstiffness_n_per_m = {km:e}\ndamping_n_s_per_m = {b:e}\n\
         [stops.upper]\ngap_m = 1e-3\nlaw = \"restitution\"\ncoefficient = {e}\n{transducer}\n"
    );
    Device::from_toml_str(&text, "rigid.toml").unwrap()
}

const NONE: &str = "[transducer]\nkind = \"none\"";
const PIEZO: &str = "[transducer]\nkind = \"piezoelectric\"\ncoupling_n_per_v = 2e-4\n\
                     capacitance_f = 1e-8\nload_resistance_ohm = 2e5";

/// A constant acceleration.
#[derive(Debug, Clone, Copy)]
struct Constant(f64);

impl Excitation for Constant {
    fn accel(&self, _t: f64) -> f64 {
        self.0
    }
}

/// Records the switches of a run.
#[derive(Default)]
struct Switches(Vec<(f64, Mode, Mode)>);

impl Observer<State, Mode> for Switches {
    fn step(&mut self, _: &Step<State>, _: Mode) {}
    fn switched(&mut self, t: f64, from: Mode, to: Mode) {
        self.0.push((t, from, to));
    }
}

/// A mass thrown at a rigid stop under a constant acceleration A towards it (no damping, a
/// negligible spring) bounces with speeds v1, e v1, e^2 v1, ...; the flights last 2 e^k v1 / A, so the
/// impacts accumulate at t1 + 2 e v1 / (A (1 - e)), after which it rests on the stop. The run
/// sticks there within the time the shortcut skips, 2 u / (A (1 - e)) with u the last rebound
/// speed (u^2 <= 2 A h, h = [`Harvester::stick_height_m`]), and has made about
/// log(u / (e v1)) / log(e) rebounds before.
#[test]
fn impacts_under_a_constant_force_accumulate_at_the_closed_form_time() {
    // A suspension too weak to matter (km gap / (m A) = 1e-7) but not absent: the velocity's
    // absolute tolerance is rtol w0 gap, which a zero km would make zero.
    // The file needs a positive damping; the model's is set to zero.
    let d = rigid_device_with(0.5, NONE, 1e-6, 1e-3);
    let a = 9.81;
    let mut h = Harvester::<4>::new(&d).unwrap();
    h.damping = 0.0;
    let gap = h.gap(Side::Upper);
    let v0 = 0.05;
    // First impact: x = v0 t + A t^2 / 2 = gap.
    let t1 = (-v0 + (v0 * v0 + 2.0 * a * gap).sqrt()) / a;
    let v1 = v0 + a * t1;
    let e = 0.5;
    let t_acc = t1 + 2.0 * e * v1 / (a * (1.0 - e));
    let mut ode = Dopri5::new(
        0.0,
        State::new(0.0, v0, 0.0, 0.0),
        Mode::FREE,
        h.solver_options(1e-10),
    );
    let mut sw = Switches::default();
    ode.integrate_observed(&Driven::new(&h, Constant(a)), 2.0 * t_acc, &mut sw)
        .unwrap();
    let stick =
        sw.0.iter()
            .find(|(_, f, t)| SwitchKind::between(*f, *t) == SwitchKind::Stick)
            .expect("the mass sticks");
    let rebounds =
        sw.0.iter()
            .filter(|(_, f, t)| SwitchKind::between(*f, *t) == SwitchKind::Rebound)
            .count();
    let u_max = (2.0 * a * h.stick_height_m).sqrt();
    let skipped = 2.0 * u_max / (a * (1.0 - e));
    assert!(
        stick.0 <= t_acc + 1e-9 && stick.0 >= t_acc - skipped - 1e-9,
        "stuck at {} s, accumulation at {t_acc} s (shortcut up to {skipped:e} s)",
        stick.0
    );
    let expected = ((u_max / (e * v1)).ln() / e.ln()).ceil() as usize;
    assert!(
        rebounds.abs_diff(expected) <= 1,
        "{rebounds} rebounds, about {expected} expected"
    );
    // Resting on the stop under a force that holds it there.
    assert_eq!(
        ode.mode(),
        Mode::FREE.with_contact(contact_of(Side::Upper), Contact::Resting)
    );
    assert_eq!(ode.y()[0], gap);
    assert_eq!(ode.y()[1], 0.0);
}

/// Below resonance the drive presses the mass onto a one-sided stop for part of every period
/// (the quasi-static deflection m A / km is 3.5 gaps): every period it impacts, chatters,
/// sticks, and is released when the drive turns; the run ends in time, and its energy balance
/// (impact losses booked at every rebound) closes to 1e-6 of its terms at rtol 1e-9.
#[test]
fn a_low_frequency_drive_sticks_and_releases_every_period_and_closes_its_balance() {
    for transducer in [NONE, PIEZO] {
        let d = rigid_device(0.7, transducer);
        let f = 5.0; // the suspension resonates at 32 Hz
        let accel_rms_g = 3.5 * 1e-3 * 40.0 / 1e-3 / 9.81 / std::f64::consts::SQRT_2;
        let h = Harvester::<4>::new(&d).unwrap();
        let drive = Sine::from_rms_g(accel_rms_g, f);
        let mut books = Books::new(&h, drive);
        let periods = 6.0;
        let mut ode = Dopri5::new(0.0, h.rest_state(), Mode::FREE, h.solver_options(1e-9));
        let mut modes = Vec::new();
        ode.integrate(&Driven::new(&h, drive), periods / f, |st, m| {
            books.step(st, m);
            if modes.last() != Some(&m) {
                modes.push(m);
            }
        })
        .unwrap();
        let sticks = modes
            .iter()
            .filter(|m| m.contact(contact_of(Side::Upper)) == Contact::Resting)
            .count();
        assert!(
            sticks >= periods as usize - 1,
            "{}: stuck {sticks} times in {periods} periods",
            d.transducer.key()
        );
        let ledger = books.ledger();
        assert!(ledger.get("impact_losses") > 0.0);
        assert!(
            ledger.relative_residual().abs() < 1e-6,
            "{}: {ledger:?}",
            d.transducer.key()
        );
    }
}
