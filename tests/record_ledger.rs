//! The energy balance of random-vibration records as they are integrated
//! (`endstop::study::record_ledger`): the exponential free-flight step closes it, and with
//! impacts the balance is set by Dormand-Prince in contact and tightens with its tolerance.
//!
//! The target is the Performance chapter's: the balance closed to 1e-6 of the sum of its
//! terms' magnitudes ([`Ledger::relative_residual`]). The records are the ones the
//! bench measures (seed 2012, stream 0, 10 s): about 0.3-1 s each.

use endstop::device::Device;
use endstop::model::Ledger;
use endstop::paper::setups::{paper_noise, paper_record, prototype2_setup};
use endstop::study::record::{simulate_record, RecordSpec, Scheme, DEFAULT_RTOL};
use endstop::study::record_ledger::{record_ledger, record_ledgers};

const SEED: u64 = 2012;
const TARGET: f64 = 1e-6;

use crate::common;
use common::device;

/// Prototype 2 as Figures 14 and 15 simulate it.
fn prototype2() -> Device {
    prototype2_setup(&common::prototype2())
}

fn ledger(dev: &Device, sa: f64, scheme: Scheme, rtol: f64) -> (Ledger, u64) {
    let mut spec = paper_record(dev, sa);
    spec.scheme = scheme;
    spec.rtol = rtol;
    let (rec, l) = record_ledger(dev, &spec, SEED, 0).unwrap();
    (l, rec.summary.impacts)
}

#[test]
fn the_ledger_observes_the_record_simulate_record_computes() {
    // Watching the integration must not change it: the same samples, bit for bit.
    let dev = prototype2();
    let spec = paper_record(&dev, 1.69e-3);
    let plain = simulate_record(&dev, &spec, SEED, 0).unwrap();
    let (watched, _) = record_ledger(&dev, &spec, SEED, 0).unwrap();
    assert_eq!(plain.v1_v, watched.v1_v);
    assert_eq!(plain.v2_v, watched.v2_v);
}

#[test]
fn the_exponential_step_closes_the_energy_balance_without_impacts() {
    // Impact-free records (the bench's accuracy records): all but the first samples are
    // exponential steps.
    for (name, dev, sa) in [
        ("prototype 2", prototype2(), 1e-4),
        ("prototype 1", device("prototype1"), 4.42e-6),
    ] {
        let (l, impacts) = ledger(&dev, sa, Scheme::Exponential, DEFAULT_RTOL);
        assert_eq!(impacts, 0, "{name}: the record must be impact-free");
        let r = l.relative_residual();
        assert!(r.abs() < TARGET, "{name}: relative residual {r:e}");
        // Not an empty ledger: the loads took energy and the drive put it in.
        assert!(
            l.loads() > 0.0 && l.excitation() > l.loads(),
            "{name}: {l:?}"
        );
    }
}

#[test]
fn with_impacts_the_balance_tightens_with_the_contact_tolerance() {
    // In and near contact the record is Dormand-Prince's; its energy error is first order in
    // rtol (as the augmented audit's is). At 100 times the default tolerance the residual
    // must fall at least tenfold and meet the target.
    for (name, dev, sa) in [
        ("prototype 2 (linear k_im)", prototype2(), 1.69e-3),
        ("prototype 1 (Hertz)", device("prototype1"), 2.85e-2),
    ] {
        let (default, impacts) = ledger(&dev, sa, Scheme::Exponential, DEFAULT_RTOL);
        let (tight, _) = ledger(&dev, sa, Scheme::Exponential, DEFAULT_RTOL / 100.0);
        assert!(impacts > 1000, "{name}: {impacts} impacts");
        let (a, b) = (default.relative_residual(), tight.relative_residual());
        assert!(
            b.abs() < 0.1 * a.abs(),
            "{name}: {a:e} at the default rtol, {b:e} at a hundredth of it"
        );
        assert!(
            b.abs() < TARGET,
            "{name}: {b:e} at a hundredth of the default rtol"
        );
    }
}

fn validation_device(name: &str) -> Device {
    let path = format!("{}/data/validation/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    Device::from_toml_str(&std::fs::read_to_string(&path).unwrap(), &path).unwrap()
}

#[test]
fn the_analysed_window_books_impacts_and_coil_losses_and_closes_its_own_balance() {
    // One second of the Validation chapter's records: rigid stops (impact losses booked at the
    // rebounds inside Dormand-Prince intervals) and Hertz stops with a coil (its resistance).
    use endstop::drive::noise::NoiseSpec;
    use endstop::study::record::transient_s;
    for name in ["random_restitution", "random_hertz_em"] {
        let dev = validation_device(name);
        let spec = RecordSpec {
            noise: NoiseSpec {
                duration_s: 1.0,
                ..paper_noise(1e-3)
            },
            transient_s: transient_s(&dev),
            rtol: DEFAULT_RTOL,
            scheme: Scheme::Exponential,
        };
        let (rec, books) = record_ledgers(&dev, &spec, SEED, 0).unwrap();
        let (_, whole) = record_ledger(&dev, &spec, SEED, 0).unwrap();
        assert_eq!(
            books.whole, whole,
            "{name}: the whole record's ledger is record_ledger's"
        );
        let w = books.analysed;
        assert!(
            rec.summary.impacts > 10,
            "{name}: {} impacts",
            rec.summary.impacts
        );
        // The window is part of the record: less drive work than the whole, but most of it.
        assert!(
            w.excitation() > 0.5 * whole.excitation() && w.excitation() < whole.excitation(),
            "{name}: {w:?} of {whole:?}"
        );
        assert_eq!(
            books.analysed_s,
            (rec.v1_v.len() - 1) as f64 / rec.sample_rate_hz
        );
        match name {
            "random_restitution" => assert!(w.impact_losses() > 0.0 && w.internal() == 0.0),
            _ => assert!(w.internal() > 0.0 && w.stop_damping() > 0.0 && w.impact_losses() == 0.0),
        }
        for (what, l) in [("whole", whole), ("window", w)] {
            let r = l.relative_residual();
            assert!(r.abs() < TARGET, "{name} {what}: relative residual {r:e}");
        }
    }
}
