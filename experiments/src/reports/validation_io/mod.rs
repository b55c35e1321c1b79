//! The validation experiment (`experiments/validation.rs` runs it): every check of
//! `endstop::validation` with the cases of `endstop::validation::cases` (the ones
//! `tests/validation.rs` asserts), written as Parquet, two plots (`plots.rs`) and the book
//! chapter's generated tables (`tables.rs`), with the wall time of each case.

use std::time::Instant;

use anyhow::{Context, Result};
use endstop::device::Device;
use endstop::study::continuation::Branch;
use endstop::validation::band_limit;
use endstop::validation::nlvib::{self, Reference};
use endstop::validation::random_law::{self, LawEnsemble};
use endstop::validation::{cases, Check, ValidationError};

use crate::io::frame::frame;
use crate::reports::band_limit_io;
use crate::{row, write_atomic, Experiment};

mod plots;
mod tables;

use plots::{linear_plot, nlvib_plot};
use tables::{checks_table, cost_md, in_groups, measure_label, nlvib_md, random_md};

/// The wall time of one case, for the chapter's cost table.
struct Cost {
    case: String,
    what: String,
    wall_s: f64,
}

fn timed<T>(
    costs: &mut Vec<Cost>,
    case: &str,
    what: &str,
    f: impl FnOnce() -> Result<T, ValidationError>,
) -> Result<T> {
    let t = Instant::now();
    let out = f().with_context(|| format!("{case}: {what}"))?;
    costs.push(Cost {
        case: case.to_string(),
        what: what.to_string(),
        wall_s: t.elapsed().as_secs_f64(),
    });
    Ok(out)
}

fn load(exp: &mut Experiment, name: &str) -> Result<Device> {
    let d = crate::load_device(&format!("validation/{name}"))?;
    let set = d.device.params.clone();
    exp.uses(&d, &set);
    Ok(d.device)
}

/// The checks found so far and the wall time of each case, in the order they ran.
#[derive(Default)]
struct Tally {
    checks: Vec<Check>,
    costs: Vec<Cost>,
}

/// What the peer comparison with NLvib leaves for the Parquet files, the plot and the tables.
struct Peer {
    reference: Reference,
    exact_rows: Vec<nlvib::PointComparison>,
    branch: Branch,
    hb: Vec<nlvib::HbComparison>,
    aft_floor: f64,
    fold_floor: f64,
    samples: Vec<nlvib::BranchSample>,
}

/// Runs every check with its cases and writes the checks, their data, the plots and the
/// chapter's tables (the `validation` binary).
pub fn run() -> Result<()> {
    let mut exp = Experiment::start("validation");
    exp.seed = Some(cases::RANDOM_SEED);
    let mut tally = Tally::default();
    let (piezo, em) = closed_form_checks(&mut exp, &mut tally)?;
    impact_checks(&mut exp, &mut tally)?;
    let (band, ensembles) = random_checks(&mut exp, &mut tally)?;
    let peer = peer_checks(&mut exp, &mut tally)?;
    let springs = crate::reports::springs_io::run(&mut exp, load)?;
    tally.checks.extend(springs.checks.iter().cloned());
    tally
        .costs
        .extend(springs.costs.iter().map(|(c, w, s)| Cost {
            case: c.clone(),
            what: w.clone(),
            wall_s: *s,
        }));
    interface_checks(&mut exp, &mut tally)?;
    write_parquet(&mut exp, &tally.checks, &ensembles, &peer)?;
    exp.write_extra_plot(
        "validation_nlvib",
        &nlvib_plot(&peer.samples, &peer.reference),
    )?;
    exp.write_extra_plot("validation_linear", &linear_plot(&piezo, &em)?)?;
    write_tables(&mut exp, &tally, &band, &ensembles, &peer)?;
    exp.finish()
}

/// Closed forms: frequency response and optimal loads. Returns the piezoelectric and the
/// electromagnetic linear devices, for the plot.
fn closed_form_checks(exp: &mut Experiment, tally: &mut Tally) -> Result<(Device, Device)> {
    let Tally { checks, costs } = tally;
    let piezo = load(exp, "piezo_linear")?;
    let em = load(exp, "em_linear")?;
    let em0 = load(exp, "em_linear_no_inductance")?;
    for d in [&piezo, &em] {
        checks.extend(timed(costs, &d.name, "frequency response", || {
            cases::frequency_response(d)
        })?);
    }
    for d in [&piezo, &em, &em0] {
        checks.extend(timed(costs, &d.name, "optimal load", || {
            cases::optimal_load(d)
        })?);
    }
    Ok((piezo, em))
}

/// The grazing of the rigid-stop oscillator, and the impact damper of Masri & Caughey: its
/// closed form against our shooting.
fn impact_checks(exp: &mut Experiment, tally: &mut Tally) -> Result<()> {
    let Tally { checks, costs } = tally;
    let rigid = load(exp, "grazing_rigid")?;
    checks.extend(timed(costs, &rigid.name, "grazing continuations", || {
        cases::grazing(&rigid)
    })?);
    let damper = load(exp, "impact_damper")?;
    checks.extend(timed(costs, &damper.name, "symmetric orbits", || {
        endstop::validation::impact_damper::checks::orbit_checks(&damper)
    })?);
    checks.extend(timed(
        costs,
        &damper.name,
        "stability boundary line",
        || endstop::validation::impact_damper::checks::boundary_checks(&damper),
    )?);
    Ok(())
}

/// The white-noise law, and the recorded study of its band limit, which decides whether the
/// rigid stops' impact term is a reference or an open question.
fn random_checks(
    exp: &mut Experiment,
    tally: &mut Tally,
) -> Result<(Vec<band_limit::BandCell>, Vec<LawEnsemble>)> {
    let Tally { checks, costs } = tally;
    let band = band_limit_io::recorded_cells()?;
    let impact_term = band_limit::ImpactTerm::of(&band)?;
    checks.extend(band_limit::independent_checks(
        &band,
        &band_limit_io::independent_cells()?,
    )?);
    let mut ensembles: Vec<LawEnsemble> = Vec::new();
    for name in [
        "random_linear_piezo",
        "random_hertz_em",
        "random_restitution",
    ] {
        let d = load(exp, name)?;
        let ens = timed(
            costs,
            name,
            &format!(
                "{} records of {} s",
                cases::RANDOM_RECORDS,
                cases::RANDOM_RECORD_S
            ),
            || cases::random_law(&d),
        )?;
        checks.extend(random_law::checks(&ens, impact_term.limit()));
        ensembles.push(ens);
    }
    Ok((band, ensembles))
}

/// The peer tool: NLvib's orbits, continuation and harmonic balance against ours.
fn peer_checks(exp: &mut Experiment, tally: &mut Tally) -> Result<Peer> {
    let Tally { checks, costs } = tally;
    let sdof = load(exp, "nlvib_sdof")?;
    let ref_dir = crate::root().join("data/references/nlvib");
    let reference = Reference::parse(|name| {
        std::fs::read_to_string(ref_dir.join(name)).map_err(|e| ValidationError::Reference {
            file: format!("data/references/nlvib/{name}"),
            message: e.to_string(),
        })
    })?;
    let ours = nlvib::Ours::new(&sdof)?;
    let (exact_checks, exact_rows) = timed(costs, &sdof.name, "through every exact orbit", || {
        nlvib::exact_point_checks(&ours, &reference, cases::NLVIB_EXACT_STRIDE)
    })?;
    checks.extend(exact_checks);
    let branch = timed(costs, &sdof.name, "continuation 0.5 to 2.5 rad/s", || {
        ours.branch(
            0.5,
            2.5,
            cases::NLVIB_MAX_STEP_RAD_S,
            cases::NLVIB_LOCATE_TOL_RAD_S,
        )
    })?;
    checks.extend(nlvib::continuation_checks(
        &ours,
        &branch,
        &reference,
        cases::NLVIB_LOCATE_TOL_RAD_S,
    )?);
    let hb = timed(costs, &sdof.name, "amplitudes at NLvib's points", || {
        nlvib::hb_convergence(&ours, &branch, &reference)
    })?;
    let (aft_floor, fold_floor) = (reference.aft_floor_m(), reference.fold_floor_rad_s());
    checks.extend(nlvib::hb_checks(&hb, aft_floor, fold_floor));
    let samples = nlvib::branch_samples(&ours, &branch)?;
    Ok(Peer {
        reference,
        exact_rows,
        branch,
        hb,
        aft_floor,
        fold_floor,
        samples,
    })
}

/// The interface circuits against their closed forms.
fn interface_checks(exp: &mut Experiment, tally: &mut Tally) -> Result<()> {
    let Tally { checks, costs } = tally;
    let bridge = load(exp, "piezo_bridge")?;
    checks.extend(timed(
        costs,
        &bridge.name,
        "interface closed forms",
        || endstop::validation::interfaces::weak_coupling_checks(&bridge),
    )?);
    let coupling = timed(costs, &bridge.name, "coupling rows", || {
        endstop::validation::interfaces::coupling_rows(&bridge)
    })?;
    checks.extend(endstop::validation::interfaces::coupling_checks(&coupling));
    Ok(())
}

/// The checks, the random records and the peer comparison as Parquet.
fn write_parquet(
    exp: &mut Experiment,
    checks: &[Check],
    ensembles: &[LawEnsemble],
    peer: &Peer,
) -> Result<()> {
    let mut df = frame(checks.iter().map(|c| {
        row![
            "group" => c.group.clone(),
            "reference" => c.source.clone(),
            "quantity" => c.quantity.clone(),
            "theirs" => c.compared.reference,
            "ours" => c.compared.ours,
            "measure" => measure_label(c.compared.measure),
            "difference" => c.difference(),
            "tolerance" => c.compared.tolerance,
            "reason" => c.reason.clone(),
            "within_tolerance" => c.passes(),
            "open_question" => c.open.clone().unwrap_or_default(),
        ]
    }))?;
    exp.write_parquet("checks", &mut df, "hypothetical+reference")?;
    let mut df = frame(ensembles.iter().flat_map(|ens| {
        ens.records.iter().map(move |r| {
            row![
                "device" => ens.device.clone(),
                "psd_g2_per_hz" => ens.psd_g2_per_hz,
                "stream" => r.stream,
                "law_w" => ens.law_w,
                "drive_w" => r.drive_w,
                "dissipation_w" => r.dissipation_w,
                "mech_damping_w" => r.mech_damping_w,
                "stop_w" => r.stop_w,
                "impact_losses_w" => r.impact_losses_w,
                "loads_w" => r.loads_w,
                "coil_w" => r.internal_w,
                "impacts_per_s" => r.impacts_per_s,
                "relative_residual" => r.relative_residual,
                "exponential_free_flight" => r.exponential,
            ]
        })
    }))?;
    exp.write_parquet("random_records", &mut df, "hypothetical")?;
    let mut df = frame(peer.samples.iter().map(|s| {
        row![
            "omega_rad_s" => s.omega_rad_s,
            "a1_amplitude_m" => s.a1_amplitude_m,
            "max_floquet_modulus" => s.max_multiplier,
            "stable" => s.stable,
            "impacting" => s.impacting,
        ]
    }))?;
    exp.write_parquet("nlvib_branch", &mut df, "reference")?;
    let mut df = frame(peer.exact_rows.iter().map(|r| {
        row![
            "segment" => r.exact.segment,
            "omega_rad_s" => r.exact.omega_rad_s,
            "a1_amplitude_m_exact" => r.exact.a1_amplitude_m,
            "a1_amplitude_m_ours" => r.a1_amplitude_m,
            "max_floquet_modulus_exact" => r.exact.max_floquet_modulus_variational,
            "max_floquet_modulus_ours" => r.max_multiplier,
            "stable_exact" => r.exact.stable,
            "stable_ours" => r.stable,
        ]
    }))?;
    exp.write_parquet("nlvib_exact", &mut df, "reference")?;
    let mut df = frame(peer.hb.iter().flat_map(|c| {
        c.amplitudes.iter().map(move |(part, w, theirs, ours)| {
            row![
                "harmonics_h" => c.harmonics,
                "part" => part.label(),
                "omega_rad_s" => *w,
                "a1_amplitude_m_nlvib" => *theirs,
                "a1_amplitude_m_ours" => *ours,
            ]
        })
    }))?;
    exp.write_parquet("nlvib_hb", &mut df, "reference")?;
    Ok(())
}

/// The chapter's tables and the experiment's numbers.
fn write_tables(
    exp: &mut Experiment,
    tally: &Tally,
    band: &[band_limit::BandCell],
    ensembles: &[LawEnsemble],
    peer: &Peer,
) -> Result<()> {
    let (checks, costs) = (&tally.checks, &tally.costs);
    let book = &exp.book_dir;
    let within = checks.iter().filter(|c| c.passes()).count();
    let judged = checks.iter().filter(|c| !c.is_open()).count();
    let label = |c: &&Check| crate::io::md::plain(&format!("{}: {}", c.group, c.quantity));
    let not_met: Vec<String> = checks
        .iter()
        .filter(|c| !c.passes() && !c.is_open())
        .map(|c| label(&c))
        .collect();
    let open: Vec<String> = checks
        .iter()
        .filter(|c| c.is_open())
        .map(|c| label(&c))
        .collect();
    let mut summary = format!("**{within} of {judged} checks are within their tolerances.**");
    if !not_met.is_empty() {
        summary.push_str(&format!(" Not met: {}.", not_met.join("; ")));
    }
    if !open.is_empty() {
        summary.push_str(&format!(
            " Reported as open questions, not judged: {}.",
            open.join("; ")
        ));
    }
    summary.push('\n');
    exp.write_numbers_md(&summary)?;
    write_atomic(
        &book.join("closed_forms.md"),
        checks_table(
            in_groups(checks, "frequency response").chain(in_groups(checks, "optimal load")),
        )
        .as_bytes(),
    )?;
    write_atomic(
        &book.join("random.md"),
        random_md(ensembles, checks).as_bytes(),
    )?;
    write_atomic(
        &book.join("grazing.md"),
        checks_table(in_groups(checks, "grazing")).as_bytes(),
    )?;
    write_atomic(
        &book.join("nlvib.md"),
        nlvib_md(
            checks,
            &peer.hb,
            peer.aft_floor,
            peer.fold_floor,
            &peer.branch,
            &peer.samples,
        )
        .as_bytes(),
    )?;
    write_atomic(
        &book.join("band_limit.md"),
        format!(
            "{}\n{}",
            band_limit_io::table_md(band)?,
            checks_table(in_groups(checks, "band limit: independent simulation"))
        )
        .as_bytes(),
    )?;
    write_atomic(
        &book.join("springs.md"),
        checks_table(
            in_groups(checks, "exact stationary law")
                .chain(in_groups(checks, "peer: NLvib's Duffing")),
        )
        .as_bytes(),
    )?;
    write_atomic(
        &book.join("escapes.md"),
        checks_table(in_groups(checks, "escape over the barrier")).as_bytes(),
    )?;
    write_atomic(
        &book.join("interfaces.md"),
        checks_table(
            in_groups(checks, "interface circuits, weak coupling")
                .chain(in_groups(checks, "interface circuits, coupling")),
        )
        .as_bytes(),
    )?;
    write_atomic(
        &book.join("impact_damper.md"),
        checks_table(in_groups(checks, "impact damper")).as_bytes(),
    )?;
    write_atomic(&book.join("cost.md"), cost_md(costs).as_bytes())?;
    exp.number("checks", judged as f64);
    exp.number("open_questions", open.len() as f64);
    exp.number("checks_within_tolerance", within as f64);
    Ok(())
}
