//! The stepped sweeps against the continued branch (the whole response curve chapter of the
//! book): the up-sweep leaves the upper branch at its fold and the down-sweep leaves the
//! lower branch where that branch ends, each within the sweep's frequency resolution (the
//! refined bracket, [`REFINE_TOL_HZ`]).

use endstop::paper::response::{
    continuation, ghost_study, setups, sweeps_and_branch, upper_fold_hz, Case, CaseRun, Setup,
    BASIN_RTOL,
};
use endstop::study::basins::{basins, refine, Attractor, BasinSettings};
use endstop::study::steady::{
    horizon_periods, settle_settings, SettleSettings, FOLD_BLOCK_PERIODS,
};
use endstop::study::sweep::REFINE_TOL_HZ;

use crate::common;

/// The setup of a case (the calibrated prototype 1 is the experiments' artefact; the published
/// set stands in for it here, which only the calibrated case would use).
fn setup(case: Case) -> Setup {
    let (p1, p2) = (common::prototype1(), common::prototype2());
    setups(&p2, &p1, &p1)
        .into_iter()
        .find(|s| s.case == case)
        .unwrap()
}

/// The sweep's transition `sweep_hz` lies within the refinement bracket ([`REFINE_TOL_HZ`])
/// of the continuation's `branch_hz`: the sweep's resolution, the closest it can say anything.
fn assert_within_bracket(sweep_hz: f64, branch_hz: f64, what: &str) {
    assert!(
        (sweep_hz - branch_hz).abs() <= REFINE_TOL_HZ,
        "{what}: sweep {sweep_hz} Hz vs branch {branch_hz} Hz"
    );
}

/// Runs the sweeps and the continuation of a case (no basins).
fn case_run(case: Case) -> CaseRun {
    sweeps_and_branch(&setup(case), &|| {}).unwrap()
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
    assert_within_bracket(jump, fold, "up jump vs fold");
    let end = r.lower_end_hz().expect("a lower branch end");
    let down = r.down_end_hz().expect("a down-sweep transition");
    assert_within_bracket(down, end, "down-sweep vs lower end");
}

/// Figure 8's prototype 1 (published, 5.5 g, 10 Hz steps refined to 0.1 Hz): the down-sweep
/// leaves the lower branch at its end within the refined bracket.
#[test]
fn prototype1_down_sweep_leaves_the_lower_branch_at_its_end() {
    let r = case_run(Case::Fig08P1Published);
    let end = r.lower_end_hz().expect("a lower branch end");
    let down = r.down_end_hz().expect("a down-sweep transition");
    assert_within_bracket(down, end, "down-sweep vs lower end");
}

/// Figure 8's prototype 1 (published, 5.5 g, 10 Hz steps refined to 0.1 Hz): the up-sweep
/// leaves the upper branch at its fold within the refined bracket. Its blocks follow the fold
/// rule ([`FOLD_BLOCK_PERIODS`]): with blocks of the ring-up time alone (5 periods) the
/// criterion accepted the slowly dying impacting state past the fold and the sweep left the
/// branch about 0.5 Hz above it.
#[test]
fn prototype1_up_sweep_leaves_the_upper_branch_at_the_fold() {
    let r = case_run(Case::Fig08P1Published);
    let fold = r.fold_hz().expect("an upper fold");
    let end = r.up_end_hz().expect("an up-sweep branch end");
    assert_within_bracket(end, fold, "up-sweep vs fold");
}

/// The fold rule's inequality for the published prototype 1: started from the stable
/// impacting orbit 1 Hz below the fold, the state at the bracket's width
/// ([`REFINE_TOL_HZ`]) past the fold stops touching the stops before the horizon of Figure 8's
/// criterion ([`horizon_periods`]) ends, and the criterion does not accept it; with blocks of
/// the ring-up time alone (5 periods) it does (the defect the rule removes).
#[test]
fn prototype1_ghost_at_the_bracket_dies_within_the_criterions_horizon() {
    let s = setup(Case::Fig08P1Published);
    let branch = continuation(&s).unwrap();
    let cfg = &s.sweep.cfg;
    let rows = ghost_study(&s, &branch, cfg, &[REFINE_TOL_HZ]).unwrap();
    let g = rows.first().expect("an upper fold");
    assert!(
        g.last_contact_period < horizon_periods(cfg),
        "ghost lives {} periods, horizon {}",
        g.last_contact_period,
        horizon_periods(cfg)
    );
    assert!(!g.accepted_in_contact, "{g:?}");
    let ring_up = SettleSettings {
        block_periods: settle_settings(&s.device, upper_fold_hz(&branch).unwrap()).block_periods,
        ..cfg.clone()
    };
    let short = ghost_study(&s, &branch, &ring_up, &[REFINE_TOL_HZ]).unwrap();
    assert!(short[0].accepted_in_contact, "{:?}", short[0]);
}

/// The fold rule changes nothing where the ring-up time already gives longer blocks:
/// Figure 13's prototype 2 keeps its blocks of the ring-up time (so its sweeps, pinned in the
/// regression snapshots, are unchanged).
#[test]
fn fold_rule_leaves_prototype2_blocks_at_the_ring_up_time() {
    let s = setup(Case::Fig13P2);
    let ring_up = settle_settings(&s.device, 700.0);
    assert!(ring_up.block_periods > FOLD_BLOCK_PERIODS);
    assert_eq!(s.sweep.cfg, ring_up);
}

/// A case at its basin frequency: the model, the catalogue of its two stable orbits, the
/// forcing and the case's setup (for its basin settings).
fn basin_inputs(
    s: Setup,
) -> (
    endstop::physics::harvester::Harvester<4>,
    Vec<Attractor>,
    endstop::study::orbit::Forcing,
    Setup,
) {
    let f = s.case.basin_freq_hz().expect("a case with basins");
    let branch = continuation(&s).unwrap();
    let h = endstop::physics::harvester::Harvester::<4>::new(&s.device).unwrap();
    let shooter = endstop::study::orbit::Shooter::new(&h, s.continuation.shooting);
    let mut stats = endstop::ode::Stats::default();
    let catalogue: Vec<Attractor> = branch
        .orbits_at(&shooter, f, &mut stats)
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
    assert_eq!(catalogue.len(), 2, "two stable orbits at {f} Hz");
    let forcing = endstop::study::orbit::Forcing {
        freq_hz: f,
        accel_rms_g: s.accel_rms_g,
    };
    (h, catalogue, forcing, s)
}

/// Figure 13's case at 720 Hz ([`basin_inputs`]).
fn fig13_basin_inputs() -> (
    endstop::physics::harvester::Harvester<4>,
    Vec<Attractor>,
    endstop::study::orbit::Forcing,
    Setup,
) {
    basin_inputs(setup(Case::Fig13P2))
}

/// The basins' integrator tolerance ([`BASIN_RTOL`]) does not decide any cell: on a 15 x 15
/// grid of each case with basins (Figure 13's prototype 2 at 720 Hz, the calibrated
/// prototype 1 at 1345 Hz), every cell ends on the same attractor as at the shooting's
/// tolerance (1e-10), and the grid runs in fewer steps. A cell's number of periods may differ
/// by one (a cell whose distance crosses the settling distance near the end of a period settles
/// a period earlier or later); no more.
#[test]
#[ignore = "characterisation: the basins at two tolerances, some 5 s"]
fn basins_do_not_depend_on_the_tolerance() {
    let (p1, p2) = (common::prototype1(), common::prototype2());
    let calibrated = endstop::paper::calibration::calibrate_prototype1(&p1)
        .unwrap()
        .device;
    for case in [Case::Fig13P2, Case::Fig08P1Calibrated] {
        let s = setups(&p2, &p1, &calibrated)
            .into_iter()
            .find(|s| s.case == case)
            .unwrap();
        let shooting_rtol = s.continuation.shooting.rtol;
        let (h, catalogue, forcing, s) = basin_inputs(s);
        let loose = s.basin_settings(15).unwrap();
        assert_eq!(loose.rtol, BASIN_RTOL);
        assert!(BASIN_RTOL > shooting_rtol);
        let tight = BasinSettings {
            rtol: shooting_rtol,
            ..loose
        };
        let a = basins(&h, &forcing, &catalogue, &loose, &|| {}).unwrap();
        let b = basins(&h, &forcing, &catalogue, &tight, &|| {}).unwrap();
        assert!(a.attractor.iter().all(Option::is_some), "{case:?}: settled");
        assert_eq!(a.attractor, b.attractor, "{case:?}: attractors");
        let off = a
            .periods
            .iter()
            .zip(&b.periods)
            .filter(|(p, q)| p != q)
            .collect::<Vec<_>>();
        assert!(
            off.iter().all(|(p, q)| p.abs_diff(**q) == 1),
            "{case:?}: periods differ by more than one: {off:?}"
        );
        assert!(a.stats.accepted < b.stats.accepted, "{case:?}: steps");
    }
}

/// Basin shares at Figure 13's 720 Hz sum to 1 and do not depend on the number of threads
/// (cells are collected in grid order): the same grid on a pool of 1 and of 2 threads gives
/// identical labels, bit for bit.
#[test]
fn basin_shares_sum_to_one_and_do_not_depend_on_the_thread_count() {
    let (h, catalogue, forcing, s) = fig13_basin_inputs();
    let bs = s.basin_settings(9).unwrap();
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

/// `refine` gives what `basins` gives on the refined grid, cell for cell (attractor and
/// periods), while integrating only the cells the coarse grid does not have.
#[test]
fn refined_basins_equal_the_refined_grid_and_reuse_the_coarse_cells() {
    let (h, catalogue, forcing, s) = fig13_basin_inputs();
    let coarse_settings = s.basin_settings(5).unwrap();
    let coarse = basins(&h, &forcing, &catalogue, &coarse_settings, &|| {}).unwrap();
    let direct = basins(
        &h,
        &forcing,
        &catalogue,
        &s.basin_settings(9).unwrap(),
        &|| {},
    )
    .unwrap();
    let integrated = std::sync::atomic::AtomicUsize::new(0);
    let count = || {
        integrated.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    };
    let refined = refine(&h, &forcing, &catalogue, &coarse_settings, &coarse, &count).unwrap();
    assert_eq!(refined.cells, direct.cells);
    assert_eq!(refined.labels, direct.labels);
    assert_eq!(refined.attractor, direct.attractor);
    assert_eq!(refined.periods, direct.periods);
    assert_eq!(
        integrated.into_inner(),
        9 * 9 - 5 * 5,
        "only the new cells integrated"
    );
    assert!(refined.stats.accepted < direct.stats.accepted);
    // Coarse basins of another grid are refused with a named error.
    let other = s.basin_settings(7).unwrap();
    let err = refine(&h, &forcing, &catalogue, &other, &coarse, &|| {}).unwrap_err();
    assert!(err.to_string().contains("refine"), "{err}");
    // So is an empty grid (no refined grid exists).
    let mut empty = coarse_settings;
    empty.grid.nx = 0;
    let err = refine(&h, &forcing, &catalogue, &empty, &coarse, &|| {}).unwrap_err();
    assert!(err.to_string().contains("empty"), "{err}");
}
