//! The physics of the harvester: Hertz line contact ([`hertz`], eqs 3-6 and 19), the end-stops
//! and their laws ([`contact`], eqs 1-2), the transducers ([`transducer`], eqs 8-10 for the
//! paper's), the lumped model ([`harvester`], eqs 7-10), its free flight split for the
//! exponential integrator ([`free_flight`]), its energy balance ([`energy`]), the linear
//! response of any device ([`linear`]) and the paper's linear two-port theory ([`two_port`],
//! eqs 11-18 and 21-22), and the interface circuits between a transducer and a DC load
//! ([`interface`]: diode bridges, SSHI, SECE).
//!
//! ```
//! use endstop::device::Device;
//! use endstop::drive::Sine;
//! use endstop::ode::HybridSystem;
//! use endstop::physics::contact::{Mode, Side};
//! use endstop::physics::harvester::{Harvester, State};
//! use endstop::physics::linear::white_noise_power_w;
//! use endstop::physics::two_port::eq21_power_w;
//!
//! let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/prototype2.toml"));
//! let device = Device::from_toml_str(text, "prototype2.toml")?;
//!
//! // Eq 7 under 0.1 g rms at 700 Hz: at rest, a quarter period in, the drive alone
//! // accelerates the mass, by +sqrt(2) 0.1 g (towards the upper stop, +x).
//! let h = Harvester::new(&device, Sine::from_rms_g(0.1, 700.0));
//! let rest = h.rest_state();
//! let dydt = h.rhs(Mode::Free, 0.25 / 700.0, &rest);
//! assert!((dydt[1] / (2f64.sqrt() * 0.1 * endstop::G) - 1.0).abs() < 1e-9);
//!
//! // Pressed 0.1 um into the upper stop (at x = +gap), the stop pushes it back, towards -x.
//! let gap = device.stops.upper.as_ref().unwrap().gap_m;
//! let y = State::new(gap + 1e-7, 0.0, rest[2], rest[3]);
//! assert!(h.rhs(Mode::Contact(Side::Upper), 0.0, &y)[1] < 0.0);
//!
//! // The linearised model under white noise of 1e-4 g^2/Hz (two-sided) over a band far wider
//! // than the resonance gives the power of eq 21.
//! let sa = 1e-4 * endstop::G * endstop::G;
//! let p = white_noise_power_w(&device, sa, 1.0, 1e6);
//! assert!((p / eq21_power_w(&device, 1e-4) - 1.0).abs() < 1e-3);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod assembly;
pub mod closed_forms;
pub mod contact;
pub mod energy;
pub mod free_flight;
pub mod harvester;
pub mod hertz;
pub mod interface;
pub mod interface_closed_forms;
pub mod linear;
pub mod suspension;
pub mod transducer;
pub mod two_port;
