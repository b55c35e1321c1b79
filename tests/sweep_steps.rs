//! Sweeps that answer the same whatever their step: on each example device of
//! `data/examples/`, the down-sweep at the default step (a quarter of the linear half-power
//! width), each step reached by a phase-continuous ramp, leaves the lower branch within the
//! refinement tolerance of the fold or grazing at which the continued orbits say that branch
//! ends, and moves by less than that tolerance when the step is divided by four.

use endstop::device::Device;
use endstop::model::Mode;
use endstop::progress::Silent;
use endstop::study::chirp::{default_ramp_rate_hz_per_s, default_step_hz, half_power_band};
use endstop::study::continuation::{frequency_diagram, DiagramEventKind};
use endstop::study::stepped::Approach;
use endstop::study::sweep::{SweepSettings, REFINE_TOL_HZ};

fn example(name: &str) -> Device {
    let path = format!("{}/data/examples/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap();
    Device::from_toml_str(&text, &path).unwrap()
}

/// The example, its drive (g rms) and range (Hz), as the book's "Model your own harvester"
/// chapter runs them.
const CASES: [(&str, f64, f64, f64); 3] = [
    ("piezo_cantilever", 0.5, 100.0, 200.0),
    ("em_asymmetric", 0.2, 44.0, 60.0),
    ("rigid_restitution", 0.3, 550.0, 750.0),
];

/// The down-sweep's end at the default step, against the continuation. The lower branch of
/// these devices ends at the highest fold or grazing below the upper fold (the end of the
/// impacting branch): below it no non-impacting orbit is left for the sweep to follow. The
/// sweep is run from six steps above that end to two below it, from the continued orbit of
/// the lower branch there, which is how the whole down-sweep arrives: on the lower branch,
/// one step at a time.
#[test]
fn the_down_sweep_leaves_the_lower_branch_at_its_end_at_the_default_step() {
    for (name, g, from, to) in CASES {
        let device = example(name);
        let band = half_power_band(&device).expect("a resonance");
        let step = default_step_hz(&device, from, to);
        assert!(step <= 0.25 * band.width_hz, "{name}: step {step} Hz");
        let rate = default_ramp_rate_hz_per_s(&device).unwrap();
        let d = frequency_diagram(&device, g, from, to, 0.01 * (to - from), &Silent).unwrap();
        let ends: Vec<f64> = d
            .events
            .iter()
            .filter(|e| matches!(e.kind, DiagramEventKind::Fold | DiagramEventKind::Grazing))
            .map(|e| e.param)
            .collect();
        let upper_fold = d
            .events_of(DiagramEventKind::Fold)
            .map(|e| e.param)
            .fold(f64::NEG_INFINITY, f64::max);
        let lower_end = ends
            .iter()
            .copied()
            .filter(|&f| f < upper_fold)
            .fold(f64::NEG_INFINITY, f64::max);
        assert!(lower_end > from, "{name}: no lower end ({ends:?})");
        // The lower branch's orbit six steps above its end (the stable orbit of smallest
        // amplitude there) starts the sweep.
        let target = lower_end + 6.0 * step;
        let first = d
            .branches
            .iter()
            .flat_map(|b| &b.points)
            .filter(|p| (p.forcing.freq_hz - target).abs() < step && p.is_stable())
            .min_by(|a, b| a.summary.x_max_m.total_cmp(&b.summary.x_max_m))
            .expect("a stable orbit above the lower end");
        let f0 = first.forcing.freq_hz;
        let n = ((f0 - (lower_end - 2.0 * step)) / step).ceil() as usize;
        let grid: Vec<f64> = (0..=n).map(|i| f0 - step * i as f64).collect();
        let settings = SweepSettings::for_device(&device, grid, REFINE_TOL_HZ);
        let down = settings
            .run_down_from(
                &device,
                g,
                Approach::Ramp { rate_per_s: rate },
                (first.fingerprint.clone(), Mode::FREE),
                &Silent,
            )
            .unwrap();
        let (kind, t) = down
            .branch_end()
            .expect("the down-sweep leaves the lower branch");
        eprintln!(
            "{name}: step {step} Hz, ramps at {rate:.3} Hz/s: leaves at {} Hz ({}), \
             the lower branch ends at {lower_end} Hz (events {ends:?})",
            t.value(),
            kind.label()
        );
        // The end computed above, not the nearest of all events: a sweep that left at another
        // fold or grazing (the upper fold, a grazing on the impacting branch) would be a sweep
        // that did not follow the lower branch to its end.
        assert!(
            (t.value() - lower_end).abs() <= REFINE_TOL_HZ,
            "{name}: leaves at {} Hz, the lower branch ends at {lower_end} Hz",
            t.value()
        );
        // The step's effect: the same end found again with a quarter of the step (a local
        // rerun around it) moves by less than the refinement tolerance.
        let (_, quarter) = settings
            .down_end_with_step_divided(&device, g, Approach::Ramp { rate_per_s: rate }, &down, 4.0)
            .unwrap()
            .expect("the end found again at a quarter of the step");
        eprintln!(
            "{name}: at a quarter of the step it leaves at {} Hz",
            quarter.value()
        );
        assert!(
            (quarter.value() - t.value()).abs() <= REFINE_TOL_HZ,
            "{name}: {} Hz at a quarter of the step vs {} Hz",
            quarter.value(),
            t.value()
        );
    }
}
