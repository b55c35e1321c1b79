//! Sobol indices of any quantity of any device over parameters the user names: a Saltelli
//! design ([`crate::num::sensitivity`]) on the unit cube of the named [`ParamRange`]s, each point
//! a device built by [`at_unit`], the quantity evaluated on every device in parallel.
//!
//! ```
//! # let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/data/prototype2.toml")).unwrap();
//! use endstop::device::{Device, ParamRange};
//! use endstop::num::sensitivity::Bootstrap;
//! use endstop::study::sensitivity::sobol;
//! let dev = Device::from_toml_str(&text, "prototype2.toml").unwrap();
//! let ranges = [
//!     ParamRange::parse("mechanics.mass_kg=2e-6..3e-6").unwrap(),
//!     ParamRange::parse("mechanics.damping_n_s_per_m=1e-3..2e-3").unwrap(),
//! ];
//! // The undamped natural frequency depends on the mass alone.
//! let quantity = |d: &Device| Ok::<_, std::convert::Infallible>(
//!     (d.mechanics.stiffness_n_per_m / d.mechanics.mass_kg).sqrt());
//! let boot = Bootstrap { resamples: 200, level: 0.95, seed: 1 };
//! let s = sobol(&dev, &ranges, 64, 7, boot, quantity).unwrap();
//! assert!(s.indices.total[0].value > 0.9 && s.indices.total[1].value.abs() < 1e-12);
//! ```

use rayon::prelude::*;

use crate::device::{at_unit, Device, ParamError, ParamRange};
use crate::num::sensitivity::{Bootstrap, Indices, Saltelli, SensitivityError};

/// Why a sensitivity study could not be made.
#[derive(Debug, thiserror::Error)]
pub enum SobolError<E: std::error::Error + 'static> {
    /// A range does not fit the device (unknown path, or the device is invalid at an end).
    #[error(transparent)]
    Range(#[from] ParamError),
    /// The design or the estimate failed.
    #[error(transparent)]
    Design(#[from] SensitivityError),
    /// The quantity failed at a design point.
    #[error("design point {index} ({point}): {source}")]
    Quantity {
        /// Index of the design point.
        index: usize,
        /// The parameters at that point, `path=value` joined by commas.
        point: String,
        /// The quantity's error.
        source: E,
    },
}

/// The result of [`sobol`]: the indices, in the order of the ranges, and every evaluation.
#[derive(Debug, Clone)]
pub struct SobolStudy {
    /// First-order and total indices with bootstrap intervals.
    pub indices: Indices,
    /// The design's points on the unit cube, in evaluation order.
    pub points: Vec<Vec<f64>>,
    /// The quantity at each point.
    pub outputs: Vec<f64>,
}

/// Sobol first-order and total indices of `quantity` over `ranges` of `device` (device
/// parameters: the quantity sees no acceleration scale), from a Saltelli design of `base` rows
/// (a power of two) seeded with `seed`; `base * (ranges + 2)` devices are evaluated, in
/// parallel.
pub fn sobol<E, F>(
    device: &Device,
    ranges: &[ParamRange],
    base: usize,
    seed: u32,
    boot: Bootstrap,
    quantity: F,
) -> Result<SobolStudy, SobolError<E>>
where
    E: std::error::Error + Send + 'static,
    F: Fn(&Device) -> Result<f64, E> + Sync,
{
    for r in ranges {
        r.check(device)?;
        if r.path == crate::device::ACCEL_SCALE_PATH {
            return Err(SobolError::Range(ParamError::Invalid {
                source_name: "range".into(),
                field: r.path.clone(),
                message: "not a device parameter: a quantity of a device sees no drive".into(),
            }));
        }
    }
    let design = Saltelli::new(base, ranges.len(), seed)?;
    let points = design.points();
    let outputs = points
        .par_iter()
        .enumerate()
        .map(|(index, u)| {
            let (dev, _) = at_unit(device, ranges, u)?;
            quantity(&dev).map_err(|source| SobolError::Quantity {
                index,
                point: ranges
                    .iter()
                    .zip(u)
                    .map(|(r, &ui)| {
                        let own = crate::device::own_value(device, &r.path).unwrap_or(f64::NAN);
                        format!("{}={:e}", r.path, r.value(own, ui))
                    })
                    .collect::<Vec<_>>()
                    .join(", "),
                source,
            })
        })
        .collect::<Result<Vec<f64>, _>>()?;
    let indices = design.indices(&outputs, boot)?;
    Ok(SobolStudy {
        indices,
        points,
        outputs,
    })
}
