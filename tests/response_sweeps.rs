//! The stepped sweeps against the continued branch (the whole response curve chapter of the
//! book): the up-sweep leaves the upper branch at its fold and the down-sweep leaves the
//! lower branch where that branch ends, each within the sweep's frequency resolution (the
//! refined bracket, [`REFINE_TOL_HZ`]).

use endstop::device::Device;
use endstop::paper::response::{continuation, setups, Case, CaseRun, Setup};
use endstop::study::basins::{basins, Attractor};
use endstop::study::sweep::REFINE_TOL_HZ;

fn published() -> (Device, Device) {
    let p1 =
        Device::from_toml_str(include_str!("../data/prototype1.toml"), "prototype1.toml").unwrap();
    let p2 =
        Device::from_toml_str(include_str!("../data/prototype2.toml"), "prototype2.toml").unwrap();
    (p1, p2)
}

/// The setup of a case (the calibrated prototype 1 is the experiments' artefact; the published
/// set stands in for it here, which only the calibrated case would use).
fn setup(case: Case) -> Setup {
    let (p1, p2) = published();
    setups(&p2, &p1, &p1)
        .into_iter()
        .find(|s| s.case == case)
        .unwrap()
}

/// Runs the sweeps and the continuation of a case (no basins).
fn case_run(case: Case) -> CaseRun {
    let s = setup(case);
    let (up, down) = rayon::join(
        || s.sweep.run(&s.device, s.accel_rms_g, |_| {}).unwrap(),
        || s.sweep.run_down(&s.device, s.accel_rms_g, |_| {}).unwrap(),
    );
    let branch = continuation(&s).unwrap();
    CaseRun {
        setup: s,
        up,
        down,
        branch,
        probe: None,
        basins: None,
        attractors: Vec::new(),
        continuation_s: 0.0,
        ghost: Vec::new(),
        up_long_blocks: None,
    }
}

/// Figure 13 (prototype 2, 0.31 g, 2 Hz steps refined to 0.1 Hz brackets, whose blocks of
/// 68 periods outlast the ghost of the fold beyond 0.1 Hz past it): the up-sweep's jump is the
/// upper fold and the down-sweep's first contact is the end of the lower branch (a grazing
/// corner), each within the refined bracket.
#[test]
fn prototype2_sweeps_leave_the_branches_at_the_fold_and_the_lower_end() {
    let r = case_run(Case::Fig13P2);
    let fold = r.fold_hz().expect("an upper fold");
    let jump = r.up_jump_hz().expect("an up-sweep jump");
    assert!(
        (jump - fold).abs() <= REFINE_TOL_HZ,
        "up jump {jump} vs fold {fold}"
    );
    let end = r.lower_end_hz().expect("a lower branch end");
    let down = r.down_end_hz().expect("a down-sweep transition");
    assert!(
        (down - end).abs() <= REFINE_TOL_HZ,
        "down-sweep {down} vs lower end {end}"
    );
}

/// Figure 8's prototype 1 (published, 5.5 g, 10 Hz steps refined to 0.1 Hz): the down-sweep
/// leaves the lower branch at its end within the refined bracket.
#[test]
fn prototype1_down_sweep_leaves_the_lower_branch_at_its_end() {
    let r = case_run(Case::Fig08P1Published);
    let end = r.lower_end_hz().expect("a lower branch end");
    let down = r.down_end_hz().expect("a down-sweep transition");
    assert!(
        (down - end).abs() <= REFINE_TOL_HZ,
        "down-sweep {down} vs lower end {end}"
    );
}

/// Figure 8's prototype 1 (published, 5.5 g): the up-sweep should leave the upper branch at
/// its fold within the refined bracket. It does not: the sweep's steady-state criterion (two
/// successive blocks of 5 periods, the ring-up time 2m/b, agreeing to 1e-3) accepts the
/// slowly dying impacting state just past the fold (the saddle-node's ghost lives 25-42
/// periods at 0.1-0.25 Hz past it), so the sweep's branch end lies about 0.5 Hz above the fold
/// (2 Hz with the calibrated gap). A finding about the criterion, documented in the book's
/// response chapter; the test is kept as it is and ignored until the criterion is changed.
#[test]
#[ignore = "finding: the steady-state criterion accepts the ghost past the fold (see the doc)"]
fn prototype1_up_sweep_leaves_the_upper_branch_at_the_fold() {
    let r = case_run(Case::Fig08P1Published);
    let fold = r.fold_hz().expect("an upper fold");
    let end = r.up_end_hz().expect("an up-sweep branch end");
    assert!(
        (end - fold).abs() <= REFINE_TOL_HZ,
        "up-sweep {end} vs fold {fold}"
    );
}

/// Basin shares at Figure 13's 720 Hz sum to 1 and do not depend on the number of threads
/// (cells are collected in grid order): the same grid on a pool of 1 and of 2 threads gives
/// identical labels, bit for bit.
#[test]
fn basin_shares_sum_to_one_and_do_not_depend_on_the_thread_count() {
    let s = setup(Case::Fig13P2);
    let branch = continuation(&s).unwrap();
    let h = endstop::physics::harvester::Harvester::new(
        &s.device,
        endstop::drive::Sine::from_rms_g(s.accel_rms_g, 720.0),
    );
    let shooter = endstop::study::orbit::Shooter::new(&h, s.continuation.shooting);
    let mut stats = endstop::ode::Stats::default();
    let catalogue: Vec<Attractor> = branch
        .orbits_at(&shooter, 720.0, &mut stats)
        .unwrap()
        .iter()
        .filter(|o| o.is_stable())
        .map(|o| {
            Attractor::of_orbit(
                &shooter,
                o,
                if o.is_impacting() { "upper" } else { "lower" },
            )
            .unwrap()
        })
        .collect();
    assert_eq!(catalogue.len(), 2, "two stable orbits at 720 Hz");
    let bs = s.basin_settings(9).unwrap();
    let forcing = endstop::study::orbit::Forcing {
        freq_hz: 720.0,
        accel_rms_g: s.accel_rms_g,
    };
    let on = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| basins(&h, &forcing, &catalogue, &bs, &|| {}).unwrap())
    };
    let (one, two) = (on(1), on(2));
    assert_eq!(one, two);
    let total: f64 = one.shares().iter().map(|s| s.1).sum();
    assert!((total - 1.0).abs() < 1e-12, "shares sum to {total}");
}

/// The candidate fix of the criterion: with blocks of at least
/// [`endstop::paper::response::LONG_BLOCK_PERIODS`] periods (longer than the ghost lives
/// 0.1 Hz past the fold), the published prototype 1's up-sweep leaves the upper branch at the
/// fold within the refined bracket.
#[test]
fn prototype1_up_sweep_with_long_blocks_leaves_the_upper_branch_at_the_fold() {
    let s = setup(Case::Fig08P1Published);
    let mut long = s.sweep.clone();
    long.cfg.block_periods = endstop::paper::response::LONG_BLOCK_PERIODS;
    let up = long.run(&s.device, s.accel_rms_g, |_| {}).unwrap();
    let branch = continuation(&s).unwrap();
    let fold = branch
        .events_of(endstop::study::continuation::EventKind::Fold)
        .filter(|e| !e.at_grazing && e.stable_before && !e.stable_after)
        .map(|e| e.param)
        .fold(f64::NEG_INFINITY, f64::max);
    let end = up.branch_end().expect("a branch end").transition.value();
    assert!(
        (end - fold).abs() <= REFINE_TOL_HZ,
        "up-sweep {end} vs fold {fold}"
    );
}
