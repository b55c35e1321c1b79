//! The physics of the harvester: Hertz line contact ([`hertz`], eqs 3-6 and 19), the end-stop
//! contact ([`contact`], eqs 1-2), the lumped electromechanical model ([`harvester`],
//! eqs 7-10), its energy balance ([`energy`]) and the linear two-port theory ([`two_port`],
//! eqs 11-18 and 21-22).

pub mod closed_forms;
pub mod contact;
pub mod energy;
pub mod free_flight;
pub mod harvester;
pub mod hertz;
pub mod linear;
pub mod transducer;
pub mod two_port;
