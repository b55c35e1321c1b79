//! Figure 13: prototype 2 at 10 V, up-sweeps from 600 to 850 Hz at 0.12 and 0.31 g rms
//! (claim F13).

use crate::device::{Device, StiffnessModel};
use crate::paper::claims::{bool_value, ClaimValue};
use crate::paper::curves::{find_curve, Curve, CurveSpec};
use crate::study::steady::steady_config;
use crate::study::stepped;
use crate::study::sweep::{SweepSettings, REFINE_TOL_HZ};

/// Prototype 2, Figure 13: 600-850 Hz in 2 Hz steps (extended to 1200 Hz if needed),
/// [`steady_config`] at 700 Hz, brackets of [`REFINE_TOL_HZ`].
pub fn sweep_settings(device: &Device) -> SweepSettings {
    SweepSettings {
        freqs_hz: stepped::linspace_step(600.0, 850.0, 2.0),
        extend_to_hz: 1200.0,
        cfg: steady_config(device, 700.0),
        refine_tol_hz: REFINE_TOL_HZ,
    }
}

/// Figure 13's curves (prototype 2, 10 V): 0.12 and 0.31 g with the linear law and
/// b_im = 0.4 N s/m, and 0.31 g with the Hertz law and b_im = 0.34 N s/m.
pub fn figure13_curves() -> Vec<CurveSpec> {
    use StiffnessModel::{Hertz, Linear};
    vec![
        CurveSpec::new(0.12, Linear, 0.4),
        CurveSpec::new(0.31, Linear, 0.4),
        CurveSpec::new(0.31, Hertz, 0.34),
    ]
}

/// Figure 13's claim values from its curves ([`figure13_curves`]).
///
/// * no impact at 0.12 g: 1 if no step has contact;
/// * jump at 0.31 g: 1 if the linear-law sweep has contact and a confirmed jump;
/// * Hertz and linear agree: 1 if both 0.31 g sweeps jump and their jump frequencies differ
///   by at most 3 % (the frequency tolerance class) of the linear one.
pub fn figure13_claims(curves: &[Curve]) -> Vec<ClaimValue> {
    use StiffnessModel::{Hertz, Linear};
    let mut out = Vec::new();
    if let Some(c) = find_curve(curves, &CurveSpec::new(0.12, Linear, 0.4)) {
        let touched = c.report.any_contact();
        out.push(bool_value(
            "F13",
            "no_impact_0p12g",
            !touched,
            if touched {
                "the mass reaches the stops".into()
            } else {
                "no step of the sweep has contact".into()
            },
        ));
    }
    let lin = find_curve(curves, &CurveSpec::new(0.31, Linear, 0.4));
    let her = find_curve(curves, &CurveSpec::new(0.31, Hertz, 0.34));
    if let Some(c) = lin {
        let yes = c.report.any_contact() && c.report.jump.is_some();
        out.push(bool_value(
            "F13",
            "jump_0p31g",
            yes,
            match c.report.jump {
                Some(_) => "impacts and a confirmed jump".into(),
                None => "no confirmed jump".into(),
            },
        ));
    }
    if let (Some(l), Some(h)) = (lin, her) {
        let (agree, note) = match (l.report.jump, h.report.jump) {
            (Some(jl), Some(jh)) => {
                let rel = (jh.value() - jl.value()).abs() / jl.value();
                (
                    rel <= 0.03,
                    "relative difference of the jumps vs 3 %".to_string(),
                )
            }
            _ => (false, "a sweep has no jump".to_string()),
        };
        out.push(bool_value("F13", "hertz_linear_agree", agree, note));
    }
    out
}
