//! The studies on devices of several masses: each mass's peaks in a steady state against the
//! linear chain's closed form, the per-mass column names, and the rigid stops of a mass file
//! found by `all_stops_rigid` (from the model's contacts, not the one-mass `[stops]`).

use endstop::device::Device;
use endstop::drive::Sine;
use endstop::model::Model;
use endstop::physics::harvester::masses::MassChain;
use endstop::physics::harvester::AssemblyError;
use endstop::study::continuation::all_stops_rigid;
use endstop::study::mass_peaks::MassPeaks;
use endstop::study::steady::{settle_and_measure, settle_settings};
use nalgebra::{Complex, SVector};

use crate::masses::{closed_form, linear_chain};

fn file(rel: &str) -> Device {
    let path = format!("{}/data/{rel}", env!("CARGO_MANIFEST_DIR"));
    Device::from_toml_str(&std::fs::read_to_string(&path).unwrap(), rel).unwrap()
}

#[test]
fn each_mass_peaks_are_the_closed_form_amplitudes_of_the_linear_chain() {
    let d = linear_chain();
    let h = MassChain::<6>::new(&d).unwrap();
    let idx = h.layout().masses.clone();
    let amplitude = 9.81;
    // Near the second mode (about 76 Hz), where the two masses' amplitudes differ by 19 % or
    // more (the closed form's ratios 1.19, 1.37, 0.69), far more than the tolerance below: a
    // peak read from the wrong mass is caught, and a velocity read for a displacement (w times
    // larger) too.
    for f_hz in [65.0, 70.0, 80.0] {
        let w = std::f64::consts::TAU * f_hz;
        let x = closed_form(w, amplitude);
        let mut y0 = SVector::<f64, 6>::zeros();
        for (k, &(ix, iv)) in idx.iter().enumerate() {
            y0[ix] = x[k].im;
            y0[iv] = (x[k] * Complex::new(0.0, w)).im;
        }
        let sine = Sine {
            amplitude_m_s2: amplitude,
            freq_hz: f_hz,
            phase_rad: 0.0,
        };
        // Started on the closed form's orbit: no block is needed to settle.
        let mut cfg = settle_settings(&d, f_hz);
        cfg.settle_blocks = 0;
        let (m, ..) = settle_and_measure(&h, sine, y0, h.mode_of(&y0), 1.0, &cfg).unwrap();
        let p = m.mass_peaks;
        assert_eq!(p.len, 2);
        // The first mass in the layout is the one whose `x_peak_m` the study reports, at the
        // same samples.
        assert_eq!(p.x_m[0], m.x_peak_m);
        let ratio = x[0].norm() / x[1].norm();
        assert!(
            !(0.85..1.15).contains(&ratio),
            "{f_hz} Hz: amplitudes too alike"
        );
        for (k, xk) in x.iter().take(2).enumerate() {
            let (xa, va) = (xk.norm(), w * xk.norm());
            // Sampled at the ends and midpoints of the steps, a peak is never above the
            // orbit's (1e-6: the integrator's rtol of 1e-8 over a block, with room), and
            // below it by at most 1 - cos(pi / s) for s samples a period: Dormand-Prince at
            // rtol 1e-8 takes more than 8 steps a period on a sinusoid (16 samples), so 2e-2.
            for (got, exact, what) in [(p.x_m[k], xa, "x"), (p.v_m_per_s[k], va, "v")] {
                assert!(
                    got <= exact * (1.0 + 1e-6) && got >= exact * (1.0 - 2e-2),
                    "{f_hz} Hz, mass {k}, {what}: {got:e} vs {exact:e}"
                );
            }
        }
    }
}

#[test]
fn per_mass_columns_name_each_mass_and_a_one_mass_model_has_none() {
    let up = file("examples/upconverter.toml");
    let h = MassChain::<6>::new(&up).unwrap();
    // The transducer's mass (the generator) comes first in the state, then the others.
    assert_eq!(
        MassPeaks::column_names(h.layout()),
        [
            "x_generator_peak_m",
            "v_generator_peak_m_per_s",
            "x_driver_peak_m",
            "v_driver_peak_m_per_s"
        ]
    );
    let one = file("examples/piezo_cantilever.toml");
    let names = endstop::with_harvester!(&one, |h| Ok::<_, AssemblyError>(
        MassPeaks::column_names(h.layout())
    ))
    .unwrap();
    assert!(names.is_empty());
    let peaks =
        endstop::with_harvester!(&one, |h| Ok::<_, AssemblyError>(MassPeaks::of(h.layout())))
            .unwrap();
    assert_eq!(peaks.len, 0);
}

#[test]
fn rigid_stops_of_a_mass_file_are_found_from_its_model() {
    // Two rigid stops between the primary and the particle.
    let damper = file("validation/impact_damper.toml");
    assert!(damper.stops.present().next().is_none(), "no one-mass stops");
    assert!(all_stops_rigid(&damper));
    // A rigid stop between the driver and the generator.
    assert!(all_stops_rigid(&file("examples/upconverter.toml")));
    // The one-sided spring of NLvib's example is compliant.
    assert!(!all_stops_rigid(&file("validation/nlvib_unilateral.toml")));
    // Without stops: none to be rigid.
    assert!(!all_stops_rigid(&damper.without_stops()));
    // One-mass files read as before.
    assert!(all_stops_rigid(&file("examples/rigid_restitution.toml")));
    assert!(!all_stops_rigid(&file("prototype1.toml")));
}

#[test]
fn the_impacting_diagram_refuses_stops_between_masses_by_name() {
    use endstop::progress::Silent;
    use endstop::study::continuation::impacting::{rigid_diagram, DiagramSettings};
    use endstop::study::continuation::ContinuationSettings;
    use endstop::study::orbit::{Forcing, OrbitError};
    let damper = file("validation/impact_damper.toml");
    let settings = ContinuationSettings::frequency(9.0, 11.0, 0.5);
    let start = Forcing {
        freq_hz: 9.0,
        accel_rms_g: 0.1,
    };
    match rigid_diagram(
        &damper,
        start,
        &settings,
        &DiagramSettings::default(),
        &Silent,
    ) {
        Err(OrbitError::Invalid(why)) => {
            assert!(
                why.contains("between `particle` and `primary`")
                    || why.contains("between `primary` and `particle`"),
                "{why}"
            );
        }
        Err(e) => panic!("expected a refusal naming the masses, got {e}"),
        Ok(_) => panic!("expected a refusal naming the masses, got a diagram"),
    }
}

#[test]
fn a_basin_slice_starts_its_masses_there_and_the_others_at_rest() {
    use endstop::progress::Silent;
    use endstop::study::basins::{basins_on, Attractor, BasinGrid, BasinSettings, Slice};
    use endstop::study::orbit::{Forcing, OrbitError};
    let d = linear_chain();
    let h = MassChain::<6>::new(&d).unwrap();
    let idx = h.layout().masses.clone();
    // The second mass's position and the first's velocity: exactly these two are set.
    let slice = Slice {
        x: idx[1].0,
        v: idx[0].1,
    };
    let y = slice.state(&h, 1e-3, 2e-2);
    for k in 0..6 {
        let want = if k == idx[1].0 {
            1e-3
        } else if k == idx[0].1 {
            2e-2
        } else {
            0.0
        };
        assert_eq!(y[k], want, "component {k}");
    }
    // A slice of two positions (or a component of no mass) is refused by name.
    let grid = BasinGrid {
        x_m: (0.0, 1e-3),
        v_m_per_s: (0.0, 0.0),
        nx: 2,
        nv: 1,
    };
    let settings = BasinSettings {
        grid,
        max_periods: 1,
        settle_tol: 1e-3,
        rtol: 1e-9,
    };
    let at_rest = Attractor {
        label: "rest".into(),
        state: nalgebra::DVector::zeros(6),
    };
    let forcing = Forcing {
        freq_hz: 70.0,
        accel_rms_g: 0.1,
    };
    let bad = Slice {
        x: idx[0].0,
        v: idx[1].0,
    };
    match basins_on(&h, &forcing, &[at_rest], &settings, bad, &Silent) {
        Err(OrbitError::Invalid(why)) => assert!(why.contains("slice"), "{why}"),
        other => panic!("expected the slice refused, got {other:?}"),
    }
}
