//! The cost of a record behind an interface circuit against the same record on a resistive
//! load: the cantilever of `data/examples/piezo_bridge.toml` behind each interface of the
//! interfaces chapter (its full bridge, parallel and series SSHI, SECE:
//! `endstop_experiments::reports::interfaces_io::variants`), and
//! `data/examples/piezo_cantilever.toml` on its resistor, each a 10 s
//! record of the same noise after a 1 s pre-roll, by the records' default scheme: the
//! resistive free flight by the exponential step, the interface's linear modes propagated
//! exactly with the intervals where a conduction or switch event may fall handed to
//! Dormand-Prince (`endstop::study::record`, its affine modes).
//! The runs alternate (resistive, then each interface, then again) so that a drift of the
//! machine's speed shifts each round's runs alike; the table gives each one's median
//! processor time and the median of the per-round ratios with their range.

use anyhow::Result;
use endstop::device::Interface;
use endstop::drive::noise::NoiseSpec;
use endstop::study::record::{simulate_record, storage_record, RecordSpec, Scheme, DEFAULT_RTOL};
use endstop_experiments as common;

use common::fmt_sig;
use common::reports::interfaces_io::{variants, SECE_EFFICIENCY, SSHI_Q};

use crate::examples::{cpu, median};

/// Seed of the records.
const SEED: u64 = 2012;

/// The level of the records (g^2/Hz): the example cantilever's.
const PSD_G2_PER_HZ: f64 = 1e-4;

/// One interface's runs against the resistive ones of the same rounds.
pub struct InterfaceCost {
    /// The interface.
    pub name: &'static str,
    /// Its runs' processor times (s): median, smallest, largest.
    pub times_s: (f64, f64, f64),
    /// Per-round ratios to the resistive run: median, smallest, largest.
    pub ratios: (f64, f64, f64),
}

/// The resistive runs and each interface's.
pub struct Costs {
    /// The resistive runs' processor times (s): median, smallest, largest.
    pub resistive_s: (f64, f64, f64),
    /// Each interface.
    pub interfaces: Vec<InterfaceCost>,
}

fn spec() -> RecordSpec {
    RecordSpec {
        noise: NoiseSpec {
            duration_s: 10.0,
            ..endstop::paper::setups::paper_noise(PSD_G2_PER_HZ)
        },
        transient_s: 1.0,
        rtol: DEFAULT_RTOL,
        scheme: Scheme::Exponential,
    }
}

/// Runs `rounds` alternated rounds on the calling thread.
pub fn measure(rounds: usize) -> Result<Costs> {
    let bridge = common::load_device("examples/piezo_bridge")?.device;
    let resistive = common::load_device("examples/piezo_cantilever")?.device;
    if !matches!(bridge.interface, Interface::FullBridge(_)) {
        anyhow::bail!("examples/piezo_bridge.toml: expected a full bridge");
    }
    let variants = variants(&bridge);
    let spec = spec();
    let mut resistive_s = Vec::new();
    let mut per: Vec<(Vec<f64>, Vec<f64>)> = vec![(Vec::new(), Vec::new()); variants.len()];
    for _ in 0..rounds {
        let (_, base) = cpu(|| Ok(simulate_record(&resistive, &spec, SEED, 0)?))?;
        resistive_s.push(base);
        for ((_, d), (times, ratios)) in variants.iter().zip(per.iter_mut()) {
            let (_, t) = cpu(|| Ok(storage_record(d, &spec, SEED, 0)?))?;
            times.push(t);
            ratios.push(t / base);
        }
    }
    let interfaces = variants
        .iter()
        .zip(per)
        .map(|((name, _), (times_s, ratios))| InterfaceCost {
            name,
            times_s: median(times_s),
            ratios: median(ratios),
        })
        .collect();
    Ok(Costs {
        resistive_s: median(resistive_s),
        interfaces,
    })
}

/// The book's table of `costs` over `rounds` rounds.
pub fn table(costs: &Costs, rounds: usize) -> String {
    let mut md = format!(
        "Processor time of a 10 s record (1 s pre-roll, Sa = {PSD_G2_PER_HZ:e} g^2/Hz, seed \
         {SEED}, stream 0) on one thread, median of {rounds} alternated rounds (resistive, \
         then each interface, then again; SSHI with Q = {SSHI_Q}, SECE with an efficiency of \
         {SECE_EFFICIENCY}), \
         measured by the whole benchmark (`just \
         bench`) at commit `{}`. The ratio is taken within each round. Each record runs its \
         default scheme: the resistive free flight by the exponential step, the interface's \
         linear modes propagated exactly, with the intervals where an event may fall handed to \
         Dormand-Prince.\n\n\
         | record | median processor time (s) | median ratio to the resistive (range) |\n\
         |---|---|---|\n",
        common::git_commit()
    );
    md.push_str(&format!(
        "| `piezo_cantilever` on its resistor (exponential free flight) | {} | 1 |\n",
        fmt_sig(costs.resistive_s.0, 3)
    ));
    for c in &costs.interfaces {
        md.push_str(&format!(
            "| `piezo_bridge`, {} (exact linear modes) | {} | {} ({} to {}) |\n",
            c.name,
            fmt_sig(c.times_s.0, 3),
            fmt_sig(c.ratios.0, 3),
            fmt_sig(c.ratios.1, 3),
            fmt_sig(c.ratios.2, 3),
        ));
    }
    md
}
