//! The description of a SECE whose transfer runs through its buck-boost inductor (`kind =
//! "sece"` with `inductance_h`): its values and their check against the transducer.

use super::DcLoad;
use crate::device::{Checker, ParamError, Transducer};

/// A SECE whose transfer runs through its buck-boost inductor: at each displacement extremum
/// the rectified element discharges into the inductor, which then discharges into the
/// storage through a flyback diode (see `physics::harvester::circuits::sece_inductor`).
#[derive(Debug, Clone, PartialEq)]
pub struct SeceInductor {
    /// Storage capacitance C_s (F).
    pub storage_capacitance_f: f64,
    /// The DC load.
    pub load: DcLoad,
    /// The inductance L (H).
    pub inductance_h: f64,
    /// The inductor's series resistance R_L (ohm).
    pub inductor_resistance_ohm: f64,
    /// The flyback diode's forward drop V_F (V).
    pub flyback_drop_v: f64,
}

impl SeceInductor {
    /// Checks which of the inductor's file keys (`inductance_h`, `inductor_resistance_ohm`,
    /// `flyback_drop_v`, in that order) an interface of `kind` gives: only `sece` takes them,
    /// the other two need `inductance_h`, and with it `efficiency` is not taken (the transfer
    /// loses what the resistance and the diode take).
    pub(super) fn check_keys(
        kind: &str,
        keys: [Option<f64>; 3],
        efficiency: bool,
        c: &Checker,
    ) -> Result<(), ParamError> {
        let names = ["inductance_h", "inductor_resistance_ohm", "flyback_drop_v"];
        for (key, f) in keys.iter().zip(names) {
            if key.is_some() && kind != "sece" {
                return Err(c.message(
                    &format!("interface.{f}"),
                    &format!("interface kind `{kind}` takes no `{f}`"),
                ));
            }
            if key.is_some() && keys[0].is_none() {
                return Err(c.missing(
                    "interface.inductance_h",
                    &format!("the inductor that `{f}` belongs to"),
                ));
            }
        }
        if keys[0].is_some() && efficiency {
            return Err(c.message(
                "interface.efficiency",
                "interface kind `sece` with `inductance_h` takes no `efficiency`: the transfer \
                 through the inductor loses what its resistance and flyback diode take",
            ));
        }
        Ok(())
    }

    /// Checks the inductor's values, and that the charge phase's loop with the element's
    /// clamped capacitance is underdamped, `R_L < 2 sqrt(L / Cp)`: with more, the element's
    /// voltage decays without reaching zero and the transfer never ends.
    pub(super) fn validate(&self, transducer: &Transducer, c: &Checker) -> Result<(), ParamError> {
        c.positive("interface.inductance_h", self.inductance_h)?;
        c.non_negative(
            "interface.inductor_resistance_ohm",
            self.inductor_resistance_ohm,
        )?;
        c.non_negative("interface.flyback_drop_v", self.flyback_drop_v)?;
        if let Transducer::Piezoelectric(p) = transducer {
            let critical = 2.0 * (self.inductance_h / p.capacitance_f).sqrt();
            if self.inductor_resistance_ohm >= critical {
                return Err(c.err(
                    "interface.inductor_resistance_ohm",
                    self.inductor_resistance_ohm,
                    &format!(
                        "below 2 sqrt(L / Cp) = {critical:e} ohm (an overdamped transfer never \
                         empties the element)"
                    ),
                ));
            }
        }
        Ok(())
    }
}
