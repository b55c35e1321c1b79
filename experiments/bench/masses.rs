//! The cost of a record of two masses against a record of one mass with about as many impacts:
//! the up-converter of `data/examples/upconverter.toml` (a driver striking a piezoelectric
//! generator through a rigid restitution stop) and its single-mass comparison
//! `data/upconversion/direct.toml` (the same total mass, element and impact, between rigid
//! stops), each a 10 s record of band-limited white noise after a 1 s pre-roll. The one-mass
//! record's level is chosen so that its impacts match the two-mass record's (the table shows
//! both counts): the cost of a record grows with its impacts, so the ratio compares the
//! propagation between them.
//!
//! Each record runs its default scheme: the one mass's linear free flight by the exponential
//! step with its rebounds located on the exact solution, the two masses' linear modes
//! propagated exactly (`endstop::study::record`, its affine modes) with the intervals where a
//! stop may be met handed to Dormand-Prince; beside them the two masses on Dormand-Prince
//! throughout (the adaptive reference). The runs alternate (one mass, two masses, two masses
//! adaptive, then again) so that a drift of the machine's speed shifts each round alike; the
//! ratios are taken within each round.

use anyhow::{Context, Result};
use endstop::study::record::{simulate_record, FreeFlightPath, RecordSpec, Scheme, DEFAULT_RTOL};
use endstop_experiments as common;

use common::fmt_sig;

use crate::examples::{cpu, median};

/// Seed of the records.
const SEED: u64 = 2012;

/// The two-mass record's level (g^2/Hz): the up-converter's driver strikes the generator
/// a few hundred times a second.
const TWO_MASS_PSD_G2_PER_HZ: f64 = 1e-3;

/// The one-mass record's level (g^2/Hz), chosen for the impact count of the two-mass record
/// (about 3300) by a scan of levels with `endstop random --records 1` (0.4: 2899 impacts,
/// 0.6: 3218, 1: 3813); the single mass's 0.5 mm stroke caps its impacts, so the level is
/// high. The table shows both counts.
const ONE_MASS_PSD_G2_PER_HZ: f64 = 0.6;

/// One record's runs.
pub struct RecordCost {
    /// What it is.
    pub name: String,
    /// Its level (g^2/Hz).
    pub psd_g2_per_hz: f64,
    /// Impacts in the record.
    pub impacts: u64,
    /// How its free flight went.
    pub path: String,
    /// Its runs' processor times (s): median, smallest, largest.
    pub times_s: (f64, f64, f64),
    /// Per-round ratios to the one-mass run: median, smallest, largest.
    pub ratios: (f64, f64, f64),
}

fn spec(psd: f64, scheme: Scheme) -> RecordSpec {
    RecordSpec {
        noise: endstop::drive::noise::NoiseSpec {
            duration_s: 10.0,
            ..endstop::paper::setups::paper_noise(psd)
        },
        transient_s: 1.0,
        rtol: DEFAULT_RTOL,
        scheme,
    }
}

fn path(p: &FreeFlightPath) -> String {
    match p {
        FreeFlightPath::Exponential => "exponential".into(),
        FreeFlightPath::Affine => "exact affine steps".into(),
        FreeFlightPath::Dopri5(why) => format!("Dormand-Prince: {why}"),
    }
}

/// Runs `rounds` alternated rounds on the calling thread: the one-mass record, the two-mass
/// record and the two-mass record on Dormand-Prince.
pub fn measure(rounds: usize) -> Result<Vec<RecordCost>> {
    let one = common::load_device("upconversion/direct")?.device;
    let two = common::load_device("examples/upconverter")?.device;
    let cases = [
        (
            "`upconversion/direct`, one mass",
            &one,
            ONE_MASS_PSD_G2_PER_HZ,
            Scheme::Exponential,
        ),
        (
            "`upconverter`, two masses",
            &two,
            TWO_MASS_PSD_G2_PER_HZ,
            Scheme::Exponential,
        ),
        (
            "`upconverter`, two masses, Dormand-Prince throughout",
            &two,
            TWO_MASS_PSD_G2_PER_HZ,
            Scheme::Dopri5,
        ),
    ];
    let mut times: Vec<Vec<f64>> = vec![Vec::new(); cases.len()];
    let mut ratios: Vec<Vec<f64>> = vec![Vec::new(); cases.len()];
    let mut last = vec![None; cases.len()];
    for _ in 0..rounds {
        let mut base = None;
        for (k, (_, device, psd, scheme)) in cases.iter().enumerate() {
            let (rec, t) = cpu(|| Ok(simulate_record(device, &spec(*psd, *scheme), SEED, 0)?))?;
            let base = *base.get_or_insert(t);
            times[k].push(t);
            ratios[k].push(t / base);
            last[k] = Some(rec.summary);
        }
    }
    cases
        .iter()
        .zip(times)
        .zip(ratios)
        .zip(last)
        .map(|((((name, _, psd, _), times), ratios), summary)| {
            let summary = summary.context("at least one round")?;
            Ok(RecordCost {
                name: name.to_string(),
                psd_g2_per_hz: *psd,
                impacts: summary.impacts,
                path: path(&summary.free_flight),
                times_s: median(times),
                ratios: median(ratios),
            })
        })
        .collect()
}

/// The book's table of `costs` over `rounds` rounds.
pub fn table(costs: &[RecordCost], rounds: usize) -> String {
    let mut md = format!(
        "Processor time of a 10 s record (1 s pre-roll, seed {SEED}, stream 0) on one thread, \
         median of {rounds} alternated rounds, measured by the whole benchmark (`just bench`) \
         at commit `{}`. The one-mass record's level is chosen for about the impacts of the \
         two-mass record; the ratio is taken within each round.\n\n\
         | record | Sa (g^2/Hz) | impacts | free flight | median processor time (s) | \
         median ratio to one mass (range) |\n|---|---|---|---|---|---|\n",
        common::git_commit()
    );
    for c in costs {
        md.push_str(&format!(
            "| {} | {:e} | {} | {} | {} | {} ({} to {}) |\n",
            c.name,
            c.psd_g2_per_hz,
            c.impacts,
            c.path,
            fmt_sig(c.times_s.0, 3),
            fmt_sig(c.ratios.0, 3),
            fmt_sig(c.ratios.1, 3),
            fmt_sig(c.ratios.2, 3),
        ));
    }
    md
}
