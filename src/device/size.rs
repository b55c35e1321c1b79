//! The device's size: the volume a designer quotes beside its power.
//!
//! An optional `[size]` table holds `volume_m3`, the volume the device occupies (m^3). Nothing
//! in the model reads it; the figures of merit that compare devices of different sizes do (the
//! normalised power density, [`crate::design::merit::normalised_power_density`]). Which
//! volume is meant (the die, the package, the moving part's swept volume) is the file's to say
//! in a comment: the merit is only as comparable as that choice.
//!
//! ```toml
//! [size]
//! volume_m3 = 1.92e-9   # 8 x 4 mm^2 active area x 60 um device layer
//! ```

use serde::{Deserialize, Serialize};

use super::{Checker, ParamError};

/// The volume of a device.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Size {
    /// The volume the device occupies (m^3).
    pub volume_m3: f64,
}

impl Size {
    /// Checks the volume: positive and finite.
    pub(crate) fn validate(&self, c: &Checker) -> Result<(), ParamError> {
        c.positive("size.volume_m3", self.volume_m3)
    }
}
