//! `endstop basins`: which of the coexisting stable periodic orbits a device lands on from each
//! initial state under a fixed sine, and for a device with two wells in which well each orbit
//! lives (the library's `study::attractors` finds and places the orbits, `study::basins` maps
//! the grid).

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::Parser;
use common::io::frame::{column_name, frame, Cell};
use common::io::md::Table;
use common::reports::basins_io::basin_map;
use common::{fmt_sig, row};
use endstop::device::Device;
use endstop::model::Model;
use endstop::study::attractors::{
    find_attractors_from, grid_seeds, seeds, AttractorSearch, Attractors,
};
use endstop::study::basins::{basins_on, BasinGrid, BasinSettings, Basins, Slice, UNSETTLED};
use endstop::study::displacement::two_wells;
use endstop::study::orbit::{Forcing, ShootingOptions};
use endstop_experiments as common;

use crate::shared::{describe, start};

/// The arguments of `endstop basins`.
#[derive(Parser, Debug)]
pub(crate) struct BasinArgs {
    /// Device file (TOML), e.g. a copy of data/examples/bistable_stops_em.toml.
    #[arg(long)]
    device: PathBuf,
    /// Drive frequency (Hz).
    #[arg(long, allow_hyphen_values = true)]
    freq: f64,
    /// RMS base acceleration (g = 9.81 m/s^2); the sine's amplitude is sqrt(2) times this.
    #[arg(long, allow_hyphen_values = true)]
    accel_rms_g: f64,
    /// Cells per side of the grid of initial states (positions by velocities).
    #[arg(long, default_value_t = 41)]
    cells: usize,
    /// Initial positions `LO,HI` (m); default: from the lower stop's gap to the upper's
    /// (required on a side without a stop).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    x_range: Option<Vec<f64>>,
    /// Initial velocities `LO,HI` (m/s); default: plus and minus the angular drive frequency
    /// times the largest |x| of the positions.
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    v_range: Option<Vec<f64>>,
    /// Largest number of drive periods a cell runs before it is reported unsettled.
    #[arg(long, default_value_t = 1000)]
    max_periods: usize,
    /// Scaled distance to an attractor's state at drive phase zero within which a cell has
    /// settled (two periods in a row).
    #[arg(long, default_value_t = 1e-3, allow_hyphen_values = true)]
    settle_tol: f64,
    /// The attractors are searched from the wells at rest and from this many by this many
    /// initial states spread over the grid.
    #[arg(long, default_value_t = 5)]
    seeds_per_side: usize,
    /// On a device of several masses, the plane of the grid, `x:MASS,v:MASS` (a position and a
    /// velocity, of one mass or two, by the device file's names); every other coordinate starts
    /// at rest. Default: the transducer's mass. A one-mass device has one plane and refuses it.
    #[arg(long)]
    slice: Option<String>,
    /// Bias voltage (V) of an electrostatic transducer; default: the device file's.
    #[arg(long, allow_hyphen_values = true)]
    bias_v: Option<f64>,
    /// Output directory; default: data/results/endstop-basins.
    #[arg(long)]
    out: Option<PathBuf>,
}

/// The most cells per side (a grid of a quarter of a million cells).
const MAX_CELLS: usize = 501;

/// Refuses a range unless it is two finite numbers, increasing.
fn check_range(name: &str, r: &[f64]) -> Result<(f64, f64)> {
    match r {
        [lo, hi] if lo.is_finite() && hi.is_finite() && lo < hi => Ok((*lo, *hi)),
        _ => bail!("--{name} = {r:?}: must be two finite numbers LO,HI with LO < HI"),
    }
}

impl BasinArgs {
    /// Refuses every option no basin map can use, naming it.
    fn check(&self) -> Result<()> {
        if !(self.freq.is_finite() && self.freq > 0.0) {
            bail!(
                "--freq = {}: must be a finite positive frequency in Hz",
                self.freq
            );
        }
        if !(self.accel_rms_g.is_finite() && self.accel_rms_g > 0.0) {
            bail!(
                "--accel-rms-g = {}: must be a finite positive acceleration in g",
                self.accel_rms_g
            );
        }
        if !(2..=MAX_CELLS).contains(&self.cells) {
            bail!("--cells = {}: must be from 2 to {MAX_CELLS}", self.cells);
        }
        if self.max_periods == 0 || self.max_periods > 1_000_000 {
            bail!(
                "--max-periods = {}: must be from 1 to 1000000",
                self.max_periods
            );
        }
        if !(self.settle_tol.is_finite() && self.settle_tol > 0.0 && self.settle_tol < 1.0) {
            bail!(
                "--settle-tol = {}: must be finite, positive and below 1",
                self.settle_tol
            );
        }
        if self.seeds_per_side > self.cells {
            bail!(
                "--seeds-per-side = {}: must be at most --cells ({})",
                self.seeds_per_side,
                self.cells
            );
        }
        if let Some(r) = &self.x_range {
            check_range("x-range", r)?;
        }
        if let Some(r) = &self.v_range {
            check_range("v-range", r)?;
        }
        Ok(())
    }

    /// The grid on `device`: the given ranges, else the stops' gaps and the velocities they
    /// give at the drive frequency.
    fn grid(&self, device: &endstop::device::Device) -> Result<BasinGrid> {
        let x_m = match &self.x_range {
            Some(r) => check_range("x-range", r)?,
            None => {
                let gap = |s: Option<&endstop::device::Stop>, side: &str| match s {
                    Some(s) => Ok(s.gap_m),
                    None => Err(anyhow::anyhow!(
                        "device `{}` has no {side} stop to bound the initial positions: give \
                         --x-range LO,HI (m)",
                        device.name
                    )),
                };
                (
                    -gap(device.stops.lower.as_ref(), "lower")?,
                    gap(device.stops.upper.as_ref(), "upper")?,
                )
            }
        };
        let v_m_per_s = match &self.v_range {
            Some(r) => check_range("v-range", r)?,
            None => {
                let v = 2.0 * std::f64::consts::PI * self.freq * x_m.0.abs().max(x_m.1.abs());
                (-v, v)
            }
        };
        Ok(BasinGrid {
            x_m,
            v_m_per_s,
            nx: self.cells,
            nv: self.cells,
        })
    }
}

/// The masses of a model by name with their position's and velocity's state components (empty
/// for a one-mass model, whose components are not named after a mass).
fn mass_components<M: Model<N>, const N: usize>(h: &M) -> Vec<(String, usize, usize)> {
    let l = h.layout();
    l.masses
        .iter()
        .enumerate()
        .filter_map(|(k, &(x, v))| Some((l.mass_name(k)?.to_string(), x, v)))
        .collect()
}

/// The grid's plane on `h` from `--slice` (see [`BasinArgs::slice`]), with the names of its
/// position's and velocity's masses (`None` on a one-mass model).
fn resolve_slice<M: Model<N>, const N: usize>(
    h: &M,
    device: &Device,
    slice: Option<&str>,
) -> Result<(Slice, Option<(String, String)>)> {
    let masses = mass_components(h);
    if device.masses.is_none() {
        if let Some(s) = slice {
            bail!(
                "--slice {s}: device `{}` has one mass, whose position and velocity the grid \
                 spans; --slice chooses the plane on a device of several masses",
                device.name
            );
        }
        return Ok((Slice::FIRST, None));
    }
    let names: Vec<&str> = masses.iter().map(|m| m.0.as_str()).collect();
    let Some(slice) = slice else {
        let (name, x, v) = &masses[0];
        return Ok((Slice { x: *x, v: *v }, Some((name.clone(), name.clone()))));
    };
    let bad = |why: &str| {
        anyhow::anyhow!(
            "--slice {slice}: {why}; give `x:MASS,v:MASS` with MASS one of the masses of `{}`: \
             {}",
            device.name,
            names.join(", ")
        )
    };
    let (Some(xm), Some(vm)) = (
        slice
            .split(',')
            .next()
            .and_then(|p| p.trim().strip_prefix("x:")),
        slice
            .split(',')
            .nth(1)
            .and_then(|p| p.trim().strip_prefix("v:")),
    ) else {
        return Err(bad("not of the form `x:MASS,v:MASS`"));
    };
    if slice.split(',').count() != 2 {
        return Err(bad("not of the form `x:MASS,v:MASS`"));
    }
    let find = |name: &str| {
        masses
            .iter()
            .find(|m| m.0 == name)
            .ok_or_else(|| bad(&format!("no mass is named `{name}`")))
    };
    let (x, v) = (find(xm)?, find(vm)?);
    Ok((Slice { x: x.1, v: v.2 }, Some((x.0.clone(), v.0.clone()))))
}

/// What the basins' run returns besides the attractors and the basins: the plane of the grid
/// with its masses' names, and every mass's name and state components.
struct Plane {
    slice: Slice,
    names: Option<(String, String)>,
    masses: Vec<(String, usize, usize)>,
}

/// A summary key from a label (`left well, small` to `left_well_small`).
fn key(label: &str) -> String {
    label
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect::<String>()
        .split('_')
        .filter(|s| !s.is_empty())
        .collect::<Vec<_>>()
        .join("_")
}

/// The attractors found from `seeds` and the basins of the grid, on the assembled model.
#[allow(clippy::too_many_arguments)]
fn attractors_and_basins<M: Model<N>, const N: usize>(
    h: &M,
    device: &Device,
    a: &BasinArgs,
    forcing: &Forcing,
    grid: BasinGrid,
    search: &AttractorSearch,
    shooting: ShootingOptions,
) -> Result<(Attractors, Basins, Plane)> {
    let (slice, names) = resolve_slice(h, device, a.slice.as_deref())?;
    // A one-mass device is seeded at its stable equilibria; a device of several masses at rest
    // (its springs' equilibrium); then the grid's cells.
    let starts: Vec<_> = if device.masses.is_none() {
        seeds(device, &grid, a.seeds_per_side)
    } else {
        let mut s = vec![(0.0, 0.0)];
        s.extend(grid_seeds(&grid, a.seeds_per_side));
        s
    }
    .into_iter()
    .map(|(x, v)| slice.state(h, x, v))
    .collect();
    let found = common::with_progress(1, "attractors", |tick| {
        let r = find_attractors_from(h, device, forcing, shooting, &starts, search);
        tick.tick();
        r
    })?;
    if found.found.is_empty() {
        bail!(
            "no stable orbit of one drive period found at {} Hz, {} g rms from {} seeds ({} did \
             not converge, {} unstable): the basins need at least one attractor",
            a.freq,
            a.accel_rms_g,
            found.seeds,
            found.not_converged,
            found.unstable
        );
    }
    let settings = BasinSettings {
        grid,
        max_periods: a.max_periods,
        settle_tol: a.settle_tol,
        rtol: shooting.rtol,
    };
    let catalogue = found.catalogue();
    let b = common::with_progress(grid.nx * grid.nv, "basins", |tick| {
        basins_on(h, forcing, &catalogue, &settings, slice, tick)
    })?;
    let plane = Plane {
        slice,
        names,
        masses: mass_components(h),
    };
    Ok((found, b, plane))
}

/// Runs `endstop basins`.
pub(crate) fn basins_study(a: BasinArgs) -> Result<()> {
    a.check()?;
    // Everything is checked and computed before the experiment writes a file.
    let loaded = common::load_device_file(&a.device)?;
    let grid = a.grid(&loaded.device)?;
    let (mut exp, loaded, device) = start("endstop-basins", &a.device, a.bias_v, a.out.clone())?;
    let forcing = Forcing {
        freq_hz: a.freq,
        accel_rms_g: a.accel_rms_g,
    };
    let shooting = ShootingOptions::default();
    let search = AttractorSearch::default();
    let (found, b, plane) = endstop::with_harvester!(&device, |h| attractors_and_basins(
        &h, &device, &a, &forcing, grid, &search, shooting
    ))?;

    write_tables(&mut exp, &device.params, &b, &found, &plane)?;
    let mut md = format!(
        "Basins of `{}` ({} set; {}) at {} Hz, {} g rms: a grid of {} by {} initial states, \
         x{} from {} to {} um and v{} from {} to {} mm/s, each started at drive phase zero with the \
         transducer at rest{} and run period by period until it stays within {} (scaled) of an \
         attractor's state at drive phase zero for two periods in a row, for at most {} \
         periods; the attractors are the stable orbits of one drive period reached from {} \
         seeds ({} and {} by {} states over the grid), each after {} periods \
         of transient and Newton's method on the period map.\n\n",
        loaded.file,
        device.params,
        describe(&device),
        a.freq,
        a.accel_rms_g,
        grid.nx,
        grid.nv,
        plane.names.as_ref().map_or(String::new(), |n| format!(" of `{}`", n.0)),
        fmt_sig(grid.x_m.0 * 1e6, 4),
        fmt_sig(grid.x_m.1 * 1e6, 4),
        plane.names.as_ref().map_or(String::new(), |n| format!(" of `{}`", n.1)),
        fmt_sig(grid.v_m_per_s.0 * 1e3, 4),
        fmt_sig(grid.v_m_per_s.1 * 1e3, 4),
        if plane.names.is_some() {
            " and every other mass at rest at its springs' equilibrium"
        } else {
            ""
        },
        a.settle_tol,
        a.max_periods,
        found.seeds,
        if plane.names.is_some() {
            "the device at rest"
        } else {
            "the wells at rest"
        },
        a.seeds_per_side,
        a.seeds_per_side,
        search.transient_periods,
    );
    md.push_str(&summarise(&mut exp, &device, &b, &found, a.max_periods));
    exp.write_numbers_md(&md)?;
    print!("{md}");

    let marks: Vec<(String, f64, f64)> = found
        .found
        .iter()
        .map(|f| {
            (
                f.label.clone(),
                f.orbit.state[plane.slice.x],
                f.orbit.state[plane.slice.v],
            )
        })
        .collect();
    let title = format!(
        "Basins at {} Hz, {} g rms: {}",
        a.freq, a.accel_rms_g, device.name
    );
    exp.write_plot(&basin_map(&title, &b, &marks))?;
    exp.finish()
}

/// Writes `basins.parquet` (the grid and each cell's attractor) and `attractors.parquet`; on
/// a device of several masses the grid's columns name their masses (`x0_<mass>_m`,
/// `v0_<mass>_m_per_s`) and each attractor carries every mass's state at drive phase zero
/// (`x_phase0_<mass>_m`, `v_phase0_<mass>_m_per_s`) after the transducer's mass's.
fn write_tables(
    exp: &mut common::Experiment,
    set: &str,
    b: &Basins,
    found: &Attractors,
    plane: &Plane,
) -> Result<()> {
    let place = |i: usize| b.attractor[i].map_or(UNSETTLED, |k| found.found[k].place.label());
    let (x0, v0) = match &plane.names {
        Some((x, v)) => (
            column_name(&format!("x0_{x}_m")),
            column_name(&format!("v0_{v}_m_per_s")),
        ),
        None => ("x0_m", "v0_m_per_s"),
    };
    let rows = b.cells.iter().enumerate().map(|(i, &(x, v))| {
        row![
            x0 => x,
            v0 => v,
            "attractor" => b.label(i),
            "place" => place(i),
            "periods" => b.periods[i] as u64,
        ]
    });
    exp.write_parquet("basins", &mut frame(rows)?, set)?;
    let shares = b.shares();
    let rows = found.found.iter().zip(&shares).map(|(f, (_, share))| {
        let s = &f.orbit.summary;
        let mut r = row![
            "attractor" => f.label.as_str(),
            "place" => f.place.label(),
            "x_phase0_m" => f.orbit.state[0],
            "v_phase0_m_per_s" => f.orbit.state[1],
            "x_lower_m" => s.x_lower_m,
            "x_upper_m" => s.x_upper_m,
            "p_w" => s.p_total_w,
            "impacts_per_period" => s.impacts as u64,
            "max_multiplier_abs" => f.orbit.max_multiplier_abs(),
            "share" => *share,
        ];
        for (name, x, v) in &plane.masses {
            r.push((
                column_name(&format!("x_phase0_{name}_m")),
                Cell::from(f.orbit.state[*x]),
            ));
            r.push((
                column_name(&format!("v_phase0_{name}_m_per_s")),
                Cell::from(f.orbit.state[*v]),
            ));
        }
        r
    });
    exp.write_parquet("attractors", &mut frame(rows)?, set)?;
    Ok(())
}

/// The numbers and the table of the attractors, with their shares.
fn summarise(
    exp: &mut common::Experiment,
    device: &endstop::device::Device,
    b: &Basins,
    found: &Attractors,
    max_periods: usize,
) -> String {
    let shares = b.shares();
    let n = b.cells.len();
    let unsettled = b.attractor.iter().filter(|a| a.is_none()).count();
    exp.number("cells", n as f64);
    exp.number("attractors", found.found.len() as f64);
    exp.number("unsettled_share", unsettled as f64 / n as f64);
    let periods_max = b.periods.iter().copied().max().unwrap_or(0);
    let periods_mean = b.periods.iter().sum::<usize>() as f64 / n as f64;
    exp.number("periods_max", periods_max as f64);
    exp.number("periods_mean", periods_mean);
    let mut t = Table::new([
        "attractor",
        "share of the cells",
        "x range (um)",
        "power (uW)",
        "impacts a period",
        "largest multiplier",
    ]);
    for (f, (_, share)) in found.found.iter().zip(&shares) {
        let k = key(&f.label);
        let s = &f.orbit.summary;
        exp.number(&format!("share_{k}"), *share);
        exp.number(&format!("p_{k}_w"), s.p_total_w);
        exp.number(&format!("x_lower_{k}_m"), s.x_lower_m);
        exp.number(&format!("x_upper_{k}_m"), s.x_upper_m);
        t.row([
            f.label.clone(),
            format!("{:.1} %", 100.0 * share),
            format!(
                "{} to {}",
                fmt_sig(s.x_lower_m * 1e6, 4),
                fmt_sig(s.x_upper_m * 1e6, 4)
            ),
            fmt_sig(s.p_total_w * 1e6, 4),
            s.impacts.to_string(),
            fmt_sig(f.orbit.max_multiplier_abs(), 3),
        ]);
    }
    let wells = match two_wells(device) {
        Some(([lo, hi], barrier)) => format!(
            " The wells are at {} and {} um with the barrier at {} um: an orbit below the \
             barrier all period is in the left well, one above it in the right well, one that \
             crosses it is inter-well.",
            fmt_sig(lo * 1e6, 4),
            fmt_sig(hi * 1e6, 4),
            fmt_sig(barrier * 1e6, 4)
        ),
        None => String::new(),
    };
    format!(
        "{} attractors from {} seeds ({} repeated one found before, {} converged on an \
         unstable orbit, {} did not converge).{wells}\n\n{}\n\
         - {} cells, every one reported: {} settled, {} ({:.1} %) unsettled after {} periods\n\
         - periods to settle: {:.1} on average, {} at most\n",
        found.found.len(),
        found.seeds,
        found.repeats,
        found.unstable,
        found.not_converged,
        t.render(),
        n,
        n - unsettled,
        unsettled,
        100.0 * unsettled as f64 / n as f64,
        max_periods,
        periods_mean,
        periods_max,
    )
}
