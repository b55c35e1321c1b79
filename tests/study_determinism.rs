//! The sensitivity study gives the same evaluations and indices on one thread and on two
//! (a tiny design: prototype 2, two base rows, twenty points).

use endstop::device::Device;
use endstop::num::sensitivity::Bootstrap;
use endstop::paper::claims::Claims;
use endstop::paper::sensitivity::RangesFile;
use endstop::paper::study::{sobol, Prototype, Scope, SobolDesign, SobolRun};

fn run(threads: usize) -> SobolRun {
    let claims = Claims::bundled().unwrap();
    let ranges = RangesFile::bundled().unwrap();
    let p2 = Device::from_toml_str(include_str!("../data/prototype2.toml"), "test").unwrap();
    let design = SobolDesign {
        base_rows: 2,
        seed: 13,
        bootstrap: Bootstrap {
            resamples: 50,
            level: 0.95,
            seed: 13,
        },
        scope: Scope::default(),
    };
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

#[test]
fn sobol_study_is_identical_on_one_and_two_threads() {
    let one = run(1);
    let two = run(2);
    // Bitwise: every point is computed by the same sequence of operations whatever the
    // thread that runs it, and results are collected in design order.
    assert_eq!(one, two);
}
