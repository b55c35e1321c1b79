//! The paper layer: Le & Halvorsen (2012) as this crate reproduces it, apart from the model.
//!
//! * [`setups`]: the prototypes as each figure simulates them (bias, contact law, b_im);
//! * [`measured`]: what the paper measured and the simulations use as targets;
//! * [`claims`]: the paper's claims (`data/claims.toml`), our values and the verdicts;
//! * [`calibration`]: the one-parameter calibration of prototype 1 and the paper's fit of b_im;
//! * [`deviations`]: why the paper deviates: the claim quantities by their fast paths, their
//!   Sobol indices over the uncertain inputs' ranges, and the multi-claim calibration;
//! * one module per figure or table with its protocol, a `run` and a `claims` function, which
//!   the experiment binaries and the tests both call.
//!
//! Nothing in the model modules imports this one.

pub mod calibration;
pub mod claims;
pub mod curves;
pub mod deviations;
pub mod ensembles;
pub mod fig05;
pub mod fig08;
pub mod fig09;
pub mod fig10;
pub mod fig11;
pub mod fig12;
pub mod fig13;
pub mod fig14;
pub mod fig15;
pub mod measured;
pub mod resolution;
pub mod response;
pub mod setups;
pub mod table3;
