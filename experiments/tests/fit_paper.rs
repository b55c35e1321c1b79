//! The paper's own fit through the general fit: the measured quantities section 3.2 states for
//! Figure 8 (`data/measured/fig08_paper.csv`: the kink at 1135 Hz and the jump at 1425 Hz at
//! 5.5 g) fitted by `endstop::fit` from the published prototype 1, against the paper layer's
//! calibration (`endstop::paper::calibration::calibrate_prototype1`).

use std::path::Path;

use endstop::device::{Device, ParamRange};
use endstop::fit::{fit, Direction, FeatureKind, FitReport, FitSettings, SweepData};
use endstop::paper::calibration::calibrate_prototype1;
use endstop_experiments::reports::fit_csv::parse_sweep;

fn root() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
}

fn published() -> Device {
    let text = std::fs::read_to_string(root().join("data/prototype1.toml")).unwrap();
    Device::from_toml_str(&text, "prototype1").unwrap()
}

fn paper_data() -> SweepData {
    let file = "data/measured/fig08_paper.csv";
    let text = std::fs::read_to_string(root().join(file)).unwrap();
    parse_sweep(&text, file, Direction::Up).unwrap()
}

const GAP: &str = "stops.both.gap_m";

fn gap_range() -> ParamRange {
    // From well below the calibrated gap up to just below the finger overlap x0 = 10 um,
    // which the gap must not exceed.
    ParamRange::auto(GAP, 4e-6, 9.9e-6)
}

fn print(r: &FitReport) {
    for p in &r.params {
        eprintln!(
            "{}: {:e} +- {:e}, 95 % {:e} .. {:e}",
            p.path, p.value, p.std_err, p.interval.0, p.interval.1
        );
    }
    eprintln!(
        "evaluations {}, stop {:?}, model {}, starts {}, warnings {:?}",
        r.evaluations,
        r.stop,
        r.model,
        r.starts.len(),
        r.warnings
    );
}

#[test]
fn the_kink_alone_fits_the_gap_the_paper_layer_calibrates_within_its_interval() {
    // The kink is the impact onset, before which the stops exert no force: it fixes the gap
    // whatever b_im, as the paper layer's calibration does (a root find on the gap alone).
    let device = published();
    let mut data = paper_data();
    data.features.retain(|f| f.kind == FeatureKind::Onset);
    assert_eq!(data.features.len(), 1);
    let r = fit(&device, &[data], &[gap_range()], &FitSettings::default()).unwrap();
    print(&r);
    let calibrated = calibrate_prototype1(&device).unwrap().record.fitted_gap_m;
    eprintln!("paper layer's calibrated gap: {calibrated:e}");
    assert!(r.stop.converged(), "{:?}", r.stop);
    let p = &r.params[0];
    assert!(
        p.interval.0 <= calibrated && calibrated <= p.interval.1,
        "calibrated gap {calibrated:e} outside {:?}",
        p.interval
    );
}

#[test]
fn the_joint_fit_of_kink_and_jump_contains_the_calibrated_gap() {
    let device = published();
    let free = [
        gap_range(),
        ParamRange::auto("stops.both.damping_n_s_per_m", 0.1, 20.0),
    ];
    let r = fit(&device, &[paper_data()], &free, &FitSettings::default()).unwrap();
    print(&r);
    let calibrated = calibrate_prototype1(&device).unwrap().record.fitted_gap_m;
    eprintln!("paper layer's calibrated gap: {calibrated:e}; the paper's b_im: 1.5 N s/m");
    assert!(r.stop.converged(), "{:?}", r.stop);
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    let p = &r.params[0];
    assert!(
        p.interval.0 <= calibrated && calibrated <= p.interval.1,
        "calibrated gap {calibrated:e} outside {:?}",
        p.interval
    );
}
