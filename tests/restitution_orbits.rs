//! Periodic orbits that bounce off a rigid stop: the monodromy by the variational equations
//! with the reset's saltation matrix `D + (f+ - D f-) n^T / (n . f-)` (D the reset's Jacobian,
//! diag(1, -e, 1, 1)) equals central differences of the event-located period map, and the
//! unused state components of a one-load transducer contribute no multiplier of modulus one.

use endstop::device::Device;
use endstop::model::Model;
use endstop::ode::Stats;
use endstop::physics::harvester::Harvester;
use endstop::study::orbit::{Forcing, Parameter, Shooter, ShootingOptions};

/// A 1 g, 32 Hz suspension (Q about 200) with a rigid stop 1 mm above rest; `transducer` the
/// TOML of its transducer table.
fn bouncing(e: f64, transducer: &str) -> Device {
    let text = format!(
        "name = \"bouncer\"\nparams = \"test\"\ndescription = \"one rigid stop\"\n\
         [mechanics]\nmass_kg = 1e-3\nstiffness_n_per_m = 40.0\ndamping_n_s_per_m = 1e-3\n\
         [stops.upper]\ngap_m = 1e-3\nlaw = \"restitution\"\ncoefficient = {e}\n{transducer}\n"
    );
    Device::from_toml_str(&text, "bouncer.toml").unwrap()
}

const NONE: &str = "[transducer]\nkind = \"none\"";
const PIEZO: &str = "[transducer]\nkind = \"piezoelectric\"\ncoupling_n_per_v = 2e-4\n\
                     capacitance_f = 1e-8\nload_resistance_ohm = 2e5";

/// On a stable orbit that rebounds off the stop (below resonance, where the linear response
/// would be three gaps), the variational monodromy equals central differences at two step
/// sizes to 1e-5 of its largest entry (rtol 1e-12: the differences' truncation, eps^2, and
/// their rounding, rtol / eps, are both below 1e-6 there).
#[test]
fn the_monodromy_through_rebounds_equals_finite_differences() {
    for transducer in [NONE, PIEZO] {
        let d = bouncing(0.8, transducer);
        let forcing = Forcing {
            freq_hz: 28.0,
            accel_rms_g: 2.0,
        };
        let h = Harvester::<4>::new(&d).unwrap();
        let cfg = ShootingOptions {
            rtol: 1e-12,
            ..ShootingOptions::default()
        };
        let shooter = Shooter::new(&h, cfg);
        let mut stats = Stats::default();
        // Settle from rest for 40 periods, then shoot.
        let (y, _, _) = shooter
            .flow(
                &forcing,
                0.0,
                h.rest_state(),
                40.0 / forcing.freq_hz,
                |_, _| {},
            )
            .unwrap();
        let o = shooter
            .solve(&forcing, Parameter::Frequency, 0.0, y, &mut stats)
            .unwrap();
        let o = shooter
            .reanchor(&o, Parameter::Frequency, &mut stats)
            .unwrap();
        assert!(
            o.summary.impacts >= 1 && o.summary.contact_fraction == 0.0,
            "{}: rebounds only ({} impacts)",
            d.transducer.key(),
            o.summary.impacts
        );
        assert!(o.is_stable(), "{}: {:?}", d.transducer.key(), o.multipliers);
        let scale = o.monodromy.abs().max();
        for eps in [3e-5, 1e-5] {
            let fd = shooter
                .monodromy_fd(&o.forcing, o.phase_rad, o.state_n::<4>(), eps)
                .unwrap();
            let diff = (fd - o.monodromy_n::<4>()).abs().max() / scale;
            assert!(
                diff < 1e-5,
                "{} eps {eps:e}: max difference {diff:e} of {scale:e}",
                d.transducer.key()
            );
        }
        // The unused components (both for none, one for the piezoelectric transducer) show as
        // multipliers of modulus zero, never one.
        let unit = o
            .multipliers
            .iter()
            .filter(|m| (m.norm() - 1.0).abs() < 1e-6)
            .count();
        assert_eq!(unit, 0, "{}: {:?}", d.transducer.key(), o.multipliers);
        let zeros = o.multipliers.iter().filter(|m| m.norm() == 0.0).count();
        assert_eq!(zeros, h.unused().len(), "{:?}", o.multipliers);
    }
}
