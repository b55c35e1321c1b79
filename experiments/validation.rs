//! Validation against references: runs every check of `endstop::validation` with the cases of
//! `endstop::validation::cases` (the ones `tests/validation.rs` asserts), and writes the checks
//! and their data as Parquet, two plots, and the book chapter's generated tables
//! (`book/src/generated/validation/`). A check outside its tolerance is reported as such in the
//! tables (the tests fail on it); the run itself fails only when a check cannot be computed.
//! It reads the recorded band-limit study; `--band-study` runs that study instead and records it
//! (`common::reports::band_limit_io`).

use endstop_experiments as common;

use std::time::Instant;

use anyhow::{Context, Result};
use common::io::frame::frame;
use common::io::md::Table;
use common::io::plot::{LegendPos, LinePlot, Series, Style, PALETTE};
use common::reports::band_limit_io;
use common::{row, write_atomic, Experiment};
use endstop::device::Device;
use endstop::validation::band_limit;
use endstop::validation::linear_harvesters::{response_curve, ClosedForm};
use endstop::validation::nlvib::{self, Reference};
use endstop::validation::random_law::{self, LawEnsemble};
use endstop::validation::{cases, Check, Measure, ValidationError, Verdict};

fn main() {
    if std::env::args().skip(1).any(|a| a == "--band-study") {
        common::run_main("validation --band-study", band_limit_io::record_study);
    } else {
        common::run_main("validation", run);
    }
}

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
    let d = common::load_device(&format!("validation/{name}"))?;
    let set = d.device.params.clone();
    exp.uses(&d, &set);
    Ok(d.device)
}

fn e(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else {
        format!("{x:.2e}")
    }
}

fn value(x: f64) -> String {
    if x == 0.0 || (x.fract() == 0.0 && x.abs() < 1e6) {
        format!("{x}")
    } else {
        format!("{x:.10e}")
    }
}

/// The verdict as the chapter's tables write it.
fn verdict_label(v: Verdict) -> &'static str {
    match v {
        Verdict::Open => "*open question*",
        Verdict::Reproduced => "within",
        Verdict::Deviates | Verdict::NotYet => "**not met**",
    }
}

fn measure_label(m: Measure) -> &'static str {
    match m {
        Measure::Relative => "relative",
        Measure::RelativeToOurs => "relative to ours",
        Measure::Absolute => "absolute",
        Measure::NotAbove => "ours - theirs",
    }
}

/// The checks of some groups as one table.
fn checks_table<'a>(checks: impl IntoIterator<Item = &'a Check>) -> String {
    let mut t = Table::new([
        "reference",
        "quantity",
        "theirs",
        "ours",
        "difference",
        "tolerance",
        "verdict",
    ]);
    for c in checks {
        t.row([
            c.source.clone(),
            c.quantity.clone(),
            value(c.compared.reference),
            value(c.compared.ours),
            format!(
                "{} ({})",
                e(c.difference()),
                measure_label(c.compared.measure)
            ),
            match &c.open {
                Some(why) => format!("{} (not applied: {why})", e(c.compared.tolerance)),
                None => format!("{}: {}", e(c.compared.tolerance), c.reason),
            },
            verdict_label(c.verdict()).to_string(),
        ]);
    }
    t.render()
}

fn in_groups<'a>(checks: &'a [Check], prefix: &'a str) -> impl Iterator<Item = &'a Check> + 'a {
    checks.iter().filter(move |c| c.group.starts_with(prefix))
}

fn run() -> Result<()> {
    let mut exp = Experiment::start("validation");
    exp.seed = Some(cases::RANDOM_SEED);
    let mut checks: Vec<Check> = Vec::new();
    let mut costs: Vec<Cost> = Vec::new();

    // Closed forms: frequency response and optimal loads.
    let piezo = load(&mut exp, "piezo_linear")?;
    let em = load(&mut exp, "em_linear")?;
    let em0 = load(&mut exp, "em_linear_no_inductance")?;
    for d in [&piezo, &em] {
        checks.extend(timed(&mut costs, &d.name, "frequency response", || {
            cases::frequency_response(d)
        })?);
    }
    for d in [&piezo, &em, &em0] {
        checks.extend(timed(&mut costs, &d.name, "optimal load", || {
            cases::optimal_load(d)
        })?);
    }

    // Grazing of the rigid-stop oscillator.
    let rigid = load(&mut exp, "grazing_rigid")?;
    checks.extend(timed(
        &mut costs,
        &rigid.name,
        "grazing continuations",
        || cases::grazing(&rigid),
    )?);

    // The white-noise law, and the recorded study of its band limit, which decides whether the
    // rigid stops' impact term is a reference or an open question.
    let band = band_limit_io::recorded_cells()?;
    let impact_term_confirmed = band_limit::BandVerdict::of(&band)?.consistent();
    let mut ensembles: Vec<LawEnsemble> = Vec::new();
    for name in [
        "random_linear_piezo",
        "random_hertz_em",
        "random_restitution",
    ] {
        let d = load(&mut exp, name)?;
        let ens = timed(
            &mut costs,
            name,
            &format!(
                "{} records of {} s",
                cases::RANDOM_RECORDS,
                cases::RANDOM_RECORD_S
            ),
            || cases::random_law(&d),
        )?;
        checks.extend(random_law::checks(&ens, impact_term_confirmed));
        ensembles.push(ens);
    }

    // The peer tool.
    let sdof = load(&mut exp, "nlvib_sdof")?;
    let ref_dir = common::root().join("data/references/nlvib");
    let reference = Reference::parse(|name| {
        std::fs::read_to_string(ref_dir.join(name)).map_err(|e| ValidationError::Reference {
            file: format!("data/references/nlvib/{name}"),
            message: e.to_string(),
        })
    })?;
    let ours = nlvib::Ours::new(&sdof);
    let (exact_checks, exact_rows) =
        timed(&mut costs, &sdof.name, "through every exact orbit", || {
            nlvib::exact_point_checks(&ours, &reference, cases::NLVIB_EXACT_STRIDE)
        })?;
    checks.extend(exact_checks);
    let branch = timed(
        &mut costs,
        &sdof.name,
        "continuation 0.5 to 2.5 rad/s",
        || {
            ours.branch(
                0.5,
                2.5,
                cases::NLVIB_MAX_STEP_RAD_S,
                cases::NLVIB_LOCATE_TOL_RAD_S,
            )
        },
    )?;
    checks.extend(nlvib::continuation_checks(
        &ours,
        &branch,
        &reference,
        cases::NLVIB_LOCATE_TOL_RAD_S,
    )?);
    let hb = timed(
        &mut costs,
        &sdof.name,
        "amplitudes at NLvib's points",
        || nlvib::hb_convergence(&ours, &branch, &reference),
    )?;
    let (aft_floor, fold_floor) = (reference.aft_floor_m(), reference.fold_floor_rad_s());
    checks.extend(nlvib::hb_checks(&hb, aft_floor, fold_floor));
    let samples = nlvib::branch_samples(&ours, &branch)?;
    let springs = common::reports::springs_io::run(&mut exp, load)?;
    checks.extend(springs.checks.iter().cloned());
    costs.extend(springs.costs.iter().map(|(c, w, s)| Cost {
        case: c.clone(),
        what: w.clone(),
        wall_s: *s,
    }));

    // The interface circuits against their closed forms.
    let bridge = load(&mut exp, "piezo_bridge")?;
    checks.extend(timed(
        &mut costs,
        &bridge.name,
        "interface closed forms",
        || endstop::validation::interfaces::weak_coupling_checks(&bridge),
    )?);
    let coupling = timed(&mut costs, &bridge.name, "coupling rows", || {
        endstop::validation::interfaces::coupling_rows(&bridge)
    })?;
    checks.extend(endstop::validation::interfaces::coupling_checks(&coupling));

    // Parquet.
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
    let mut df = frame(samples.iter().map(|s| {
        row![
            "omega_rad_s" => s.omega_rad_s,
            "a1_amplitude_m" => s.a1_amplitude_m,
            "max_floquet_modulus" => s.max_multiplier,
            "stable" => s.stable,
            "impacting" => s.impacting,
        ]
    }))?;
    exp.write_parquet("nlvib_branch", &mut df, "reference")?;
    let mut df = frame(exact_rows.iter().map(|r| {
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
    let mut df = frame(hb.iter().flat_map(|c| {
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

    // Plots.
    exp.write_extra_plot("validation_nlvib", &nlvib_plot(&samples, &reference))?;
    exp.write_extra_plot("validation_linear", &linear_plot(&piezo, &em)?)?;

    // The chapter's tables.
    let book = &exp.book_dir;
    let within = checks.iter().filter(|c| c.passes()).count();
    let judged = checks.iter().filter(|c| !c.is_open()).count();
    let label = |c: &&Check| format!("{}: {}", c.group, c.quantity);
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
            in_groups(&checks, "frequency response").chain(in_groups(&checks, "optimal load")),
        )
        .as_bytes(),
    )?;
    write_atomic(
        &book.join("random.md"),
        random_md(&ensembles, &checks).as_bytes(),
    )?;
    write_atomic(
        &book.join("grazing.md"),
        checks_table(in_groups(&checks, "grazing")).as_bytes(),
    )?;
    write_atomic(
        &book.join("nlvib.md"),
        nlvib_md(&checks, &hb, aft_floor, fold_floor, &branch, &samples).as_bytes(),
    )?;
    write_atomic(
        &book.join("band_limit.md"),
        band_limit_io::table_md(&band)?.as_bytes(),
    )?;
    write_atomic(
        &book.join("springs.md"),
        checks_table(
            in_groups(&checks, "exact stationary law")
                .chain(in_groups(&checks, "escape over the barrier"))
                .chain(in_groups(&checks, "peer: NLvib's Duffing")),
        )
        .as_bytes(),
    )?;
    write_atomic(
        &book.join("interfaces.md"),
        checks_table(
            in_groups(&checks, "interface circuits, weak coupling")
                .chain(in_groups(&checks, "interface circuits, coupling")),
        )
        .as_bytes(),
    )?;
    write_atomic(&book.join("cost.md"), cost_md(&costs).as_bytes())?;
    exp.number("checks", judged as f64);
    exp.number("open_questions", open.len() as f64);
    exp.number("checks_within_tolerance", within as f64);
    exp.finish()
}

fn random_md(ensembles: &[LawEnsemble], checks: &[Check]) -> String {
    let mut t = Table::new([
        "device",
        "impacts per s",
        "m Sa / 2 (W)",
        "band deficit (est.)",
        "less the deficit (W)",
        "drive (W, 95 %)",
        "dissipation (W, 95 %)",
        "mech. damper",
        "stops (damping)",
        "impact losses",
        "coil",
        "loads",
    ]);
    for ens in ensembles {
        let (d, s) = (ens.drive(), ens.dissipation());
        let share = |f: fn(&random_law::RecordPowers) -> f64| {
            format!("{:.1} %", 100.0 * ens.mean(f) / s.mean)
        };
        t.row([
            ens.device.clone(),
            format!("{:.1}", ens.mean(|r| r.impacts_per_s)),
            format!("{:.4e}", ens.law_w),
            format!("{:.2} %", 100.0 * ens.band_deficit),
            format!("{:.4e}", ens.band_law_w()),
            format!("{:.4e} +- {:.1e}", d.mean, d.ci95),
            format!("{:.4e} +- {:.1e}", s.mean, s.ci95),
            share(|r| r.mech_damping_w),
            share(|r| r.stop_w),
            share(|r| r.impact_losses_w),
            share(|r| r.internal_w),
            share(|r| r.loads_w),
        ]);
    }
    let spec_line = format!(
        "Each ensemble: {} records (noise streams 0 to {} of seed {}), each {} s analysed after \
         the device's pre-roll of five ring-up times, two-sided level Sa = {} g^2/Hz flat to \
         10 kHz, sampled at 100 kHz. The shares divide each dissipation by the total.\n\n",
        cases::RANDOM_RECORDS,
        cases::RANDOM_RECORDS - 1,
        cases::RANDOM_SEED,
        cases::RANDOM_RECORD_S,
        cases::RANDOM_PSD_G2_PER_HZ,
    );
    format!(
        "{spec_line}{}\n{}",
        t.render(),
        checks_table(in_groups(checks, "random vibration"))
    )
}

fn nlvib_md(
    checks: &[Check],
    hb: &[nlvib::HbComparison],
    aft_floor: f64,
    fold_floor: f64,
    branch: &endstop::study::continuation::Branch,
    samples: &[nlvib::BranchSample],
) -> String {
    let mut t = Table::new([
        "H",
        "NLvib fold (rad/s)",
        "our fold (rad/s)",
        "fold difference (rad/s)",
        "points compared",
        "largest a1 difference (m)",
    ]);
    for c in hb {
        t.row([
            c.harmonics.to_string(),
            format!("{:.9}", c.fold_rad_s),
            format!("{:.9}", c.our_fold_rad_s),
            e(c.fold_difference()),
            c.amplitudes.len().to_string(),
            e(c.worst_amplitude_difference()),
        ]);
    }
    let unstable = samples.iter().filter(|s| !s.stable).count();
    let events: Vec<String> = branch
        .events
        .iter()
        .map(|ev| {
            format!(
                "{} at Omega = {:.9} rad/s",
                ev.label(),
                ev.param * 2.0 * std::f64::consts::PI
            )
        })
        .collect();
    format!(
        "Our branch: {} points, {} of them unstable; events in branch order: {}.\n\n\
         The floors: the AFT sampling floor (largest change of an H = 40 amplitude with four \
         times finer sampling) is {} m; the deepest micro turning point of the sampled contact \
         force below the fold is {} rad/s.\n\n{}\n{}",
        samples.len(),
        unstable,
        events.join("; "),
        e(aft_floor),
        e(fold_floor),
        t.render(),
        checks_table(in_groups(checks, "peer"))
    )
}

fn cost_md(costs: &[Cost]) -> String {
    let mut t = Table::new(["device", "case", "wall time (s)"]);
    for c in costs {
        t.row([c.case.clone(), c.what.clone(), format!("{:.2}", c.wall_s)]);
    }
    format!(
        "Wall-clock seconds of each case in the run that generated this page (the random \
         ensembles run their records in parallel on the machine's cores).\n\n{}",
        t.render()
    )
}

fn nlvib_plot(samples: &[nlvib::BranchSample], reference: &Reference) -> LinePlot {
    let mut series = Vec::new();
    // Our branch in runs of equal stability: solid where stable, dashed where not.
    let mut run: Vec<(f64, f64)> = Vec::new();
    let mut labelled = [false, false];
    let flush = |run: &mut Vec<(f64, f64)>,
                 stable: bool,
                 labelled: &mut [bool; 2],
                 series: &mut Vec<Series>| {
        if run.len() > 1 {
            let k = usize::from(!stable);
            let label = if labelled[k] {
                ""
            } else if stable {
                "ours, stable"
            } else {
                "ours, unstable"
            };
            labelled[k] = true;
            series.push(Series::new(
                label,
                std::mem::take(run),
                PALETTE[0],
                if stable { Style::Line } else { Style::Dashed },
            ));
        }
        run.clear();
    };
    let mut last: Option<bool> = None;
    for s in samples {
        if let Some(l) = last {
            if l != s.stable {
                let keep = run.last().copied();
                flush(&mut run, l, &mut labelled, &mut series);
                run.extend(keep);
            }
        }
        run.push((s.omega_rad_s, s.a1_amplitude_m));
        last = Some(s.stable);
    }
    if let Some(l) = last {
        flush(&mut run, l, &mut labelled, &mut series);
    }
    for (k, (h, points)) in reference
        .hb
        .iter()
        .filter(|(h, _)| [3, 40].contains(h))
        .enumerate()
    {
        series.push(Series::new(
            &format!("NLvib-py harmonic balance, H = {h}"),
            points
                .iter()
                .step_by(4)
                .map(|p| (p.omega_rad_s, p.a1_amplitude_m))
                .collect(),
            PALETTE[1 + k],
            Style::Points,
        ));
    }
    LinePlot::new(
        "One-sided spring oscillator: first-harmonic amplitude (ours and NLvib-py)",
        "Omega [rad/s]",
        "first-harmonic amplitude [m]",
        series,
    )
    .x(0.5, 2.5)
    .legend(LegendPos::UpperRight)
}

fn linear_plot(piezo: &Device, em: &Device) -> Result<LinePlot> {
    let mut series = Vec::new();
    for (k, d) in [piezo, em].into_iter().enumerate() {
        let at = cases::response_frequencies_hz(d)?;
        let (lo, hi) = (0.8 * at[0], 1.1 * at[at.len() - 1]);
        let grid: Vec<f64> = (0..=400)
            .map(|i| lo + (hi - lo) * i as f64 / 400.0)
            .collect();
        let (closed, ours) = response_curve(d, cases::LINEAR_ACCEL_RMS_G, &grid, &at)?;
        let label = match ClosedForm::of(d)? {
            ClosedForm::Piezoelectric(_) => "piezoelectric",
            ClosedForm::Electromagnetic(_) => "electromagnetic",
        };
        series.push(Series::new(
            &format!("{label}: closed form"),
            closed.iter().map(|(f, v)| (*f, v.norm())).collect(),
            PALETTE[2 * k],
            Style::Line,
        ));
        series.push(Series::new(
            &format!("{label}: time-domain steady state"),
            ours.iter().map(|(f, v)| (*f, v.norm())).collect(),
            PALETTE[2 * k + 1],
            Style::Points,
        ));
    }
    let (lo, hi) = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.1))
        .fold((f64::MAX, f64::MIN), |(a, b), y| (a.min(y), b.max(y)));
    Ok(LinePlot::new(
        "Linear harvesters: load voltage per base acceleration",
        "frequency [Hz]",
        "|V/A| [V s^2/m]",
        series,
    )
    .y(0.5 * lo, 3.0 * hi)
    .log(false, true)
    .legend(LegendPos::UpperRight))
}
