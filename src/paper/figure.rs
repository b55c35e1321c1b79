//! The one shape of every figure and table of the paper ([`crate::paper::figures`]): what it
//! runs on, how it runs, and which numbers of the paper's claims it gives.
//!
//! The experiment binaries and the tests run a figure and take its claim values through this
//! trait, so a figure is run the same way wherever it is run:
//!
//! ```
//! use endstop::device::Device;
//! use endstop::paper::claims::Claims;
//! use endstop::paper::figures::fig05::Fig05;
//! use endstop::paper::setups::Prototypes;
//! use endstop::paper::Figure;
//!
//! let load = |text: &str| Device::from_toml_str(text, "data").unwrap();
//! let setup = Prototypes {
//!     prototype1: load(include_str!("../../data/prototype1.toml")),
//!     prototype2: load(include_str!("../../data/prototype2.toml")),
//! };
//! let run = Fig05::run(&setup, &|| {}).unwrap();
//! let values = Fig05::claims(&run, &Claims::bundled().unwrap()).unwrap();
//! assert!(values.iter().all(|v| v.ours.is_finite()));
//! ```

use crate::paper::claims::{Claims, ClaimsError, Value};
use crate::progress::Progress;

/// A figure or table of the paper: its setup, its run, and our values of its claims.
pub trait Figure {
    /// The experiment's name: its binary, results directory and book chapter (`fig08`).
    const NAME: &'static str;

    /// What a run needs: the parameter files' devices (the figure sets bias and end-stop model
    /// itself) and the options of its protocol.
    type Setup;

    /// Everything the figure computes.
    type Run;

    /// Why a run fails.
    type Error: std::error::Error + Send + Sync + 'static;

    /// How many times [`Figure::run`] calls `progress` (at least about: an extended sweep
    /// steps further), for a progress bar.
    fn work(setup: &Self::Setup) -> usize;

    /// Runs the figure, calling `progress` after each unit of work (from any thread).
    fn run(setup: &Self::Setup, progress: &dyn Progress) -> Result<Self::Run, Self::Error>;

    /// Our values of the figure's claims under every parameter set it runs, each checked
    /// against `claims` (the tolerance classes a rule needs are read from it too).
    fn claims(run: &Self::Run, claims: &Claims) -> Result<Vec<Value>, ClaimsError>;
}
