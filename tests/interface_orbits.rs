//! Periodic orbits of a harvester with an interface: the Jacobian of each mode's vector field,
//! the monodromy through saltation matrices against finite differences of the period map,
//! Newton's method with it, and the continuation of the steady state through folds. The
//! studies are the generic ones (`study::periodic`, `study::orbit`) on the assembled model.

use crate::common;
use endstop::circuits::{Bridge, CircuitMode, Heading};
use endstop::device::{Device, Diode, Interface, Inversion};
use endstop::drive::{Excitation, Sine};
use endstop::model::{Contact, Mode, Model};
use endstop::physics::contact::Side;
use endstop::physics::harvester::stops::contact_of;
use endstop::physics::harvester::AssemblyError;
use endstop::progress::Silent;
use endstop::study::orbit::ShootingOptions;
use endstop::study::periodic::{
    measure, period_map, state_of, steady_state, JacobianKind, SteadySettings,
};
use nalgebra::SVector;

/// The example cantilever with a stop behind a full bridge (`data/examples/piezo_bridge.toml`).
fn example() -> Device {
    common::device("examples/piezo_bridge")
}

fn with_interface(d: &Device, kind: &str) -> Device {
    let Interface::FullBridge(r) = &d.interface else {
        unreachable!("the example has a full bridge")
    };
    let mut out = d.clone();
    out.interface = match kind {
        "full_bridge" => d.interface.clone(),
        "parallel_sshi" => Interface::ParallelSshi(r.clone(), Inversion::QualityFactor(3.0)),
        "series_sshi" => Interface::SeriesSshi(r.clone(), Inversion::QualityFactor(3.0)),
        "sece" => Interface::Sece {
            storage_capacitance_f: r.storage_capacitance_f,
            load: r.load.clone(),
            efficiency: 0.8,
        },
        _ => unreachable!(),
    };
    out
}

/// The analytic Jacobian equals central differences of the vector field in every bridge
/// mode, free and in contact, for ideal, resistive and Shockley diodes. The modes are affine
/// in the state (but for Shockley's exponential), so the differences are exact but for
/// rounding, about eps / h = 1e-10 of a column's scale; 1e-6 leaves room for Shockley's
/// second derivative (times h^2, about 1e-12 relative).
#[test]
fn jacobian_matches_differences_of_the_vector_field() {
    let base = example();
    let mut resistive = base.clone();
    let mut shockley = base.clone();
    if let Interface::FullBridge(r) = &mut resistive.interface {
        r.diode = Diode::PiecewiseLinear {
            forward_drop_v: 0.2,
            on_resistance_ohm: 50.0,
        };
    }
    if let Interface::FullBridge(r) = &mut shockley.interface {
        r.diode = Diode::Shockley {
            saturation_current_a: 1e-9,
            ideality: 1.5,
            thermal_voltage_v: 0.02585,
        };
    }
    let mut checked = 0;
    for d in [
        base,
        resistive,
        shockley,
        common::device("examples/em_bridge"),
    ] {
        let n: Result<usize, AssemblyError> =
            endstop::with_harvester!(&d, |m| Ok(jacobian_checks(&m, &d.name)));
        checked += n.unwrap();
    }
    assert_eq!(checked, 4 * 6 * 16);
}

/// [`jacobian_matches_differences_of_the_vector_field`] on one model: the entries checked.
fn jacobian_checks<M: Model<N>, const N: usize>(m: &M, name: &str) -> usize {
    let sc = m.scales();
    let mut y = SVector::<f64, N>::zeros();
    y[0] = 1.05e-4;
    y[1] = -0.03;
    y[2] = 0.17 * sc[2];
    y[3] = 0.11 * sc[3];
    let a = Sine::from_rms_g(0.3, 120.0).accel(1e-3);
    let upper = Mode::FREE.with_contact(contact_of(Side::Upper), Contact::Pressed);
    let mut checked = 0;
    for contact in [Mode::FREE, upper] {
        for bridge in [Bridge::Off, Bridge::Positive, Bridge::Negative] {
            let bits = CircuitMode {
                bridge,
                heading: Heading::Up,
            }
            .bits();
            let mode = contact.with_circuit(0, bits);
            checked += common::interface_checks::assert_jacobian_matches_differences(
                m,
                mode,
                &y,
                a,
                &format!("{name} {mode:?}"),
            );
        }
    }
    checked
}

/// A steady state of `m` at 0.3 g, 120 Hz, by iterating the period map from rest for 3000
/// periods (the slowest multiplier, about 0.96, leaves 1e-50 of the start): shooting does not
/// converge for SSHI at some loads, iteration does. Returns the state and the last scaled
/// change.
fn iterated<M: Model<N>, const N: usize>(m: &M) -> (SVector<f64, N>, f64) {
    let sine = Sine::from_rms_g(0.3, 120.0);
    let sc = m.scales();
    let mut y = SVector::<f64, N>::zeros();
    let mut residual = f64::INFINITY;
    for _ in 0..3000 {
        let p = period_map(m, sine, &y, 1e-9).unwrap();
        residual = (p - y).component_div(&sc).amax();
        y = p;
    }
    (y, residual)
}

/// The monodromy and dP/df through saltation matrices against central differences of the
/// period map, at each interface's steady state on the example cantilever (0.3 g, 120 Hz).
/// The differences step 1e-5 of each state scale (and 1e-5 Hz) with the integrator at rtol
/// 1e-11: their error is the integration's (and the event location's) noise over the step,
/// about 1e-11 / 1e-5 = 1e-6 of the map's scale, times the global error's growth over a
/// period; plus the truncation, the step squared times the third derivative, about 1e-10.
/// Entries of the scaled monodromy are compared against 1e-4 of its largest entry: some
/// hundred times that noise, and far below the saltation's share (the events' jumps, which
/// the check requires to be there: at least the two conduction changes or extrema).
#[test]
fn monodromy_matches_differences_of_the_period_map() {
    for kind in ["full_bridge", "parallel_sshi", "series_sshi", "sece"] {
        let d = with_interface(&example(), kind);
        let r: Result<(), AssemblyError> = endstop::with_harvester!(&d, |m| {
            monodromy_check(&m, kind);
            Ok(())
        });
        r.unwrap();
    }
}

/// [`monodromy_matches_differences_of_the_period_map`] on one model.
fn monodromy_check<M: Model<N>, const N: usize>(model: &M, kind: &str) {
    let (y, residual) = iterated(model);
    assert!(residual < 1e-9, "{kind}: not settled ({residual:e})");
    let sine = Sine::from_rms_g(0.3, 120.0);
    let common::linearisation::Against {
        lin,
        stats,
        monodromy_rel: diff,
        dp_rel: diff_p,
    } = common::linearisation::against_differences(model, sine, y, 1e-11);
    let mu = endstop::study::orbit::multipliers(&lin.monodromy).unwrap();
    let m = measure(model, sine, &y, 1e-9).unwrap();
    eprintln!(
        "{kind}: events {}; |M - M_fd| / |M| = {diff:.2e}, |dP/df - fd| / |dP/df| = \
         {diff_p:.2e}, max |mu| {:.6}, x_peak {:.5e} m, contact {}",
        stats.events,
        mu[0].norm(),
        m.x_peak_m,
        m.contact
    );
    assert!(stats.events >= 2, "{kind}: {} events", stats.events);
    assert!(
        diff < 1e-4,
        "{kind}: monodromy differs by {diff:e}\n{}",
        lin.monodromy
    );
    assert!(
        diff_p < 1e-4,
        "{kind}: dP/df differs by {diff_p:e}\n{}",
        lin.dp
    );
    // The iteration settled, so the orbit is stable: every multiplier inside the circle.
    assert!(mu[0].norm() < 1.0, "{kind}: {}", mu[0].norm());
}

/// Newton with the exact Jacobian and with forward differences reach the same steady state
/// with the full bridge, to the shooting's tolerance, and the same largest multiplier to the
/// differences' accuracy (1e-4: about rtol / 1e-6 = 1e-3 of the entries' noise averaged by
/// the eigenvalue).
#[test]
fn both_jacobians_shoot_to_the_same_orbit() {
    let d = example();
    let sine = Sine::from_rms_g(0.3, 120.0);
    let run = |jacobian| {
        let set = SteadySettings {
            jacobian,
            ..SteadySettings::default()
        };
        let r: Result<_, endstop::study::periodic::PeriodicError> =
            endstop::with_harvester!(&d, |h| steady_state(&h, sine, &h.rest_state(), &set));
        r.unwrap()
    };
    let (a, b) = (run(JacobianKind::Saltation), run(JacobianKind::Differences));
    eprintln!(
        "saltation: {} steps, residual {:.1e}, max |mu| {:.7}; differences: {} steps, \
         residual {:.1e}, max |mu| {:.7}",
        a.newton_steps, a.residual, a.max_multiplier, b.newton_steps, b.residual, b.max_multiplier
    );
    assert!((a.p_dc_w - b.p_dc_w).abs() < 1e-6 * a.p_dc_w);
    assert!((a.max_multiplier - b.max_multiplier).abs() < 1e-4);
}

/// The example cantilever's steady state with a full bridge, continued in frequency at 1 g
/// from 110 to 300 Hz: the stop bends the response to higher frequencies, the branch turns at
/// two folds (the lower one where the orbit grazes the stop, a corner of the branch), and the
/// stretch between them (the middle branch) is unstable while the rest is stable. Far above
/// resonance the bridge stops conducting: the piezoelectric element's charge is then conserved
/// (a multiplier of 1: the orbits form a family), which marks no event and decides no
/// stability, and the storage decays by its slow mode, exp(-T / (R_L C_s)), about 0.99.
#[test]
fn continuation_passes_the_folds_of_the_stop() {
    use endstop::study::continuation::{frequency_branch, EventKind};
    use endstop::study::orbit::is_neutral;
    let d = example();
    let branch = frequency_branch(&d, 1.0, 110.0, 300.0, 2.0, &Silent).unwrap();
    for p in &branch.points {
        eprintln!(
            "pt {:.4} Hz: x_peak {:.3e} m, max |mu| {:.6}, t_f {:+.3}",
            p.orbit.forcing.freq_hz,
            p.orbit.summary.x_max_m,
            p.orbit.multipliers[0].norm(),
            p.param_tangent()
        );
    }
    let folds: Vec<_> = branch.events_of(EventKind::Fold).collect();
    eprintln!(
        "{} points, folds at {:?} Hz, rejected {}",
        branch.points.len(),
        folds.iter().map(|e| e.param).collect::<Vec<_>>(),
        branch.rejected_steps()
    );
    // The branch reaches the end of the range (its last step may pass it).
    let last = branch.points.last().unwrap().orbit.forcing.freq_hz;
    assert!(last >= 300.0, "ends at {last} Hz");
    assert_eq!(folds.len(), 2, "{:?}", branch.events);
    // The first point past each fold.
    let (i1, i2) = (folds[0].after_point + 1, folds[1].after_point + 1);
    for e in &branch.events {
        eprintln!("event {:?} at {} Hz", e.kind, e.param);
    }
    // The neutral multiplier marks no event: the folds are the branch's only events
    // (with the grazing of the stop at the lower one).
    assert!(
        branch
            .events
            .iter()
            .all(|e| matches!(e.kind, EventKind::Fold | EventKind::Grazing)),
        "{:?}",
        branch.events
    );
    // Where the bridge no longer conducts (well above the upper fold) the orbit has a
    // neutral multiplier; below the lower fold, where it conducts, none.
    let neutral = |p: &endstop::study::continuation::BranchPoint| {
        let m = &p.orbit.multipliers;
        m.iter().filter(|m| is_neutral(**m, false)).count()
    };
    for p in &branch.points {
        let f = p.orbit.forcing.freq_hz;
        if f > 280.0 {
            assert_eq!(neutral(p), 1, "{f} Hz: {:?}", p.orbit.multipliers);
        }
        if f < 130.0 {
            assert_eq!(neutral(p), 0, "{f} Hz: {:?}", p.orbit.multipliers);
        }
    }
    let tol = ShootingOptions::default().residual_tol;
    for (i, p) in branch.points.iter().enumerate() {
        assert!(p.orbit.residual < tol, "{i}");
        let middle = i >= i1 && i < i2;
        // A point next to a fold has a multiplier within its step of 1: judged only away.
        let near_fold = [i1, i2].iter().any(|&k| i + 1 >= k && i <= k);
        // Off the bridge's conduction the conserved charge's multiplier is 1 to rounding:
        // neutral, it decides no stability.
        let stable = p.orbit.is_stable();
        if !near_fold {
            assert_eq!(
                stable, !middle,
                "point {i} at {} Hz",
                p.orbit.forcing.freq_hz
            );
        }
    }
}

/// Shooting from rest finds the steady state of the example cantilever with parallel SSHI at
/// 50 kohm and series SSHI at 100 kohm (where a Newton search that asked the residual to fall
/// at each step stalled near 1e-2), and it is the orbit the period map iterated from rest
/// reaches: 1500 periods contract the distance by the largest multiplier's modulus to the
/// 1500th power (below 1e-29 for both), so the iterate is the orbit to rounding; the two agree
/// within 1e-6 of each state scale (the shooting's tolerance of 1e-7 on the residual, over a
/// gap 1 - |mu| of 0.05 and 0.08, allows 2e-6) and the DC power within 1e-6 relative.
#[test]
fn shooting_finds_the_sshi_orbits_at_large_loads() {
    for (kind, load_ohm) in [("parallel_sshi", 50e3), ("series_sshi", 100e3)] {
        let mut d = with_interface(&example(), kind);
        d.interface = d.interface.with_load_resistance(load_ohm);
        let r: Result<(), AssemblyError> = endstop::with_harvester!(&d, |m| {
            sshi_check(&m, kind, load_ohm);
            Ok(())
        });
        r.unwrap();
    }
}

/// [`shooting_finds_the_sshi_orbits_at_large_loads`] on one model.
fn sshi_check<M: Model<N>, const N: usize>(model: &M, kind: &str, load_ohm: f64) {
    let sine = Sine::from_rms_g(0.3, 120.0);
    let set = SteadySettings::default();
    let s = steady_state(model, sine, &SVector::<f64, N>::zeros(), &set).unwrap();
    let sc = model.scales();
    let mut y = SVector::<f64, N>::zeros();
    for _ in 0..1500 {
        y = period_map(model, sine, &y, set.rtol).unwrap();
    }
    let dist = (state_of::<N>(&s) - y).component_div(&sc).amax();
    let iterated = measure(model, sine, &y, set.rtol).unwrap();
    eprintln!(
        "{kind} at {load_ohm} ohm: {} Newton steps, max |mu| {:.5}, distance to the \
         iterated orbit {dist:.1e}, P_DC {:.6e} W vs {:.6e} W",
        s.newton_steps, s.max_multiplier, s.p_dc_w, iterated.p_dc_w
    );
    assert!(s.max_multiplier.powi(1500) < 1e-29, "{kind}");
    assert!(dist < 1e-6, "{kind}: {dist}");
    assert!(
        (s.p_dc_w - iterated.p_dc_w).abs() < 1e-6 * iterated.p_dc_w,
        "{kind}"
    );
}

/// An up-sweep of the example at 1 g in steps of 2 Hz jumps off the upper branch after the fold
/// at 168.46 Hz: at 170 Hz Newton's method from the upper orbit does not converge, and the
/// period map iterated from the transient's end finds the lower orbit. It is the orbit: 1500
/// further periods (a contraction by its largest multiplier, about 0.97, to the 1500th power,
/// below 1e-15) move it by less than 1e-6 of each state scale (its residual is below the
/// tolerance of 1e-7 over a gap 1 - |mu| of 0.03, so about 3e-6 at most), and its DC power is
/// on the lower branch, below a tenth of the upper orbit's at 168 Hz.
#[test]
fn the_period_map_finds_the_orbit_past_a_fold() {
    let d = example();
    let set = SteadySettings::default();
    let freqs: Vec<f64> = (0..=30).map(|i| 110.0 + 2.0 * f64::from(i)).collect();
    let states: Vec<_> = endstop::study::periodic::frequency_sweep(&d, &freqs, 1.0, &set, &Silent)
        .unwrap()
        .into_iter()
        .map(|s| s.unwrap())
        .collect();
    let (upper, past) = (&states[29], &states[30]);
    eprintln!(
        "168 Hz: {:?}, P_DC {:.4e} W; 170 Hz: {:?}, max |mu| {:.5}, residual {:.1e}, P_DC \
         {:.4e} W",
        upper.method, upper.p_dc_w, past.method, past.max_multiplier, past.residual, past.p_dc_w
    );
    assert!(matches!(
        past.method,
        endstop::study::periodic::SteadyMethod::PeriodMap { .. }
    ));
    assert!(past.residual < set.tol);
    assert!(past.max_multiplier.powi(1500) < 1e-15);
    let moved: Result<f64, AssemblyError> = endstop::with_harvester!(&d, |model| {
        let y0 = state_of(past);
        let mut y = y0;
        for _ in 0..1500 {
            y = period_map(&model, Sine::from_rms_g(1.0, 170.0), &y, set.rtol).unwrap();
        }
        Ok((y - y0).component_div(&model.scales()).amax())
    });
    let moved = moved.unwrap();
    eprintln!("moved by {moved:.1e} in 1500 periods");
    assert!(moved < 1e-6);
    assert!(past.p_dc_w < 0.1 * upper.p_dc_w);
}

/// The electromagnetic example behind its bridge at 45 Hz and 0.2 g rms: the EMF (about
/// `Phi a / |omega0^2 - omega^2|` times omega, 0.42 V) stays below the battery and two drops
/// (1.8 V), so the bridge never conducts and the coil current stays at zero. The continuation
/// starts there from rest and reaches 46 Hz; each orbit's largest multiplier is the free
/// oscillator's, `exp(-b T / (2 m))` (the coil exerts no force, the stops are not reached, the
/// storage's own mode decays as `exp(-T / (R_s C_s))`, below 1e-9), to 1e-6: the variational
/// integration's error at its tolerance, with no neutral multiplier of the held current.
#[test]
fn an_orbit_that_never_conducts_has_no_neutral_multiplier() {
    use endstop::study::continuation::impacting::DiagramSettings;
    use endstop::study::continuation::{diagram, ContinuationSettings};
    use endstop::study::orbit::Forcing;
    let d = common::device("examples/em_bridge");
    let start = Forcing {
        freq_hz: 45.0,
        accel_rms_g: 0.2,
    };
    let cont = ContinuationSettings::frequency(45.0, 46.0, 0.5);
    let dia = diagram(&d, start, &cont, &DiagramSettings::default(), &Silent).unwrap();
    let (m, b) = (d.mechanics.mass_kg, d.mechanics.damping_n_s_per_m);
    let mut n = 0;
    for p in dia.branches.iter().flat_map(|br| br.points.iter()) {
        let t = 1.0 / p.forcing.freq_hz;
        let free = (-b * t / (2.0 * m)).exp();
        let largest = p.multipliers.iter().map(|z| z.norm()).fold(0.0, f64::max);
        assert!(
            (largest - free).abs() < 1e-6,
            "{} Hz: largest |mu| {largest}, free oscillator {free}",
            p.forcing.freq_hz
        );
        n += 1;
    }
    assert!(n >= 2, "{n} points");
}
