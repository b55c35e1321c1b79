//! `endstop`: run the harvester model of Le & Halvorsen (2012), generalised to any
//! single-degree-of-freedom impact harvester, on your own device file.
//!
//! ```text
//! endstop sweep    --device my.toml --from 500 --to 900 --accel-rms-g 0.3 [--out DIR]
//! endstop random   --device my.toml --psd 1e-3 [--out DIR]
//! endstop random   --device my.toml --accel-file shaker.csv [--out DIR]
//! endstop response --device my.toml --from 600 --to 850 --accel-rms-g 0.31 [--out DIR]
//! endstop basins   --device my.toml --freq 30 --accel-rms-g 0.5 [--cells 41] [--out DIR]
//! endstop design --device my.toml --range load.resistance_ohm=1e4..1e6 \
//!             --range stops.upper.gap_m=5e-5..3e-4 --freq-hz 120 --accel-rms-g 0.3 \
//!             [--interfaces ifaces.toml] [--max-impact-speed-m-s 0.1] [--out DIR]
//! endstop fit --device my.toml --up-sweep up.csv [--down-sweep down.csv] \
//!             --free stops.both.gap_m=7e-6..10e-6 [--free ...] [--out DIR]
//! ```
//!
//! Each writes the same kinds of output as the figure experiments: Parquet data with
//! provenance metadata, an SVG and a PNG plot, `summary.json`, and `numbers.md`. Any device
//! the description allows runs (any stops, any transducer); the column names are the same for
//! every device, and for a transducer with one load the second load's columns are zero.

mod basins;
mod charge;
mod design;
mod design_noise;
mod design_plot;
mod design_record;
mod design_table;
mod merit;
mod random;
mod random_args;
mod random_storage;
mod response;
mod shared;
mod sweep;

use endstop_experiments as common;

use clap::{Parser, Subcommand};

use shared::RangeArgs;

#[derive(Parser, Debug)]
#[command(
    name = "endstop",
    version,
    about = "Simulate a vibration energy harvester with end-stops on your own device",
    long_about = "Simulate a vibration energy harvester with end-stops (the model of \
Le & Halvorsen 2012, eqs 1-10, with any stops and transducer) on a device described by a TOML \
file. Start from data/prototype1.toml, data/prototype2.toml or a file of data/examples/: copy \
it, edit the values (SI units; the key names carry the unit), and pass it with --device. Every \
value is checked on load; an error names the file, the field, the value and its valid \
range.\n\nThe studies (besides charge and fit):\n  sweep     stepped-sine up-sweep: RMS \
voltages, power, impact onset and jump\n  random    band-limited white noise or a measured \
acceleration record: power, efficiency, output spectrum, bandwidth\n  response  the whole \
frequency response: up- and down-sweeps, periodic orbits continued in frequency with their \
stability, folds and grazing points\n  basins    which of the coexisting stable orbits each \
initial state ends on under a fixed sine (for a double well: in which well)\n\nOutputs keep \
their column names for every device: v1_rms_v and p1_w are the load of a one-load transducer \
(piezoelectric, electromagnetic), and v2_rms_v, p2_w are then zero."
)]
struct Cli {
    #[command(subcommand)]
    study: Study,
}

#[derive(Subcommand, Debug)]
enum Study {
    /// Stepped-sine up-sweep with continuation (each frequency starts from the previous
    /// steady state), with impact onset and jump refined by bisection.
    Sweep(RangeArgs),
    /// Random vibration: an ensemble of band-limited white-noise records (10 kHz band,
    /// 100 kHz sampling), or one measured acceleration record (--accel-file), with mean
    /// power, output power spectrum and the drive's spectrum; behind an interface circuit
    /// also each record's DC power, efficiency, storage voltage and energy ledger.
    Random(random_args::RandomArgs),
    /// The whole frequency response: up- and down-sweeps, the periodic orbits continued in
    /// frequency (pseudo-arclength, through folds) with their Floquet multipliers, and the
    /// folds and grazing points on the branch, for any device (a circuit's switchings are
    /// events of the orbit like its impacts).
    Response(response::ResponseArgs),
    /// Basins of attraction under a fixed sine: the stable periodic orbits reached from a set
    /// of seeds (for a device with two wells, each placed in its well or across the barrier),
    /// and which of them each initial state of a grid ends on.
    Basins(basins::BasinArgs),
    /// Charge the storage of a device with an interface circuit: the time for its voltage to
    /// go from a start value to a target under a sine, with V_s(t).
    Charge(charge::ChargeArgs),
    /// Fit free device parameters to measured sweeps (CSV with units in the header): the
    /// fitted device file with provenance, values with standard errors and 95 % intervals,
    /// their correlation, warnings for what the data do not determine, and plots of the data
    /// against the fitted model with residuals.
    Fit(common::reports::fit_io::FitArgs),
    /// Design: the device parameters within ranges and the interface circuit that deliver the
    /// most DC power under a sine (the worst of a band of frequencies), within limits on the
    /// impact speed, contact force, displacement and impacts per second; an infeasible
    /// problem is reported with its least violating design.
    Design(design::DesignArgs),
}

fn main() {
    common::run_main("endstop", || match Cli::parse().study {
        Study::Sweep(a) => sweep::sweep(a),
        Study::Charge(a) => charge::charge(a),
        Study::Random(a) => random::random(a),
        Study::Response(a) => response::response(a),
        Study::Basins(a) => basins::basins_study(a),
        Study::Fit(a) => common::reports::fit_io::run(a),
        Study::Design(a) => design::design(a),
    });
}
