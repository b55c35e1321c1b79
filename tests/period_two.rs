//! Orbits of two drive periods born at a period doubling (`study::orbit::Shooter::
//! period_doubled`), against the stepped sweep that settles on them.

use endstop::device::Device;
use endstop::ode::Stats;
use endstop::physics::harvester::Harvester;
use endstop::progress::Silent;
use endstop::study::orbit::{flip_vector, Forcing, Parameter, Shooter, ShootingOptions};
use endstop::study::sweep::{SweepSettings, REFINE_TOL_HZ};
use nalgebra::{SMatrix, SVector};

/// A one-stop impact oscillator (1 g, 32 Hz, Q = 50, a rigid stop 1 mm above rest,
/// restitution 0.8) with a weakly coupled piezoelectric transducer on its load (coupling
/// factor theta^2 / (k Cp) = 5e-5, so that the mechanics are those of the bare oscillator):
/// driven at 10 g its one-impact orbit loses stability by a period doubling near 36.6 Hz, and
/// the period-two orbit born there is stable below it.
const BOUNCER: &str = "name = \"bouncer\"\nparams = \"test\"\ndescription = \"one rigid stop\"\n\
    [mechanics]\nmass_kg = 1e-3\nstiffness_n_per_m = 40.0\ndamping_n_s_per_m = 4e-3\n\
    [stops.upper]\ngap_m = 1e-3\nlaw = \"restitution\"\ncoefficient = 0.8\n\
    [transducer]\nkind = \"piezoelectric\"\ncoupling_n_per_v = 1e-5\n\
    capacitance_f = 50e-9\nload_resistance_ohm = 1e5\n";

const ACCEL_RMS_G: f64 = 10.0;

/// The period-two orbit seeded from the flip-unstable period-one orbit at 36.5 Hz equals the
/// orbit a down-sweep settles on there: stable, two impacts in its two periods, split from
/// the period-one orbit, with the sweep's RMS voltage.
#[test]
fn period_two_orbit_from_the_flip_matches_the_stepped_sweep() {
    let device = Device::from_toml_str(BOUNCER, "bouncer.toml").unwrap();
    let grid = vec![38.0, 37.5, 37.0, 36.5];
    let settings = SweepSettings::for_device(&device, grid, REFINE_TOL_HZ);
    // Blocks of an even number of periods: a block's RMS of a period-two orbit is its RMS.
    assert_eq!(settings.cfg.block_periods % 2, 0);
    let sweep = settings
        .run_down(&device, ACCEL_RMS_G, &Silent)
        .unwrap()
        .sweep;
    let (f, last) = (sweep.values[3], &sweep.steps[3]);
    assert_eq!(f, 36.5);
    assert!(last.measurement.converged);

    let h = Harvester::<4>::new(&device).unwrap();
    let shooter = Shooter::new(&h, ShootingOptions::default());
    let forcing = Forcing {
        freq_hz: f,
        accel_rms_g: ACCEL_RMS_G,
    };
    let mut stats = Stats::default();
    // The period-one orbit, from the sweep's state a step before (still on it there).
    let y37 = SVector::<f64, 4>::from_column_slice(sweep.steps[2].state.as_slice());
    let one = shooter
        .solve(&forcing, Parameter::Frequency, 0.0, y37, &mut stats)
        .unwrap();
    assert!(one.is_flip_unstable(), "{:?}", one.multipliers);

    // The flip eigenvector is one: M v = mu v (the inverse iteration's residual is of the order
    // of its shift, 1e-8 mu, times the ratio of the other multipliers to this one).
    let v = flip_vector::<4>(&one).unwrap();
    let m: SMatrix<f64, 4, 4> = one.monodromy_n();
    let mu = one.multipliers[0].re;
    assert!(
        (m * v - v * mu).norm() < 1e-6,
        "{:e}",
        (m * v - v * mu).norm()
    );

    let two = shooter
        .period_doubled(&one, &forcing, Parameter::Frequency, &mut stats)
        .unwrap();
    assert_eq!(two.periods, 2);
    assert!(two.is_stable(), "{:?}", two.multipliers);
    assert_eq!(two.summary.impacts, 2);
    let split = shooter
        .one_period_split(&two, Parameter::Frequency)
        .unwrap();
    assert!(split > 1e-2, "one period moves it by {split:e} only");

    // The sweep's RMS is that of its last block, accepted when it differs from the block
    // before by less than the steady-state criterion (relative): the residual transient is
    // below that, and the sweep's integrator (rtol 1e-8) and the orbit's (1e-10) add far
    // less. So the two agree to the criterion.
    let swept = last.measurement.v1_rms_v;
    let shot = two.summary.v1_rms_v;
    let rel = (shot / swept - 1.0).abs();
    eprintln!("36.5 Hz: period-two orbit {shot:.7e} V, stepped sweep {swept:.7e} V ({rel:.1e})");
    assert!(rel < settings.cfg.rel_change_tol, "{rel:e}");
    // The period-one orbit is far from it: the check tells the two apart.
    assert!((one.summary.v1_rms_v / swept - 1.0).abs() > 10.0 * settings.cfg.rel_change_tol);
}
