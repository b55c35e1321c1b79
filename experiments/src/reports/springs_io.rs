//! The nonlinear-spring rows of the validation experiment: the exact stationary law on three
//! devices, the escape over a double well's barrier and NLvib's Duffing example, with the
//! cases of `endstop::validation::spring_cases` (those `tests/springs_validation.rs` asserts),
//! and their data as Parquet.

use anyhow::{Context, Result};
use endstop::device::Device;
use endstop::validation::nlvib_duffing::{self, DuffingComparison, DuffingReference};
use endstop::validation::stationary_law::StationaryLaw;
use endstop::validation::{spring_cases, Check, ValidationError};

use crate::io::frame::frame;
use crate::io::plot::{error_bars, LinePlot, Panels, Series, Style, PALETTE};
use crate::{row, Experiment};

/// One exact-law case's panel: the ensemble's displacement density with its interval across
/// records (`density`: x (m), density (1/m), half-width of its 95 % interval (1/m)) beside
/// the exact stationary law.
fn density_panel(
    name: &str,
    psd_g2_per_hz: f64,
    density: &[(f64, f64, f64)],
    law: &StationaryLaw,
) -> LinePlot {
    let um = |x: f64| x * 1e6;
    let mut series = vec![Series::new(
        "ensemble (bars: 95 %)",
        density.iter().map(|d| (um(d.0), d.1 / 1e6)).collect(),
        PALETTE[0],
        Style::Points,
    )];
    series.extend(error_bars(
        density.iter().map(|d| (um(d.0), d.1 / 1e6, d.2 / 1e6)),
        PALETTE[0],
    ));
    series.push(Series::new(
        "exact law exp(-U/theta)",
        density
            .iter()
            .map(|d| (um(d.0), law.density(d.0) / 1e6))
            .collect(),
        PALETTE[1],
        Style::Line,
    ));
    LinePlot::new(
        &format!("{name}, Sa = {psd_g2_per_hz:e} g^2/Hz"),
        "displacement x [um]",
        "probability density [1/um]",
        series,
    )
}

/// What the rows computed, for the chapter's text.
pub struct SpringRows {
    /// Every check.
    pub checks: Vec<Check>,
    /// NLvib's Duffing example per H.
    pub duffing: Vec<DuffingComparison>,
    /// (case, what, wall time in s).
    pub costs: Vec<(String, String, f64)>,
}

/// Runs the rows; `load` reads a device of `data/validation/`.
pub fn run(
    exp: &mut Experiment,
    mut load: impl FnMut(&mut Experiment, &str) -> Result<Device>,
) -> Result<SpringRows> {
    let mut checks = Vec::new();
    let mut costs = Vec::new();
    let mut densities = Vec::new();
    let mut panels = Vec::new();
    let mut timed = |case: &str, what: &str, t: std::time::Instant| {
        costs.push((
            case.to_string(),
            what.to_string(),
            t.elapsed().as_secs_f64(),
        ));
    };
    for (name, psd) in spring_cases::STATIONARY_CASES {
        let d = load(exp, name)?;
        let t = std::time::Instant::now();
        let (ens, c) = spring_cases::stationary(&d, psd).with_context(|| name.to_string())?;
        timed(
            name,
            &format!(
                "{} records of {} s",
                spring_cases::STATIONARY_RECORDS,
                spring_cases::STATIONARY_RECORD_S
            ),
            t,
        );
        checks.extend(c);
        let law = StationaryLaw::of(&d, &spring_cases::spec(&d, psd, 1.0))?;
        panels.push(density_panel(name, psd, &ens.density(), &law));
        for (x, p, ci) in ens.density() {
            densities.push(row![
                "device" => name,
                "x_m" => x,
                "density_per_m" => p,
                "density_ci95_per_m" => ci,
                "exact_density_per_m" => law.density(x),
            ]);
        }
    }
    exp.write_parquet("springs_density", &mut frame(densities)?, "hypothetical")?;
    exp.write_extra_plot("validation_springs_density", &Panels::row(panels))?;

    let mut rows = Vec::new();
    for case in spring_cases::ESCAPE_CASES {
        let kd = load(exp, case.file)?;
        let t = std::time::Instant::now();
        let (levels, c) = spring_cases::escapes(&kd, &case)?;
        timed(
            case.file,
            &format!(
                "{} levels of {} records of {} s",
                case.ratios.len(),
                case.records,
                spring_cases::KRAMERS_RECORD_S
            ),
            t,
        );
        checks.extend(c);
        for l in &levels {
            let (p, s, th) = (
                l.ensemble.passage_rate(),
                l.ensemble.settled_rate(),
                &l.theory,
            );
            rows.push(row![
                "device" => case.file,
                "barrier_over_theta" => th.barrier_over_theta,
                "energy_loss_delta" => th.loss,
                "regime" => format!("{:?}", th.regime),
                "passages_per_s" => p.mean,
                "passages_ci95_per_s" => p.ci95,
                "rice_passages_per_s" => th.passage_rate_per_s,
                "settled_escapes_per_s" => s.mean,
                "settled_escapes_ci95_per_s" => s.ci95,
                "settled_reference_per_s" => th.settled_reference_per_s(),
                "kramers_per_s" => th.kramers_per_s,
                "kramers_harmonic_per_s" => th.kramers_harmonic_per_s,
                "energy_diffusion_half_per_s" => 0.5 * th.diffusion_escape_per_s,
                "own_error" => th.own_error(),
                "passages" => l.ensemble.passages(),
                "settled_escapes" => l.ensemble.settled(),
            ]);
        }
    }
    exp.write_parquet("springs_kramers", &mut frame(rows)?, "hypothetical")?;

    let duffing = load(exp, "nlvib_duffing")?;
    let dir = crate::root().join("data/references/nlvib_duffing");
    let reference = DuffingReference::parse(|name| {
        std::fs::read_to_string(dir.join(name)).map_err(|e| ValidationError::Reference {
            file: format!("data/references/nlvib_duffing/{name}"),
            message: e.to_string(),
        })
    })?;
    let t = std::time::Instant::now();
    let ours = nlvib_duffing::Ours::new(&duffing)?;
    let branch = ours.branch(0.5, 1.6, spring_cases::NLVIB_DUFFING_MAX_STEP_RAD_S)?;
    let hb = nlvib_duffing::hb_convergence(&ours, &branch, &reference)?;
    timed(
        "nlvib_duffing",
        "continuation 0.5 to 1.6 rad/s and NLvib's points",
        t,
    );
    checks.extend(nlvib_duffing::checks(&hb));
    let rows = hb.iter().flat_map(|c| {
        c.points.iter().map(move |p| {
            row![
                "harmonics_h" => c.harmonics,
                "part" => ["resonant", "middle", "low"][p.0],
                "omega_rad_s" => p.1,
                "a1_amplitude_m_nlvib" => p.2,
                "a1_amplitude_m_ours" => p.3,
                "nlvib_between_folds" => p.4,
                "stable_ours" => p.5,
            ]
        })
    });
    exp.write_parquet("nlvib_duffing", &mut frame(rows)?, "reference")?;
    Ok(SpringRows {
        checks,
        duffing: hb,
        costs,
    })
}

/// The paired cost of a nonlinear device's record against its linear twin: the same device
/// with a linear suspension of the reference well's stiffness (the same small-oscillation
/// frequency, mass, damping, stops and transducer), one 10 s record each at `psd_g2_per_hz`,
/// alternating `repeats` times so that a change of the machine's speed hits both.
pub struct PairedCost {
    /// Wall times of the nonlinear device's records (s), sorted.
    pub nonlinear_s: Vec<f64>,
    /// Wall times of the linear twin's records (s), sorted.
    pub linear_s: Vec<f64>,
    /// Each pair's ratio (nonlinear over linear), sorted.
    pub ratios: Vec<f64>,
    /// How each record's free flight went (nonlinear, linear).
    pub paths: (String, String),
    /// The nonlinear record's summary.
    pub summary: endstop::study::record::RecordSummary,
}

/// Runs the pairs (see [`PairedCost`]).
pub fn paired_record_cost(
    device: &Device,
    psd_g2_per_hz: f64,
    repeats: usize,
) -> Result<PairedCost> {
    use endstop::study::record::{simulate_record, FreeFlightPath};
    let mut twin = device.clone();
    twin.mechanics.suspension = endstop::device::Suspension::Linear;
    twin.name = format!("{}_linear_twin", device.name);
    let spec = endstop::paper::setups::paper_record(device, psd_g2_per_hz);
    let label = |p: FreeFlightPath| match p {
        FreeFlightPath::Exponential => "exponential".to_string(),
        FreeFlightPath::Affine => "exact affine modes".to_string(),
        FreeFlightPath::Dopri5(why) => format!("dormand-prince: {why}"),
    };
    let (mut a, mut b, mut r) = (Vec::new(), Vec::new(), Vec::new());
    let mut paths = (String::new(), String::new());
    let mut summary = None;
    for _ in 0..repeats {
        let t = std::time::Instant::now();
        let rn = simulate_record(device, &spec, 2012, 0)?;
        let tn = t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        let rl = simulate_record(&twin, &spec, 2012, 0)?;
        let tl = t.elapsed().as_secs_f64();
        paths = (label(rn.summary.free_flight), label(rl.summary.free_flight));
        summary = Some(rn.summary);
        a.push(tn);
        b.push(tl);
        r.push(tn / tl);
    }
    for v in [&mut a, &mut b, &mut r] {
        v.sort_by(f64::total_cmp);
    }
    Ok(PairedCost {
        nonlinear_s: a,
        linear_s: b,
        ratios: r,
        paths,
        summary: summary.context("at least one pair")?,
    })
}
