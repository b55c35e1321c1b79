//! Figure 11: output power PSDs of prototype 1 at 30 V (Hertz contact, b_im = 1.5 N s/m) at the
//! low levels Sa = 4.42e-6, 1.12e-4 and 3.49e-4 g²/Hz: the device stays linear and the
//! bandwidth does not change (claim F11), under the published and the calibrated parameter
//! sets.

use endstop_experiments as common;

use endstop_experiments::broadband_io as bbio;

use anyhow::Result;
use bbio::{find, pm, sa_label, spread_str};
use common::{fmt_sig, Experiment};
use endstop::num::stats::ratio_spread;
use endstop::paper::ensembles::P1_BAND_HZ;
use endstop::paper::ensembles::P1_NPERSEG;
use endstop::study::ensemble::DEFAULT_SEED;

/// The paper's levels (g²/Hz) and records per level and set (see `endstop::broadband`).
const LEVELS: [f64; 3] = endstop::paper::fig11::FIG11_LEVELS;
const REALISATIONS: usize = endstop::paper::fig11::FIG11_REALISATIONS;

fn main() {
    common::run_main("fig11", run);
}

fn run() -> Result<()> {
    let mut exp = Experiment::start("fig11");
    exp.seed = Some(DEFAULT_SEED);
    let sets = bbio::prototype1_sets(&mut exp)?;
    let mut cases = Vec::new();
    for (set, dev) in &sets {
        for &sa in &LEVELS {
            let s = bbio::spec(dev, sa, P1_NPERSEG, P1_BAND_HZ, REALISATIONS, false);
            cases.push((set.clone(), dev.clone(), s));
        }
    }
    let levels = bbio::run(cases, "fig11")?;

    let mut md = bbio::settings_md(&levels[0]);
    md.push_str(&format!(
        "\nEnd-stop gap xmax: published {} um, calibrated {} um.\n\n**Power and contact**\n\n",
        fmt_sig(sets[0].1.geometry.endstop_gap_m * 1e6, 3),
        fmt_sig(sets[1].1.geometry.endstop_gap_m * 1e6, 3),
    ));
    md.push_str(&bbio::power_table_md(&levels));
    md.push_str("\n**Peak and widths of the ensemble-mean output PSD** (CI: delete-one jackknife over the records, 95 %), and the spread of the same widths read from single records\n\n");
    md.push_str(&bbio::width_table_md(&levels));
    let lin = endstop::physics::two_port::linear_widths(&sets[0].1, P1_BAND_HZ.0, P1_BAND_HZ.1);
    md.push_str(&format!(
        "\nLinearised theory (eqs 11-17, no end-stops): 3 dB width {} Hz, half-amplitude width \
         {} Hz, peak {} Hz.\n\n**Claims**\n\n| set | impacts in all records | 3 dB width ratio \
         3.49e-4 / 4.42e-6 | half-amplitude ratio | single records: 3 dB ratio mean ± std \
         [5 %, 95 %] |\n|---|---|---|---|---|\n",
        fmt_sig(lin.bw3db_hz(), 3),
        fmt_sig(lin.bw6db_hz(), 3),
        fmt_sig(lin.half_power.map_or(f64::NAN, |b| b.peak_hz), 4),
    ));
    exp.number("linear_theory_bw3db_hz", lin.bw3db_hz());
    exp.number("linear_theory_bw6db_hz", lin.bw6db_hz());

    for (set, _) in &sets {
        let lo = find(&levels, set, LEVELS[0]);
        let hi = find(&levels, set, LEVELS[2]);
        let (r, rci) = hi.ens.mean_width(0.5).ratio(&lo.ens.mean_width(0.5));
        let (r6, r6ci) = hi.ens.mean_width(0.25).ratio(&lo.ens.mean_width(0.25));
        let rs = ratio_spread(&hi.ens.single_bw3db_hz(), &lo.ens.single_bw3db_hz());
        let impacts: u64 = bbio::for_set(&levels, set).map(|l| l.ens.impacts).sum();
        exp.claim_with_uncertainty("F11", "bw_ratio_3p49e-4_over_4p42e-6", set, r, Some(rci));
        exp.claim(
            "F11",
            "linear_regime_no_impact",
            set,
            if impacts == 0 { 1.0 } else { 0.0 },
        );
        md.push_str(&format!(
            "| {set} | {impacts} | {} | {} | {} |\n",
            pm(r, rci),
            pm(r6, r6ci),
            spread_str(&rs, 3)
        ));
        exp.number(&format!("impacts_{set}"), impacts as f64);
        for l in bbio::for_set(&levels, set) {
            let t = sa_label(l.sa());
            exp.number(
                &format!("bw3db_{t}_{set}_hz"),
                l.ens.mean_width(0.5).estimate,
            );
            exp.number(
                &format!("bw6db_{t}_{set}_hz"),
                l.ens.mean_width(0.25).estimate,
            );
            exp.number(&format!("efficiency_{t}_{set}"), l.ens.efficiency.mean);
            exp.number(&format!("x_peak_{t}_{set}_m"), l.ens.x_peak_m);
        }
    }
    exp.write_numbers_md(&md)?;

    // As the paper: log y over (600.0, 2000.0); the calibrated set is dashed.
    bbio::write_p1_spectra(
        &exp,
        "fig11",
        "Figure 11: prototype 1 at 30 V, output power PSD (both loads, one-sided)",
        &levels,
        (600.0, 2000.0),
        true,
    )?;
    exp.finish()
}
