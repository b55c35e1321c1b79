//! The I/O shared by the sine-sweep experiments (Figures 8, 9 and 13, and `endstop sweep`):
//! the per-step rows of a sweep in the project's column names (through [`crate::io::frame`]), and
//! the cells of the claims and convergence tables of the book.

use endstop::device::{Device, StiffnessModel, Stop, StopLaw};
use endstop::paper::claims::{Answer, Claim, Value};
use endstop::paper::curves::{law_key, Curve, CurveConvergence};
use endstop::paper::setups::ParamSet;
use endstop::study::mass_peaks::MassPeaks;
use endstop::study::steady::Measurement;

use crate::io::frame::{column_name, Cell, Row};
use crate::io::md::Table;
use crate::row;

/// The columns of one steady-state measurement, between the columns that say where it was
/// taken and those that say what was simulated: RMS voltages, powers, peak displacement,
/// contact, measured blocks and convergence. SI units unless the name says otherwise.
pub fn measurement_cells(m: &Measurement) -> Row {
    row![
        "v1_rms_v" => m.v1_rms_v,
        "v2_rms_v" => m.v2_rms_v,
        "vdiff_rms_v" => m.vdiff_rms_v,
        "p1_w" => m.p1_w,
        "p2_w" => m.p2_w,
        "x_peak_m" => m.x_peak_m,
        "contact_fraction" => m.contact_fraction,
        "impacts_per_period" => m.impacts_per_period,
        "blocks" => m.blocks as u32,
        "converged" => m.converged,
    ]
}

/// The per-mass column names of `device`'s model ([`MassPeaks::column_names`]: each mass's
/// `x_<mass>_peak_m` and `v_<mass>_peak_m_per_s`), none for a device of one mass.
pub fn mass_columns(device: &Device) -> anyhow::Result<Vec<&'static str>> {
    let names: Vec<String> = endstop::with_harvester!(device, |h| {
        use endstop::model::Model;
        Ok::<_, anyhow::Error>(MassPeaks::column_names(h.layout()))
    })?;
    Ok(names.iter().map(|n| column_name(n)).collect())
}

/// The cells of `peaks` under the columns `names` of [`mass_columns`] (null where a peak was
/// not measured).
pub fn mass_cells(names: &[&'static str], peaks: &MassPeaks) -> Row {
    let values = peaks.values();
    names
        .iter()
        .enumerate()
        .map(|(i, n)| (*n, Cell::from(values.get(i).copied())))
        .collect()
}

/// One row per step of a sweep of `device` (the device as simulated: its parameter-set label,
/// end-stop law, damping, gap and bias go into every row, see [`device_cells`]), labelled
/// `series`. Steps from index `extended_from` on lie beyond the requested range. SI units
/// unless the name says otherwise.
pub fn sweep_rows<'a>(
    series: &str,
    device: &Device,
    steps: impl Iterator<Item = &'a Measurement>,
    extended_from: Option<usize>,
) -> Vec<Row> {
    let beyond_from = extended_from.unwrap_or(usize::MAX);
    steps
        .enumerate()
        .map(|(i, m)| {
            [
                row!["freq_hz" => m.freq_hz, "accel_rms_g" => m.accel_rms_g],
                measurement_cells(m),
                row![
                    "beyond_paper_range" => i >= beyond_from,
                    "series" => series,
                ],
                device_cells(device),
            ]
            .concat()
        })
        .collect()
}

/// The columns that say which device was simulated: `params`, `stiffness` (the paper's
/// `hertz` or `linear` for its Hertz line stops, else the law key of a symmetric pair, or
/// `upper:<law>/lower:<law>` with `none` for a missing side), `bim_n_s_per_m` and
/// `endstop_gap_m` (those of a symmetric pair, null otherwise), `tension_free` (of any stop)
/// and `bias_v` (null without an electrostatic transducer).
pub fn device_cells(device: &Device) -> Row {
    let sym = device.stops.symmetric();
    let law = |s: Option<&Stop>| match s {
        Some(Stop {
            law: StopLaw::HertzLine(h),
            ..
        }) => law_key(if h.linear_fit {
            StiffnessModel::Linear
        } else {
            StiffnessModel::Hertz
        }),
        Some(s) => s.law.key(),
        None => "none",
    };
    let stiffness = match sym {
        Some(s) => law(Some(s)).to_string(),
        None => format!(
            "upper:{}/lower:{}",
            law(device.stops.upper.as_ref()),
            law(device.stops.lower.as_ref())
        ),
    };
    row![
        "params" => device.params.as_str(),
        "stiffness" => stiffness,
        "bim_n_s_per_m" => sym.map(|s| s.damping_n_s_per_m),
        "tension_free" => device.stops.present().any(|(_, s)| s.tension_free),
        "endstop_gap_m" => sym.map(|s| s.gap_m),
        "bias_v" => device.bias_v(),
    ]
}

/// The rows of every curve of a figure, each with its own end-stop model applied to `base`.
pub fn curve_rows(base: &Device, curves: &[Curve]) -> Vec<Row> {
    curves
        .iter()
        .flat_map(|c| {
            sweep_rows(
                &c.spec.label(),
                &c.spec.device(base),
                c.report.measurements(),
                c.report.extended_from,
            )
        })
        .collect()
}

/// One claim's cells in a generated table under a parameter set: (our value, what it is,
/// verdict). Qualitative claims read yes/no; numbers get `sig` significant digits and their
/// bracket half-width.
pub fn claim_cells(claim: &Claim, values: &[Value], set: ParamSet, sig: usize) -> [String; 3] {
    let Some(v) = values
        .iter()
        .find(|v| v.claim == claim.id && v.quantity == claim.quantity && v.set == set)
    else {
        return ["-".into(), "no value".into(), "not yet".into()];
    };
    let ours = match v.ours {
        Answer::YesNo(yes) => yes_no(yes).to_string(),
        Answer::Number(x) => format!(
            "{}{}",
            crate::fmt_sig(x, sig),
            v.uncertainty
                .map(|u| format!(" +- {}", crate::fmt_sig(u, 1)))
                .unwrap_or_default()
        ),
    };
    [
        ours,
        v.note.clone(),
        format!("**{}**", claim.verdict(Some(v.ours)).label()),
    ]
}

/// The paper's value of a claim for a table: yes/no for a qualitative claim.
pub fn paper_cell(claim: &Claim) -> String {
    match claim.paper {
        Answer::YesNo(yes) => yes_no(yes).to_string(),
        Answer::Number(v) => format!("{v} {}", claim.unit),
    }
}

/// A yes/no as the tables write it.
fn yes_no(yes: bool) -> &'static str {
    if yes {
        "yes"
    } else {
        "no"
    }
}

/// The claims table of a prototype 1 figure under both parameter sets: claim, quantity,
/// paper, then our value, what it is and the verdict under each set.
pub fn claims_table_both_sets<'a>(
    claims: impl Iterator<Item = &'a Claim>,
    values: &[Value],
    sig: usize,
) -> Table<9> {
    let mut t = Table::new([
        "claim",
        "quantity",
        "paper",
        "published: ours",
        "what",
        "verdict",
        "calibrated: ours",
        "what",
        "verdict",
    ]);
    for c in claims {
        let [a, b, v] = claim_cells(c, values, ParamSet::Published, sig);
        let [d, e, w] = claim_cells(c, values, ParamSet::Calibrated, sig);
        t.row([
            c.id.clone(),
            format!("`{}`", c.quantity),
            paper_cell(c),
            a,
            b,
            v,
            d,
            e,
            w,
        ]);
    }
    t
}

/// The columns of a convergence table of up-sweeps, after those that name the sweep.
pub const CONVERGENCE_COLUMNS: [&str; 7] = [
    "onset change",
    "branch end change",
    "same kind of end",
    "max V1 change",
    "max V2 change",
    "frequencies compared / excluded",
    "within limits",
];

/// One sweep's cells in a convergence table, in the order of [`CONVERGENCE_COLUMNS`].
pub fn convergence_cells(v: &CurveConvergence) -> [String; 7] {
    let cmp = v.comparison;
    [
        pct(cmp.onset_rel),
        pct(cmp.end_rel),
        if cmp.same_end_kind { "yes" } else { "no" }.into(),
        pct(Some(cmp.max_v1_rel)),
        pct(Some(cmp.max_v2_rel)),
        format!("{} / {}", cmp.compared, cmp.excluded),
        if v.within_limits { "yes" } else { "**no**" }.into(),
    ]
}

/// A frequency (Hz) for a table with 5 significant digits, "none" if absent.
pub fn hz(x: Option<f64>) -> String {
    x.map(|v| crate::fmt_sig(v, 5))
        .unwrap_or_else(|| "none".into())
}

/// A relative change as a percentage with 2 significant digits, "n/a" if absent.
pub fn pct(x: Option<f64>) -> String {
    match x {
        Some(v) if v.is_finite() => format!("{} %", crate::fmt_sig(100.0 * v, 2)),
        _ => "n/a".into(),
    }
}
