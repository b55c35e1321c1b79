//! Figure 12: output power PSDs of prototype 1 at 30 V (Hertz contact, b_im = 1.5 N s/m) at
//! Sa = 7.4e-3, 1.31e-2 and 2.85e-2 g²/Hz, where the mass hits the stops: the 3 dB bandwidth
//! grows with the input (claim F12), under the published and the calibrated parameter sets.

use endstop_experiments as common;

use endstop_experiments::broadband_io as bbio;

use anyhow::Result;
use bbio::{find, pm, sa_label, spread_str, Level};
use common::{fmt_sig, Experiment};
use endstop::num::stats::ratio_spread;
use endstop::paper::ensembles::P1_BAND_HZ;
use endstop::paper::ensembles::P1_NPERSEG;
use endstop::study::ensemble::DEFAULT_SEED;

/// The paper's levels (g²/Hz) and records per level and set (see `endstop::broadband`).
const LEVELS: [f64; 3] = endstop::paper::fig12::FIG12_LEVELS;
const REALISATIONS: usize = endstop::paper::fig12::FIG12_REALISATIONS;

fn main() {
    common::run_main("fig12", run);
}

fn run() -> Result<()> {
    let mut exp = Experiment::start("fig12");
    exp.seed = Some(DEFAULT_SEED);
    let sets = bbio::prototype1_sets(&mut exp)?;
    let mut cases = Vec::new();
    for (set, dev) in &sets {
        for &sa in &LEVELS {
            let s = bbio::spec(dev, sa, P1_NPERSEG, P1_BAND_HZ, REALISATIONS, false);
            cases.push((set.clone(), dev.clone(), s));
        }
    }
    let levels = bbio::run(cases, "fig12")?;

    let mut md = bbio::settings_md(&levels[0]);
    md.push_str(&format!(
        "\nEnd-stop gap xmax: published {} um, calibrated {} um (fitted to Figure 8's onset by \
         the narrowband calibration).\n\n**Power and contact**\n\n",
        fmt_sig(sets[0].1.geometry.endstop_gap_m * 1e6, 3),
        fmt_sig(sets[1].1.geometry.endstop_gap_m * 1e6, 3),
    ));
    md.push_str(&bbio::power_table_md(&levels));
    md.push_str("\n**Peak and widths of the ensemble-mean output PSD** (CI: delete-one jackknife over the records, 95 %), and the spread of the same widths read from single records\n\n");
    md.push_str(&bbio::width_table_md(&levels));
    let lin = endstop::physics::two_port::linear_widths(&sets[0].1, P1_BAND_HZ.0, P1_BAND_HZ.1);
    md.push_str(&format!(
        "\nLinearised theory (eqs 11-17, no end-stops): 3 dB width {} Hz, half-amplitude width \
         {} Hz, peak {} Hz.\n\n**Claims and the two readings of \"3 dB\"**\n\n| set | reading | \
         width at 7.4e-3 (Hz) | width at 2.85e-2 (Hz) | ratio | single records: ratio mean \
         ± std [5 %, 95 %] |\n|---|---|---|---|---|---|\n",
        fmt_sig(lin.bw3db_hz(), 3),
        fmt_sig(lin.bw6db_hz(), 3),
        fmt_sig(lin.half_power.map_or(f64::NAN, |b| b.peak_hz), 4),
    ));
    exp.number("linear_theory_bw3db_hz", lin.bw3db_hz());
    exp.number("linear_theory_bw6db_hz", lin.bw6db_hz());

    for (set, _) in &sets {
        let lo = find(&levels, set, LEVELS[0]);
        let hi = find(&levels, set, LEVELS[2]);
        for (fraction, reading) in [(0.5, "half power (3 dB, scored)"), (0.25, "half amplitude")] {
            let (wa, wb) = (lo.ens.mean_width(fraction), hi.ens.mean_width(fraction));
            let (r, rci) = wb.ratio(&wa);
            let single = |l: &Level| {
                if fraction == 0.5 {
                    l.ens.single_bw3db_hz()
                } else {
                    l.ens.single_bw6db_hz()
                }
            };
            let rs = ratio_spread(&single(hi), &single(lo));
            md.push_str(&format!(
                "| {set} | {reading} | {} | {} | {} | {} |\n",
                pm(wa.estimate, wa.ci95),
                pm(wb.estimate, wb.ci95),
                pm(r, rci),
                spread_str(&rs, 3),
            ));
            let tag = if fraction == 0.5 { "bw3db" } else { "bw6db" };
            exp.number(&format!("{tag}_7p4e-3_{set}_hz"), wa.estimate);
            exp.number(&format!("{tag}_2p85e-2_{set}_hz"), wb.estimate);
            exp.number(&format!("{tag}_ratio_{set}"), r);
            if fraction == 0.5 {
                exp.claim_with_uncertainty("F12", "bw_7p4e-3_hz", set, wa.estimate, Some(wa.ci95));
                exp.claim_with_uncertainty("F12", "bw_2p85e-2_hz", set, wb.estimate, Some(wb.ci95));
                exp.claim_with_uncertainty(
                    "F12",
                    "bw_ratio_2p85e-2_over_7p4e-3",
                    set,
                    r,
                    Some(rci),
                );
            }
        }
        for l in bbio::for_set(&levels, set) {
            let t = sa_label(l.sa());
            exp.number(&format!("efficiency_{t}_{set}"), l.ens.efficiency.mean);
            exp.number(
                &format!("contact_fraction_{t}_{set}"),
                l.ens.contact_fraction.mean,
            );
        }
    }
    exp.write_numbers_md(&md)?;

    // As the paper: log y over (500.0, 3000.0); the calibrated set is dashed.
    bbio::write_p1_spectra(
        &exp,
        "fig12",
        "Figure 12: prototype 1 at 30 V, output power PSD (both loads, one-sided)",
        &levels,
        (500.0, 3000.0),
        false,
    )?;
    exp.finish()
}
