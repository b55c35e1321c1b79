//! The ngspice netlist of the paper's electrostatic pair behind a full bridge of Shockley
//! diodes into a storage capacitor and a resistor: the circuit of
//! [`crate::circuits`] with an electrostatic pair as its element
//! (`data/examples/prototype2_bridge.toml`, with Shockley diodes in place of its
//! piecewise-linear ones).
//!
//! It is the paper's netlist ([`crate::spice::netlist`]: the mobility analogue of the
//! mechanics, the stop law, the pair's two transducers with each electrode's load RL || CL to
//! ground, which behind the bridge are the model's bleed resistors and load capacitors) with
//! the bridge of [`crate::spice::bridge`] across the electrodes `n1` and `n2`. The storage `Cs`
//! and the DC load `RL` sit between the floating nodes `a` and `b`, neither grounded: the
//! model's port, whose bridge current leaves one electrode and enters the other. For the
//! bridge's symmetric diodes the floating storage splits its voltage evenly about the
//! electrodes' mean, so each diode of a conducting path carries half the path's voltage, as
//! the model has it. The storage voltage is written as the vector `v(a,b)`
//! ([`STORAGE_VECTOR`]).
//!
//! ngspice adds its `gmin` (1e-12 S by default) across every junction; a lower `gmin` stops
//! ngspice with "timestep too small" at the blocking bridge's node `a` (ngspice 39).

use crate::device::Device;
use crate::spice::bridge::{ShockleyBridge, Unsupported};
use crate::spice::netlist::{
    num, write_analysis, write_control, write_header, write_initial_state, write_mechanics,
    write_pair, write_parameters, write_spring_law, PaperParts,
};
use crate::spice::{SpiceDrive, SpiceOptions};

/// The storage voltage's vector in the `wrdata` output.
pub const STORAGE_VECTOR: &str = "v(a,b)";

/// The vectors [`pair_bridge_netlist`] writes with `wrdata`, after the time.
pub const PAIR_BRIDGE_VECTORS: [&str; 5] = ["v(n1)", "v(n2)", "v(xpos)", "v(vel)", STORAGE_VECTOR];

/// The netlist of `device` (an area-overlap pair with one Hertz line stop for both sides,
/// behind a full bridge of Shockley diodes into a resistor) driven by `drive`, starting from
/// `opts.initial` with the storage at `storage_v0` (V; its nodes at `+-storage_v0 / 2`).
pub fn pair_bridge_netlist(
    device: &Device,
    drive: &SpiceDrive,
    opts: &SpiceOptions,
    storage_v0: f64,
) -> Result<String, Unsupported> {
    let parts = PaperParts::of(device).ok_or(Unsupported(
        "the paper's topology: an area-overlap pair and one Hertz line stop for both sides",
    ))?;
    let rect = ShockleyBridge::of(device)?;
    let mut s = String::new();
    write_header(
        &mut s,
        device,
        drive,
        &opts.title,
        "src/spice/pair_bridge.rs",
    );
    s.push_str(
        "* Behind a full bridge of Shockley diodes from n1, n2 into Cs || RL between the\n\
         * floating nodes a and b, in place of the paper's resistive loads.\n",
    );
    write_parameters(&mut s, device, &parts, drive);
    write_spring_law(&mut s, parts.hertz, opts.hertz_newton_steps);
    write_mechanics(&mut s, parts.stop);
    write_pair(&mut s);
    s.push_str("\n* --- full bridge into the storage Cs and the load RL (floating) ---\n");
    rect.write(&mut s, ["n1", "n2"], ["a", "b"]);
    // `0.0 - x` rather than `-x`: a rest state writes 0, not -0.
    let storage = format!(
        " V(a)={} V(b)={}",
        num(0.5 * storage_v0),
        num(0.0 - 0.5 * storage_v0)
    );
    write_initial_state(&mut s, &opts.initial, parts.e.bias_v, &storage);
    write_analysis(&mut s, &opts.solver, &opts.transient);
    if let Some(file) = &opts.transient.wrdata_file {
        write_control(&mut s, file, &PAIR_BRIDGE_VECTORS);
    }
    s.push_str(".end\n");
    Ok(s)
}
