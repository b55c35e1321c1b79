//! The integrator at the edges of its step control: every sample instant of a sampled input
//! ends a step, a restart forgets the cached derivative, a grazing crossing between the guard
//! probes is found; and what it returns where it cannot go on (a blow-up, a step below the
//! resolution of time, a non-finite step onto an event, endless switching): a named error with
//! the time, never a silent NaN. Its accuracy against exact solutions is `integrator.rs`.

use endstop::drive::Sampled;
use endstop::model::{Driven, Mode, Model};
use endstop::ode::Dopri5;
use endstop::ode::HybridSystem;
use endstop::ode::SolverError;
use endstop::physics::harvester::Harvester;
use endstop::physics::transducer::State;
use nalgebra::SVector;

use crate::common::device;
use crate::integrator::{opts, Oscillator};

/// y' = y^2 blows up at t = 1.
struct BlowUp;

impl HybridSystem for BlowUp {
    type State = SVector<f64, 1>;
    fn guard_count(&self) -> usize {
        3
    }
    type Mode = ();
    fn rhs(&self, _: (), _t: f64, y: &SVector<f64, 1>) -> SVector<f64, 1> {
        SVector::<f64, 1>::new(y[0] * y[0])
    }
    fn guards(&self, _: (), _t: f64, _y: &SVector<f64, 1>, g: &mut [f64]) {
        g.fill(f64::NEG_INFINITY);
    }
    fn switch(&self, _: (), _: usize, _: f64, _: &mut SVector<f64, 1>) {}
}

#[test]
fn a_blow_up_is_an_error_with_the_time_never_a_silent_nan() {
    let mut ode = Dopri5::new(0.0, SVector::<f64, 1>::new(1.0), (), opts(1e-8, 1e-8));
    let err = ode.integrate(&BlowUp, 2.0, |_, _| {}).unwrap_err();
    let t = match &err {
        SolverError::StepSizeTooSmall { t, .. }
        | SolverError::NonFinite { t, .. }
        | SolverError::TooManySteps { t, .. } => *t,
        other => panic!("unexpected error {other:?}"),
    };
    assert!((t - 1.0).abs() < 1e-3, "stopped at {t}: {err}");
    assert!(err.to_string().contains("t = "), "{err}");
}

#[test]
fn every_sample_instant_of_a_sampled_input_is_a_step_boundary() {
    let samples: std::sync::Arc<[f64]> = (0..101).map(|k| (k as f64 * 0.37).sin()).collect();
    let ex = Sampled::new(samples, 1e5);
    let d = device("prototype1");
    let h = Harvester::<4>::new(&d).unwrap();
    let mut ode = Dopri5::new(0.0, State::zeros(), Mode::FREE, h.solver_options(1e-8));
    let mut ends = Vec::new();
    ode.integrate(&Driven::new(&h, ex.clone()), ex.duration_s(), |st, _| {
        ends.push(st.t1())
    })
    .unwrap();
    for k in 1..=100 {
        let t = ex.time_of(k);
        assert!(
            ends.contains(&t),
            "no step ends exactly at sample {k} (t = {t:e})"
        );
    }
}

#[test]
fn restart_drops_the_cached_derivative() {
    // Before the fields were private, a caller could write the state between two calls and the
    // next step reused the derivative of the old state (its first step was wrong by 13 % here).
    let sys = Oscillator { w: 1.0 };
    let o = opts::<2>(1e-8, 1e-8);
    let mut a = Dopri5::new(0.0, SVector::<f64, 2>::new(1.0, 0.0), (), o.clone());
    a.integrate(&sys, 1.0, |_, _| {}).unwrap();
    let moved = SVector::<f64, 2>::new(0.0, 2.0);
    a.restart(1.0, moved, ());
    let mut first = None;
    a.integrate(&sys, 2.0, |st, _| {
        first.get_or_insert((st.h, st.y1));
    })
    .unwrap();
    // The restarted integrator is a fresh one at the new point (same options, same steps).
    let mut b = Dopri5::new(1.0, moved, (), o);
    b.integrate(&sys, 2.0, |_, _| {}).unwrap();
    assert_eq!(a.y(), b.y());
    assert_eq!(a.t(), 2.0);
    // And its first step follows x = 2 sin(t - 1): the controller holds a step's local error
    // to about atol + rtol |x| (~1e-8 here); the stale derivative gave 1e-6.
    let (h, y1) = first.unwrap();
    assert!((y1[0] - 2.0 * h.sin()).abs() < 1e-8, "{y1:?} after {h}");
}

/// y' = w cos(w t), y = sin(w t) from y(0) = 0: a forcing so fast that the step it needs is
/// below the spacing of doubles at the start time.
struct FastForcing {
    w: f64,
}

impl HybridSystem for FastForcing {
    type State = SVector<f64, 1>;
    fn guard_count(&self) -> usize {
        3
    }
    type Mode = ();
    fn rhs(&self, _: (), t: f64, _y: &SVector<f64, 1>) -> SVector<f64, 1> {
        SVector::<f64, 1>::new(self.w * (self.w * t).cos())
    }
    fn guards(&self, _: (), _t: f64, _y: &SVector<f64, 1>, g: &mut [f64]) {
        g.fill(f64::NEG_INFINITY);
    }
    fn switch(&self, _: (), _: usize, _: f64, _: &mut SVector<f64, 1>) {}
}

#[test]
fn a_step_below_the_resolution_of_time_is_a_step_size_error_with_the_time() {
    // At t = 1e7 s doubles are 1.9e-9 s apart, and w = 1e9 rad/s asks for steps of ~1e-11 s:
    // such a step cannot advance t. The absolute floor (1e-14 s) is far below; the relative
    // floor (16 eps |t| = 3.6e-8 s) stops the run at once, rather than accepting steps that
    // leave t unchanged until the step budget runs out.
    let t0 = 1e7;
    let mut o = opts::<1>(1e-8, 1e-8);
    o.max_steps = 1_000_000;
    let mut ode = Dopri5::new(t0, SVector::<f64, 1>::new((1e9 * t0).sin()), (), o);
    let err = ode
        .integrate(&FastForcing { w: 1e9 }, t0 + 1.0, |_, _| {})
        .unwrap_err();
    match &err {
        SolverError::StepSizeTooSmall { t, h, .. } => {
            assert_eq!(*t, t0, "{err}");
            assert!(*h < 16.0 * f64::EPSILON * t0, "{err}");
        }
        other => panic!("expected a step-size error, got {other}"),
    }
    assert!(err.to_string().contains("t = 1e7 s"), "{err}");
}

/// Free flight onto a wall at x = 1 (as `integrator::Flight`) whose right-hand side turns to
/// NaN once a guard has been seen positive: the step re-taken to land on the event is then
/// non-finite.
struct PoisonedFlight {
    seen_positive: std::cell::Cell<bool>,
}

impl HybridSystem for PoisonedFlight {
    type State = SVector<f64, 2>;
    fn guard_count(&self) -> usize {
        3
    }
    type Mode = u8;
    fn rhs(&self, mode: u8, _t: f64, y: &SVector<f64, 2>) -> SVector<f64, 2> {
        match (mode, self.seen_positive.get()) {
            (0, false) => SVector::<f64, 2>::new(y[1], 0.7),
            (0, true) => SVector::<f64, 2>::repeat(f64::NAN),
            _ => SVector::<f64, 2>::zeros(),
        }
    }
    fn guards(&self, mode: u8, _t: f64, y: &SVector<f64, 2>, g: &mut [f64]) {
        let v: [f64; 3] = {
            if mode == 0 {
                if y[0] > 1.0 {
                    self.seen_positive.set(true);
                }
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
fn a_non_finite_step_onto_an_event_is_an_error() {
    let sys = PoisonedFlight {
        seen_positive: std::cell::Cell::new(false),
    };
    let mut ode = Dopri5::new(
        0.0,
        SVector::<f64, 2>::new(0.0, 0.3),
        0u8,
        opts(1e-9, 1e-12),
    );
    let mut observed_nan = false;
    let res = ode.integrate(&sys, 5.0, |st, _| {
        observed_nan |= !st.y1.iter().all(|v| v.is_finite());
    });
    assert!(!observed_nan, "a non-finite step reached the observer");
    match res {
        // The wall is reached at t = 1.26 s; the error carries the start of the failed step.
        Err(SolverError::NonFinite { t, state }) => {
            assert!(t > 0.5 && t < 1.27, "t = {t}");
            assert!(state.iter().all(|v| v.is_finite()), "{state:?}");
        }
        other => panic!("expected a non-finite error, got {other:?}"),
    }
}

/// Two modes whose guards are both positive at x > 0, whatever the mode: every switch lands in
/// a mode that asks to leave at once.
struct Chatter;

impl HybridSystem for Chatter {
    type State = SVector<f64, 1>;
    fn guard_count(&self) -> usize {
        3
    }
    type Mode = bool;
    fn rhs(&self, _: bool, _t: f64, _y: &SVector<f64, 1>) -> SVector<f64, 1> {
        SVector::<f64, 1>::new(1.0)
    }
    fn guards(&self, _: bool, _t: f64, y: &SVector<f64, 1>, g: &mut [f64]) {
        let v: [f64; 3] = { [y[0], f64::NEG_INFINITY, f64::NEG_INFINITY] };
        g.copy_from_slice(&v);
    }
    fn switch(&self, mode: bool, _: usize, _: f64, _: &mut SVector<f64, 1>) -> bool {
        !mode
    }
}

#[test]
fn endless_switching_at_one_time_is_a_chattering_error() {
    // Run on a thread with a deadline: without a cap the integrator would switch forever.
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut ode = Dopri5::new(0.25, SVector::<f64, 1>::new(0.5), false, opts(1e-8, 1e-8));
        let _ = tx.send(ode.integrate(&Chatter, 1.0, |_, _| {}));
    });
    let res = rx
        .recv_timeout(std::time::Duration::from_secs(20))
        .expect("the integrator did not return within 20 s");
    match res {
        Err(SolverError::Chattering {
            t,
            switches,
            ref modes,
            ..
        }) => {
            assert_eq!(t, 0.25);
            assert_eq!(switches, endstop::ode::MAX_SWITCHES_AT_ONE_TIME + 1);
            assert_eq!(modes[..3], ["false", "true", "false"]);
        }
        other => panic!("expected a chattering error, got {other:?}"),
    }
}
/// A ball thrown up towards a ceiling at x = 1 under constant deceleration: x'' = -a with the
/// apex at time `t_apex` and height `1 + excess`.
struct Graze {
    a: f64,
}

impl HybridSystem for Graze {
    type State = SVector<f64, 2>;
    fn guard_count(&self) -> usize {
        3
    }
    type Mode = u8;
    fn rhs(&self, mode: u8, _t: f64, y: &SVector<f64, 2>) -> SVector<f64, 2> {
        if mode == 0 {
            SVector::<f64, 2>::new(y[1], -self.a)
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

/// Runs [`Graze`] over [0, 2] with a first step of exactly [0, 1]; returns the switch time
/// (if any) and the first accepted step's length.
fn graze(t_apex: f64, excess: f64) -> (Option<f64>, f64) {
    let a = 2.0 * (1.0 + excess) / (t_apex * t_apex);
    let sys = Graze { a };
    let mut o = opts::<2>(1e-9, 1e-12);
    o.h_init = 1.0;
    let mut ode = Dopri5::new(0.0, SVector::<f64, 2>::new(0.0, a * t_apex), 0u8, o);
    let (mut hit, mut first_h) = (None, None);
    ode.integrate(&sys, 2.0, |st, m| {
        first_h.get_or_insert(st.h);
        if m == 0 {
            hit = Some(st.t1());
        }
    })
    .unwrap();
    let switched = (ode.mode() == 1).then(|| hit.unwrap());
    (switched, first_h.unwrap())
}

#[test]
fn a_grazing_crossing_between_the_guard_probes_is_found() {
    // The guard x - 1 is sampled at theta = 0, 1/3, 2/3, 1 of the step [0, 1]; with the apex
    // 1e-3 above the ceiling the guard is positive only for |t - t_apex| < sqrt(2e-3 / a)
    // (0.003 to 0.03 s), inside one probe interval, so every probe sees it negative. The
    // trajectory is a quadratic, which the dense output reproduces exactly, so the crossing is
    // located to the event time tolerance (1e-14 s) plus rounding.
    for t_apex in [0.1f64, 0.5, 0.9] {
        let excess = 1e-3f64;
        let a = 2.0 * (1.0 + excess) / (t_apex * t_apex);
        let exact = t_apex - (2.0 * excess / a).sqrt();
        let (hit, _) = graze(t_apex, excess);
        let hit = hit.unwrap_or_else(|| panic!("apex at {t_apex}: grazing contact missed"));
        assert!(
            (hit - exact).abs() < 1e-12,
            "apex at {t_apex}: {hit} vs {exact}"
        );
        // Just below the ceiling: no event, and the first step did span [0, 1].
        let (miss, first_h) = graze(t_apex, -excess);
        assert_eq!(miss, None, "apex at {t_apex}, below the ceiling");
        assert_eq!(first_h, 1.0);
    }
}
