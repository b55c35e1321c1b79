//! The static equilibria of a device: the real roots of its suspension's restoring force
//! with its stops' springs between and on the stops ([`crate::laws::suspension::equilibria`]),
//! sorted by position: the wells (stable), the barriers between them (unstable) and any rest
//! on a stop.
//!
//! ```
//! use endstop::device::Device;
//! use endstop::laws::suspension::Place;
//! use endstop::physics::statics::{equilibria, reference_well};
//!
//! // The example's double well has its wells at +-0.5 mm and its barrier at rest; its
//! // reference well (the stable equilibrium nearest rest) is one of the two. The equilibria
//! // are found numerically, to far better than 1e-9 m.
//! let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/examples/bistable_stops_em.toml"));
//! let device = Device::from_toml_str(text, "bistable_stops_em.toml")?;
//! let eq = equilibria(&device);
//! let wells: Vec<f64> = eq
//!     .iter()
//!     .filter(|e| e.stable && e.place == Place::Free)
//!     .map(|e| e.x_m)
//!     .collect();
//! assert_eq!(wells.len(), 2);
//! assert!((wells[0] + 0.5e-3).abs() < 1e-9 && (wells[1] - 0.5e-3).abs() < 1e-9);
//! let well = reference_well(&device).unwrap();
//! assert!((well.x_m.abs() - 0.5e-3).abs() < 1e-9);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use crate::device::Device;
use crate::laws::suspension::{self, Equilibrium};

/// The static equilibria of `device`'s suspension with its stops' springs, sorted by position
/// ([`crate::laws::suspension::equilibria`]): the wells (stable), the barriers between them
/// (unstable) and any rest on a stop.
pub fn equilibria(device: &Device) -> Vec<Equilibrium> {
    let (upper, lower) = device.stop_models();
    suspension::equilibria(
        &device.restoring_polynomial(),
        upper.as_ref(),
        lower.as_ref(),
    )
}

/// The reference well of `device` (the stable equilibrium nearest rest), if any.
pub fn reference_well(device: &Device) -> Option<Equilibrium> {
    suspension::reference_well(&equilibria(device))
}
