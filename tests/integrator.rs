//! The integrator against exact solutions: a free oscillator, free flight onto a wall, a
//! piecewise-linear contact on the real harvester model, and the energy balance of a run with
//! impacts. Tolerances are stated in the integrator's own units (rtol) or derived from them.
//! How it steps at its edges (step boundaries, restarts, grazing crossings) and the errors it
//! returns are `integrator_stepping.rs`.

use endstop::device::StiffnessModel;
use endstop::drive::Excitation;
use endstop::drive::Sine;
use endstop::model::{Books, Contact, Driven, FlightSplit, FlightVisitor, Mode, Model};
use endstop::model::{NoFlight, Remainder};
use endstop::ode::Dopri5;
use endstop::ode::HybridSystem;
use endstop::ode::Options;
use endstop::ode::Rk4;
use endstop::paper::setups::{comb_mut, endstop, with_endstop};
use endstop::physics::contact::Side;
use endstop::physics::harvester::stops::contact_of;
use endstop::physics::harvester::Harvester;
use endstop::physics::transducer::State;
use nalgebra::SVector;

use crate::common;
use common::device;

/// Integrator options with the given tolerances (shared with `integrator_stepping`).
pub(crate) fn opts<const N: usize>(rtol: f64, atol: f64) -> Options<SVector<f64, N>> {
    Options {
        rtol,
        atol: SVector::repeat(atol),
        h_max: 1.0,
        h_min: 1e-14,
        h_init: 1e-4,
        max_steps: 10_000_000,
        event_time_tol: 1e-14,
    }
}

/// y'' = -w^2 y, single mode; optional wall at x = wall.
pub(crate) struct Oscillator {
    pub(crate) w: f64,
}

impl HybridSystem for Oscillator {
    type State = SVector<f64, 2>;
    fn guard_count(&self) -> usize {
        3
    }
    type Mode = ();
    fn rhs(&self, _: (), _t: f64, y: &SVector<f64, 2>) -> SVector<f64, 2> {
        SVector::<f64, 2>::new(y[1], -self.w * self.w * y[0])
    }
    fn guards(&self, _: (), _t: f64, _y: &SVector<f64, 2>, g: &mut [f64]) {
        g.fill(f64::NEG_INFINITY);
    }
    fn switch(&self, _: (), _: usize, _: f64, _: &mut SVector<f64, 2>) {}
}

#[test]
fn free_oscillator_error_is_of_the_order_of_the_tolerance_and_shrinks_with_it() {
    let sys = Oscillator {
        w: 2.0 * std::f64::consts::PI,
    };
    let mut errs = Vec::new();
    for rtol in [1e-6, 1e-8, 1e-10] {
        let y0 = SVector::<f64, 2>::new(1.0, 0.0);
        let mut ode = Dopri5::new(0.0, y0, (), opts(rtol, rtol));
        let mut max_err: f64 = 0.0;
        ode.integrate(&sys, 10.0, |st, _| {
            // Check the dense output too, at the midpoint of every step.
            let t = st.t0 + 0.5 * st.h;
            let e = (st.at(t)[0] - (sys.w * t).cos()).abs();
            max_err = max_err.max(e);
        })
        .unwrap();
        let e_end = (ode.y()[0] - (sys.w * 10.0).cos()).abs();
        max_err = max_err.max(e_end);
        // Global error over 10 periods: bounded by 100 x the local tolerance (error accumulates
        // over ~10 periods and the controller targets the local error only).
        assert!(max_err < 100.0 * rtol, "rtol {rtol}: max error {max_err:e}");
        errs.push(max_err);
    }
    // Tightening the tolerance by 100 must cut the error by at least 10.
    assert!(
        errs[1] < errs[0] / 10.0 && errs[2] < errs[1] / 10.0,
        "{errs:?}"
    );
}

/// Free flight with constant acceleration onto a wall at x = 1: x = v0 t + a t^2 / 2.
struct Flight {
    a: f64,
}

impl HybridSystem for Flight {
    type State = SVector<f64, 2>;
    fn guard_count(&self) -> usize {
        3
    }
    type Mode = u8;
    fn rhs(&self, mode: u8, _t: f64, y: &SVector<f64, 2>) -> SVector<f64, 2> {
        if mode == 0 {
            SVector::<f64, 2>::new(y[1], self.a)
        } else {
            SVector::<f64, 2>::zeros()
        }
    }
    fn guards(&self, mode: u8, _t: f64, y: &SVector<f64, 2>, g: &mut [f64]) {
        let v: [f64; 3] = {
            if mode == 0 {
                [y[0] - 1.0, f64::NEG_INFINITY, f64::NEG_INFINITY]
            } else {
                [f64::NEG_INFINITY; 3]
            }
        };
        g.copy_from_slice(&v);
    }
    fn switch(&self, _: u8, _: usize, _: f64, _: &mut SVector<f64, 2>) -> u8 {
        1
    }
}

#[test]
fn free_flight_hits_the_wall_at_the_exact_time() {
    let (v0, a) = (0.3, 0.7);
    let sys = Flight { a };
    let mut ode = Dopri5::new(0.0, SVector::<f64, 2>::new(0.0, v0), 0u8, opts(1e-9, 1e-12));
    let mut t_hit = f64::NAN;
    ode.integrate(&sys, 5.0, |st, m| {
        if m == 0 {
            t_hit = st.t1();
        }
    })
    .unwrap();
    let exact = (-v0 + (v0 * v0 + 2.0 * a).sqrt()) / a;
    // The trajectory is a quadratic, which the 4th-order dense output represents exactly, so
    // the event is located to the root finder's time tolerance (1e-14 s) plus rounding.
    assert!((t_hit - exact).abs() < 1e-12, "{t_hit} vs {exact}");
    assert_eq!(ode.stats().events, 1);
}

#[test]
fn fixed_step_classical_rk4_converges_at_fourth_order() {
    // The tableau-driven engine with the classical RK4 on the free oscillator over 10 periods
    // (no breakpoints: the span is cut into n equal steps): halving the step must cut the
    // global error by 2^4 = 16 (to within the next term's share at these steps). The error is
    // taken on the phase plane (x and v / w): after whole periods x sits at a maximum, where a
    // phase error shows only to second order.
    let sys = Oscillator {
        w: 2.0 * std::f64::consts::PI,
    };
    let err = |n: usize| {
        let mut ode = Rk4::new(0.0, SVector::<f64, 2>::new(1.0, 0.0), (), n, 1e-14);
        ode.integrate(&sys, 10.0).unwrap();
        assert_eq!(ode.t(), 10.0);
        assert_eq!(ode.stats().accepted, n as u64);
        assert_eq!(ode.stats().rhs_evals, 4 * n as u64);
        let (x, v) = (ode.y()[0], ode.y()[1] / sys.w);
        (x - (sys.w * 10.0).cos()).hypot(v + (sys.w * 10.0).sin())
    };
    let (coarse, fine) = (err(1000), err(2000));
    let ratio = coarse / fine;
    assert!(
        (14.0..18.0).contains(&ratio),
        "{coarse:e} / {fine:e} = {ratio}"
    );
}

#[test]
fn fixed_step_rk4_switches_at_the_exact_crossing_time() {
    // The trajectory is a quadratic, which RK4 integrates exactly, so the crossing located on
    // shortened steps is exact to the root finder's tolerance; after the switch the state
    // stays put (mode 1 has no motion), so the velocity tells the switch time.
    let (v0, a) = (0.3, 0.7);
    let sys = Flight { a };
    let mut ode = Rk4::new(0.0, SVector::<f64, 2>::new(0.0, v0), 0u8, 7, 1e-14);
    ode.integrate(&sys, 5.0).unwrap();
    assert_eq!(ode.mode(), 1);
    assert_eq!(ode.stats().events, 1);
    let t_hit = (ode.y()[1] - v0) / a;
    let exact = (-v0 + (v0 * v0 + 2.0 * a).sqrt()) / a;
    assert!((t_hit - exact).abs() < 1e-12, "{t_hit} vs {exact}");
    assert!((ode.y()[0] - 1.0).abs() < 1e-12);
    assert_eq!(ode.t(), 5.0);
}

fn elastic_p1(km: f64, kim: f64) -> Harvester<4> {
    let mut d = with_endstop(&device("prototype1"), StiffnessModel::Linear, 0.0);
    d.mechanics.damping_n_s_per_m = 1e-300;
    d.mechanics.stiffness_n_per_m = km;
    comb_mut(&mut d).bias_v = 0.0;
    let d = endstop::paper::setups::with_stops(&d, |s| {
        s.law = endstop::device::StopLaw::Linear {
            stiffness_n_per_m: kim,
        }
    });
    let mut h = Harvester::<4>::new(&d).unwrap();
    h.damping = 0.0;
    h
}

/// The mode with the stop on `side` in the state `c` and the other apart.
fn at_stop(side: Side, c: Contact) -> Mode {
    Mode::FREE.with_contact(contact_of(side), c)
}

#[test]
fn piecewise_linear_contact_on_the_harvester_model_matches_the_exact_solution() {
    // Undamped, unbiased (the electrical states stay zero), linear stop: the motion is a
    // free sine until x = xmax and a faster sine about x_c while in contact.
    let (km, kim) = (166.5, 1.94e6);
    let h = elastic_p1(km, kim);
    let (m, xmax) = (h.mass_kg, h.gap(Side::Upper));
    let w0 = (km / m).sqrt();
    let w1 = ((km + kim) / m).sqrt();
    let v0 = 1.5 * w0 * xmax;
    let t_in = (xmax * w0 / v0).asin() / w0;
    let v_in = v0 * (w0 * t_in).cos();
    let xc = kim * xmax / (km + kim);
    let theta = 2.0 * (v_in / w1).atan2(xmax - xc);
    let t_out = t_in + theta / w1;

    let mut o = h.solver_options(1e-10);
    o.event_time_tol = 1e-16;
    let sys = Driven::new(&h, Sine::from_rms_g(0.0, 1000.0));
    let mut ode = Dopri5::new(0.0, State::new(0.0, v0, 0.0, 0.0), Mode::FREE, o);
    let mut switches: Vec<(f64, Mode, f64)> = Vec::new();
    let mut last = Mode::FREE;
    ode.integrate(&sys, t_out * 1.01, |st, mode| {
        if mode != last {
            switches.push((st.t0, mode, st.y0[1]));
            last = mode;
        }
    })
    .unwrap();
    assert_eq!(switches.len(), 2, "{switches:?}");
    assert_eq!(switches[0].1, at_stop(Side::Upper, Contact::Pressed));
    assert_eq!(switches[1].1, Mode::FREE);
    // Event times to 1e-9 relative (the contact lasts ~3.7 us; 1e-9 of t_out is ~0.2 ps).
    assert!(
        ((switches[0].0 - t_in) / t_in).abs() < 1e-9,
        "entry {} vs {t_in}",
        switches[0].0
    );
    assert!(
        ((switches[1].0 - t_out) / t_out).abs() < 1e-9,
        "exit {} vs {t_out}",
        switches[1].0
    );
    // The contact duration itself, to 1e-6 relative.
    let dur = switches[1].0 - switches[0].0;
    assert!(((dur - theta / w1) / (theta / w1)).abs() < 1e-6, "{dur}");
    // Elastic impact: the exit speed equals the entry speed.
    assert!(
        ((switches[1].2 + v_in) / v_in).abs() < 1e-8,
        "{} vs {}",
        switches[1].2,
        -v_in
    );
}

/// The ledger of `h` under `drive` over `duration_s` from rest at rtol 1e-10, with the run's
/// number of events.
fn booked_run(h: &Harvester<4>, drive: Sine, duration_s: f64) -> (endstop::model::Ledger, u64) {
    let mut books = Books::new(h, drive);
    let mut ode = Dopri5::new(0.0, h.rest_state(), Mode::FREE, h.solver_options(1e-10));
    ode.integrate_observed(&Driven::new(h, drive), duration_s, &mut books)
        .unwrap();
    (books.ledger(), ode.stats().events)
}

#[test]
fn energy_balance_closes_over_a_run_with_impacts() {
    // Prototype 1 driven hard at 1300 Hz (Hertz stop, b_im = 1.5, Vb = 30 V): impacts on both
    // stops every period.
    let d = device("prototype1");
    let drive = Sine::from_rms_g(8.0, 1300.0);
    let (ledger, events) = booked_run(&Harvester::<4>::new(&d).unwrap(), drive, 40.0 / 1300.0);
    assert!(events > 40, "expected impacts, got {events} events");
    assert!(
        ledger.get("stop_damping") > 0.0 && ledger.get("loads") > 0.0,
        "no end-stop or load dissipation"
    );
    // The source's work matters at this tolerance (it is ~1e-4 of the dissipation): a sign
    // error in the electrical bookkeeping would fail the check below.
    let residual = ledger.relative_residual();
    assert!(residual.abs() < 1e-6, "relative residual {residual:e}");
    // Tension-free contact: the same balance (the clipped phase has no contact force).
    let d2 = d.with_tension_free(true);
    let (ledger2, events2) = booked_run(&Harvester::<4>::new(&d2).unwrap(), drive, 40.0 / 1300.0);
    let r2 = ledger2.relative_residual();
    assert!(events2 > 40);
    assert!(r2.abs() < 1e-6, "tension-free relative residual {r2:e}");
}

/// The model under its drive with a record of what each mode switch booked: (from, to, the
/// end-stop damper's, the clip losses' and the re-engagement gains' share), each switch booked
/// by the model's own [`Model::book_switch`] from the states around its reset.
struct WatchedSwitches<'m> {
    sys: Driven<'m, Harvester<4>, Sine, 4>,
    bookings: std::cell::RefCell<Vec<(Mode, Mode, [f64; 3])>>,
}

impl HybridSystem for WatchedSwitches<'_> {
    type State = State;
    type Mode = Mode;
    fn guard_count(&self) -> usize {
        self.sys.guard_count()
    }
    fn rhs(&self, m: Mode, t: f64, y: &State) -> State {
        self.sys.rhs(m, t, y)
    }
    fn guards(&self, m: Mode, t: f64, y: &State, g: &mut [f64]) {
        self.sys.guards(m, t, y, g);
    }
    fn next_breakpoint(&self, t: f64) -> f64 {
        self.sys.next_breakpoint(t)
    }
    fn switch(&self, m: Mode, i: usize, t: f64, y: &mut State) -> Mode {
        let before = *y;
        let to = self.sys.switch(m, i, t, y);
        let h = self.sys.model;
        let terms = h.ledger_terms();
        let mut book = vec![0.0; terms.len()];
        h.book_switch(m, to, &before, y, &mut book);
        let share = |name: &str| {
            terms
                .iter()
                .position(|t| t.name == name)
                .map_or(0.0, |i| book[i])
        };
        self.bookings.borrow_mut().push((
            m,
            to,
            [
                share("stop_damping"),
                share("clip_losses"),
                share("reengagement_gains"),
            ],
        ));
        to
    }
}

/// The stop whose contact changes from `a` to `b` between two modes, with its two states.
fn changed_contact(a: Mode, b: Mode) -> Option<(Contact, Contact)> {
    Side::BOTH
        .iter()
        .map(|&s| contact_of(s))
        .find(|&k| a.contact(k) != b.contact(k))
        .map(|k| (a.contact(k), b.contact(k)))
}

#[test]
fn tension_free_stop_books_clip_losses_and_reengagement_gains_apart() {
    // The tension-free variant at 8 g, 1300 Hz: every impact unloads while still pressed
    // (a clip). Some clips re-engage at once: the clip is located on the dense output, and the
    // step re-taken onto it can end with the contact force still slightly positive (~1e-8 N),
    // so the clipped mode's re-engagement guard fires at the same instant. The damper's
    // account must hold the damper only (it once took the spring energy of re-engagements as
    // negative losses), and clip losses and re-engagement gains are each booked with their
    // sign.
    let d = device("prototype1").with_tension_free(true);
    let h = Harvester::<4>::new(&d).unwrap();
    let drive = Sine::from_rms_g(8.0, 1300.0);
    let sys = WatchedSwitches {
        sys: Driven::new(&h, drive),
        bookings: Default::default(),
    };
    let mut books = Books::new(&h, drive);
    let mut ode = Dopri5::new(0.0, h.rest_state(), Mode::FREE, h.solver_options(1e-10));
    ode.integrate_observed(&sys, 40.0 / 1300.0, &mut books)
        .unwrap();
    let (mut clips, mut reengagements) = (0, 0);
    for &(from, to, [damper, clip, gain]) in sys.bookings.borrow().iter() {
        assert_eq!(damper, 0.0, "{from:?} -> {to:?} moved the damper's account");
        match changed_contact(from, to) {
            Some((Contact::Pressed, Contact::Clipped)) => {
                clips += 1;
                assert!(clip > 0.0 && gain == 0.0, "clip booked {clip:e}, {gain:e}");
            }
            Some((Contact::Clipped, Contact::Pressed)) => {
                reengagements += 1;
                assert!(
                    gain > 0.0 && clip == 0.0,
                    "re-engagement booked {gain:e}, {clip:e}"
                );
            }
            _ => assert!(clip == 0.0 && gain == 0.0, "{from:?} -> {to:?}"),
        }
    }
    assert!(
        clips > 40 && reengagements > 0,
        "{clips} clips, {reengagements} re-engagements"
    );
    let ledger = books.ledger();
    let (clip_losses, gains) = (ledger.get("clip_losses"), ledger.get("reengagement_gains"));
    // Passive: the stop absorbs more than it returns (its damper plus the clip losses minus
    // the re-engagement gains), and the balance closes as above.
    assert!(gains <= clip_losses, "{ledger:?}");
    assert!(
        ledger.get("stop_damping") + clip_losses - gains > 0.0,
        "{ledger:?}"
    );
    let r = ledger.relative_residual();
    assert!(r.abs() < 1e-6, "relative residual {r:e}");
}

/// Mode switches (time, new mode) and counters of prototype 1 driven at 8 g, 1300 Hz (impacts
/// on both stops every period) over 40 periods.
fn impacting_run(rtol: f64) -> (Vec<(f64, Mode)>, endstop::ode::Stats) {
    let h = Harvester::<4>::new(&device("prototype1")).unwrap();
    let sys = Driven::new(&h, Sine::from_rms_g(8.0, 1300.0));
    let mut ode = Dopri5::new(0.0, h.rest_state(), Mode::FREE, h.solver_options(rtol));
    let mut switches = Vec::new();
    let mut last = Mode::FREE;
    ode.integrate(&sys, 40.0 / 1300.0, |st, m| {
        if m != last {
            switches.push((st.t0, m));
            last = m;
        }
    })
    .unwrap();
    (switches, ode.stats())
}

#[test]
fn the_first_step_after_an_event_is_rarely_rejected_and_event_times_hold() {
    let (switches, stats) = impacting_run(1e-8);
    let (reference, _) = impacting_run(1e-11);
    assert!(stats.events > 100, "{stats:?}");
    // The step after a switch is chosen from the new mode's dynamics, so that the first trial
    // is normally accepted: fewer than one rejection per two events. (Restoring the step from
    // before the switch cost ~6 rejections per contact entry: the contact rings ~100 times
    // faster than the free motion.)
    assert!(
        2 * stats.rejected_after_event < stats.events,
        "{} rejections after {} events",
        stats.rejected_after_event,
        stats.events
    );
    // Results do not move: every switch matches a run at a 1000 times tighter tolerance, to
    // 100 times the tolerance times the period (the global-error allowance of the free
    // oscillator test above).
    assert_eq!(switches.len(), reference.len());
    let mut worst: f64 = 0.0;
    for (a, b) in switches.iter().zip(&reference) {
        assert_eq!(a.1, b.1);
        worst = worst.max((a.0 - b.0).abs());
    }
    let bound = 100.0 * 1e-8 / 1300.0;
    assert!(worst < bound, "event times off by up to {worst:e} s");
}

/// The free flight split of a model checked against its right-hand side on the states and
/// drive values given (see the test below); the number of components checked.
struct SplitMatchesRhs<'a> {
    h: &'a Harvester<4>,
    name: &'a str,
    points: Vec<(f64, State)>,
}

impl FlightVisitor<4> for SplitMatchesRhs<'_> {
    type Output = Result<usize, NoFlight>;

    fn visit<R: Remainder<4>>(self, split: FlightSplit<4>, remainder: R) -> Self::Output {
        let (l, c) = (split.l, split.c);
        let mut checked = 0;
        for (a, y) in &self.points {
            let want = self.h.rhs(Mode::FREE, y, *a);
            let got = l * y + c * *a + remainder.remainder(y);
            for k in 0..4 {
                let size = (l.row(k).transpose().component_mul(y)).abs().max()
                    + (c[k] * a).abs()
                    + want[k].abs();
                assert!(
                    (got[k] - want[k]).abs() <= 1e-12 * size,
                    "{} a {a} y {y:?} component {k}: {} vs {}",
                    self.name,
                    got[k],
                    want[k]
                );
                checked += 1;
            }
        }
        Ok(checked)
    }

    fn refused(self, why: NoFlight) -> Self::Output {
        Err(why)
    }
}

#[test]
fn free_flight_split_sums_to_the_right_hand_side() {
    // The exponential free-flight step integrates `L y + c a(t)` exactly and extrapolates the
    // remainder `N(y)`; their sum must be the free-flight right-hand side of eqs 7-10. Across
    // the whole gap and at charges far from rest the two agree to rounding (1e-12 of the
    // largest term of each component: the remainder is written in closed form, not as a
    // difference).
    for name in ["prototype1", "prototype2"] {
        let d = device(name);
        let h = Harvester::<4>::new(&d).unwrap();
        let drive = Sine::from_rms_g(2.0, 700.0);
        let s = h.scales();
        let mut points = Vec::new();
        for (i, t) in [0.0, 1.1e-4, 3.7e-4].into_iter().enumerate() {
            for frac in [-0.99, -0.4, 0.0, 0.3, 0.95] {
                let y = State::new(
                    frac * endstop(&d).gap_m,
                    (0.7 - i as f64) * s[1],
                    (0.3 + frac) * s[2],
                    (i as f64 - 1.3) * s[3],
                );
                points.push((drive.accel(t), y));
            }
        }
        let checked = h
            .flight(
                1e-5,
                SplitMatchesRhs {
                    h: &h,
                    name,
                    points,
                },
            )
            .unwrap_or_else(|why| panic!("{name}: no free flight split: {why:?}"));
        assert_eq!(checked, 3 * 5 * 4, "{name}");
    }
}
