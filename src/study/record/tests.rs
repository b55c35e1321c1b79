//! The one record engine against the engine it replaced, on devices with their own loads.

use super::*;
use crate::paper::setups::{paper_noise, prototype1_setup, prototype2_setup};
use crate::physics::harvester::Harvester;

fn load(rel: &str) -> Device {
    let root = env!("CARGO_MANIFEST_DIR");
    let text = std::fs::read_to_string(format!("{root}/{rel}")).unwrap();
    Device::from_toml_str(&text, rel).unwrap()
}

/// FNV-1a over the little-endian bytes of each value's bits.
fn hash(v: &[f64]) -> u64 {
    let mut h: u64 = 0xcbf29ce484222325;
    for x in v {
        for b in x.to_bits().to_le_bytes() {
            h ^= b as u64;
            h = h.wrapping_mul(0x100000001b3);
        }
    }
    h
}

/// Records of 50 ms (seed 2012, stream 3, the pre-roll the device's own or 50 ms if shorter)
/// give the same bits as the record engine before the model abstraction: repository
/// `endstop`, commit 54fdb70 (`study::record` over that commit's loaded model, `Harvester<E>`), its
/// `simulate_record` run on the same specs, with the sampled outputs hashed as [`hash`] does
/// and `p1_w` printed as bits. The exponential Adams step, the stop check and the
/// Dormand-Prince intervals are the same operations in the same order, so a change of the
/// step's arithmetic shows here (regrouping the input terms of the step fails it); a last-bit
/// change of the pair's small remainder does not (two regroupings of it were tried: its
/// contribution is below the state's resolution). The devices are those whose path that
/// commit's engine fixes: the paper's pair on both prototypes (nonlinear flights; prototype 1
/// strikes its stops 19 times). A linear flight takes another path now (see
/// [`linear_flights_keep_the_old_engines_accuracy`]).
#[test]
fn loaded_records_are_the_old_engines_bit_for_bit() {
    let p1 = prototype1_setup(&load("data/prototype1.toml"));
    let p2 = prototype2_setup(&load("data/prototype2.toml"));
    let cases = [
        (
            "p2",
            p2,
            1.69e-3,
            0x56bde3efc7a04726u64,
            0x15f6cd9b98a49847u64,
            0x3e3b475f2aad8aecu64,
        ),
        (
            "p1",
            p1,
            2.85e-2,
            0x5518d9ec4899b09c,
            0x37f3d982194d03e1,
            0x3e659de5225fb94c,
        ),
    ];
    for (name, device, psd, v1, v2, p1_bits) in cases {
        let r = simulate_record(
            &device,
            &short_spec(&device, psd, Scheme::Exponential),
            2012,
            3,
        )
        .unwrap();
        assert_eq!(r.summary.free_flight, FreeFlightPath::Exponential, "{name}");
        assert_eq!(hash(&r.v1_v), v1, "{name}: v1");
        assert_eq!(hash(&r.v2_v), v2, "{name}: v2");
        assert_eq!(r.summary.p1_w.to_bits(), p1_bits, "{name}: p1");
    }
}

/// The spec of [`loaded_records_are_the_old_engines_bit_for_bit`]: 50 ms at level `psd`.
fn short_spec(device: &Device, psd: f64, scheme: Scheme) -> RecordSpec {
    RecordSpec {
        noise: NoiseSpec {
            duration_s: 0.05,
            ..paper_noise(psd)
        },
        transient_s: transient_s(device).min(0.05),
        rtol: DEFAULT_RTOL,
        scheme,
    }
}

/// Linear flights (a coil on Hertzian stops, struck once in the record of
/// [`loaded_records_are_the_old_engines_bit_for_bit`], and a linear piezoelectric cantilever)
/// are propagated exactly now, one propagator product per interval with no remainder history
/// to refill after a contact, where the engine of commit 54fdb70 took the exponential step and
/// handed the intervals after a contact to Dormand-Prince. Both are approximations of one
/// trajectory, so the check is against the Dormand-Prince reference at a tolerance 1e-4 times
/// tighter: the new record's `p1_w` is no further from it than the old engine's `p1_w` (its
/// bits recorded from that commit as above) is, or within `50 * DEFAULT_RTOL` relative if that
/// is larger, and its `v1` within `50 * DEFAULT_RTOL` of its largest value (the reference's
/// own steps are controlled to `1e-4 * DEFAULT_RTOL`; 50 allows for the error growing over
/// the record's thousands of steps).
#[test]
fn linear_flights_keep_the_old_engines_accuracy() {
    let cases = [
        (
            "hertz_em",
            "data/validation/random_hertz_em.toml",
            0x3f0c6fb67f9e37eeu64,
        ),
        (
            "lin_piezo",
            "data/validation/random_linear_piezo.toml",
            0x3efb72e6adb2abec,
        ),
    ];
    for (name, path, old_bits) in cases {
        linear_flight_case(name, &load(path), f64::from_bits(old_bits));
    }
}

/// One case of [`linear_flights_keep_the_old_engines_accuracy`] at level 1e-3 g²/Hz.
fn linear_flight_case(name: &str, device: &Device, old_p1: f64) {
    let psd = 1e-3;
    let new = simulate_record(
        device,
        &short_spec(device, psd, Scheme::Exponential),
        2012,
        3,
    )
    .unwrap();
    let mut tight = short_spec(device, psd, Scheme::Dopri5);
    tight.rtol = 1e-4 * DEFAULT_RTOL;
    let reference = simulate_record(device, &tight, 2012, 3).unwrap();
    assert_eq!(
        new.summary.free_flight,
        FreeFlightPath::Exponential,
        "{name}"
    );
    let p_ref = reference.summary.p1_w;
    let old_err = ((old_p1 - p_ref) / p_ref).abs();
    let new_err = ((new.summary.p1_w - p_ref) / p_ref).abs();
    let bound = old_err.max(50.0 * DEFAULT_RTOL);
    assert!(
        new_err <= bound,
        "{name}: p1: new {new_err:.3e} > bound {bound:.3e} (old {old_err:.3e})"
    );
    let scale = reference.v1_v.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let v_err = new
        .v1_v
        .iter()
        .zip(&reference.v1_v)
        .fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()))
        / scale;
    assert!(
        v_err <= 50.0 * DEFAULT_RTOL,
        "{name}: v1: {v_err:.3e} of its largest value"
    );
}

/// A device without a transducer between rigid restitution stops (1 kHz, zeta 0.005, +-10 um,
/// e = 0.6), as the bench's floor case.
const NO_TRANSDUCER: &str = "name = \"bare\"\nparams = \"hypothetical\"\n\
    description = \"an oscillator between restitution stops\"\n\
    [mechanics]\nmass_kg = 1e-3\nstiffness_n_per_m = 39478.4176\n\
    damping_n_s_per_m = 6.28318531e-2\n\
    [stops.both]\ngap_m = 10e-6\nlaw = \"restitution\"\ncoefficient = 0.6\n\
    [transducer]\nkind = \"none\"\n";

/// Runs a record of a model two ways: on `(x, v)` alone and on the whole state.
struct BothWays<'a> {
    model: &'a Harvester<4>,
    drive: &'a SampledDrive,
}

impl FlightVisitor<4> for BothWays<'_> {
    type Output = Option<(Record, Record)>;

    fn visit<R: Remainder<4>>(self, split: FlightSplit<4>, r: R) -> Self::Output {
        let dt = 1.0 / self.drive.sample_rate_hz;
        let whole = ExpFlight::new(self.model, dt, split, r).unwrap();
        let mech = whole.mechanical(self.model, false)?;
        let on_xv = run(self.model, self.drive, DEFAULT_RTOL, mech, &mut (), None);
        let on_all = run(self.model, self.drive, DEFAULT_RTOL, whole, &mut (), None);
        Some((on_xv.unwrap().0, on_all.unwrap().0))
    }

    fn refused(self, why: NoFlight) -> Self::Output {
        panic!("no flight split: {why:?}")
    }
}

/// A record without a transducer runs on `(x, v)` alone and is the whole-state record bit for
/// bit (the 2 x 2 products are the 4 x 4 ones less the products by the zeros the model holds),
/// impacts included: 0.2 s from rest under `-10 cos(2 pi 1000 t)` m/s^2 at 50 kHz, which
/// strikes the stops hundreds of times. A piezoelectric device keeps its whole state.
#[test]
fn a_record_without_a_transducer_runs_on_the_mechanical_state_alone() {
    let device = Device::from_toml_str(NO_TRANSDUCER, "bare").unwrap();
    let model = Harvester::<4>::new(&device).unwrap();
    let fs = 50e3;
    let w = 2.0 * std::f64::consts::PI * 1000.0 / fs;
    let drive = SampledDrive {
        accel: (0..=10_000).map(|k| -10.0 * (w * k as f64).cos()).collect(),
        sample_rate_hz: fs,
        transient_samples: 0,
    };
    let (on_xv, on_all) = model
        .flight(
            1.0 / fs,
            BothWays {
                model: &model,
                drive: &drive,
            },
        )
        .expect("a device without a transducer has the mechanical path");
    assert!(
        on_xv.summary.impacts > 100,
        "{} impacts",
        on_xv.summary.impacts
    );
    assert_eq!(on_xv, on_all);
    // The same oscillator and stops with a piezoelectric element on its load.
    let text = NO_TRANSDUCER.replace(
        "kind = \"none\"",
        "kind = \"piezoelectric\"\ncoupling_n_per_v = 5e-3\ncapacitance_f = 50e-9\n\
         load_resistance_ohm = 16e3",
    );
    let piezo = Device::from_toml_str(&text, "piezo").unwrap();
    let model = Harvester::<4>::new(&piezo).unwrap();
    let both = model.flight(
        1.0 / fs,
        BothWays {
            model: &model,
            drive: &drive,
        },
    );
    assert!(both.is_none(), "a piezoelectric device carries its voltage");
}

/// The energy of each analysed sample of a record, with the first analysed sample's state.
struct Energies<'m> {
    model: &'m crate::physics::harvester::masses::MassChain<6>,
    energies: Vec<f64>,
}

impl RecordObserver for Energies<'_> {
    fn sample(&mut self, y: &[f64], mode: Mode) {
        let y = nalgebra::SVector::<f64, 6>::from_column_slice(y);
        self.energies.push(self.model.stored_energy(mode, &y));
    }
}

/// Two undamped masses (1 g and 0.2 g on springs of 98.7 and 50.5 N/m to the frame) with
/// rigid stops of restitution 1 on both sides between them (0.1 mm), set moving by 50 ms of
/// a 50 Hz drive and then left free for 5 s: the record's exact steps carry the rebounds
/// (located on the exact solution inside the sample intervals; fewer than a tenth of them
/// are events of Dormand-Prince), and the energy at every sample stays the first analysed sample's. Each
/// exact step moves the energy, a quadratic form of the state, by at most a few tens of eps
/// of itself (the propagator's entries are exact to rounding); each rebound is located on a
/// series summed to rounding and its reset changes the energy by at most 32 eps (the two
/// masses' new velocities in six roundings each). The bound, 64 eps per interval and per
/// impact summed without cancellation, holds for both.
#[test]
fn rebounds_on_exact_steps_keep_the_energy_of_two_undamped_masses() {
    let stop = |side: &str| {
        format!(
            "[[stops]]\nmasses = [1, 0]\nside = \"{side}\"\ngap_m = 1e-4\nlaw = \"restitution\"\n\
             coefficient = 1.0\n"
        )
    };
    let text = format!(
        "name = \"pair\"\nparams = \"test\"\ndescription = \"two masses\"\n\
         [[masses]]\nname = \"a\"\nmass_kg = 1e-3\n[[masses]]\nname = \"b\"\nmass_kg = 2e-4\n\
         [[springs]]\nmasses = [0]\nstiffness_n_per_m = 98.7\n\
         [[springs]]\nmasses = [1]\nstiffness_n_per_m = 50.5\n{}{}\
         [transducer]\nkind = \"none\"\n",
        stop("upper"),
        stop("lower")
    );
    let device = Device::from_toml_str(&text, "pair.toml").unwrap();
    let model = crate::physics::harvester::masses::MassChain::<6>::new(&device).unwrap();
    let fs = 100e3;
    let (pulse, free) = (5_000usize, 500_000usize);
    let w = 2.0 * std::f64::consts::PI * 50.0 / fs;
    let accel: Vec<f64> = (0..pulse + free)
        .map(|k| {
            if k < pulse {
                100.0 * (w * k as f64).sin()
            } else {
                0.0
            }
        })
        .collect();
    let drive = SampledDrive {
        accel: accel.into(),
        sample_rate_hz: fs,
        transient_samples: pulse,
    };
    let mut seen = Energies {
        model: &model,
        energies: Vec::new(),
    };
    let (record, _) = drive_found(&device, &drive, 1e-10, Scheme::Exponential, &mut seen).unwrap();
    let s = record.summary;
    assert_eq!(s.free_flight, FreeFlightPath::Affine);
    assert!(s.impacts > 2000, "{} impacts", s.impacts);
    assert!(
        10 * s.stats.events < s.impacts,
        "{} of {} impacts on Dormand-Prince",
        s.stats.events,
        s.impacts
    );
    let e0 = seen.energies[0];
    let worst = seen
        .energies
        .iter()
        .fold(0.0f64, |m, e| m.max((e - e0).abs() / e0));
    let bound = 64.0 * (free as f64 + s.impacts as f64) * f64::EPSILON;
    println!(
        "{} impacts, {} on Dormand-Prince: energy {worst:.2e}, bound {bound:.2e}",
        s.impacts, s.stats.events
    );
    assert!(worst < bound, "energy drifts by {worst:e} > {bound:e}");
}
