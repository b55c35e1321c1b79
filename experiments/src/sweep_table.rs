//! The per-step table of up-sweeps (Figures 8, 13 and `endstop sweep`): one row per sweep step,
//! with the device options that produced it, in the project's column names (units in the names).

use anyhow::Result;
use endstop::device::Device;
use endstop::device::StiffnessModel;
use endstop::paper::claims::Claim;
use endstop::paper::claims::ClaimValue;
use endstop::paper::curves::Curve;
use endstop::study::steady::Measurement;
use polars::prelude::*;

/// Column builder: push sweeps, then take the data frame.
#[derive(Default)]
pub struct SweepTable {
    f: Vec<f64>,
    a: Vec<f64>,
    v1: Vec<f64>,
    v2: Vec<f64>,
    vd: Vec<f64>,
    p1: Vec<f64>,
    p2: Vec<f64>,
    x: Vec<f64>,
    cf: Vec<f64>,
    imp: Vec<f64>,
    blocks: Vec<u32>,
    conv: Vec<bool>,
    beyond: Vec<bool>,
    series: Vec<String>,
    params: Vec<String>,
    stiffness: Vec<String>,
    bim: Vec<f64>,
    tf: Vec<bool>,
    gap: Vec<f64>,
    bias: Vec<f64>,
}

impl SweepTable {
    /// Adds the steps of one sweep of `device` (the device as simulated: its parameter-set
    /// label, end-stop law, damping, gap and bias go into every row), labelled `series`. Steps
    /// from index `extended_from` on lie beyond the requested range.
    pub fn push<'a>(
        &mut self,
        series: &str,
        device: &Device,
        steps: impl Iterator<Item = &'a Measurement>,
        extended_from: Option<usize>,
    ) {
        let ext = extended_from.unwrap_or(usize::MAX);
        let law = match device.endstop.stiffness {
            StiffnessModel::Hertz => "hertz",
            StiffnessModel::Linear => "linear",
        };
        for (i, m) in steps.enumerate() {
            self.f.push(m.freq_hz);
            self.a.push(m.accel_rms_g);
            self.v1.push(m.v1_rms_v);
            self.v2.push(m.v2_rms_v);
            self.vd.push(m.vdiff_rms_v);
            self.p1.push(m.p1_w);
            self.p2.push(m.p2_w);
            self.x.push(m.x_peak_m);
            self.cf.push(m.contact_fraction);
            self.imp.push(m.impacts_per_period);
            self.blocks.push(m.blocks as u32);
            self.conv.push(m.converged);
            self.beyond.push(i >= ext);
            self.series.push(series.to_string());
            self.params.push(device.params.clone());
            self.stiffness.push(law.to_string());
            self.bim.push(device.endstop.damping_n_s_per_m);
            self.tf.push(device.endstop.tension_free);
            self.gap.push(device.geometry.endstop_gap_m);
            self.bias.push(device.electrical.bias_v);
        }
    }

    /// Adds every curve of a figure, each with its own end-stop options applied to `base`.
    pub fn push_curves(&mut self, base: &Device, curves: &[Curve]) {
        for c in curves {
            let dev = c.spec.device(base);
            self.push(
                &c.spec.label(),
                &dev,
                c.report.measurements(),
                c.report.extended_from,
            );
        }
    }

    /// The data frame (SI units unless the column name says otherwise).
    pub fn frame(self) -> Result<DataFrame> {
        Ok(df!(
            "freq_hz" => self.f,
            "accel_rms_g" => self.a,
            "v1_rms_v" => self.v1,
            "v2_rms_v" => self.v2,
            "vdiff_rms_v" => self.vd,
            "p1_w" => self.p1,
            "p2_w" => self.p2,
            "x_peak_m" => self.x,
            "contact_fraction" => self.cf,
            "impacts_per_period" => self.imp,
            "blocks" => self.blocks,
            "converged" => self.conv,
            "beyond_paper_range" => self.beyond,
            "series" => self.series,
            "params" => self.params,
            "stiffness" => self.stiffness,
            "bim_n_s_per_m" => self.bim,
            "tension_free" => self.tf,
            "endstop_gap_m" => self.gap,
            "bias_v" => self.bias,
        )?)
    }
}

/// One claim's cells in a generated table: (our value, what it is, verdict). Qualitative
/// claims read yes/no; numbers get `sig` significant digits and their bracket half-width.
pub fn claim_cells(claim: &Claim, values: &[ClaimValue], sig: usize) -> (String, String, String) {
    let Some(v) = values
        .iter()
        .find(|v| v.id == claim.id && v.quantity == claim.quantity)
    else {
        return ("-".into(), "no value".into(), "not yet".into());
    };
    let ours = if claim.unit == "bool" {
        if v.value > 0.5 { "yes" } else { "no" }.to_string()
    } else {
        format!(
            "{}{}",
            crate::fmt_sig(v.value, sig),
            v.uncertainty
                .map(|u| format!(" +- {}", crate::fmt_sig(u, 1)))
                .unwrap_or_default()
        )
    };
    (
        ours,
        v.note.clone(),
        claim.verdict(Some(v.value)).label().to_string(),
    )
}
