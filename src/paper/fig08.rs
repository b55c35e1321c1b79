//! Figure 8: prototype 1 at 30 V, stepped-sine up-sweeps from 900 to 1600 Hz at 4.1 and
//! 5.5 g rms with several end-stop models (claims F8-a to F8-f).

use crate::device::{Device, StiffnessModel};
use crate::paper::claims::{bool_value, ClaimValue};
use crate::paper::curves::{branch_end_value, find_curve, Curve, CurveSpec};
use crate::study::steady::steady_config;
use crate::study::stepped;
use crate::study::sweep::{SweepSettings, REFINE_TOL_HZ};

/// Prototype 1, Figure 8: the low acceleration, no impacts (g rms).
pub const P1_LOW_ACCEL_RMS_G: f64 = 4.1;

/// Prototype 1, Figure 8: the high acceleration, with impacts (g rms).
pub const P1_HIGH_ACCEL_RMS_G: f64 = 5.5;

/// Prototype 1, Figure 8: first frequency of the up-sweep (Hz).
pub const P1_SWEEP_START_HZ: f64 = 900.0;

/// Prototype 1, Figure 8: last frequency of the up-sweep (Hz).
pub const P1_SWEEP_STOP_HZ: f64 = 1600.0;

/// Prototype 1: default frequency step of the up-sweeps (Hz).
pub const P1_SWEEP_STEP_HZ: f64 = 10.0;

/// Prototype 1, Figure 8: 900-1600 Hz in 10 Hz steps (extended to 2400 Hz if needed),
/// [`steady_config`] at 1220 Hz, brackets of [`REFINE_TOL_HZ`].
pub fn sweep_settings(device: &Device) -> SweepSettings {
    SweepSettings {
        freqs_hz: stepped::linspace_step(P1_SWEEP_START_HZ, P1_SWEEP_STOP_HZ, P1_SWEEP_STEP_HZ),
        extend_to_hz: 2400.0,
        cfg: steady_config(device, 1220.0),
        refine_tol_hz: REFINE_TOL_HZ,
    }
}

/// Figure 8's curves (prototype 1, 30 V): 4.1 g Hertz 1.5; 5.5 g Hertz b_im = 0, 1.5, 10;
/// 5.5 g linear (eq 19) b_im = 2; and, as a sensitivity, 5.5 g Hertz 1.5 tension-free.
pub fn figure8_curves() -> Vec<CurveSpec> {
    use StiffnessModel::{Hertz, Linear};
    vec![
        CurveSpec::new(P1_LOW_ACCEL_RMS_G, Hertz, 1.5),
        CurveSpec::new(P1_HIGH_ACCEL_RMS_G, Hertz, 0.0),
        CurveSpec::new(P1_HIGH_ACCEL_RMS_G, Hertz, 1.5),
        CurveSpec::new(P1_HIGH_ACCEL_RMS_G, Hertz, 10.0),
        CurveSpec::new(P1_HIGH_ACCEL_RMS_G, Linear, 2.0),
        CurveSpec::new(P1_HIGH_ACCEL_RMS_G, Hertz, 1.5).tension_free(),
    ]
}

/// Figure 8's claim values from its curves ([`figure8_curves`]).
///
/// * F8-a: 1 if the 4.1 g sweep never touches a stop.
/// * F8-b: refined onset of the 5.5 g Hertz b_im = 1.5 sweep.
/// * F8-c, d, e, f: where the impacting branch of each 5.5 g sweep ends (jump, or loss of
///   contact when there is no jump; the note says which).
/// * F8-e order: 1 only if all three Hertz sweeps end with a confirmed jump and the jump
///   frequencies fall strictly as b_im grows.
pub fn figure8_claims(curves: &[Curve], stop_hz: f64) -> Vec<ClaimValue> {
    use StiffnessModel::{Hertz, Linear};
    let hi = P1_HIGH_ACCEL_RMS_G;
    let mut out = Vec::new();
    if let Some(c) = find_curve(curves, &CurveSpec::new(P1_LOW_ACCEL_RMS_G, Hertz, 1.5)) {
        let touched = c.report.any_contact();
        out.push(bool_value(
            "F8-a",
            "no_impact_4p1g",
            !touched,
            if touched {
                "the mass reaches the stops".into()
            } else {
                "no step of the sweep has contact".into()
            },
        ));
    }
    let h15 = find_curve(curves, &CurveSpec::new(hi, Hertz, 1.5));
    if let Some(t) = h15.and_then(|c| c.report.onset) {
        out.push(ClaimValue {
            id: "F8-b",
            quantity: "impact_onset_5p5g_hz",
            value: t.value(),
            uncertainty: Some(t.half_width()),
            note: "first contact, refined".into(),
        });
    }
    let jump_claims = [
        (
            "F8-c",
            "jump_hertz_bim1p5_hz",
            CurveSpec::new(hi, Hertz, 1.5),
        ),
        ("F8-d", "jump_hertz_bim0_hz", CurveSpec::new(hi, Hertz, 0.0)),
        (
            "F8-e",
            "jump_hertz_bim10_hz",
            CurveSpec::new(hi, Hertz, 10.0),
        ),
        (
            "F8-f",
            "jump_linear_bim2_hz",
            CurveSpec::new(hi, Linear, 2.0),
        ),
    ];
    for (id, q, spec) in jump_claims {
        if let Some(v) = find_curve(curves, &spec).and_then(|c| branch_end_value(id, q, c, stop_hz))
        {
            out.push(v);
        }
    }
    let jumps: Vec<Option<f64>> = [0.0, 1.5, 10.0]
        .iter()
        .map(|&b| {
            find_curve(curves, &CurveSpec::new(hi, Hertz, b))
                .and_then(|c| c.report.jump.map(|t| t.value()))
        })
        .collect();
    let (ordered, note) = match (jumps[0], jumps[1], jumps[2]) {
        (Some(j0), Some(j1), Some(j10)) => (
            j0 > j1 && j1 > j10,
            "all three sweeps jump; order of the jump frequencies".to_string(),
        ),
        _ => (
            false,
            "not every one of the three sweeps ends with a jump".to_string(),
        ),
    };
    out.push(bool_value("F8-e", "jump_order_by_bim", ordered, note));
    out
}
