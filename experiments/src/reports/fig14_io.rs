//! Figure 14's outputs (the figure itself is `endstop::paper::figures::fig14`): the numbers of
//! the summary, the Parquet tables, the book's tables (settings, powers, convergence, slopes,
//! claims, the end-stop readings) and the plots of one run.

use anyhow::Result;
use endstop::paper::claims::{keys, Claims};
use endstop::paper::figures::fig14::{self, Fig14, F14B_LEVEL, FIG14_LEVELS, TIGHT_RTOL};
use endstop::paper::setups::ParamSet;
use endstop::paper::Figure;
use endstop::physics::two_port::eq21_power_w;

use crate::io::md::Table;
use crate::io::plot::{error_bars, LegendPos, LinePlot, Series, Style, PALETTE};
use crate::reports::record_io::{self, pm, sa_label, Level};
use crate::{fmt_sig, Experiment};

/// Writes Figure 14's outputs.
pub fn write(mut exp: Experiment, run: &fig14::Run, claims: &Claims) -> Result<()> {
    let f = fig14::findings(run);
    let l_b = &run.levels[F14B_LEVEL];
    let labels = |idx: &[usize]| -> String {
        let v: Vec<String> = idx.iter().map(|&i| sa_label(FIG14_LEVELS[i])).collect();
        v.join(", ")
    };

    exp.number("efficiency_eq21", f.eq21);
    exp.number("efficiency_linear_pooled", f.pooled.mean);
    exp.number("efficiency_linear_pooled_ci95", f.pooled.ci95);
    exp.number("efficiency_linear_records", f.pooled.n as f64);
    for l in &run.levels {
        let t = sa_label(l.sa());
        exp.number(&format!("p_{t}_w"), l.ens.power_w.mean);
        exp.number(&format!("efficiency_{t}"), l.ens.efficiency.mean);
        exp.number(
            &format!("contact_fraction_{t}"),
            l.ens.contact_fraction.mean,
        );
        exp.number(&format!("x_rms_{t}_m"), l.ens.x_rms_m.mean);
    }

    let mut md = record_io::settings_md(&run.levels[0]);
    md.push_str(&format!(
        "\nEq 21 with Qm = sqrt(K m)/b (its derivation's reading; see Table 3 for the others): \
         efficiency {} %.\n\n",
        fmt_sig(f.eq21 * 100.0, 4)
    ));
    md.push_str(&record_io::power_table(&run.levels).render());
    md.push_str(&format!(
        "\n**Convergence.** The same records with Dormand-Prince everywhere (no exponential \
         free-flight step) at the relative tolerance {:e} instead of the exponential scheme \
         with Dormand-Prince at {:e} in and near contacts:\n\n",
        TIGHT_RTOL, run.levels[0].ens.spec.record.rtol
    ));
    let mut t = Table::new([
        "Sa (g²/Hz)",
        "record",
        "P (nW)",
        "P, tight tolerance (nW)",
        "relative change",
        "record-to-record std of P at this level (relative)",
    ]);
    for c in &run.convergence {
        let l = &run.levels[c.level];
        let change = c.p_tight_w / c.p_w - 1.0;
        t.row([
            sa_label(l.sa()),
            c.record.to_string(),
            fmt_sig(c.p_w * 1e9, 5),
            fmt_sig(c.p_tight_w * 1e9, 5),
            format!("{change:.1e}"),
            fmt_sig(l.ens.power_w.std / l.ens.power_w.mean, 2),
        ]);
        exp.number(
            &format!("convergence_rel_change_{}_{}", sa_label(l.sa()), c.record),
            change,
        );
    }
    md.push_str(&t.render());
    let mut t = Table::new([
        "Sa from (g²/Hz)",
        "to (g²/Hz)",
        "log-log slope of P(Sa) (1 = linear)",
    ]);
    for &(a, b, s) in &f.slopes {
        t.row([
            sa_label(FIG14_LEVELS[a]),
            sa_label(FIG14_LEVELS[b]),
            fmt_sig(s, 3),
        ]);
    }
    md.push('\n');
    md.push_str(&t.render());
    let eff_b = &l_b.ens.efficiency;
    md.push_str(&format!(
        "\n**Claims** (published set). F14-a: the {} records of the {} levels without any \
         impact ({}) pooled give an efficiency of {} % against eq 21's {} %; the difference is \
         {} standard errors. F14-b: at 1.69e-3 g²/Hz the efficiency is {} %. Sublinear growth \
         (efficiency falling from level to level once the mass is in contact at least {} of \
         the time, levels {}; the last below the linear value beyond both CIs): **{}**.\n",
        f.pooled.n,
        f.linear_levels.len(),
        labels(&f.linear_levels),
        pm(f.pooled.mean * 100.0, f.pooled.ci95 * 100.0),
        fmt_sig(f.eq21 * 100.0, 4),
        fmt_sig(f.pooled_minus_eq21_se, 2),
        pm(eff_b.mean * 100.0, eff_b.ci95 * 100.0),
        fig14::FREQUENT_CONTACT,
        labels(&f.frequent_levels),
        if f.sublinear { "yes" } else { "no" },
    ));
    md.push_str(&format!(
        "\n**Other end-stop readings at {} g²/Hz** (not scored; same records):\n\n",
        sa_label(l_b.sa())
    ));
    let mut t = Table::new([
        "end-stop model",
        "efficiency (%)",
        "time in contact",
        "impacts per record",
    ]);
    let reading_row = |label: String, l: &Level| {
        [
            label,
            pm(l.ens.efficiency.mean * 100.0, l.ens.efficiency.ci95 * 100.0),
            format!("{:.2e}", l.ens.contact_fraction.mean),
            fmt_sig(l.impacts_per_record(), 3),
        ]
    };
    t.row(reading_row(
        "linear k_im, b_im = 0.4 N s/m (published, scored)".into(),
        l_b,
    ));
    for (i, l) in run.other_readings.iter().enumerate() {
        t.row(reading_row(l.variant.clone().unwrap_or_default(), l));
        exp.number(
            &format!("efficiency_1p69e-3_variant_{i}"),
            l.ens.efficiency.mean,
        );
    }
    md.push_str(&t.render());
    exp.write_numbers_md(&md)?;

    record_io::write_level_tables(
        &exp,
        Fig14::NAME,
        &run.levels,
        None,
        ParamSet::Published.label(),
    )?;
    write_power_plot(&exp, run)?;
    write_efficiency_plot(&exp, run, f.eq21, claims)?;
    exp.finish()
}

/// Figure 14 as in the paper: power (nW) against Sa, log-log, with eq 21's line.
fn write_power_plot(exp: &Experiment, run: &fig14::Run) -> Result<()> {
    let (lo, hi): (f64, f64) = (5e-6, 4e-3);
    let n = 60;
    let line: Vec<(f64, f64)> = (0..=n)
        .map(|i| {
            let sa = lo * (hi / lo).powf(i as f64 / n as f64);
            (sa, eq21_power_w(&run.device, sa) * 1e9)
        })
        .collect();
    let levels = &run.levels;
    let mut series = vec![
        Series::new(
            "linear theory, eq 21 (Qm = sqrt(K m)/b)",
            line,
            PALETTE[6],
            Style::Dashed,
        ),
        Series::new(
            &format!(
                "simulation, mean of {} records (bars: 95 % CI)",
                levels[0].ens.records.len()
            ),
            levels
                .iter()
                .map(|l| (l.sa(), l.ens.power_w.mean * 1e9))
                .collect(),
            PALETTE[0],
            Style::LinePoints,
        ),
    ];
    series.extend(error_bars(
        levels
            .iter()
            .map(|l| (l.sa(), l.ens.power_w.mean * 1e9, l.ens.power_w.ci95 * 1e9)),
        PALETTE[0],
    ));
    let plot = LinePlot::new(
        "Figure 14: prototype 2 at 15 V, output power of both loads",
        "acceleration PSD Sa [g²/Hz] (two-sided)",
        "output power [nW]",
        series,
    )
    .x(lo, hi)
    .y(1e-1, 3e2)
    .log(true, true)
    .legend(LegendPos::UpperLeft);
    exp.write_plot(&plot)
}

/// Efficiency and time in contact against Sa.
fn write_efficiency_plot(
    exp: &Experiment,
    run: &fig14::Run,
    eq21: f64,
    claims: &Claims,
) -> Result<()> {
    let (lo, hi) = (5e-6, 4e-3);
    let levels = &run.levels;
    let mut series = vec![
        Series::new(
            "eq 21",
            vec![(lo, eq21 * 100.0), (hi, eq21 * 100.0)],
            PALETTE[6],
            Style::Dashed,
        ),
        Series::new(
            "simulation (bars: 95 % CI)",
            levels
                .iter()
                .map(|l| (l.sa(), l.ens.efficiency.mean * 100.0))
                .collect(),
            PALETTE[0],
            Style::LinePoints,
        ),
        Series::new(
            "time in contact [0.01 %]",
            levels
                .iter()
                .map(|l| (l.sa(), l.ens.contact_fraction.mean * 1e4))
                .collect(),
            PALETTE[1],
            Style::LinePoints,
        ),
    ];
    if let Some(c) = claims.claim(keys::F14B_EFF) {
        let sa = FIG14_LEVELS[F14B_LEVEL];
        series.push(Series::new(
            &format!("paper: {} % at {} g²/Hz", c.paper.to_f64(), sa_label(sa)),
            vec![(sa, c.paper.to_f64())],
            PALETTE[3],
            Style::Points,
        ));
    }
    series.extend(error_bars(
        levels.iter().map(|l| {
            let e = &l.ens.efficiency;
            (l.sa(), e.mean * 100.0, e.ci95 * 100.0)
        }),
        PALETTE[0],
    ));
    let plot = LinePlot::new(
        "Prototype 2 at 15 V: efficiency 2P/(m Sa) and time in contact",
        "acceleration PSD Sa [g²/Hz] (two-sided)",
        "efficiency [%]; time in contact [0.01 %]",
        series,
    )
    .x(lo, hi)
    .y(0.0, 100.0)
    .log(true, false)
    // Upper right: above the efficiency, which falls where the level is high, and clear of
    // the contact time, which lies along the lower axis at the low levels.
    .legend(LegendPos::UpperRight);
    exp.write_extra_plot("fig14_efficiency", &plot)
}
