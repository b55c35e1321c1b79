//! Basins on nonlinear suspensions: the attractors found by settling seeds
//! (`endstop::study::attractors`) and placed by well, and the basins they give.

use endstop::device::Device;
use endstop::physics::harvester::Harvester;
use endstop::progress::Silent;
use endstop::study::attractors::{find_attractors, seeds, AttractorSearch, Attractors, Place};
use endstop::study::basins::{basins, BasinGrid, BasinSettings};
use endstop::study::continuation::frequency_branch;
use endstop::study::orbit::{Forcing, Shooter, ShootingOptions};

fn example(name: &str) -> Device {
    let path = format!("{}/data/examples/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap();
    Device::from_toml_str(&text, &path).unwrap()
}

/// The attractors of `device` under `forcing` from its wells at rest and 3 x 3 states over
/// `grid`, with the default search.
fn search(device: &Device, forcing: &Forcing, grid: &BasinGrid) -> Attractors {
    let h = Harvester::<4>::new(device).unwrap();
    find_attractors(
        &h,
        device,
        forcing,
        ShootingOptions::default(),
        &seeds(device, grid, 3),
        &AttractorSearch::default(),
    )
    .unwrap()
}

/// A bistable device under a weak drive (0.05 g rms at 30 Hz, below the wells' 40 Hz, far
/// too weak to carry the mass over the barrier from a well's bottom): every attractor is
/// intra-well, each well has its own (a softening well below its resonance keeps a small and
/// a large orbit, mirror images of the other well's), the cell at each well's bottom at rest
/// ends on an orbit of its own well, every attractor's basin is nonempty, and every cell of
/// the grid is reported.
#[test]
fn each_well_keeps_its_orbit_and_its_bottom_at_low_drive() {
    let device = example("bistable_stops_em");
    let forcing = Forcing {
        freq_hz: 30.0,
        accel_rms_g: 0.05,
    };
    let h = Harvester::<4>::new(&device).unwrap();
    // Positions in steps of 250 um from -750 to 750 um (the wells at +-500 um are cells);
    // velocities with v = 0 a cell.
    let grid = BasinGrid {
        x_m: (-7.5e-4, 7.5e-4),
        v_m_per_s: (-0.1, 0.1),
        nx: 7,
        nv: 5,
    };
    let found = search(&device, &forcing, &grid);
    let places: Vec<Place> = found.found.iter().map(|f| f.place).collect();
    let left = places.iter().filter(|p| **p == Place::LeftWell).count();
    let right = places.iter().filter(|p| **p == Place::RightWell).count();
    assert!(left > 0 && left == right, "{places:?}");
    assert_eq!(
        left + right,
        places.len(),
        "an attractor is not intra-well: {places:?}"
    );
    // Mirror pairs (the device is symmetric): the k-th orbit of each well by amplitude has
    // the same amplitude and power, to the orbits' accuracy (1e-6 relative is far above it).
    for k in 0..left {
        let (l, r) = (
            &found.found[k].orbit.summary,
            &found.found[left + k].orbit.summary,
        );
        assert!((l.x_max_m / r.x_max_m - 1.0).abs() < 1e-6, "{l:?} {r:?}");
        assert!(
            (l.p_total_w / r.p_total_w - 1.0).abs() < 1e-6,
            "{l:?} {r:?}"
        );
    }
    assert_eq!(found.seeds, 2 + 9);
    assert_eq!(
        found.found.len() + found.repeats + found.unstable + found.not_converged,
        found.seeds,
        "every seed is accounted for"
    );
    for f in &found.found {
        assert!(f.orbit.is_stable());
        let s = &f.orbit.summary;
        // In its well: the orbit never reaches the barrier at x = 0.
        match f.place {
            Place::LeftWell => assert!(s.x_upper_m < 0.0, "{s:?}"),
            _ => assert!(s.x_lower_m > 0.0, "{s:?}"),
        }
    }
    let settings = BasinSettings {
        grid,
        max_periods: 1000,
        settle_tol: 1e-3,
        rtol: 1e-10,
    };
    let b = basins(&h, &forcing, &found.catalogue(), &settings, &|| {}).unwrap();
    assert_eq!(b.cells.len(), 35);
    assert_eq!(b.attractor.len(), 35);
    assert_eq!(b.periods.len(), 35);
    let total: f64 = b.shares().iter().map(|s| s.1).sum();
    assert!((total - 1.0).abs() < 1e-12, "shares sum to {total}");
    let cell = |x: f64, v: f64| {
        b.cells
            .iter()
            .position(|c| (c.0 - x).abs() < 1e-12 && c.1 == v)
            .unwrap()
    };
    let place = |i: usize| b.attractor[i].map(|k| found.found[k].place);
    assert_eq!(place(cell(-5e-4, 0.0)), Some(Place::LeftWell));
    assert_eq!(place(cell(5e-4, 0.0)), Some(Place::RightWell));
    for (label, share) in &b.shares()[..found.found.len()] {
        assert!(*share > 0.0, "{label} has an empty basin");
    }
}

/// Between the folds of the hardening example (0.1 g rms; its response's folds lie near 104.7
/// and 114.0 Hz), the search from rest and a few seeds finds two stable orbits, a small and a
/// large one, which are the stable orbits of the continued branch at that frequency.
#[test]
fn the_hardening_device_has_the_branch_s_two_stable_orbits_between_its_folds() {
    let device = example("hardening_em");
    let forcing = Forcing {
        freq_hz: 110.0,
        accel_rms_g: 0.1,
    };
    let grid = BasinGrid {
        x_m: (-4e-4, 4e-4),
        v_m_per_s: (-0.25, 0.25),
        nx: 3,
        nv: 3,
    };
    let found = search(&device, &forcing, &grid);
    let labels: Vec<&str> = found.found.iter().map(|f| f.label.as_str()).collect();
    assert_eq!(labels, ["orbit, small", "orbit, large"], "{found:?}");
    let (small, large) = (&found.found[0].orbit, &found.found[1].orbit);
    assert!(large.summary.x_max_m > 2.0 * small.summary.x_max_m);
    // The continuation's stable orbits at 110 Hz are the same two (the states at drive phase
    // zero agree to 1e-6 scaled, far above the orbits' accuracy of about 1e-9 and far below
    // their distance).
    let branch = frequency_branch(&device, 0.1, 80.0, 140.0, 1.0, &Silent).unwrap();
    let start = Harvester::<4>::new(&device).unwrap();
    let shooter = Shooter::new(&start, ShootingOptions::default());
    let mut stats = Default::default();
    let stable: Vec<_> = branch
        .orbits_at(&shooter, 110.0, &mut stats)
        .unwrap()
        .into_iter()
        .filter(|o| o.is_stable())
        .collect();
    assert_eq!(stable.len(), 2);
    for f in &found.found {
        let near = stable.iter().any(|o| {
            let y = shooter.state_at_phase(o, 0.0).unwrap();
            shooter.norm(&(y - f.orbit.state_n::<4>())) < 1e-6
        });
        assert!(near, "{} is not an orbit of the branch", f.label);
    }
}
