//! The one record engine against the engine it replaced, on devices with their own loads.

use super::*;
use crate::paper::setups::{paper_noise, prototype1_setup, prototype2_setup};

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
/// contribution is below the state's resolution). The devices: the paper's pair on both
/// prototypes (prototype 1 striking its stops 19 times), a coil on Hertzian stops that are
/// struck once, and a linear piezoelectric cantilever.
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
        (
            "hertz_em",
            load("data/validation/random_hertz_em.toml"),
            1e-3,
            0xcf23e73bc0ee11a7,
            0x600f98ab98233825,
            0x3f0c6fb67f9e37ee,
        ),
        (
            "lin_piezo",
            load("data/validation/random_linear_piezo.toml"),
            1e-3,
            0x509c3d030b72d710,
            0x600f98ab98233825,
            0x3efb72e6adb2abec,
        ),
    ];
    for (name, device, psd, v1, v2, p1_bits) in cases {
        let spec = RecordSpec {
            noise: NoiseSpec {
                duration_s: 0.05,
                ..paper_noise(psd)
            },
            transient_s: transient_s(&device).min(0.05),
            rtol: DEFAULT_RTOL,
            scheme: Scheme::Exponential,
        };
        let r = simulate_record(&device, &spec, 2012, 3).unwrap();
        assert_eq!(r.summary.free_flight, FreeFlightPath::Exponential, "{name}");
        assert_eq!(hash(&r.v1_v), v1, "{name}: v1");
        assert_eq!(hash(&r.v2_v), v2, "{name}: v2");
        assert_eq!(r.summary.p1_w.to_bits(), p1_bits, "{name}: p1");
    }
}
