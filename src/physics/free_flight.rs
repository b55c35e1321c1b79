//! The harvester in free flight (no contact force) as `y' = L y + c a(t) + N(y)`, for the
//! exponential integrator of random records ([`crate::ode::exponential`]): `L` is the model
//! linearised about rest, `c = (0, 1, 0, 0)` takes the base acceleration, and `N` is the
//! remainder.
//!
//! * The paper's area-overlap pair: `N` comes only from the capacitances' dependence on x
//!   (eq 10) and is written in closed form (below).
//! * A gap-closing pair: `N` is the right-hand side minus `L y`.
//! * Piezoelectric, electromagnetic, or no transducer: the free flight is linear and `N` is
//!   zero, so the exponential step is exact for the linearly interpolated input.
//! * A nonlinear suspension ([`crate::physics::suspension`]), with any transducer: `L` is the
//!   Jacobian at the reference well (not at rest, which may be a barrier's top) and `N` the
//!   right-hand side minus `L y`, which is constant at the well and grows with the distance
//!   from it.
//!
//! For the area-overlap pair, with `Ct = C0 + Cp + CL`, `Gamma = C0 Vb / x0` and
//! `dC = C0 x / x0`:
//!
//! * `L`: `x' = v`, `m v' = -(km + 2 Gamma²/Ct) x - b v - Gamma (s1 - s2)/Ct`,
//!   `RL s1' = -(s1 + Gamma x)/Ct`, `RL s2' = -(s2 - Gamma x)/Ct`
//!   (the differential two-port of eqs 11-17, with the common mode beside it);
//! * `N`: `m N_v = (C0/x0) [ (V1² - V2²)/2 + Vb (dC/Ct) (V1 + V2) ]`,
//!   `RL N_s1 = V1 dC/Ct`, `RL N_s2 = -V2 dC/Ct`, with the exact node voltages of
//!   [`crate::physics::harvester::Harvester::electrical`].
//!
//! `N` is written in closed form (not as the right-hand side minus `L y`) so that it keeps
//! its relative precision: it is of relative size `dC/Ct`, a few per cent at the stops.
//! [`FreeFlight::linear`] + [`FreeFlight::remainder`] equals the free-flight right-hand side
//! to rounding (tested).

use nalgebra::SMatrix;

use crate::drive::Excitation;
use crate::physics::contact::Mode;
use crate::physics::harvester::Harvester;
use crate::physics::suspension::Spring;
use crate::physics::transducer::{PairGeometry, State, TransducerModel};

/// The free-flight split of one device (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FreeFlight {
    kind: FlightKind,
}

/// The remainder `N(y)` of a free flight and the load voltages it is computed from: the
/// exponential step's one evaluation per sample. Each kind of [`FreeFlight`] implements it, so
/// that a record's loop is compiled for the kind it integrates ([`FreeFlight::kind`]).
pub trait Remainder: Copy {
    /// `N(y)` and the load voltages at `y`.
    fn remainder_and_voltages(&self, y: &State) -> (State, [f64; 2]);

    /// `N(y)`.
    #[inline(always)]
    fn remainder(&self, y: &State) -> State {
        self.remainder_and_voltages(y).0
    }
}

/// The kinds of free flight, each with its own [`Remainder`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FlightKind {
    /// The paper's area-overlap pair, with the closed-form remainder.
    AreaOverlap(AreaOverlapFlight),
    /// Any other device.
    General(GeneralFlight),
}

/// The paper's pair, with the closed-form remainder.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AreaOverlapFlight {
    dcdx: f64,
    vb: f64,
    ct: f64,
    gamma: f64,
    inv_ct: f64,
    inv_mass: f64,
    inv_rl: f64,
    inv_ct_rl: f64,
    mass_kg: f64,
    damping: f64,
    km: f64,
}

/// Any other device: `L` is the Jacobian at the reference well (at rest for a linear
/// suspension); `N` is zero for a linear transducer on a linear suspension.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeneralFlight {
    l: SMatrix<f64, 4, 4>,
    transducer: TransducerModel,
    nonlinear: bool,
    inv_mass: f64,
    damping: f64,
    km: f64,
    spring: Spring,
}

// The method lives beside the split it returns, so that the model's module does not import
// this one (which builds on it).
impl<E: Excitation> Harvester<E> {
    /// The free-flight model split into its linearisation about rest and a small remainder,
    /// for [`crate::ode::exponential`] (see [`FreeFlight`]).
    pub fn free_flight(&self) -> FreeFlight {
        FreeFlight::of(self)
    }
}

impl FreeFlight {
    /// The split of a model's free flight.
    pub fn of<E: Excitation>(h: &Harvester<E>) -> Self {
        if let (TransducerModel::Pair(p), false) = (h.transducer, h.spring.nonlinear) {
            if let PairGeometry::AreaOverlap { x0 } = p.geometry {
                let ct = p.c0 + p.cp + p.cl;
                return Self {
                    kind: FlightKind::AreaOverlap(AreaOverlapFlight {
                        dcdx: p.c0 / x0,
                        vb: p.vb,
                        ct,
                        gamma: p.c0 * p.vb / x0,
                        inv_ct: 1.0 / ct,
                        inv_mass: 1.0 / h.mass_kg,
                        inv_rl: 1.0 / p.rl,
                        inv_ct_rl: 1.0 / (ct * p.rl),
                        mass_kg: h.mass_kg,
                        damping: h.damping,
                        km: h.km,
                    }),
                };
            }
        }
        Self {
            kind: FlightKind::General(GeneralFlight {
                l: h.jacobian(
                    Mode::Free,
                    &if h.spring.nonlinear {
                        h.well_state()
                    } else {
                        h.rest_state()
                    },
                ),
                transducer: h.transducer,
                nonlinear: h.spring.nonlinear || matches!(h.transducer, TransducerModel::Pair(_)),
                inv_mass: 1.0 / h.mass_kg,
                damping: h.damping,
                km: h.km,
                spring: h.spring,
            }),
        }
    }

    /// The kind of free flight, with its remainder.
    pub fn kind(&self) -> FlightKind {
        self.kind
    }

    /// True when the remainder is identically zero (the exponential step is then exact).
    pub fn is_linear(&self) -> bool {
        matches!(self.kind, FlightKind::General(g) if !g.nonlinear)
    }

    /// `(L, c)`: the linearised free-flight model and the column of the base acceleration.
    pub fn linear(&self) -> (SMatrix<f64, 4, 4>, State) {
        let c = State::new(0.0, 1.0, 0.0, 0.0);
        match &self.kind {
            FlightKind::AreaOverlap(f) => {
                let (m, g, ct) = (f.mass_kg, f.gamma, f.ct);
                let k_oc = f.km + 2.0 * g * g / ct;
                let rc = f.inv_ct_rl;
                #[rustfmt::skip]
                let l = SMatrix::<f64, 4, 4>::new(
                    0.0, 1.0, 0.0, 0.0,
                    -k_oc / m, -f.damping / m, -g / (m * ct), g / (m * ct),
                    -g * rc, 0.0, -rc, 0.0,
                    g * rc, 0.0, 0.0, -rc,
                );
                (l, c)
            }
            FlightKind::General(g) => (g.l, c),
        }
    }

    /// The load voltages at a state (V), as the model computes them.
    #[inline]
    pub fn voltages(&self, y: &State) -> [f64; 2] {
        match &self.kind {
            FlightKind::AreaOverlap(f) => f.voltages(y),
            FlightKind::General(g) => g.transducer.electrical(y).v,
        }
    }

    /// The remainder `N(y)` (see the module docs).
    #[inline(always)]
    pub fn remainder(&self, y: &State) -> State {
        self.remainder_and_voltages(y).0
    }

    /// The remainder `N(y)` and the load voltages.
    #[inline(always)]
    pub fn remainder_and_voltages(&self, y: &State) -> (State, [f64; 2]) {
        match &self.kind {
            FlightKind::AreaOverlap(f) => f.remainder_and_voltages(y),
            FlightKind::General(g) => g.remainder_and_voltages(y),
        }
    }
}

impl Remainder for GeneralFlight {
    #[inline(always)]
    fn remainder_and_voltages(&self, y: &State) -> (State, [f64; 2]) {
        let volts = self.transducer.electrical(y).v;
        if !self.nonlinear {
            return (State::zeros(), volts);
        }
        let (fe, rates) = self.transducer.force_and_rates(y);
        let f = State::new(
            y[1],
            (-self.damping * y[1] - self.km * y[0] - self.spring.force(y[0]) + fe) * self.inv_mass,
            rates[0],
            rates[1],
        );
        (f - self.l * y, volts)
    }
}

impl AreaOverlapFlight {
    /// The node voltages V1, V2 at a state (V).
    #[inline(always)]
    pub fn voltages(&self, y: &State) -> [f64; 2] {
        let dc = self.dcdx * y[0];
        [
            (y[2] + dc * self.vb) / (self.ct + dc),
            (y[3] - dc * self.vb) / (self.ct - dc),
        ]
    }
}

impl Remainder for AreaOverlapFlight {
    #[inline(always)]
    fn remainder_and_voltages(&self, y: &State) -> (State, [f64; 2]) {
        let dc = self.dcdx * y[0];
        let [v1, v2] = self.voltages(y);
        let r = dc * self.inv_ct;
        let n = State::new(
            0.0,
            self.dcdx * (0.5 * (v1 * v1 - v2 * v2) + self.vb * r * (v1 + v2)) * self.inv_mass,
            v1 * r * self.inv_rl,
            -v2 * r * self.inv_rl,
        );
        (n, [v1, v2])
    }
}
