//! Periodic orbits by shooting, their Floquet multipliers and their continuation in frequency
//! (the whole response curve chapter of the book): exact linear limits, the two monodromy
//! computations against each other, residuals and the fold's convergence.

use endstop::device::{Device, StiffnessModel};
use endstop::model::Model;
use endstop::ode::Stats;
use endstop::paper::setups::{comb, endstop, stiffness_model, with_endstop};
use endstop::physics::harvester::Harvester;
use endstop::physics::linear::LinearResponse;
use endstop::progress::Silent;
use endstop::study::continuation::{
    continue_branch, first_orbit, Branch, ContinuationSettings, EventKind,
};
use endstop::study::orbit::{FoldSearch, Forcing, Parameter, Shooter, ShootingOptions};
use nalgebra::{Complex, Matrix3};

use crate::common;

/// Prototype 2 as Figure 13 simulates it at 0.31 g: 10 V, linear k_im, b_im = 0.4 N s/m.
fn prototype2() -> Device {
    with_endstop(
        &common::prototype2().with_bias(10.0),
        StiffnessModel::Linear,
        0.4,
    )
}

/// The eigenvalues of the linear model of eqs 11-17, written from the equations and not from
/// the harvester's right-hand side: the differential mode (x, v, V) with
/// m x'' + b x' + km x + 2 Gamma V = m a and Ct V' + V / RL = Gamma x', and the common mode
/// Ct Vc' + Vc / RL = 0 (Ct = C0 + Cp + CL, Gamma = C0 Vb / x0).
fn linear_eigenvalues(d: &Device) -> Vec<Complex<f64>> {
    let m = d.mechanics.mass_kg;
    let b = d.mechanics.damping_n_s_per_m;
    let km = d.mechanics.stiffness_n_per_m;
    let e = comb(d);
    let ct = e.c0_f + e.cp_f + e.load_capacitance_f;
    let gamma = e.c0_f * e.bias_v / e.finger_overlap_m;
    let rl = e.load_resistance_ohm;
    let a = Matrix3::new(
        0.0,
        1.0,
        0.0,
        -km / m,
        -b / m,
        -2.0 * gamma / m,
        0.0,
        gamma / ct,
        -1.0 / (rl * ct),
    );
    let mut ev: Vec<Complex<f64>> = a.complex_eigenvalues().iter().copied().collect();
    ev.push(Complex::new(-1.0 / (rl * ct), 0.0));
    ev
}

/// Multipliers sorted by modulus, then by imaginary part (pairs conjugates consistently).
fn sorted(mut v: Vec<Complex<f64>>) -> Vec<Complex<f64>> {
    v.sort_by(|a, b| b.norm().total_cmp(&a.norm()).then(b.im.total_cmp(&a.im)));
    v
}

/// Far from the stops (stops removed, 1e-3 g rms at 600 Hz: |x| about 3e-9 m against a finger
/// overlap of tens of um, so the model's nonlinearity changes the power by (x/x0)^2 ~ 1e-8
/// relative) the shooting orbit's power equals the linear transfer function's to 1e-6, and its
/// multipliers equal exp(lambda T) of the linear model's eigenvalues to 1e-8 (the monodromy is
/// integrated with rtol 1e-10; its error is a few 1e-10).
#[test]
fn far_from_the_stops_the_orbit_is_the_linear_steady_state() {
    let d = prototype2();
    let (f, a) = (600.0, 1e-3);
    let h = Harvester::<4>::new(&d).unwrap().without_stops();
    let shooter = Shooter::new(&h, ShootingOptions::default());
    let forcing = Forcing {
        freq_hz: f,
        accel_rms_g: a,
    };
    let mut stats = Stats::default();
    let o = first_orbit(
        &shooter,
        &forcing,
        Parameter::Frequency,
        h.rest_state(),
        0,
        &mut stats,
    )
    .unwrap();
    assert!(o.residual < 1e-9, "residual {:e}", o.residual);
    assert!(o.summary.x_max_m < 1e-3 * comb(&d).finger_overlap_m);
    // A sine of RMS a has the power of a white PSD a^2 / 2 through |H|^2 (see the linear PSD).
    let p_lin =
        LinearResponse::of(&d).output_psd_w_per_hz(0.5 * a * a * endstop::G * endstop::G, f);
    let rel = (o.summary.p_total_w - p_lin).abs() / p_lin;
    assert!(
        rel < 1e-6,
        "power {:e} vs linear {p_lin:e}: {rel:e}",
        o.summary.p_total_w
    );
    let lin = sorted(
        linear_eigenvalues(&d)
            .into_iter()
            .map(|l| (l / f).exp())
            .collect(),
    );
    let ours = sorted(o.multipliers.to_vec());
    for (m, l) in ours.iter().zip(&lin) {
        assert!((m - l).norm() < 1e-8, "multiplier {m} vs exp(lambda T) {l}");
    }
    assert!(o.is_stable());
}

/// Prototype 2 at 0.31 g (Figure 13's linear-law curve) continued from 600 to 850 Hz.
fn fig13_branch(cfg: ShootingOptions) -> (Harvester<4>, Branch) {
    let d = prototype2();
    let h = Harvester::<4>::new(&d).unwrap();
    let mut s = ContinuationSettings::frequency(600.0, 850.0, 2.0);
    s.shooting = cfg;
    let shooter = Shooter::new(&h, cfg);
    let forcing = Forcing {
        freq_hz: 600.0,
        accel_rms_g: 0.31,
    };
    let mut stats = Stats::default();
    let o = first_orbit(
        &shooter,
        &forcing,
        Parameter::Frequency,
        h.rest_state(),
        200,
        &mut stats,
    )
    .unwrap();
    let b = continue_branch(&h, o, &s, &Silent).unwrap();
    (h, b)
}

/// On impacting orbits (both the stable and the unstable one at 720 Hz, inside Figure 13's
/// hysteresis band) the monodromy by the variational equations with saltation matrices equals
/// central differences of the event-located period map at two step sizes to 1e-5 of its
/// largest entry. With rtol 1e-12, measured: the difference falls as eps^2 (truncation,
/// 1.6e-5 relative at eps = 1e-4, 1.4e-6 at 3e-5) to a floor of about 3e-7 (the integration's
/// error over eps) below eps = 1e-5; a missing saltation term changes entries by order one.
#[test]
fn variational_monodromy_equals_finite_differences_on_impacting_orbits() {
    let (h, b) = fig13_branch(ShootingOptions::default());
    let cfg = ShootingOptions {
        rtol: 1e-12,
        ..ShootingOptions::default()
    };
    let shooter = Shooter::new(&h, cfg);
    let mut stats = Stats::default();
    let orbits = b.orbits_at(&shooter, 720.0, &mut stats).unwrap();
    let impacting: Vec<_> = orbits.iter().filter(|o| o.is_impacting()).collect();
    assert_eq!(
        impacting.len(),
        2,
        "a stable and an unstable impacting orbit at 720 Hz"
    );
    assert!(impacting.iter().any(|o| o.is_stable()) && impacting.iter().any(|o| !o.is_stable()));
    for o in impacting {
        let scale = o.monodromy.abs().max();
        for eps in [3e-5, 1e-5] {
            let fd = shooter
                .monodromy_fd(&o.forcing, o.phase_rad, o.state_n::<4>(), eps)
                .unwrap();
            let diff = (fd - o.monodromy_n::<4>()).abs().max() / scale;
            assert!(
                diff < 1e-5,
                "eps {eps:e}: max difference {diff:e} of {scale:e}"
            );
        }
    }
}

/// Every orbit of the branch has |P(y) - y| / |y| below 1e-9, the branch has exactly one fold
/// away from grazing (the upper branch's) and halving the integrator tolerance moves every
/// fold by less than 0.05 %.
#[test]
fn branch_residuals_and_fold_convergence() {
    let (_, b) = fig13_branch(ShootingOptions::default());
    let (_, bh) = fig13_branch(ShootingOptions::default().halved());
    for br in [&b, &bh] {
        assert!(br.max_residual() < 1e-9, "residual {:e}", br.max_residual());
    }
    let folds: Vec<_> = b.events_of(EventKind::Fold).collect();
    let folds_h: Vec<_> = bh.events_of(EventKind::Fold).collect();
    assert_eq!(folds.len(), folds_h.len());
    assert_eq!(
        folds.iter().filter(|e| !e.at_grazing).count(),
        1,
        "one smooth fold"
    );
    for (a, c) in folds.iter().zip(&folds_h) {
        let rel = (a.param - c.param).abs() / a.param;
        assert!(rel < 5e-4, "fold {} vs {} ({rel:e})", a.param, c.param);
    }
}

/// Continuation in the RMS acceleration (the parameter of Figure 9) far from the stops: the
/// branch has no event and the power grows as the square of the acceleration, to 1e-6 (the
/// model's nonlinearity at |x| of a few nm is (x/x0)^2 ~ 1e-8, the orbits' error ~1e-9).
#[test]
fn amplitude_continuation_in_the_linear_regime_scales_the_power_with_the_square() {
    let d = prototype2();
    let h = Harvester::<4>::new(&d).unwrap().without_stops();
    let s = ContinuationSettings::amplitude(1e-3, 1e-2, 1e-3);
    let shooter = Shooter::new(&h, s.shooting);
    let forcing = Forcing {
        freq_hz: 600.0,
        accel_rms_g: 1e-3,
    };
    let mut stats = Stats::default();
    let first = first_orbit(
        &shooter,
        &forcing,
        Parameter::Amplitude,
        h.rest_state(),
        0,
        &mut stats,
    )
    .unwrap();
    let b = continue_branch(&h, first, &s, &Silent).unwrap();
    assert!(b.events.is_empty());
    assert!(b.points.len() >= 9, "{} points", b.points.len());
    let ref_ratio = {
        let o = &b.points[0].orbit;
        o.summary.p_total_w / o.forcing.accel_rms_g.powi(2)
    };
    for p in &b.points {
        let o = &p.orbit;
        let r = o.summary.p_total_w / o.forcing.accel_rms_g.powi(2);
        assert!(
            ((r - ref_ratio) / ref_ratio).abs() < 1e-6,
            "at {} g: {r:e} vs {ref_ratio:e}",
            o.forcing.accel_rms_g
        );
    }
}

/// A free-flight branch arriving at grazing where the impacting orbit leaves at an angle
/// (a prototype 1 variant of the sensitivity study with a tension-free contact and b_im = 3.8
/// N s/m, at 5.5 g scaled by 1.2): the continuation records the grazing and goes on past it
/// onto the impacting orbits. Before the corner hop from the free-flight side it slid back down
/// the free-flight branch from the grazing frequency and reported a stable-to-stable "fold"
/// there, with no grazing.
#[test]
fn a_grazing_corner_is_crossed_from_the_free_flight_side() {
    use endstop::paper::deviations::RangesFile;
    use endstop::study::continuation::frequency_branch;
    let p1 = common::prototype1();
    // Point 3 of the scrambled Sobol sequence of seed 99 in the study's unit cube.
    let u: Vec<f64> = (0..8)
        .map(|k| f64::from(sobol_burley::sample(3, k, 99)))
        .collect();
    let v = RangesFile::bundled()
        .unwrap()
        .prototype1
        .variant(&p1, &u)
        .unwrap();
    let d = v.device.with_bias(endstop::paper::setups::P1_BIAS_V);
    assert!(endstop(&d).tension_free && endstop(&d).damping_n_s_per_m > 3.0);
    let g = 5.5 * v.accel_scale;
    let grazing = |b: &Branch| {
        b.events
            .iter()
            .find(|e| e.kind == EventKind::Grazing)
            .map(|e| e.param)
    };
    let b = frequency_branch(&d, g, 900.0, 2000.0, 10.0, &Silent).unwrap();
    // The grazing orbit is a free-flight orbit, independent of b_im: the same device with
    // b_im = 0 (whose branch crosses grazing smoothly) gives the reference. Tolerance: the
    // event location (1e-4 Hz) and the hop's first step.
    let undamped = with_endstop(&d, stiffness_model(&d), 0.0);
    let reference = grazing(&frequency_branch(&undamped, g, 900.0, 2000.0, 10.0, &Silent).unwrap())
        .expect("the undamped branch grazes");
    let found = grazing(&b).expect("the branch grazes");
    assert!((found - reference).abs() < 0.01, "{found} vs {reference}");
    let spurious = b
        .events
        .iter()
        .any(|e| e.kind == EventKind::Fold && e.stable_before && e.stable_after && !e.at_grazing);
    assert!(
        !spurious,
        "{:?}",
        b.events
            .iter()
            .map(|e| (e.kind, e.param))
            .collect::<Vec<_>>()
    );
    assert!(b.points.iter().any(|p| p.orbit.is_impacting()));
}

/// The fold of Figure 13's upper branch found directly from the branch's last point 1 Hz
/// before it ([`Shooter::fold_near`]) is the continuation's fold: the same frequency to 1e-7
/// relative, a multiplier at 1 to 1e-3, and the branch turning back below it. Both locate the
/// frequency's extremum along the arclength (the continuation to 1e-4, the direct search to
/// 1e-5), which leaves the frequency off by the square of that times the branch's curvature,
/// and both solve the orbit to a residual of 1e-9: 1e-7 is well above either error and far
/// below the move of the fold with the integrator's tolerance
/// (`branch_residuals_and_fold_convergence`).
#[test]
fn fold_found_directly_is_the_continuations_fold() {
    let (h, b) = fig13_branch(ShootingOptions::default());
    let fold = b
        .events_of(EventKind::Fold)
        .find(|e| !e.at_grazing)
        .expect("a smooth fold");
    // The last point at least 1 Hz before the fold (half the continuation's largest step):
    // far enough that the search has to move.
    let start = &b.points[..=fold.after_point]
        .iter()
        .rev()
        .find(|p| fold.param - p.orbit.forcing.freq_hz >= 1.0)
        .expect("a point 1 Hz before the fold")
        .orbit;
    let shooter = Shooter::new(&h, ShootingOptions::default());
    let search = FoldSearch {
        param: Parameter::Frequency,
        param_scale: 1.0,
        tol: 1e-5,
        max_step: 2.0,
    };
    let mut stats = Stats::default();
    let found = shooter.fold_near(start, &search, &mut stats).unwrap();
    let o = &found.orbit;
    let rel = (o.forcing.freq_hz - fold.param).abs() / fold.param;
    let near_one = o
        .multipliers
        .iter()
        .map(|m| (m - 1.0).norm())
        .fold(f64::INFINITY, f64::min);
    println!(
        "fold {} Hz from {} Hz: continuation {} Hz ({rel:e}), multiplier off 1 by {near_one:e}",
        o.forcing.freq_hz, start.forcing.freq_hz, fold.param
    );
    assert!(
        rel < 1e-7,
        "{} vs {} ({rel:e})",
        o.forcing.freq_hz,
        fold.param
    );
    assert!(near_one < 1e-3, "multiplier off 1 by {near_one:e}");
    // The upper branch ends at its largest frequency (the jump down of an up-sweep).
    assert!(found.curvature < 0.0, "curvature {:e}", found.curvature);
}
