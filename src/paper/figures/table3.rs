//! Table 3: electromechanical coupling k^2, quality factor Qm and figure of merit k^2 Qm of
//! both prototypes (eqs 15-18), with the broadband efficiency of eq 21 (claims T3-a, T3-b and
//! F14-a's linear-theory value).

use std::convert::Infallible;

use crate::device::Device;
use crate::paper::claims::{keys, ClaimKey, Claims, ClaimsError, Value};
use crate::paper::qm::{QmReading, EQ21_QM, TABLE3_QM};
use crate::paper::setups::{comb, comb_mut, ParamSet, Prototypes, P1_BIAS_V, P2_BIAS_V};
use crate::paper::Figure;
use crate::physics::two_port::{bias_for_coupling, TwoPort};
use crate::progress::Progress;

/// The abstract's k^2 for prototype 1 (a fraction): 1.44 %.
pub const ABSTRACT_K2_P1: f64 = 0.0144;

/// Load resistances of eq 21's efficiency curve (ohm): 200 points, logarithmic from 0.1 to
/// 1000 MOhm.
pub fn load_grid_ohm() -> Vec<f64> {
    (0..200)
        .map(|i| 1e5 * 10f64.powf(i as f64 * 4.0 / 199.0))
        .collect()
}

/// One prototype of Table 3 at its bias voltage.
#[derive(Debug, Clone, PartialEq)]
pub struct Prototype {
    /// `prototype 1` or `prototype 2`.
    pub label: &'static str,
    /// `p1` or `p2`, the suffix of its numbers' names.
    pub key: &'static str,
    /// The claim numbers of this prototype: k^2 (%), Qm, k^2 Qm.
    pub keys: [ClaimKey; 3],
    /// Table 3's bias voltage (V).
    pub bias_v: f64,
    /// The device at that bias.
    pub device: Device,
    /// The two-port (eqs 15-18).
    pub two_port: TwoPort,
    /// C0 from the geometry, eq 10 with Table 1 (F).
    pub c0_geometry_f: f64,
    /// k^2 with that C0.
    pub k2_c0_geometry: f64,
    /// k^2 without the load capacitance in eq 18 (the transducer alone).
    pub k2_without_cl: f64,
}

impl Prototype {
    /// Qm under a reading.
    pub fn qm(&self, reading: QmReading) -> f64 {
        reading.of(&self.two_port)
    }

    /// Eq 21's efficiency 2P/(m Sa) with Qm under a reading (fraction).
    pub fn efficiency(&self, reading: QmReading) -> f64 {
        self.two_port.broadband_efficiency(self.qm(reading))
    }

    /// Eq 21's efficiency with its own Qm reading ([`EQ21_QM`]).
    pub fn eq21_efficiency(&self) -> f64 {
        self.efficiency(EQ21_QM)
    }
}

/// Table 3's numbers.
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    /// Prototype 1 at 30 V and prototype 2 at 15 V.
    pub prototypes: [Prototype; 2],
    /// The bias at which eq 18 gives the abstract's k^2 = 1.44 % for prototype 1 (V).
    pub bias_for_abstract_k2_p1_v: f64,
    /// Eq 21's efficiency of prototype 2 against the load: (RL in ohm, efficiency).
    pub efficiency_against_load: Vec<(f64, f64)>,
}

fn prototype(
    label: &'static str,
    key: &'static str,
    keys: [ClaimKey; 3],
    bias_v: f64,
    d: &Device,
) -> Prototype {
    let device = d.with_bias(bias_v);
    let mut geometric = device.clone();
    comb_mut(&mut geometric).c0_f = comb(d)
        .c0_from_geometry_f()
        .expect("the paper's device files give the finger geometry");
    let mut no_cl = device.clone();
    comb_mut(&mut no_cl).load_capacitance_f = 0.0;
    Prototype {
        label,
        key,
        keys,
        bias_v,
        two_port: TwoPort::of(&device),
        c0_geometry_f: comb(&geometric).c0_f,
        k2_c0_geometry: TwoPort::of(&geometric).k2,
        k2_without_cl: TwoPort::of(&no_cl).k2,
        device,
    }
}

/// The claim numbers of Table 3 for prototype 1 (T3-a): k^2 (%), Qm, k^2 Qm.
const P1_KEYS: [ClaimKey; 3] = [keys::T3A_K2_P1, keys::T3A_QM_P1, keys::T3A_K2QM_P1];

/// The claim numbers of Table 3 for prototype 2 (T3-b).
const P2_KEYS: [ClaimKey; 3] = [keys::T3B_K2_P2, keys::T3B_QM_P2, keys::T3B_K2QM_P2];

/// Evaluates Table 3 for the two prototypes' parameter files.
fn evaluate(prototype1: &Device, prototype2: &Device) -> Run {
    let p2 = prototype("prototype 2", "p2", P2_KEYS, P2_BIAS_V, prototype2);
    let efficiency_against_load = load_grid_ohm()
        .into_iter()
        .map(|r_ohm| {
            let mut d = p2.device.clone();
            comb_mut(&mut d).load_resistance_ohm = r_ohm;
            let tp = TwoPort::of(&d);
            (r_ohm, tp.broadband_efficiency(EQ21_QM.of(&tp)))
        })
        .collect();
    Run {
        prototypes: [
            prototype("prototype 1", "p1", P1_KEYS, P1_BIAS_V, prototype1),
            p2,
        ],
        bias_for_abstract_k2_p1_v: bias_for_coupling(prototype1, ABSTRACT_K2_P1),
        efficiency_against_load,
    }
}

/// Table 3: k^2, Qm and k^2 Qm of both prototypes, and eq 21's efficiency.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Table3;

impl Figure for Table3 {
    const NAME: &'static str = "table3";
    type Setup = Prototypes;
    type Run = Run;
    type Error = Infallible;

    fn work(_: &Prototypes) -> usize {
        0
    }

    /// Evaluates Table 3 for the two prototypes' parameter files (no simulation).
    fn run(setup: &Prototypes, _: &dyn Progress) -> Result<Run, Infallible> {
        Ok(evaluate(&setup.prototype1, &setup.prototype2))
    }

    /// Claims T3-a and T3-b (k^2, Qm under [`TABLE3_QM`], k^2 Qm of each prototype) and
    /// F14-a's eq 21 efficiency of prototype 2 (Qm under [`EQ21_QM`]).
    fn claims(run: &Run, claims: &Claims) -> Result<Vec<Value>, ClaimsError> {
        let set = ParamSet::Published;
        let mut out = Vec::new();
        for p in &run.prototypes {
            let (tp, qm) = (&p.two_port, p.qm(TABLE3_QM));
            let [k2, qm_key, k2qm] = p.keys;
            let at = format!("eq 18 at {} V", p.bias_v);
            out.push(Value::new(k2, set, tp.k2 * 100.0, None, at.clone()));
            out.push(Value::new(
                qm_key,
                set,
                qm,
                None,
                format!("Qm = {}", TABLE3_QM.label()),
            ));
            out.push(Value::new(k2qm, set, tp.k2 * qm, None, at));
        }
        out.push(Value::new(
            keys::F14A_EFF_EQ21,
            set,
            run.prototypes[1].eq21_efficiency() * 100.0,
            None,
            format!("eq 21 with Qm = {}", EQ21_QM.label()),
        ));
        claims.known(out)
    }
}
