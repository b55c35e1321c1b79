//! The paper layer: Le & Halvorsen (2012) as this crate reproduces it, apart from the model.
//!
//! * [`figures`]: one module per figure or table, each a [`Figure`] (its setup, `run` and
//!   `claims`), which the experiment binaries and the tests both call;
//! * [`claims`]: the paper's claims (`data/claims.toml`), their keys, our values and the
//!   verdicts;
//! * [`setups`]: the prototypes as each figure simulates them (bias, contact law, b_im), the
//!   parameter sets, and the devices a figure runs on;
//! * [`measured`]: what the paper measured and the simulations use as targets;
//! * [`qm`]: the readings of the paper's quality factor Qm (Table 3, eq 21);
//! * the protocols that several figures share: [`sweeps`] (prototype 1's stepped sine),
//!   [`curves`] (the curves of an up-sweep figure), [`ensembles`] (random vibration),
//!   [`prototype2_records`] (the ensembles of Figures 14 and 15);
//! * [`calibration`]: the one-parameter calibration of prototype 1 and the paper's fit of b_im;
//! * the studies around the figures: [`response`] (the whole response curve),
//!   [`resolution`] (the width estimator), [`crosscheck`] (ngspice), and [`deviations`] (why
//!   the paper deviates: the claim quantities by their fast paths, their Sobol indices over
//!   the uncertain inputs' ranges, and the multi-claim calibration).
//!
//! Nothing in the model modules imports this one; within it, the figures import the shared
//! modules and the studies import the figures, never the other way.

pub mod calibration;
pub mod claims;
pub mod crosscheck;
pub mod curves;
pub mod deviations;
pub mod ensembles;
pub mod figure;
pub mod figures;
pub mod measured;
pub mod prototype2_records;
pub mod qm;
pub mod resolution;
pub mod response;
pub mod setups;
pub mod sweeps;

pub use figure::Figure;
