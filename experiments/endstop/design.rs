//! `endstop design`: the designer's inverse question on a device file, the I/O around
//! [`endstop::design`]. The ranges, vibration and limits come from the command line; the
//! interfaces to choose among from `--interfaces FILE` (TOML, `[[interface]]` tables in the
//! device file's form) or, without it, the device's own interface. The vibration is sines,
//! a noise (`--psd`) or a measured record (`--accel-file`).
//!
//! Everything is computed before anything is written: a run that fails leaves no output.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Parser;

use crate::design_noise::{self, NoiseArgs};
use crate::design_record::{self, ReadRecord, RecordArgs};
use endstop::design::{
    interfaces, merit, Answer, Evaluated, Limits, Problem, SearchSettings, Study, Verdict,
    Vibration,
};
use endstop::device::{Device, Interface, ParamRange, Spacing};
use endstop::drive::Sine;
use endstop::progress::Silent;
use endstop::study::periodic::SteadySettings;

use crate::shared::start;

use endstop_experiments::{fmt_sig, Experiment};

/// The arguments of `endstop design`.
#[derive(Parser, Debug)]
pub struct DesignArgs {
    /// Device file (TOML), e.g. a copy of data/examples/piezo_bridge.toml.
    #[arg(long)]
    device: PathBuf,
    /// A decision variable, `PATH=LO..HI[:log|:linear]` (repeat for more); PATH is a key of the
    /// device file, or `load.resistance_ohm` for the load of whichever interface.
    #[arg(long = "range", required = true)]
    ranges: Vec<String>,
    /// A drive frequency (Hz); repeat for a band, whose worst frequency is the objective.
    #[arg(
        long = "freq-hz",
        required_unless_present_any = ["psd", "accel_file"],
        allow_hyphen_values = true
    )]
    freqs_hz: Vec<f64>,
    /// RMS base acceleration of the sines (g).
    #[arg(
        long,
        required_unless_present_any = ["psd", "accel_file"],
        allow_hyphen_values = true
    )]
    accel_rms_g: Option<f64>,
    /// The noise objective (--psd) in place of the sines.
    #[command(flatten)]
    noise: NoiseArgs,
    /// The measured record (--accel-file) in place of the sines.
    #[command(flatten)]
    record: RecordArgs,
    /// Interfaces to choose among: a TOML file of `[[interface]]` tables, each as a device
    /// file's `[interface]` (`kind = "resistive"` for the transducer's own load); default: the
    /// device's own interface.
    #[arg(long)]
    interfaces: Option<PathBuf>,
    /// Largest impact speed the stops survive (m/s).
    #[arg(long, allow_hyphen_values = true)]
    max_impact_speed_m_s: Option<f64>,
    /// Largest contact force the stops survive (N).
    #[arg(long, allow_hyphen_values = true)]
    max_contact_force_n: Option<f64>,
    /// Largest displacement (m).
    #[arg(long, allow_hyphen_values = true)]
    max_displacement_m: Option<f64>,
    /// Most impacts per second.
    #[arg(long, allow_hyphen_values = true)]
    max_impacts_per_s: Option<f64>,
    /// Points of the search's global sample per interface.
    #[arg(long, default_value_t = 32)]
    samples: usize,
    /// Scramble of the sample.
    #[arg(long, default_value_t = 0)]
    seed: u32,
    /// Points per side of the power map over the first two ranges (0: no map).
    #[arg(long, default_value_t = 11)]
    map_points: usize,
    /// Target storage voltage for the charging time of the best design (V); only behind a
    /// circuit with a storage.
    #[arg(long, allow_hyphen_values = true)]
    target_v: Option<f64>,
    /// Output directory; default: data/results/endstop-design.
    #[arg(long)]
    out: Option<PathBuf>,
}

/// The interfaces of `--interfaces`, read by the library ([`interfaces::from_toml_str`]) so
/// that errors name the file and the field.
fn interfaces_of(device: &Device, path: &std::path::Path) -> Result<Vec<Interface>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("--interfaces: cannot read {}", path.display()))?;
    interfaces::from_toml_str(device, &text, &path.display().to_string()).context("--interfaces")
}

/// Refuses options no design study can use, naming the option.
fn check(a: &DesignArgs) -> Result<()> {
    if let Some(g) = a.accel_rms_g {
        if !(g.is_finite() && g > 0.0) {
            bail!("--accel-rms-g must be a finite positive number, not {g}");
        }
    }
    if a.freqs_hz.iter().any(|f| !(f.is_finite() && *f > 0.0))
        || a.freqs_hz.windows(2).any(|w| w[1] <= w[0])
    {
        bail!(
            "--freq-hz must be positive frequencies in increasing order, got {:?}",
            a.freqs_hz
        );
    }
    for (name, v) in [
        ("--max-impact-speed-m-s", a.max_impact_speed_m_s),
        ("--max-contact-force-n", a.max_contact_force_n),
        ("--max-displacement-m", a.max_displacement_m),
        ("--max-impacts-per-s", a.max_impacts_per_s),
        ("--target-v", a.target_v),
    ] {
        if let Some(v) = v {
            if !(v.is_finite() && v > 0.0) {
                bail!("{name} must be a finite positive number, not {v}");
            }
        }
    }
    if a.samples == 0 || a.samples > 4096 {
        bail!("--samples must be in 1..=4096, not {}", a.samples);
    }
    if a.map_points == 1 || a.map_points > 101 {
        bail!(
            "--map-points must be 0 (no map) or in 2..=101, not {}",
            a.map_points
        );
    }
    Ok(())
}

fn words(p: &Problem, a: &Answer) -> String {
    let d = &a.design;
    let values: Vec<String> = p
        .ranges
        .iter()
        .zip(d.values.iter().zip(&d.unit))
        .map(|(r, (v, u))| format!("`{}` = {}{}", r.path, fmt_sig(*v, 4), at_end(r, *u)))
        .collect();
    let perf = d.result.as_ref().ok();
    let q =
        |f: fn(&endstop::design::Performance) -> f64| perf.map_or("-".into(), |x| fmt_sig(f(x), 4));
    // Under a noise or a record the impact speed and the contact force are not measured.
    let impacts = if p.measures_impacts() {
        format!(
            "impact speed {} m/s, contact force {} N, ",
            q(|x| x.impact_speed_m_s),
            q(|x| x.contact_force_n)
        )
    } else {
        String::new()
    };
    format!(
        "{} with the `{}` interface, {}: power {} W ({}), {impacts}displacement {} m, {} \
         impacts/s{}",
        match a.verdict {
            Verdict::Optimum => "**optimum**",
            Verdict::Infeasible =>
                "**infeasible**: no design tried meets every limit; the least violating is",
        },
        p.interfaces[d.interface].key(),
        values.join(", "),
        q(|x| x.power_w),
        if p.noise.is_some() {
            "mean over the records"
        } else if p.record.is_some() {
            "mean over the record"
        } else {
            "worst over the band"
        },
        q(|x| x.displacement_m),
        q(|x| x.impacts_per_s),
        if a.verdict == Verdict::Infeasible {
            format!(" (violation {})", fmt_sig(d.violation, 3))
        } else {
            String::new()
        }
    )
}

/// Says whether a design's value lies at an end of its range (unit coordinate 0 or 1, where
/// the search clamps it): the best design may then lie beyond the range. A switch's two
/// settings are its whole range, and are not said to be ends.
fn at_end(range: &ParamRange, unit: f64) -> &'static str {
    if range.spacing == Spacing::Switch {
        ""
    } else if unit <= 0.0 {
        " (the lower end of its range)"
    } else if unit >= 1.0 {
        " (the upper end of its range)"
    } else {
        ""
    }
}

/// Records in `summary.json` what repeats the run besides the device file (recorded with its
/// text) and the seed: the arguments as given, the interfaces chosen among, the search's
/// settings and the steady state's.
fn record_settings(
    exp: &mut endstop_experiments::Experiment,
    a: &DesignArgs,
    p: &Problem,
    search: &SearchSettings,
) -> Result<()> {
    use serde_json::{json, to_value};
    let s = &p.steady;
    exp.setting("command", json!("design"));
    exp.setting("device", json!(a.device.display().to_string()));
    exp.setting("ranges", json!(a.ranges));
    exp.setting("freqs_hz", json!(a.freqs_hz));
    exp.setting("accel_rms_g", json!(a.accel_rms_g));
    exp.setting("noise", to_value(p.noise)?);
    exp.setting(
        "accel_file",
        json!(a
            .record
            .accel_file
            .as_ref()
            .map(|f| f.display().to_string())),
    );
    if let Some(r) = &p.record {
        exp.setting("accel_scale", json!(a.record.accel_scale));
        exp.setting("record_sample_rate_hz", json!(r.sample_rate_hz));
        exp.setting("record_transient_s", json!(r.transient_s));
    }
    exp.setting(
        "interfaces_file",
        json!(a.interfaces.as_ref().map(|f| f.display().to_string())),
    );
    exp.setting(
        "interfaces",
        json!(p.interfaces.iter().map(Interface::key).collect::<Vec<_>>()),
    );
    exp.setting("limits", to_value(p.limits)?);
    exp.setting("map_points", json!(a.map_points));
    exp.setting("target_v", json!(a.target_v));
    exp.setting("search", to_value(search)?);
    exp.setting(
        "steady",
        json!({
            "rtol": s.rtol,
            "transient_periods": s.transient_periods,
            "max_newton": s.max_newton,
            "tol": s.tol,
            "jacobian": format!("{:?}", s.jacobian),
            "max_map_periods": s.max_map_periods,
        }),
    );
    Ok(())
}

/// `endstop design`.
pub fn design(a: DesignArgs) -> Result<()> {
    check(&a)?;
    let (mut exp, loaded, device) = start("endstop-design", &a.device, None, a.out.clone())?;
    let record = a.record.objective()?;
    let p = problem(&a, &device, record.as_ref())?;
    let settings = SearchSettings {
        samples: a.samples,
        seed: a.seed,
        ..SearchSettings::default()
    };
    exp.seed = Some(u64::from(a.seed));
    record_settings(&mut exp, &a, &p, &settings)?;
    let budget = settings.budget(p.interfaces.len(), p.ranges.len());
    let study: Study =
        endstop_experiments::with_progress(budget, "designs evaluated (at most)", |pr| {
            p.solve(&settings, pr)
        })?;
    let maps = power_maps(&a, &p, &study);
    let merits = merits(&a, &p, &study, record.as_ref())?;
    let confirmed = design_noise::confirm(&mut exp, &p, &study)?;

    // Everything is computed: now write.
    write_outputs(&mut exp, &device, &p, &study, &maps, &merits)?;
    let md = summary_md(&a, &loaded.file, &p, &study, &merits, record.as_ref())
        + &confirmed
        + &crate::design_table::first_range_table(&p, &maps);
    exp.write_numbers_md(&md)?;
    print!("{md}");
    exp.write_plot(&crate::design_plot::plots(&p, &study, &maps))?;
    exp.finish()
}

/// The design problem of the command line on `device`.
fn problem(a: &DesignArgs, device: &Device, record: Option<&ReadRecord>) -> Result<Problem> {
    let ranges = a
        .ranges
        .iter()
        .map(|r| ParamRange::parse(r).with_context(|| format!("--range {r}")))
        .collect::<Result<Vec<_>>>()?;
    let interfaces = match &a.interfaces {
        Some(path) => interfaces_of(device, path)?,
        None => vec![device.interface.clone()],
    };
    let limits = Limits {
        impact_speed_m_s: a.max_impact_speed_m_s,
        contact_force_n: a.max_contact_force_n,
        displacement_m: a.max_displacement_m,
        impacts_per_s: a.max_impacts_per_s,
    };
    if let Some(r) = record {
        let o = r.objective.clone();
        return Ok(Problem::under_record(
            device.clone(),
            interfaces,
            ranges,
            o,
            limits,
        )?);
    }
    Ok(match a.noise.objective()? {
        Some(n) => Problem::under_noise(device.clone(), interfaces, ranges, n, limits)?,
        None => Problem::new(
            device.clone(),
            interfaces,
            ranges,
            Vibration {
                freqs_hz: a.freqs_hz.clone(),
                accel_rms_g: sine_g(a),
            },
            limits,
        )?,
    })
}

/// The sines' RMS acceleration (g); NaN under noise, which has none.
fn sine_g(a: &DesignArgs) -> f64 {
    a.accel_rms_g.unwrap_or(f64::NAN)
}

/// The power maps: per interface, over the first two ranges, the others at that interface's
/// answer (none with fewer than two ranges or points).
fn power_maps(a: &DesignArgs, p: &Problem, study: &Study) -> Vec<(usize, Vec<Evaluated>)> {
    if a.map_points >= 2 && p.ranges.len() >= 2 {
        let n = a.map_points;
        endstop_experiments::with_progress(n * n * p.interfaces.len(), "power map points", |pr| {
            (0..p.interfaces.len())
                .filter_map(|i| {
                    let at = study.per_interface[i].as_ref()?.design.unit.clone();
                    let grid = p.grid(i, 0, 1, n, &at);
                    for _ in 0..grid.len() {
                        pr.tick();
                    }
                    Some((i, grid))
                })
                .collect()
        })
    } else {
        Vec::new()
    }
}

/// The figures of merit of the answer.
struct Merits {
    limit_m: Option<f64>,
    effectiveness: Option<f64>,
    band: Option<merit::HalfPowerBand>,
    charging: Option<Result<f64, String>>,
    /// The normalised power density (kg s m^-3) and the volume (m^3) it is over, where the
    /// device gives its volume.
    density: Option<(f64, f64)>,
}

/// The answer's figures of merit: its effectiveness, its half-power band over the given
/// frequencies and its charging time to the target.
fn merits(
    a: &DesignArgs,
    p: &Problem,
    study: &Study,
    record: Option<&ReadRecord>,
) -> Result<Merits> {
    let best = &study.answer.design;
    let (best_dev, _) = p.device_at(best.interface, &best.unit)?;
    let perf = best.result.as_ref().ok();
    let limit_m = a
        .max_displacement_m
        .or_else(|| merit::displacement_limit_m(&best_dev));
    // Under noise or a record the effectiveness's sine bound and the charging's sine do not
    // apply.
    let sine = perf.filter(|_| p.noise.is_none() && p.record.is_none());
    let effectiveness = sine.zip(limit_m).map(|(q, zl)| {
        merit::effectiveness(
            q.power_w,
            best_dev.mechanics.mass_kg,
            zl,
            sine_g(a) * endstop::G,
            q.worst_freq_hz,
        )
    });
    let rms_g = match (&p.noise, record) {
        (Some(n), _) => design_noise::noise_rms_g(n),
        (None, Some(r)) => r.rms_g,
        (None, None) => sine_g(a),
    };
    let density = perf.zip(best_dev.size).map(|(q, size)| {
        let v = size.volume_m3;
        let npd = merit::normalised_power_density(q.power_w, v, rms_g * endstop::G);
        (npd, v)
    });
    let band = if a.freqs_hz.len() >= 3 {
        let pts = endstop::study::periodic::frequency_sweep(
            &best_dev,
            &a.freqs_hz,
            sine_g(a),
            &SteadySettings::default(),
            &Silent,
        )?;
        let pw: Vec<f64> = pts
            .iter()
            .map(|s| s.as_ref().map_or(f64::NAN, |s| s.p_dc_w))
            .collect();
        merit::half_power_band(&a.freqs_hz, &pw)
    } else {
        None
    };
    let charging = match (a.target_v, sine) {
        (Some(v), Some(q)) => merit::charging_time_s(
            &best_dev,
            Sine::from_rms_g(sine_g(a), q.worst_freq_hz),
            v,
            600.0,
            &Silent,
        )
        .map(|r| r.map_err(|e| e.to_string())),
        _ => None,
    };
    Ok(Merits {
        limit_m,
        effectiveness,
        band,
        charging,
        density,
    })
}

/// The designs and the maps as Parquet, and the summary's numbers.
fn write_outputs(
    exp: &mut Experiment,
    device: &Device,
    p: &Problem,
    study: &Study,
    maps: &[(usize, Vec<Evaluated>)],
    merits: &Merits,
) -> Result<()> {
    let best = &study.answer.design;
    let mut df = crate::design_table::design_rows(p, &study.evaluations, "search")?;
    exp.write_parquet("designs", &mut df, &device.params)?;
    for (i, grid) in maps {
        let mut df = crate::design_table::design_rows(p, grid, "map")?;
        exp.write_parquet(
            &format!("map_{}", p.interfaces[*i].key()),
            &mut df,
            &device.params,
        )?;
    }
    exp.number("power_w", best.power_w());
    exp.number(
        "feasible",
        f64::from(u8::from(study.answer.verdict == Verdict::Optimum)),
    );
    exp.number("evaluations", study.evaluations.len() as f64);
    if let Some(e) = merits.effectiveness {
        exp.number("effectiveness", e);
    }
    if let Some((npd, v)) = merits.density {
        exp.number("normalised_power_density_kg_s_per_m3", npd);
        exp.number("volume_m3", v);
    }
    Ok(())
}

/// The summary in words: the question, the answer (overall and per interface) and its
/// figures of merit.
fn summary_md(
    a: &DesignArgs,
    file: &str,
    p: &Problem,
    study: &Study,
    merits: &Merits,
    record: Option<&ReadRecord>,
) -> String {
    let (limit_m, effectiveness) = (merits.limit_m, merits.effectiveness);
    let question = match (&p.noise, record) {
        (Some(n), _) => design_noise::question(n),
        (None, Some(r)) => design_record::question(p, &r.described, r.rms_g),
        (None, None) => format!(
            "under {} g rms at {} Hz (the objective is the worst of these frequencies)",
            sine_g(a),
            a.freqs_hz
                .iter()
                .map(|f| fmt_sig(*f, 6))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    let mut md = format!(
        "Design of `{}` {question}, over {}; interfaces: {}.\n\n- {}\n",
        file,
        p.ranges
            .iter()
            .map(|r| format!(
                "`{}` in [{}, {}]",
                r.path,
                fmt_sig(r.lo, 4),
                fmt_sig(r.hi, 4)
            ))
            .collect::<Vec<_>>()
            .join(", "),
        p.interfaces
            .iter()
            .map(|i| format!("`{}`", i.key()))
            .collect::<Vec<_>>()
            .join(", "),
        words(p, &study.answer),
    );
    for (i, ans) in study.per_interface.iter().enumerate() {
        match ans {
            Some(ans) => md.push_str(&format!(
                "- `{}` alone: {}\n",
                p.interfaces[i].key(),
                words(p, ans)
            )),
            None => md.push_str(&format!(
                "- `{}`: no design could be evaluated\n",
                p.interfaces[i].key()
            )),
        }
    }
    let best = &study.answer.design;
    if p.ranges
        .iter()
        .zip(&best.unit)
        .any(|(r, u)| !at_end(r, *u).is_empty())
    {
        md.push_str(
            "- the answer lies at an end of a range: a better design may lie beyond it (widen \
             that range where the device allows)\n",
        );
    }
    md.push_str(&format!(
        "- designs evaluated: {}\n",
        study.evaluations.len()
    ));
    if let (Some(e), Some(zl)) = (effectiveness, limit_m) {
        md.push_str(&format!(
            "- harvester effectiveness (Mitcheson et al. 2008: over the ideal velocity-damped \
             resonant generator's m A Z_l w / 2 with Z_l = {} m): {}\n",
            fmt_sig(zl, 3),
            fmt_sig(e, 3)
        ));
    }
    md.push_str(&crate::merit::power_density_line(merits.density));
    if let Some(b) = &merits.band {
        md.push_str(&format!(
            "- half-power band of the answer over the given frequencies: {}\n",
            match b.width_hz() {
                Some(w) => format!("{} Hz wide", fmt_sig(w, 3)),
                None => "wider than the frequencies given".to_string(),
            }
        ));
    }
    match &merits.charging {
        Some(Ok(t)) => md.push_str(&format!(
            "- charging time of the storage from 0 V to {} V with the load open: {} s\n",
            a.target_v.unwrap_or_default(),
            fmt_sig(*t, 4)
        )),
        Some(Err(e)) => md.push_str(&format!("- charging to the target: {e}\n")),
        None => {}
    }
    md
}
