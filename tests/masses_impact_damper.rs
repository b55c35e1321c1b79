//! The impact damper of Masri & Caughey (J. Appl. Mech. 33, 1966): our shooting's symmetric
//! two-impacts-per-cycle orbits, Floquet multipliers and stability boundary against the
//! closed form derived from their conditions (`endstop::validation::impact_damper`; the
//! tolerances and their reasons are stated there, before the runs).

use endstop::device::Device;
use endstop::validation::impact_damper::{checks, ImpactDamper};
use endstop::validation::Check;

const FILE: &str = include_str!("../data/validation/impact_damper.toml");

fn device() -> Device {
    Device::from_toml_str(FILE, "impact_damper.toml").unwrap()
}

fn assert_all(checks: &[Check]) {
    for c in checks {
        println!(
            "{}: theirs {:.12e}, ours {:.12e}, difference {:.2e} (tolerance {:.0e})",
            c.quantity,
            c.compared.reference,
            c.compared.ours,
            c.difference(),
            c.compared.tolerance
        );
    }
    for c in checks {
        assert!(c.passes(), "{}: {:?}", c.quantity, c.compared);
    }
}

#[test]
fn the_file_is_an_impact_damper_and_other_devices_are_not() {
    let d = ImpactDamper::of(&device()).unwrap();
    assert_eq!(
        (d.primary_kg, d.particle_kg, d.clearance_m, d.restitution),
        (0.1, 5e-3, 0.02, 0.6)
    );
    let up = Device::from_toml_str(
        include_str!("../data/examples/upconverter.toml"),
        "upconverter.toml",
    )
    .unwrap();
    assert!(ImpactDamper::of(&up).is_err());
}

/// Without damping the steady response to alternating impulses has Masri & Caughey's tangent:
/// `g = (Phi(T/2) + I)^-1 (0, 1) = (-tan(pi w_n / (2 w)) / (2 w_n), 1/2)`. The closed form
/// builds `Phi` from sines and cosines: 1e-12 relative is a few hundred roundings of the 2x2
/// solve away from tan's.
#[test]
fn the_undamped_flow_gives_the_alternating_impulses_tangent() {
    let mut d = ImpactDamper::of(&device()).unwrap();
    d.damping_n_s_per_m = 0.0;
    let wn = (d.stiffness_n_per_m / d.primary_kg).sqrt();
    for w in [0.7 * wn, 1.3 * wn, 2.1 * wn] {
        let half = std::f64::consts::PI / w;
        let g = (d.free_flow(half) + nalgebra::Matrix2::identity())
            .lu()
            .solve(&nalgebra::Vector2::new(0.0, 1.0))
            .unwrap();
        let tan = -(0.5 * wn * half).tan() / (2.0 * wn);
        assert!((g[0] / tan - 1.0).abs() < 1e-12, "{} vs {tan}", g[0]);
        assert!((g[1] - 0.5).abs() < 1e-12, "{}", g[1]);
    }
}

#[test]
fn shooting_finds_the_closed_form_orbits_and_multipliers() {
    let checks = checks::orbit_checks(&device()).unwrap();
    assert_eq!(checks.len(), 4 * checks::POINTS.len());
    assert_all(&checks);
}

#[test]
fn the_stability_boundary_is_where_the_closed_form_says() {
    let checks = checks::boundary_checks(&device()).unwrap();
    // The count and at least one boundary.
    assert!(checks.len() >= 2, "{} checks", checks.len());
    assert_all(&checks);
}
