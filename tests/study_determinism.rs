//! The sensitivity study gives the same evaluations and indices on one thread and on two, and
//! in pieces (one point or one start at a time, as the tasks of a cluster) as in one call
//! (a tiny design: prototype 2, two base rows, twenty points).

use endstop::device::Device;
use endstop::num::minimax::MinimaxSettings;
use endstop::num::sensitivity::Bootstrap;
use endstop::paper::claims::Claims;
use endstop::paper::deviations::RangesFile;
use endstop::paper::deviations::{
    calibrate, calibrate_start, calibration_of_fits, calibration_starts, evaluate_at, sobol,
    sobol_indices, Prototype, Scope, SobolDesign, SobolRun,
};

fn p2() -> Device {
    Device::from_toml_str(include_str!("../data/prototype2.toml"), "test").unwrap()
}

fn design() -> SobolDesign {
    SobolDesign {
        factors: 8,
        base_rows: 2,
        seed: 13,
        bootstrap: Bootstrap {
            resamples: 50,
            level: 0.95,
            seed: 13,
        },
        scope: Scope::default(),
    }
}

/// The study in one call, on `threads` threads.
fn run(threads: usize) -> SobolRun {
    let claims = Claims::bundled().unwrap();
    let ranges = RangesFile::bundled().unwrap();
    let (p2, design) = (p2(), design());
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(|| {
            sobol(
                Prototype::P2,
                &ranges.prototype2,
                &p2,
                design,
                &claims,
                &|| {},
            )
        })
        .unwrap()
}

/// The study in pieces: every point evaluated on its own, in turn, then the indices.
fn pieces() -> SobolRun {
    let claims = Claims::bundled().unwrap();
    let ranges = RangesFile::bundled().unwrap();
    let (p2, design) = (p2(), design());
    let evaluations = design
        .design()
        .unwrap()
        .points()
        .iter()
        .map(|u| {
            evaluate_at(
                Prototype::P2,
                &ranges.prototype2,
                &p2,
                u,
                &claims,
                design.scope,
            )
        })
        .collect::<Result<Vec<_>, _>>()
        .unwrap();
    sobol_indices(Prototype::P2, design, evaluations).unwrap()
}

#[test]
fn sobol_study_is_identical_on_one_and_two_threads_and_in_pieces() {
    let one = pieces();
    let two = run(2);
    // Bitwise: every point is computed by the same sequence of operations whatever the
    // thread (or process) that runs it, and results are collected in design order.
    assert_eq!(one, two);
}

#[test]
fn calibration_in_pieces_is_the_calibration() {
    // Prototype 2 without ensembles: the objective is Table 3 (analytic), so the searches
    // are cheap; the published start and one Sobol start, a few iterations each.
    let claims = Claims::bundled().unwrap();
    let ranges = RangesFile::bundled().unwrap();
    let p2 = p2();
    let r = &ranges.prototype2;
    let settings = MinimaxSettings {
        starts: 1,
        max_iters: 5,
        seed: 13,
        ..MinimaxSettings::default()
    };
    let scope = Scope::default();
    let whole = calibrate(Prototype::P2, r, &p2, settings, &claims, scope, &|| {}).unwrap();
    let starts = calibration_starts(r, &p2, settings).unwrap();
    assert_eq!(starts.len(), 2);
    // The starts in reverse order: the result must not depend on the order they arrive in.
    let fits = (0..starts.len())
        .rev()
        .map(|i| calibrate_start(Prototype::P2, r, &p2, settings, &claims, scope, i).unwrap())
        .collect();
    let parts = calibration_of_fits(Prototype::P2, r, &p2, &claims, scope, fits).unwrap();
    assert_eq!(whole, parts);
    assert!(calibrate_start(Prototype::P2, r, &p2, settings, &claims, scope, 2).is_err());
}
