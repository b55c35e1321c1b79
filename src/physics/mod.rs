//! The physics of the harvester: Hertz line contact ([`hertz`], eqs 3-6 and 19), the end-stops
//! and their laws ([`contact`], eqs 1-2), the transducers ([`transducer`], eqs 8-10 for the
//! paper's), the lumped model ([`harvester`], eqs 7-10), its free flight split for the
//! exponential integrator ([`free_flight`]), its energy balance ([`energy`]), the linear
//! response of any device ([`linear`]) and the paper's linear two-port theory ([`two_port`],
//! eqs 11-18 and 21-22), and the interface circuits between a transducer and a DC load
//! ([`interface`]: diode bridges, SSHI, SECE).

pub mod closed_forms;
pub mod contact;
pub mod energy;
pub mod free_flight;
pub mod harvester;
pub mod hertz;
pub mod interface;
pub mod linear;
pub mod transducer;
pub mod two_port;
