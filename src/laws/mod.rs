//! The force laws of a device's parts, in plain physical parameters: Hertz line
//! contact ([`hertz`], eqs 3-6 and 19), the end-stops' contact laws ([`contact`], eqs 1-2),
//! the suspension's restoring force with the static equilibria it makes with the stops
//! ([`suspension`]), and the electrostatic pair's capacitances, node voltages and force
//! ([`pair`], eqs 7-10).
//!
//! These laws read no device file: a device validates itself with them (its equilibria, its
//! reference well) and builds them from its descriptions ([`crate::device`]); the harvester
//! assembled from a device evaluates them ([`crate::physics::harvester`]). They are also
//! reached as `physics::contact`, `physics::hertz` and `physics::suspension`.

pub mod contact;
pub mod hertz;
pub mod pair;
pub mod suspension;
