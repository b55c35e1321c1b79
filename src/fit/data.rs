//! What a fit is fitted to: measured sweeps (a quantity at measured frequencies, at a stated
//! RMS acceleration, up or down) with optional frequency features (the impact onset, the end of
//! the impacting branch), each with its standard deviation, checked before any simulation.

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Sweep direction: up (increasing frequency) or down.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Direction {
    /// Increasing frequency.
    Up,
    /// Decreasing frequency.
    Down,
}

impl Direction {
    /// Label for tables.
    pub fn label(self) -> &'static str {
        match self {
            Direction::Up => "up",
            Direction::Down => "down",
        }
    }
}

/// The measured quantity of a sweep.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Quantity {
    /// RMS voltage of load 1 (V).
    V1RmsV,
    /// Mean power of both loads together (W).
    PTotalW,
}

impl Quantity {
    /// Column name with its unit.
    pub fn column(self) -> &'static str {
        match self {
            Quantity::V1RmsV => "v1_rms_v",
            Quantity::PTotalW => "p_total_w",
        }
    }
}

/// A frequency feature of a sweep.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FeatureKind {
    /// First contact with a stop of an up-sweep (the kink of Figure 8).
    Onset,
    /// Where an up-sweep's impacting branch ends: the jump down, or the loss of contact when
    /// there is no jump ([`crate::study::sweep::SweepReport::branch_end`]); on a down-sweep,
    /// the jump up or the first contact ([`crate::study::sweep::DownSweepReport::branch_end`]).
    BranchEnd,
}

impl FeatureKind {
    /// Label for tables.
    pub fn label(self) -> &'static str {
        match self {
            FeatureKind::Onset => "onset",
            FeatureKind::BranchEnd => "branch end (jump)",
        }
    }
}

/// A measured frequency feature with its standard deviation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Feature {
    /// Which feature.
    pub kind: FeatureKind,
    /// Measured frequency (Hz).
    pub freq_hz: f64,
    /// Its standard deviation (Hz).
    pub sigma_hz: f64,
}

/// One measured point of a sweep.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Point {
    /// Drive frequency (Hz).
    pub freq_hz: f64,
    /// Measured value, in the sweep's [`Quantity`].
    pub value: f64,
    /// Standard deviation of the value (same unit); `None`: unknown, estimated from the
    /// residuals (see [`crate::fit::Uncertainty`]).
    pub sigma: Option<f64>,
}

/// A measured sweep.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepData {
    /// Name for tables and errors (a file name).
    pub label: String,
    /// Up or down.
    pub direction: Direction,
    /// Stated RMS base acceleration (g).
    pub accel_rms_g: f64,
    /// The measured quantity.
    pub quantity: Quantity,
    /// Measured points, in sweep order (frequency increasing for up, decreasing for down).
    pub points: Vec<Point>,
    /// The stepped sweep's frequency grid (Hz, in sweep order); `None`: the points'
    /// frequencies. A sweep with features only needs one.
    pub grid_hz: Option<Vec<f64>>,
    /// Measured frequency features.
    pub features: Vec<Feature>,
}

/// A data set that cannot be fitted.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum DataError {
    /// A value is NaN, infinite, or not positive where it must be.
    #[error("{label}: {what} = {value} at item {index} must be finite{positive}")]
    NotFinite {
        /// The data set.
        label: String,
        /// Which value.
        what: &'static str,
        /// Index of the point or feature (0-based).
        index: usize,
        /// The value.
        value: f64,
        /// "" or " and positive".
        positive: &'static str,
    },
    /// The frequencies do not follow the sweep's direction strictly.
    #[error(
        "{label}: frequency {freq_hz} Hz at item {index} does not {order} the previous one \
         ({direction} sweep)"
    )]
    NotMonotonic {
        /// The data set.
        label: String,
        /// Index of the offending point (0-based).
        index: usize,
        /// Its frequency.
        freq_hz: f64,
        /// "exceed" or "stay below".
        order: &'static str,
        /// "up" or "down".
        direction: &'static str,
    },
    /// A sweep without points needs a grid, and a grid needs two frequencies.
    #[error("{label}: no frequency grid (a sweep with features only needs `grid_hz` of two or more frequencies)")]
    NoGrid {
        /// The data set.
        label: String,
    },
    /// A measured point or feature lies outside the simulated grid.
    #[error("{label}: {what} at {freq_hz} Hz lies outside the sweep's grid {lo} .. {hi} Hz")]
    OutsideGrid {
        /// The data set.
        label: String,
        /// What lies outside.
        what: &'static str,
        /// Its frequency.
        freq_hz: f64,
        /// Grid's lowest frequency.
        lo: f64,
        /// Grid's highest frequency.
        hi: f64,
    },
    /// An onset is only defined for an up-sweep.
    #[error("{label}: an impact onset feature needs an up-sweep")]
    OnsetOnDown {
        /// The data set.
        label: String,
    },
}

fn finite(
    label: &str,
    what: &'static str,
    index: usize,
    value: f64,
    positive: bool,
) -> Result<(), DataError> {
    if value.is_finite() && (!positive || value > 0.0) {
        Ok(())
    } else {
        Err(DataError::NotFinite {
            label: label.into(),
            what,
            index,
            value,
            positive: if positive { " and positive" } else { "" },
        })
    }
}

/// A measured point's drop across a jump must be at least this fraction of the larger of the
/// two values: the jump of an impacting branch loses most of its response, whereas the steep
/// flank of a linear resonance sampled at a quarter of its half-power width changes by a few
/// tens of percent between points.
pub const JUMP_MIN_REL_DROP: f64 = 0.25;

/// ... and at least this many times the change between each neighbouring pair of points: a
/// jump is a discontinuity, a flank changes alike from point to point.
pub const JUMP_MIN_NEIGHBOUR_RATIO: f64 = 3.0;

/// ... and at least this many standard deviations of the difference, where the points state
/// theirs.
pub const JUMP_MIN_SIGMAS: f64 = 5.0;

/// A jump the measured points show: between the point `before` (the last on the branch the
/// sweep starts on) and the next (the first on the branch it jumps to).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MeasuredJump {
    /// Index of the last point before the jump.
    pub before: usize,
    /// Frequency of that point (Hz).
    pub from_hz: f64,
    /// Frequency of the next point (Hz).
    pub to_hz: f64,
}

impl MeasuredJump {
    /// The middle of the bracket (Hz).
    pub fn mid_hz(&self) -> f64 {
        0.5 * (self.from_hz + self.to_hz)
    }

    /// The standard deviation of a frequency uniformly distributed across the bracket
    /// (Hz): its width over sqrt(12).
    pub fn sigma_hz(&self) -> f64 {
        (self.to_hz - self.from_hz).abs() / 12f64.sqrt()
    }
}

impl SweepData {
    /// Measured values that enter the misfit (points and features).
    pub fn len(&self) -> usize {
        self.points.len() + self.features.len()
    }

    /// True if the data set has neither points nor features.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The jump the measured points show, when the data set states no branch end of its own
    /// (see [`MeasuredJump`] and the criteria [`JUMP_MIN_REL_DROP`],
    /// [`JUMP_MIN_NEIGHBOUR_RATIO`], [`JUMP_MIN_SIGMAS`]): the largest change against the
    /// sweep's direction of jumping (down in an up-sweep, up in a down-sweep) between
    /// consecutive points.
    pub fn measured_jump(&self) -> Option<MeasuredJump> {
        if self
            .features
            .iter()
            .any(|f| f.kind == FeatureKind::BranchEnd)
        {
            return None;
        }
        self.points_jump()
    }

    /// The jump the measured points show, whether or not the data set states a branch end:
    /// the largest change against the sweep's direction of jumping between consecutive
    /// points, when it meets the criteria of [`SweepData::measured_jump`].
    pub fn points_jump(&self) -> Option<MeasuredJump> {
        let sign = match self.direction {
            Direction::Up => 1.0,
            Direction::Down => -1.0,
        };
        let pts = &self.points;
        let drop = |i: usize| sign * (pts[i].value - pts[i + 1].value);
        let k = (0..pts.len().saturating_sub(1)).max_by(|&a, &b| drop(a).total_cmp(&drop(b)))?;
        let d = drop(k);
        let scale = pts[k].value.abs().max(pts[k + 1].value.abs());
        let neighbours = [k.checked_sub(1), Some(k + 1).filter(|&j| j + 1 < pts.len())]
            .into_iter()
            .flatten()
            .map(|j| (pts[j].value - pts[j + 1].value).abs())
            .fold(0.0, f64::max);
        let noise = match (pts[k].sigma, pts[k + 1].sigma) {
            (Some(a), Some(b)) => a.hypot(b),
            _ => 0.0,
        };
        (d > 0.0
            && d >= JUMP_MIN_REL_DROP * scale
            && d >= JUMP_MIN_NEIGHBOUR_RATIO * neighbours
            && d >= JUMP_MIN_SIGMAS * noise)
            .then(|| MeasuredJump {
                before: k,
                from_hz: pts[k].freq_hz,
                to_hz: pts[k + 1].freq_hz,
            })
    }

    /// Measured values that enter the misfit: points, features, and the bracket of a jump the
    /// points show ([`SweepData::measured_jump`]).
    pub fn n_values(&self) -> usize {
        self.len() + usize::from(self.measured_jump().is_some())
    }

    /// The stepped sweep's grid, in sweep order.
    pub fn grid(&self) -> Vec<f64> {
        self.grid_hz
            .clone()
            .unwrap_or_else(|| self.points.iter().map(|p| p.freq_hz).collect())
    }

    /// Checks every value (finite; frequencies, accelerations and standard deviations
    /// positive), the order of the frequencies, and that points and features lie on the grid.
    pub fn validate(&self) -> Result<(), DataError> {
        let l = &self.label;
        finite(l, "accel_rms_g", 0, self.accel_rms_g, true)?;
        let (order, dir) = match self.direction {
            Direction::Up => ("exceed", "up"),
            Direction::Down => ("stay below", "down"),
        };
        let check_order = |freqs: &[f64]| -> Result<(), DataError> {
            for (i, w) in freqs.windows(2).enumerate() {
                let ok = match self.direction {
                    Direction::Up => w[1] > w[0],
                    Direction::Down => w[1] < w[0],
                };
                if !ok {
                    return Err(DataError::NotMonotonic {
                        label: l.clone(),
                        index: i + 1,
                        freq_hz: w[1],
                        order,
                        direction: dir,
                    });
                }
            }
            Ok(())
        };
        for (i, p) in self.points.iter().enumerate() {
            finite(l, "freq_hz", i, p.freq_hz, true)?;
            finite(l, self.quantity.column(), i, p.value, false)?;
            if let Some(s) = p.sigma {
                finite(l, "sigma", i, s, true)?;
            }
        }
        check_order(&self.points.iter().map(|p| p.freq_hz).collect::<Vec<_>>())?;
        for (i, f) in self.features.iter().enumerate() {
            finite(l, "feature freq_hz", i, f.freq_hz, true)?;
            finite(l, "feature sigma_hz", i, f.sigma_hz, true)?;
            if f.kind == FeatureKind::Onset && self.direction == Direction::Down {
                return Err(DataError::OnsetOnDown { label: l.clone() });
            }
        }
        let grid = self.grid();
        if grid.len() < 2 {
            return Err(DataError::NoGrid { label: l.clone() });
        }
        for (i, &f) in grid.iter().enumerate() {
            finite(l, "grid_hz", i, f, true)?;
        }
        check_order(&grid)?;
        let lo = grid.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = grid.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let outside = |what, f: f64| {
            if f < lo || f > hi {
                Err(DataError::OutsideGrid {
                    label: l.clone(),
                    what,
                    freq_hz: f,
                    lo,
                    hi,
                })
            } else {
                Ok(())
            }
        };
        for p in &self.points {
            outside("a point", p.freq_hz)?;
        }
        for f in &self.features {
            outside("a feature", f.freq_hz)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn up_sweep(values: &[f64], sigma: Option<f64>) -> SweepData {
        SweepData {
            label: "t".into(),
            direction: Direction::Up,
            accel_rms_g: 1.0,
            quantity: Quantity::V1RmsV,
            points: values
                .iter()
                .enumerate()
                .map(|(i, &v)| Point {
                    freq_hz: 100.0 + 2.0 * i as f64,
                    value: v,
                    sigma: sigma.map(|s| s * v),
                })
                .collect(),
            grid_hz: None,
            features: vec![],
        }
    }

    #[test]
    fn a_fall_of_most_of_the_response_is_the_jump_and_a_resonance_flank_is_not() {
        // A hardening branch rising to its fold, then the jump down to the low branch.
        let jump = up_sweep(&[1.0, 1.5, 2.2, 3.1, 4.0, 1.0, 0.8, 0.7], Some(0.02));
        let j = jump.measured_jump().expect("a jump");
        assert_eq!((j.before, j.from_hz, j.to_hz), (4, 108.0, 110.0));
        assert!((j.sigma_hz() - 2.0 / 12f64.sqrt()).abs() < 1e-12);
        assert_eq!(jump.n_values(), jump.len() + 1);
        // A linear resonance of half-power width 5.44 Hz (the piezoelectric example's)
        // sampled every 2 Hz: its flank falls by up to about 30 % between points, but alike
        // from point to point.
        let flank: Vec<f64> = (0..12)
            .map(|i| {
                let df = 100.0 + 2.0 * i as f64 - 110.0;
                1.0 / (1.0 + (2.0 * df / 5.44f64).powi(2)).sqrt()
            })
            .collect();
        assert_eq!(up_sweep(&flank, Some(0.02)).measured_jump(), None);
        // A fall hidden in noise of 10 %: not a jump by the five-sigma criterion.
        assert_eq!(
            up_sweep(&[1.0, 1.0, 1.0, 0.6, 0.6, 0.6], Some(0.1)).measured_jump(),
            None
        );
        // Values not yet filled in (all zero) show no jump.
        assert_eq!(up_sweep(&[0.0; 6], None).measured_jump(), None);
    }
}
