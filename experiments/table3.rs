//! Table 3: electromechanical coupling k^2, quality factor Qm and figure of merit k^2 Qm of
//! both prototypes (eqs 15-18), with the broadband efficiency of eq 21 (claims T3-a, T3-b,
//! F14-a's linear-theory value).

use endstop_experiments as common;

use anyhow::Result;
use common::{fmt_sig, load_device, Experiment};
use endstop::physics::two_port::QmReading;
use endstop::physics::two_port::TwoPort;
use polars::prelude::*;

/// One row of the output: device label, bias voltage (V), Qm reading, two-port.
type Row = (String, f64, QmReading, TwoPort);

fn main() {
    common::run_main("table3", run);
}

/// The Qm reading of our Table 3 verdicts (see `endstop::physics::two_port::TABLE3_QM`).
const DEFAULT_QM: QmReading = endstop::physics::two_port::TABLE3_QM;
/// The Qm reading of eq 21 (see `endstop::physics::two_port::EQ21_QM`).
const EQ21_QM: QmReading = endstop::physics::two_port::EQ21_QM;

fn run() -> Result<()> {
    let mut exp = Experiment::start("table3");
    let p1 = load_device("prototype1")?;
    let p2 = load_device("prototype2")?;
    exp.uses(&p1, "published");
    exp.uses(&p2, "published");
    let cases = [
        ("prototype 1", "p1", 30.0, &p1),
        ("prototype 2", "p2", 15.0, &p2),
    ];

    // One row per device and Qm reading: (device label, bias, reading, two-port).
    let mut rows: Vec<Row> = Vec::new();
    let mut md = String::from("| device | Vb (V) | C (pF) | Gamma (uN/V) | K (N/m) | f_oc = sqrt(K/m)/2pi (Hz) | k^2 (%) | rL (eq 22) |\n|---|---|---|---|---|---|---|---|\n");
    let mut md_q = String::from(
        "\n| device | Qm reading | Qm | k^2 Qm | eq 21 efficiency (%) |\n|---|---|---|---|---|\n",
    );
    for (label, key, vb, dev) in cases {
        let tp = TwoPort::of(&dev.device.with_bias(vb));
        md.push_str(&format!(
            "| {label} | {vb} | {} | {} | {} | {} | {} | {} |\n",
            fmt_sig(tp.capacitance_f * 1e12, 4),
            fmt_sig(tp.gamma_n_per_v * 1e6, 4),
            fmt_sig(tp.stiffness_n_per_m, 5),
            fmt_sig(tp.resonance_hz(), 5),
            fmt_sig(tp.k2 * 100.0, 4),
            fmt_sig(tp.r_load(), 4),
        ));
        for reading in QmReading::ALL {
            let qm = tp.qm(reading);
            let eff = tp.broadband_efficiency(qm);
            md_q.push_str(&format!(
                "| {label} | {}{} | {} | {} | {} |\n",
                reading.label(),
                if reading == DEFAULT_QM {
                    " (default)"
                } else {
                    ""
                },
                fmt_sig(qm, 5),
                fmt_sig(tp.k2 * qm, 4),
                fmt_sig(eff * 100.0, 4),
            ));
            rows.push((label.to_string(), vb, reading, tp));
        }
        let (claim, qm) = (if key == "p1" { "T3-a" } else { "T3-b" }, tp.qm(DEFAULT_QM));
        exp.claim(claim, &format!("k2_pct_{key}"), "published", tp.k2 * 100.0);
        exp.claim(claim, &format!("qm_{key}"), "published", qm);
        exp.claim(claim, &format!("k2qm_{key}"), "published", tp.k2 * qm);
        exp.number(&format!("k2_{key}"), tp.k2);
        exp.number(&format!("stiffness_k_{key}_n_per_m"), tp.stiffness_n_per_m);
        exp.number(&format!("resonance_oc_{key}_hz"), tp.resonance_hz());
        exp.number(&format!("r_load_{key}"), tp.r_load());
        for reading in QmReading::ALL {
            let tag = match reading {
                QmReading::Suspension => "suspension",
                QmReading::OpenCircuit => "open_circuit",
                QmReading::MeasuredResonance => "measured",
            };
            exp.number(&format!("qm_{key}_{tag}"), tp.qm(reading));
        }
        let eff = tp.broadband_efficiency(tp.qm(EQ21_QM));
        exp.number(&format!("eff_eq21_{key}"), eff);
        if key == "p2" {
            exp.claim("F14-a", "eff_eq21_pct", "published", eff * 100.0);
        }
        // Table 2's C0 versus eq 10 evaluated with Table 1's geometry.
        let c0_geo = dev.device.c0_from_geometry_f();
        let mut geo = dev.device.with_bias(vb);
        geo.electrical.c0_f = c0_geo;
        let tpg = TwoPort::of(&geo);
        exp.number(&format!("c0_geometry_{key}_f"), c0_geo);
        exp.number(&format!("k2_c0_geometry_{key}"), tpg.k2);
    }
    md.push_str(&md_q);
    md.push_str("\n**C0 from the geometry.** Eq 10 gives C0 = 2 Nf eps0 x0 t/g0 from Table 1; it differs from Table 2's C0, and so would k^2:\n\n| device | C0 Table 2 (pF) | C0 eq 10 (pF) | k^2 with eq 10's C0 (%) |\n|---|---|---|---|\n");
    for (label, key, vb, dev) in cases {
        let c0g = dev.device.c0_from_geometry_f();
        let mut geo = dev.device.with_bias(vb);
        geo.electrical.c0_f = c0g;
        md.push_str(&format!(
            "| {label} | {} | {} | {} |\n",
            fmt_sig(dev.device.electrical.c0_f * 1e12, 3),
            fmt_sig(c0g * 1e12, 4),
            fmt_sig(TwoPort::of(&geo).k2 * 100.0, 4)
        ));
        let _ = key;
    }
    // The abstract's k^2 = 1.44 % for prototype 1: the bias at which eq 18 gives it.
    let target = 0.0144;
    let (mut lo, mut hi) = (1.0, 100.0);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if TwoPort::of(&p1.device.with_bias(mid)).k2 < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    exp.number("bias_for_k2_1p44_p1_v", 0.5 * (lo + hi));
    md.push_str(&format!(
        "\nThe abstract quotes k^2 = 1.44 % for prototype 1; eq 18 gives that value at Vb = {} V, not at Table 3's 30 V.\n",
        fmt_sig(0.5 * (lo + hi), 3)
    ));
    // Another reading of the abstract's coupling factors: eq 18 without the load capacitance
    // (C = (C0 + Cp)/2, K with C0 + Cp), i.e. the transducer alone.
    let mut no_cl = Vec::new();
    for (key, vb, dev) in [("p1", 30.0, &p1), ("p2", 15.0, &p2)] {
        let mut d = dev.device.with_bias(vb);
        d.electrical.load_capacitance_f = 0.0;
        let k2 = TwoPort::of(&d).k2;
        exp.number(&format!("k2_without_cl_{key}"), k2);
        no_cl.push(fmt_sig(k2 * 100.0, 3));
    }
    md.push_str(&format!(
        "Without the load capacitance in eq 18 (the transducer alone), k^2 = {} % for prototype 1 at 30 V and {} % for prototype 2 at 15 V; the abstract quotes 1.44 % and 2.52 %.\n",
        no_cl[0], no_cl[1]
    ));
    exp.write_numbers_md(&md)?;

    let col = |f: &dyn Fn(&Row) -> f64| -> Vec<f64> { rows.iter().map(f).collect() };
    let mut df = df!(
        "device" => rows.iter().map(|r| r.0.clone()).collect::<Vec<_>>(),
        "bias_v" => col(&|r| r.1),
        "qm_reading" => rows.iter().map(|r| r.2.label().to_string()).collect::<Vec<_>>(),
        "k2" => col(&|r| r.3.k2),
        "qm" => col(&|r| r.3.qm(r.2)),
        "efficiency_eq21" => col(&|r| r.3.broadband_efficiency(r.3.qm(r.2))),
        "capacitance_f" => col(&|r| r.3.capacitance_f),
        "gamma_n_per_v" => col(&|r| r.3.gamma_n_per_v),
        "stiffness_k_n_per_m" => col(&|r| r.3.stiffness_n_per_m),
        "r_load" => col(&|r| r.3.r_load()),
        "resonance_oc_hz" => col(&|r| r.3.resonance_hz()),
        "params" => vec!["published"; rows.len()],
    )?;
    exp.write_parquet("table3", &mut df, "published")?;
    // Table 3 is a table; its plot is eq 21's efficiency against the normalised load.
    write_efficiency_plot(&exp, &p2.device)?;
    exp.finish()
}

fn write_efficiency_plot(exp: &Experiment, p2: &endstop::device::Device) -> Result<()> {
    use common::plot::{LinePlot, Series, Style, PALETTE};
    let base = p2.with_bias(15.0);
    let mut pts = Vec::new();
    let mut marker = Vec::new();
    for i in 0..200 {
        let r_ohm = 1e5 * 10f64.powf(i as f64 * 4.0 / 199.0);
        let mut d = base.clone();
        d.electrical.load_resistance_ohm = r_ohm;
        let tp = TwoPort::of(&d);
        pts.push((r_ohm / 1e6, 100.0 * tp.broadband_efficiency(tp.qm(EQ21_QM))));
    }
    let tp = TwoPort::of(&base);
    marker.push((
        base.electrical.load_resistance_ohm / 1e6,
        100.0 * tp.broadband_efficiency(tp.qm(EQ21_QM)),
    ));
    let plot = LinePlot::new(
        "Eq 21: broadband efficiency of prototype 2 at 15 V against the load",
        "load resistance RL [MOhm]",
        "efficiency 2P/(m Sa) [%]",
        vec![
            Series::new("eq 21, Qm = sqrt(K m)/b", pts, PALETTE[0], Style::Line),
            Series::new(
                "Table 2's RL = 15.2 MOhm",
                marker,
                PALETTE[1],
                Style::Points,
            ),
        ],
    )
    .log(true, false)
    .y(0.0, 100.0);
    exp.write_plot(&plot)
}
