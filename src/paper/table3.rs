//! Table 3: electromechanical coupling k^2, quality factor Qm and figure of merit k^2 Qm of
//! both prototypes (eqs 15-18), with the broadband efficiency of eq 21 (claims T3-a, T3-b and
//! F14-a's linear-theory value).

use crate::device::Device;
use crate::paper::claims::{Claims, Value};
use crate::paper::setups::{comb, comb_mut, P1_BIAS_V, P2_BIAS_V};
use crate::physics::two_port::{bias_for_coupling, QmReading, TwoPort, EQ21_QM, TABLE3_QM};

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
    /// `p1` or `p2`, the suffix of the claims' quantities.
    pub key: &'static str,
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
        self.two_port.qm(reading)
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

fn prototype(label: &'static str, key: &'static str, bias_v: f64, d: &Device) -> Prototype {
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
        bias_v,
        two_port: TwoPort::of(&device),
        c0_geometry_f: comb(&geometric).c0_f,
        k2_c0_geometry: TwoPort::of(&geometric).k2,
        k2_without_cl: TwoPort::of(&no_cl).k2,
        device,
    }
}

/// Evaluates Table 3 for the two prototypes' parameter files.
pub fn run(prototype1: &Device, prototype2: &Device) -> Run {
    let p2 = prototype("prototype 2", "p2", P2_BIAS_V, prototype2);
    let efficiency_against_load = load_grid_ohm()
        .into_iter()
        .map(|r_ohm| {
            let mut d = p2.device.clone();
            comb_mut(&mut d).load_resistance_ohm = r_ohm;
            let tp = TwoPort::of(&d);
            (r_ohm, tp.broadband_efficiency(tp.qm(EQ21_QM)))
        })
        .collect();
    Run {
        prototypes: [prototype("prototype 1", "p1", P1_BIAS_V, prototype1), p2],
        bias_for_abstract_k2_p1_v: bias_for_coupling(prototype1, ABSTRACT_K2_P1),
        efficiency_against_load,
    }
}

/// Claims T3-a and T3-b (k^2, Qm under [`TABLE3_QM`], k^2 Qm of each prototype) and F14-a's
/// eq 21 efficiency of prototype 2 (Qm under [`EQ21_QM`]).
pub fn claims(run: &Run, _claims: &Claims) -> Vec<Value> {
    let mut out = Vec::new();
    for (id, p) in ["T3-a", "T3-b"].into_iter().zip(&run.prototypes) {
        let (tp, qm) = (&p.two_port, p.qm(TABLE3_QM));
        let q = |name: &str| format!("{name}_{}", p.key);
        let at = format!("eq 18 at {} V", p.bias_v);
        out.push(Value::new(
            id,
            &q("k2_pct"),
            "published",
            tp.k2 * 100.0,
            None,
            at.clone(),
        ));
        out.push(Value::new(
            id,
            &q("qm"),
            "published",
            qm,
            None,
            format!("Qm = {}", TABLE3_QM.label()),
        ));
        out.push(Value::new(
            id,
            &q("k2qm"),
            "published",
            tp.k2 * qm,
            None,
            at,
        ));
    }
    out.push(Value::new(
        "F14-a",
        "eff_eq21_pct",
        "published",
        run.prototypes[1].eq21_efficiency() * 100.0,
        None,
        format!("eq 21 with Qm = {}", EQ21_QM.label()),
    ));
    out
}
