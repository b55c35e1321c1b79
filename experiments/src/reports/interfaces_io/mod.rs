//! From the harvester to the battery (the program `interfaces`): the example devices
//! `data/examples/piezo_bridge.toml` (a piezoelectric cantilever with a stop) and
//! `data/examples/em_bridge.toml` (an electromagnetic harvester with stops) behind each
//! interface circuit. [`run`] writes the DC power against the load for every interface, the DC
//! power against frequency with each steady state's stability and the energy ledger of each
//! interface (`steady.rs`), a charging curve and random ensembles (`records.rs`), as Parquet,
//! plots and the chapter's generated tables (`book/src/generated/interfaces/`).

use anyhow::Result;
use endstop::device::{DcLoad, Device, Interface, Inversion, Rectifier};
use endstop::study::periodic::SteadySettings;

use crate::Experiment;

mod records;
mod steady;

/// The drive of the chapter's sine studies (g rms).
const ACCEL_RMS_G: f64 = 0.3;
/// Seed of the random ensembles.
const SEED: u64 = 33;

/// Runs the chapter's studies and writes their outputs.
pub fn run() -> Result<()> {
    let mut exp = Experiment::start("interfaces");
    exp.seed = Some(SEED);
    let piezo = crate::load_device("examples/piezo_bridge")?;
    let em = crate::load_device("examples/em_bridge")?;
    let resistive = crate::load_device("examples/piezo_cantilever")?;
    for d in [&piezo, &em, &resistive] {
        let set = d.device.params.clone();
        exp.uses(d, &set);
    }
    let settings = SteadySettings::default();
    steady::power_vs_load(&mut exp, &piezo, &resistive, &settings)?;
    steady::power_vs_frequency(&mut exp, &piezo, &em, &settings)?;
    steady::ledger(&exp, &piezo, &em, &settings)?;
    records::charging(&mut exp, &piezo)?;
    records::ensembles(&mut exp, &piezo)?;
    // The storage's time constant the chapter's prose quotes, R_L C_s of the bridge example.
    if let Interface::FullBridge(Rectifier {
        storage_capacitance_f: cs,
        load: DcLoad::Resistor { resistance_ohm },
        ..
    }) = &piezo.device.interface
    {
        crate::write_atomic(
            &exp.book_dir.join("storage_tau.md"),
            format!("{} s", crate::fmt_sig(cs * resistance_ohm, 2)).as_bytes(),
        )?;
    }
    exp.write_numbers_md("The interface circuits' chapter data.\n")?;
    exp.finish()
}

/// Quality factor of the SSHI variants' inversion branch ([`variants`]).
pub const SSHI_Q: f64 = 3.0;

/// Energy efficiency of the SECE variant's extraction ([`variants`]).
pub const SECE_EFFICIENCY: f64 = 0.8;

/// The interfaces the chapter puts behind a device: its own full bridge and, for a
/// piezoelectric device, the parallel and series SSHI ([`SSHI_Q`]) and SECE
/// ([`SECE_EFFICIENCY`]) on the same storage and load. The benchmark times the same variants.
pub fn variants(d: &Device) -> Vec<(&'static str, Device)> {
    let Interface::FullBridge(r) = &d.interface else {
        return vec![("full_bridge", d.clone())];
    };
    let with = |i: Interface| {
        let mut x = d.clone();
        x.interface = i;
        x
    };
    let q = Inversion::QualityFactor(SSHI_Q);
    let mut v = vec![("full_bridge", d.clone())];
    if matches!(d.transducer, endstop::device::Transducer::Piezoelectric(_)) {
        v.push(("parallel_sshi", with(Interface::ParallelSshi(r.clone(), q))));
        v.push(("series_sshi", with(Interface::SeriesSshi(r.clone(), q))));
        v.push((
            "sece",
            with(Interface::Sece {
                storage_capacitance_f: r.storage_capacitance_f,
                load: r.load.clone(),
                efficiency: SECE_EFFICIENCY,
            }),
        ));
    }
    v
}

/// The device's suspension resonance (Hz).
pub(crate) fn resonance_hz(d: &Device) -> f64 {
    d.suspension_omega_rad_s() / (2.0 * std::f64::consts::PI)
}
