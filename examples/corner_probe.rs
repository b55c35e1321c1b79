//! One continuation of the deviations study at one history-match point, as given and with the
//! drive scaled by (1 + k eps): its end and events both ways, or its error.
//!
//! Usage: `cargo run --release --example corner_probe -- p1:2 f8c [k]`; cases: f8c f8d f8e
//! f8f (Figure 8's Hertz b_im fitted, 0, 10 and linear 2), f9-20 f9-30 f9-40 (Figure 9's
//! amplitude branches), f13a f13b f13c (Figure 13's 0.12 g, 0.31 g linear, 0.31 g Hertz).

use endstop::device::{Device, StiffnessModel};
use endstop::paper::deviations::sweeps::{P1_STOP_HZ, P2_HERTZ_BIM, P2_RANGE_HZ, P2_STEP_HZ};
use endstop::paper::deviations::{RangesFile, Variant};
use endstop::paper::figures::fig09::{FIG9_EXTEND_G, FIG9_RANGE_G, FIG9_STEP_G};
use endstop::paper::measured::P1_RESONANCE_HZ;
use endstop::paper::setups::{endstop, with_endstop, FIG13_BIAS_V, P1_BIAS_V};
use endstop::paper::sweeps::{P1_HIGH_ACCEL_RMS_G, P1_SWEEP_START_HZ, P1_SWEEP_STEP_HZ};
use endstop::progress::Silent;
use endstop::study::continuation::{self, Branch, ContinuationSettings};
use endstop::study::orbit::{Forcing, OrbitError};

const POINTS: &str = include_str!("../tests/fixtures/history_points.csv");

fn variant(label: &str) -> Result<Variant, Box<dyn std::error::Error>> {
    let root = env!("CARGO_MANIFEST_DIR");
    let ranges = RangesFile::bundled()?;
    for line in POINTS.lines().filter(|l| !l.starts_with('#')).skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        if format!("{}:{}", f[0], f[1]) != label {
            continue;
        }
        let coords = f[2..10]
            .iter()
            .map(|s| s.parse::<f64>())
            .collect::<Result<Vec<_>, _>>()?;
        let (file, r) = match f[0] {
            "p1" => ("prototype1", &ranges.prototype1),
            _ => ("prototype2", &ranges.prototype2),
        };
        let base = Device::from_toml_str(
            &std::fs::read_to_string(format!("{root}/data/{file}.toml"))?,
            file,
        )?;
        return Ok(r.variant(&base, &coords)?);
    }
    Err(format!("no point {label}").into())
}

fn run(v: &Variant, case: &str, scale: f64) -> Result<Branch, OrbitError> {
    let s = v.accel_scale * scale;
    let fig8 = |law, bim: Option<f64>| {
        let base = v.device.with_bias(P1_BIAS_V);
        let bim = bim.unwrap_or_else(|| endstop(&base).damping_n_s_per_m);
        continuation::frequency_branch(
            &with_endstop(&base, law, bim),
            P1_HIGH_ACCEL_RMS_G * s,
            P1_SWEEP_START_HZ,
            P1_STOP_HZ,
            P1_SWEEP_STEP_HZ,
            &Silent,
        )
    };
    let fig9 = |volts: f64| {
        let device = v.device.with_bias(volts);
        let settings =
            ContinuationSettings::amplitude(FIG9_RANGE_G.0 * s, FIG9_EXTEND_G * s, FIG9_STEP_G * s);
        let start = Forcing {
            freq_hz: P1_RESONANCE_HZ,
            accel_rms_g: FIG9_RANGE_G.0 * s,
        };
        continuation::branch_from_rest(&device, start, &settings, 200, &Silent)
    };
    let fig13 = |law, bim: Option<f64>, g: f64| {
        let base = v.device.with_bias(FIG13_BIAS_V);
        let bim = bim.unwrap_or_else(|| endstop(&base).damping_n_s_per_m);
        continuation::frequency_branch(
            &with_endstop(&base, law, bim),
            g * s,
            P2_RANGE_HZ.0,
            P2_RANGE_HZ.1,
            P2_STEP_HZ,
            &Silent,
        )
    };
    match case {
        "f8c" => fig8(StiffnessModel::Hertz, None),
        "f8d" => fig8(StiffnessModel::Hertz, Some(0.0)),
        "f8e" => fig8(StiffnessModel::Hertz, Some(10.0)),
        "f8f" => fig8(StiffnessModel::Linear, Some(2.0)),
        "f9-20" => fig9(20.0),
        "f9-30" => fig9(30.0),
        "f9-40" => fig9(40.0),
        "f13a" => fig13(StiffnessModel::Linear, None, 0.12),
        "f13b" => fig13(StiffnessModel::Linear, None, 0.31),
        "f13c" => fig13(StiffnessModel::Hertz, Some(P2_HERTZ_BIM), 0.31),
        other => Err(OrbitError::Invalid(format!("unknown case {other}"))),
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(label), Some(case)) = (args.first(), args.get(1)) else {
        return Err("usage: corner_probe <prototype:run> <case> [k]".into());
    };
    let k: f64 = args.get(2).map_or(Ok(4.0), |a| a.parse())?;
    let v = variant(label)?;
    for (name, scale) in [("plain", 1.0), ("perturbed", 1.0 + k * f64::EPSILON)] {
        let t0 = std::time::Instant::now();
        match run(&v, case, scale) {
            Ok(b) => {
                let events: Vec<String> = b
                    .events
                    .iter()
                    .map(|e| format!("{} {:.4}", e.label(), e.param))
                    .collect();
                println!(
                    "{label} {case} {name} {:.1} s: ends {:.4} after {} points; events [{}]",
                    t0.elapsed().as_secs_f64(),
                    b.params().last().unwrap_or(f64::NAN),
                    b.points.len(),
                    events.join(", ")
                );
            }
            Err(e) => println!(
                "{label} {case} {name} {:.1} s: FAILED {e}",
                t0.elapsed().as_secs_f64()
            ),
        }
    }
    Ok(())
}
