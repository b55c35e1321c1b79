//! Figure 9: prototype 1 at its measured resonance, amplitude sweeps at 20, 30 and 40 V
//! (claims F9-a and F9-b).

use crate::device::{Device, StiffnessModel};
use crate::ode::SolverError;
use crate::paper::claims::{bool_value, ClaimValue};
use crate::paper::measured::P1_RESONANCE_HZ;
use crate::study::amplitude::{AmplitudeReport, AmplitudeSettings};
use crate::study::steady::{steady_config, Measurement};
use crate::study::stepped;

/// Figure 9's bias voltages (V).
pub const FIG9_BIASES_V: [f64; 3] = [20.0, 30.0, 40.0];

/// Figure 9's end-stop model: the Hertz fit of Figure 8 (the paper does not say).
pub const FIG9_BIM_N_S_PER_M: f64 = 1.5;

/// Two onsets are "the same" when they differ by at most this (g): the amplitude-threshold
/// tolerance class of the claims file.
pub const ONSET_SAME_TOL_G: f64 = 0.25;

/// Which power Figure 9 plots (the paper does not say; see the book's "Readings of ambiguities").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PowerReading {
    /// The power of one load, <V1^2>/RL.
    OneLoad,
    /// The power of both loads, <V1^2 + V2^2>/RL.
    BothLoads,
}

impl PowerReading {
    /// The power of a measurement under this reading (W).
    pub fn of(self, m: &Measurement) -> f64 {
        match self {
            PowerReading::OneLoad => m.p1_w,
            PowerReading::BothLoads => m.p_total_w(),
        }
    }

    /// Label for tables.
    pub fn label(self) -> &'static str {
        match self {
            PowerReading::OneLoad => "one load",
            PowerReading::BothLoads => "both loads",
        }
    }
}

/// One bias voltage of Figure 9.
#[derive(Debug, Clone)]
pub struct AmplitudeCurve {
    /// Bias voltage (V).
    pub bias_v: f64,
    /// The continuation.
    pub report: AmplitudeReport,
}

/// Figure 9: prototype 1 at its measured resonance 1220 Hz, 0.5-5.5 g rms in 0.1 g steps
/// (extended to 8 g if needed), [`steady_config`] at 1220 Hz, onset brackets of 0.005 g.
pub fn amplitude_settings(device: &Device) -> AmplitudeSettings {
    AmplitudeSettings {
        freq_hz: P1_RESONANCE_HZ,
        accels_rms_g: stepped::linspace_step(0.5, 5.5, 0.1),
        extend_to_g: 8.0,
        cfg: steady_config(device, P1_RESONANCE_HZ),
        refine_tol_g: 0.005,
    }
}

/// Runs Figure 9's amplitude continuations (one per bias voltage in `biases_v`) in parallel;
/// the device's end-stop is set to Hertz with [`FIG9_BIM_N_S_PER_M`].
pub fn run_figure9(
    device: &Device,
    biases_v: &[f64],
    settings: &AmplitudeSettings,
    on_step: &(dyn Fn() + Sync),
) -> Result<Vec<AmplitudeCurve>, SolverError> {
    use rayon::prelude::*;
    let dev = device.with_endstop(StiffnessModel::Hertz, FIG9_BIM_N_S_PER_M);
    biases_v
        .par_iter()
        .map(|&vb| {
            let report = settings.run(&dev.with_bias(vb), |_| on_step())?;
            Ok(AmplitudeCurve { bias_v: vb, report })
        })
        .collect()
}

/// Figure 9's claim values under a power reading.
///
/// * F9-a: refined onsets at 20, 30, 40 V (found beyond 5.5 g by the extension if needed;
///   the note says so); "the same for all" is 1 when all exist and their spread is at most
///   [`ONSET_SAME_TOL_G`].
/// * F9-b: the power at 5.5 g at 20 and 40 V (nW) and their ratio.
pub fn figure9_claims(curves: &[AmplitudeCurve], reading: PowerReading) -> Vec<ClaimValue> {
    let mut out = Vec::new();
    let by_vb = |vb: f64| curves.iter().find(|c| c.bias_v == vb);
    let mut onsets = Vec::new();
    for (vb, q) in [
        (20.0, "onset_g_20v"),
        (30.0, "onset_g_30v"),
        (40.0, "onset_g_40v"),
    ] {
        let Some(c) = by_vb(vb) else { continue };
        onsets.push(c.report.onset.map(|t| t.value()));
        if let Some(t) = c.report.onset {
            let beyond = c.report.extended_from.is_some();
            out.push(ClaimValue {
                id: "F9-a",
                quantity: q,
                value: t.value(),
                uncertainty: Some(t.half_width()),
                note: if beyond {
                    "first contact, beyond the paper's 5.5 g (extended continuation)".into()
                } else {
                    "first contact, refined".into()
                },
            });
        }
    }
    let all: Option<Vec<f64>> = onsets.iter().copied().collect();
    let (same, note) = match all {
        Some(v) if v.len() == 3 => {
            let spread = v.iter().cloned().fold(f64::MIN, f64::max)
                - v.iter().cloned().fold(f64::MAX, f64::min);
            (
                spread <= ONSET_SAME_TOL_G,
                format!("spread of the three onsets vs {ONSET_SAME_TOL_G} g"),
            )
        }
        _ => (false, "an onset is missing".to_string()),
    };
    out.push(bool_value("F9-a", "onset_same_all_vb", same, note));
    let p = |vb: f64| by_vb(vb).map(|c| reading.of(c.report.at_stop()));
    let note = format!("{} at 5.5 g", reading.label());
    if let Some(p20) = p(20.0) {
        out.push(ClaimValue {
            id: "F9-b",
            quantity: "p_sat_20v_nw",
            value: p20 * 1e9,
            uncertainty: None,
            note: note.clone(),
        });
    }
    if let Some(p40) = p(40.0) {
        out.push(ClaimValue {
            id: "F9-b",
            quantity: "p_sat_40v_nw",
            value: p40 * 1e9,
            uncertainty: None,
            note: note.clone(),
        });
    }
    if let (Some(p20), Some(p40)) = (p(20.0), p(40.0)) {
        out.push(ClaimValue {
            id: "F9-b",
            quantity: "p_sat_ratio_40v_20v",
            value: p40 / p20,
            uncertainty: None,
            note,
        });
    }
    out
}
