//! Periodic orbits of a harvester with an interface: the Jacobian of each mode's vector field,
//! the monodromy through saltation matrices against finite differences of the period map,
//! Newton's method with it, and the continuation of the steady state through folds.

use crate::common;
use endstop::device::{Device, Diode, Interface, Inversion};
use endstop::drive::Sine;
use endstop::ode::HybridSystem;
use endstop::physics::contact::{Mode, Side};
use endstop::physics::harvester::State;
use endstop::physics::interface::{Bridge, Heading, IfMode, Interfaced};
use endstop::progress::Silent;
use endstop::study::interface::continuation::{continue_frequency, IfContinuationSettings};
use endstop::study::interface::monodromy::linearise;
use endstop::study::interface::{
    measure, period_map_of, steady_model, steady_state, JacobianKind, SteadySettings,
};

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
        let m = Interfaced::new(&d, Sine::from_rms_g(0.3, 120.0)).unwrap();
        let sc = m.scales();
        let y = State::new(1.05e-4, -0.03, 0.17 * sc[2], 0.11 * sc[3]);
        for contact in [Mode::Free, Mode::Contact(Side::Upper)] {
            for bridge in [Bridge::Off, Bridge::Positive, Bridge::Negative] {
                let mode = IfMode {
                    contact,
                    bridge,
                    heading: Heading::Up,
                };
                let j = m.jacobian(mode, &y);
                for c in 0..4 {
                    let h = 1e-6 * sc[c];
                    let (mut yp, mut ym) = (y, y);
                    yp[c] += h;
                    ym[c] -= h;
                    let fd = (m.rhs(mode, 1e-3, &yp) - m.rhs(mode, 1e-3, &ym)) / (2.0 * h);
                    for r in 0..4 {
                        // A rate's scale: the row's scale times the suspension's 754 rad/s,
                        // over the column's.
                        let scale = (fd[r].abs() + j[(r, c)].abs()).max(754.0 * sc[r] / sc[c]);
                        assert!(
                            (fd[r] - j[(r, c)]).abs() <= 1e-6 * scale,
                            "{} {mode:?} ({r},{c}): {} vs {}",
                            d.name,
                            j[(r, c)],
                            fd[r]
                        );
                        checked += 1;
                    }
                }
            }
        }
    }
    assert_eq!(checked, 4 * 6 * 16);
}

/// A steady state of `d` at 0.3 g, 120 Hz, by iterating the period map from rest for 3000
/// periods (the slowest multiplier, about 0.96, leaves 1e-50 of the start): shooting does not
/// converge for SSHI at some loads (see the module docs of `study::interface`), iteration does.
fn iterated(d: &Device) -> (endstop::physics::interface::Interfaced<Sine>, State, f64) {
    let model = steady_model(d, Sine::from_rms_g(0.3, 120.0)).unwrap();
    let sc = model.scales();
    let mut y = State::zeros();
    let mut residual = f64::INFINITY;
    for _ in 0..3000 {
        let p = period_map_of(&model, &y, 1e-9).unwrap();
        residual = (p - y).component_div(&sc).amax();
        y = p;
    }
    (model, y, residual)
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
        let (model, y, residual) = iterated(&d);
        assert!(residual < 1e-9, "{kind}: not settled ({residual:e})");
        let rtol = 1e-11;
        let lin = linearise(&model, &y, rtol).unwrap();
        let sc = model.scales();
        let scaled = |m: &nalgebra::Matrix4<f64>| {
            nalgebra::Matrix4::from_diagonal(&sc.map(|v| 1.0 / v))
                * m
                * nalgebra::Matrix4::from_diagonal(&sc)
        };
        let exact = scaled(&lin.monodromy);
        let mut fd = nalgebra::Matrix4::zeros();
        for c in 0..4 {
            let h = 1e-5 * sc[c];
            let (mut yp, mut ym) = (y, y);
            yp[c] += h;
            ym[c] -= h;
            let col = (period_map_of(&model, &yp, rtol).unwrap()
                - period_map_of(&model, &ym, rtol).unwrap())
                / (2.0 * h);
            fd.set_column(c, &col);
        }
        let fd = scaled(&fd);
        let diff = (exact - fd).amax() / exact.amax();
        // dP/df by central differences in the frequency, scaled by the state scales.
        let df = 1e-5;
        let p_at = |f: f64| {
            let m = steady_model(&d, Sine::from_rms_g(0.3, f)).unwrap();
            period_map_of(&m, &y, rtol).unwrap()
        };
        let dp_fd = ((p_at(120.0 + df) - p_at(120.0 - df)) / (2.0 * df)).component_div(&sc);
        let dp = lin.dp_dfreq.component_div(&sc);
        let diff_p = (dp - dp_fd).amax() / dp.amax();
        let mu = endstop::study::orbit::multipliers(&lin.monodromy).unwrap();
        let m = measure(&model, &y, 1e-9).unwrap();
        eprintln!(
            "{kind}: events {} min transversality {:.3e}; |M - M_fd| / |M| = {diff:.2e}, \
             |dP/df - fd| / |dP/df| = {diff_p:.2e}, max |mu| {:.6}, x_peak {:.5e} m, contact {}",
            lin.events,
            lin.min_transversality,
            mu[0].norm(),
            m.x_peak_m,
            m.contact
        );
        assert!(lin.events >= 2, "{kind}: {} events", lin.events);
        assert!(
            diff < 1e-4,
            "{kind}: monodromy differs by {diff:e}\n{exact}{fd}"
        );
        assert!(
            diff_p < 1e-4,
            "{kind}: dP/df differs by {diff_p:e}\n{dp}{dp_fd}"
        );
        // The iteration settled, so the orbit is stable: every multiplier inside the circle.
        assert!(mu[0].norm() < 1.0, "{kind}: {}", mu[0].norm());
    }
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
        steady_state(&d, sine, &State::zeros(), &set).unwrap()
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
/// resonance the bridge stops conducting and the largest multiplier is the storage's slow
/// mode, exp(-T / (R_L C_s)), about 0.99.
#[test]
fn continuation_passes_the_folds_of_the_stop() {
    let d = example();
    let mut set = IfContinuationSettings::new(110.0, 300.0, 1.0);
    set.max_points = 1000;
    set.max_freq_step_hz = 2.0;
    set.ds_max = 2.0;
    let branch = continue_frequency(&d, &set, &Silent).unwrap();
    for p in &branch.points {
        eprintln!(
            "pt {:.4} Hz: P_DC {:.4e} W, V_DC {:.4} V, x_peak {:.3e} m, max |mu| {:.6}, t_f {:+.3}",
            p.steady.freq_hz,
            p.steady.p_dc_w,
            p.steady.vdc_v,
            p.steady.x_peak_m,
            p.steady.max_multiplier,
            p.tangent_freq
        );
    }
    eprintln!(
        "{} points, folds {:?}, end {:?}, Newton {}, rejected {}",
        branch.points.len(),
        branch.folds,
        branch.end,
        branch.newton_iterations,
        branch.rejected_steps
    );
    assert_eq!(
        branch.end,
        endstop::study::interface::continuation::IfBranchEnd::Reached
    );
    assert_eq!(branch.folds.len(), 2, "{:?}", branch.folds);
    let (i1, i2) = (branch.folds[0].1, branch.folds[1].1);
    for (i, p) in branch.points.iter().enumerate() {
        assert!(p.steady.residual < set.tol, "{i}");
        let middle = i >= i1 && i < i2;
        // A point next to a fold has a multiplier within its step of 1: judged only away.
        let near_fold = [i1, i2].iter().any(|&k| i + 1 >= k && i <= k);
        if !near_fold {
            assert_eq!(
                p.is_stable(),
                !middle,
                "point {i} at {} Hz",
                p.steady.freq_hz
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
        let sine = Sine::from_rms_g(0.3, 120.0);
        let set = SteadySettings::default();
        let s = steady_state(&d, sine, &State::zeros(), &set).unwrap();
        let model = steady_model(&d, sine).unwrap();
        let sc = model.scales();
        let mut y = State::zeros();
        for _ in 0..1500 {
            y = period_map_of(&model, &y, set.rtol).unwrap();
        }
        let dist = (State::from(s.state) - y).component_div(&sc).amax();
        let iterated = measure(&model, &y, set.rtol).unwrap();
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
    let states: Vec<_> =
        endstop::study::interface::sweep::frequency_sweep(&d, &freqs, 1.0, &set, &Silent)
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
        endstop::study::interface::SteadyMethod::PeriodMap { .. }
    ));
    assert!(past.residual < set.tol);
    assert!(past.max_multiplier.powi(1500) < 1e-15);
    let model = steady_model(&d, Sine::from_rms_g(1.0, 170.0)).unwrap();
    let mut y = State::from(past.state);
    for _ in 0..1500 {
        y = period_map_of(&model, &y, set.rtol).unwrap();
    }
    let moved = (y - State::from(past.state))
        .component_div(&model.scales())
        .amax();
    eprintln!("moved by {moved:.1e} in 1500 periods");
    assert!(moved < 1e-6);
    assert!(past.p_dc_w < 0.1 * upper.p_dc_w);
}
