//! Table 3's outputs (the table itself is `endstop::paper::figures::table3`): the numbers of
//! the summary, the book's tables (the two-port of each prototype, the readings of Qm, C0 from
//! the geometry), the Parquet table and the plot of eq 21's efficiency against the load.

use anyhow::Result;
use endstop::paper::figures::table3::{self, ABSTRACT_K2_P1};
use endstop::paper::qm::{QmReading, TABLE3_QM};
use endstop::paper::setups::comb;
use endstop::paper::setups::ParamSet;

use crate::io::frame::frame;
use crate::io::md::Table;
use crate::io::plot::{LinePlot, Series, Style, PALETTE};
use crate::{fmt_sig, row, Experiment};

/// The key of a Qm reading in the summary's numbers.
fn reading_key(reading: QmReading) -> &'static str {
    match reading {
        QmReading::Suspension => "suspension",
        QmReading::OpenCircuit => "open_circuit",
        QmReading::MeasuredResonance => "measured",
    }
}

/// Writes everything of one run of Table 3: the numbers of the summary, the book's tables,
/// the Parquet table and the plot of eq 21's efficiency against the load.
pub fn write(mut exp: Experiment, run: &table3::Run) -> Result<()> {
    let mut t = Table::new([
        "device",
        "Vb (V)",
        "C (pF)",
        "Gamma (uN/V)",
        "K (N/m)",
        "f_oc = sqrt(K/m)/2pi (Hz)",
        "k^2 (%)",
        "rL (eq 22)",
    ]);
    let mut tq = Table::new([
        "device",
        "Qm reading",
        "Qm",
        "k^2 Qm",
        "eq 21 efficiency (%)",
    ]);
    let mut tc = Table::new([
        "device",
        "C0 Table 2 (pF)",
        "C0 eq 10 (pF)",
        "k^2 with eq 10's C0 (%)",
    ]);
    let mut rows = Vec::new();
    for p in &run.prototypes {
        let (tp, key) = (&p.two_port, p.key);
        t.row([
            p.label.to_string(),
            p.bias_v.to_string(),
            fmt_sig(tp.capacitance_f * 1e12, 4),
            fmt_sig(tp.gamma_n_per_v * 1e6, 4),
            fmt_sig(tp.stiffness_n_per_m, 5),
            fmt_sig(tp.resonance_hz(), 5),
            fmt_sig(tp.k2 * 100.0, 4),
            fmt_sig(tp.r_load(), 4),
        ]);
        for reading in QmReading::ALL {
            let (qm, eff) = (p.qm(reading), p.efficiency(reading));
            let default = if reading == TABLE3_QM {
                " (default)"
            } else {
                ""
            };
            tq.row([
                p.label.to_string(),
                format!("{}{default}", reading.label()),
                fmt_sig(qm, 5),
                fmt_sig(tp.k2 * qm, 4),
                fmt_sig(eff * 100.0, 4),
            ]);
            rows.push(row![
                "device" => p.label,
                "bias_v" => p.bias_v,
                "qm_reading" => reading.label(),
                "k2" => tp.k2,
                "qm" => qm,
                "efficiency_eq21" => eff,
                "capacitance_f" => tp.capacitance_f,
                "gamma_n_per_v" => tp.gamma_n_per_v,
                "stiffness_k_n_per_m" => tp.stiffness_n_per_m,
                "r_load" => tp.r_load(),
                "resonance_oc_hz" => tp.resonance_hz(),
                "params" => ParamSet::Published.label(),
            ]);
            exp.number(&format!("qm_{key}_{}", reading_key(reading)), qm);
        }
        tc.row([
            p.label.to_string(),
            fmt_sig(comb(&p.device).c0_f * 1e12, 3),
            fmt_sig(p.c0_geometry_f * 1e12, 4),
            fmt_sig(p.k2_c0_geometry * 100.0, 4),
        ]);
        exp.number(&format!("k2_{key}"), tp.k2);
        exp.number(&format!("stiffness_k_{key}_n_per_m"), tp.stiffness_n_per_m);
        exp.number(&format!("resonance_oc_{key}_hz"), tp.resonance_hz());
        exp.number(&format!("r_load_{key}"), tp.r_load());
        exp.number(&format!("eff_eq21_{key}"), p.eq21_efficiency());
        exp.number(&format!("c0_geometry_{key}_f"), p.c0_geometry_f);
        exp.number(&format!("k2_c0_geometry_{key}"), p.k2_c0_geometry);
        exp.number(&format!("k2_without_cl_{key}"), p.k2_without_cl);
    }
    exp.number("bias_for_k2_1p44_p1_v", run.bias_for_abstract_k2_p1_v);

    let [q1, q2] = &run.prototypes;
    let mut md = t.render();
    md.push('\n');
    md.push_str(&tq.render());
    md.push_str(
        "\n**C0 from the geometry.** Eq 10 gives C0 = 2 Nf eps0 x0 t/g0 from Table 1; it \
         differs from Table 2's C0, and so would k^2:\n\n",
    );
    md.push_str(&tc.render());
    md.push_str(&format!(
        "\nThe abstract quotes k^2 = {} % for prototype 1; eq 18 gives that value at Vb = {} V, \
         not at Table 3's {} V.\n",
        fmt_sig(ABSTRACT_K2_P1 * 100.0, 3),
        fmt_sig(run.bias_for_abstract_k2_p1_v, 3),
        q1.bias_v,
    ));
    md.push_str(&format!(
        "Without the load capacitance in eq 18 (the transducer alone), k^2 = {} % for prototype \
         1 at {} V and {} % for prototype 2 at {} V; the abstract quotes 1.44 % and 2.52 %.\n",
        fmt_sig(q1.k2_without_cl * 100.0, 3),
        q1.bias_v,
        fmt_sig(q2.k2_without_cl * 100.0, 3),
        q2.bias_v,
    ));
    exp.write_numbers_md(&md)?;
    exp.write_parquet("table3", &mut frame(rows)?, ParamSet::Published.label())?;

    // Table 3 is a table; its plot is eq 21's efficiency against the load.
    let marker_rl = comb(&q2.device).load_resistance_ohm;
    let plot = LinePlot::new(
        "Eq 21: broadband efficiency of prototype 2 at 15 V against the load",
        "load resistance RL [MOhm]",
        "efficiency 2P/(m Sa) [%]",
        vec![
            Series::new(
                "eq 21, Qm = sqrt(K m)/b",
                run.efficiency_against_load
                    .iter()
                    .map(|&(r, e)| (r / 1e6, 100.0 * e))
                    .collect(),
                PALETTE[0],
                Style::Line,
            ),
            Series::new(
                "Table 2's RL = 15.2 MOhm",
                vec![(marker_rl / 1e6, 100.0 * q2.eq21_efficiency())],
                PALETTE[1],
                Style::Points,
            ),
        ],
    )
    .log(true, false)
    .y(0.0, 100.0);
    exp.write_plot(&plot)?;
    exp.finish()
}
