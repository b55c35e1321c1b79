//! The harvester's free flight split for the exponential integrator of sampled records
//! ([`crate::model::FlightSplit`]): `y' = L y + c a(t) + R(y)` off the stops, with
//! `c = (0, 1, 0, 0)` taking the base acceleration. A transducer with its own loads has one; a
//! port behind an interface circuit has none (its modes are integrated through their affine
//! forms, [`crate::model::Model::affine`]).
//!
//! * The paper's area-overlap pair on a linear suspension: `L` is the model linearised about
//!   rest and `R` comes only from the capacitances' dependence on x (eq 10), written in closed
//!   form (below).
//! * A gap-closing pair: `R` is the right-hand side minus `L y`.
//! * Piezoelectric, electromagnetic, or no transducer: the free flight is linear and `R` is
//!   zero, so the exponential step is exact for the linearly interpolated input.
//! * A nonlinear suspension ([`crate::laws::suspension`]), with any transducer: `L` is the
//!   Jacobian at the reference well (not at rest, which may be a barrier's top) and `R` the
//!   right-hand side minus `L y`, which is constant at the well and grows with the distance
//!   from it.
//!
//! For the area-overlap pair, with `Ct = C0 + Cp + CL`, `Gamma = C0 Vb / x0` and
//! `dC = C0 x / x0`:
//!
//! * `L`: `x' = v`, `m v' = -(km + 2 Gamma²/Ct) x - b v - Gamma (s1 - s2)/Ct`,
//!   `RL s1' = -(s1 + Gamma x)/Ct`, `RL s2' = -(s2 - Gamma x)/Ct`
//!   (the differential two-port of eqs 11-17, with the common mode beside it);
//! * `R`: `m R_v = (C0/x0) [ (V1² - V2²)/2 + Vb (dC/Ct) (V1 + V2) ]`,
//!   `RL R_s1 = V1 dC/Ct`, `RL R_s2 = -V2 dC/Ct`, with the exact node voltages.
//!
//! `R` is written in closed form (not as the right-hand side minus `L y`) so that it keeps its
//! relative precision: it is of relative size `dC/Ct`, a few per cent at the stops. `L y + R(y)`
//! equals the free-flight right-hand side to rounding (tested).

use nalgebra::{SMatrix, SVector};

use crate::laws::contact::Side;
use crate::laws::suspension::Spring;
use crate::model::{FlightSplit, FlightVisitor, Mode, NoFlight, Remainder, MAX_OUTPUTS};
use crate::physics::transducer::{PairGeometry, TransducerModel};

use super::port::{head, Port};
use super::Harvester;

/// The paper's area-overlap pair on a linear suspension, with the closed-form remainder.
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

/// Any other loaded transducer: `L` is the Jacobian at the reference well (at rest for a
/// linear suspension); `R` is zero for a linear transducer on a linear suspension.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GeneralFlight<const N: usize> {
    l: SMatrix<f64, N, N>,
    transducer: TransducerModel,
    nonlinear: bool,
    inv_mass: f64,
    damping: f64,
    km: f64,
    spring: Spring,
}

impl<const N: usize> Harvester<N> {
    /// Hands the free flight split for steps of `dt_s` to `visitor` (see the module docs and
    /// [`crate::model::Model::flight`]), or says why there is none: behind a circuit, or for a
    /// capacitor pair whose free flight could reach an inadmissible state that only the adaptive
    /// integrator checks (a capacitance plus Cp not positive before a stop, or no stop on one
    /// side).
    pub(super) fn visit_flight<V: FlightVisitor<N>>(&self, dt_s: f64, visitor: V) -> V::Output {
        let Port::Loaded(transducer) = self.port else {
            return visitor.refused(NoFlight::Unavailable);
        };
        if let TransducerModel::Pair(p) = transducer {
            for side in Side::BOTH {
                let gap = self.gap(side);
                if !gap.is_finite() {
                    return visitor.refused(NoFlight::UnboundedPair);
                }
                if let PairGeometry::AreaOverlap { x0 } = p.geometry {
                    if p.c0 * gap / x0 >= p.c0 + p.cp {
                        return visitor.refused(NoFlight::CapacitanceVanishes);
                    }
                }
            }
        }
        let mut c = SVector::<f64, N>::zeros();
        c[1] = 1.0;
        let reach_m = self.spring.fast_path_reach_m(self.km, self.mass_kg, dt_s);
        let centre_m = self.spring.well_m;
        if let Some(f) = self.area_overlap_flight(transducer) {
            let split = FlightSplit {
                l: f.linear(),
                c,
                linear: false,
                reach_m,
                centre_m,
            };
            return visitor.visit(split, f);
        }
        let nonlinear = self.spring.nonlinear || matches!(transducer, TransducerModel::Pair(_));
        let f = GeneralFlight {
            l: self.linearised_at_reference(),
            transducer,
            nonlinear,
            inv_mass: 1.0 / self.mass_kg,
            damping: self.damping,
            km: self.km,
            spring: self.spring,
        };
        let split = FlightSplit {
            l: f.l,
            c,
            linear: !nonlinear,
            reach_m,
            centre_m,
        };
        visitor.visit(split, f)
    }
}

impl<const N: usize> Harvester<N> {
    /// `L` of the free flight split, the model off the stops linearised about its reference
    /// state (in closed form for the paper's area-overlap pair), whether or not the split is
    /// offered to an integrator; `None` behind a circuit. The linear theory of
    /// [`crate::physics::linear`] is taken from it.
    pub fn flight_matrix(&self) -> Option<SMatrix<f64, N, N>> {
        let Port::Loaded(transducer) = self.port else {
            return None;
        };
        Some(match self.area_overlap_flight(transducer) {
            Some(f) => f.linear(),
            None => self.linearised_at_reference(),
        })
    }

    /// The Jacobian of the free flight at the reference state: the reference well of a
    /// nonlinear suspension, rest otherwise.
    fn linearised_at_reference(&self) -> SMatrix<f64, N, N> {
        let at = if self.spring.nonlinear {
            self.well_state()
        } else {
            SVector::zeros()
        };
        self.linearised(Mode::FREE, &at)
    }

    /// The closed-form split of the paper's area-overlap pair on a linear suspension, if the
    /// transducer is one.
    fn area_overlap_flight(&self, transducer: TransducerModel) -> Option<AreaOverlapFlight> {
        let (TransducerModel::Pair(p), false) = (transducer, self.spring.nonlinear) else {
            return None;
        };
        let PairGeometry::AreaOverlap { x0 } = p.geometry else {
            return None;
        };
        let ct = p.c0 + p.cp + p.cl;
        Some(AreaOverlapFlight {
            dcdx: p.c0 / x0,
            vb: p.vb,
            ct,
            gamma: p.c0 * p.vb / x0,
            inv_ct: 1.0 / ct,
            inv_mass: 1.0 / self.mass_kg,
            inv_rl: 1.0 / p.rl,
            inv_ct_rl: 1.0 / (ct * p.rl),
            mass_kg: self.mass_kg,
            damping: self.damping,
            km: self.km,
        })
    }
}

impl AreaOverlapFlight {
    /// `L` in closed form (see the module docs).
    fn linear<const N: usize>(&self) -> SMatrix<f64, N, N> {
        let (m, g, ct) = (self.mass_kg, self.gamma, self.ct);
        let k_oc = self.km + 2.0 * g * g / ct;
        let rc = self.inv_ct_rl;
        let mut l = SMatrix::<f64, N, N>::zeros();
        l[(0, 1)] = 1.0;
        l[(1, 0)] = -k_oc / m;
        l[(1, 1)] = -self.damping / m;
        l[(1, 2)] = -g / (m * ct);
        l[(1, 3)] = g / (m * ct);
        l[(2, 0)] = -g * rc;
        l[(2, 2)] = -rc;
        l[(3, 0)] = g * rc;
        l[(3, 3)] = -rc;
        l
    }

    /// The node voltages V1, V2 at a state (V).
    #[inline(always)]
    fn voltages<const N: usize>(&self, y: &SVector<f64, N>) -> [f64; 2] {
        let dc = self.dcdx * y[0];
        [
            (y[2] + dc * self.vb) / (self.ct + dc),
            (y[3] - dc * self.vb) / (self.ct - dc),
        ]
    }
}

impl<const N: usize> Remainder<N> for AreaOverlapFlight {
    #[inline(always)]
    fn remainder_and_outputs(
        &self,
        y: &SVector<f64, N>,
        outputs: &mut [f64; MAX_OUTPUTS],
    ) -> SVector<f64, N> {
        let dc = self.dcdx * y[0];
        let [v1, v2] = self.voltages(y);
        let r = dc * self.inv_ct;
        let mut n = SVector::<f64, N>::zeros();
        n[1] = self.dcdx * (0.5 * (v1 * v1 - v2 * v2) + self.vb * r * (v1 + v2)) * self.inv_mass;
        n[2] = v1 * r * self.inv_rl;
        n[3] = -v2 * r * self.inv_rl;
        outputs[0] = v1;
        outputs[1] = v2;
        n
    }
}

impl<const N: usize> Remainder<N> for GeneralFlight<N> {
    #[inline(always)]
    fn remainder_and_outputs(
        &self,
        y: &SVector<f64, N>,
        outputs: &mut [f64; MAX_OUTPUTS],
    ) -> SVector<f64, N> {
        let h = head(y);
        let volts = self.transducer.electrical(&h).v;
        outputs[0] = volts[0];
        outputs[1] = volts[1];
        if !self.nonlinear {
            return SVector::zeros();
        }
        let (fe, rates) = self.transducer.force_and_rates(&h);
        let mut f = SVector::<f64, N>::zeros();
        f[0] = y[1];
        f[1] =
            (-self.damping * y[1] - self.km * y[0] - self.spring.force(y[0]) + fe) * self.inv_mass;
        f[2] = rates[0];
        f[3] = rates[1];
        f - self.l * y
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device::Device;
    use crate::model::Model;

    /// Hands back the split and `L y + R(y)` at a few states against the free flight's
    /// right-hand side.
    struct Check<'a> {
        h: &'a Harvester<4>,
    }

    impl FlightVisitor<4> for Check<'_> {
        type Output = Option<f64>;

        fn visit<R: Remainder<4>>(self, split: FlightSplit<4>, r: R) -> Option<f64> {
            let sc = self.h.scales();
            let (mut worst, mut out_diff, mut out_size) = (0.0f64, 0.0f64, 0.0f64);
            for k in 0..5 {
                let f = k as f64 / 5.0 - 0.4;
                let y = SVector::<f64, 4>::new(
                    f * 0.9 * sc[0],
                    -f * sc[1],
                    0.3 * f * sc[2],
                    -0.2 * f * sc[3],
                ) + self.h.well_state();
                let rhs = self.h.rhs(Mode::FREE, &y, 0.0);
                let mut out = [0.0; 8];
                let sum = split.l * y + r.remainder_and_outputs(&y, &mut out);
                let mut o = [0.0; 8];
                self.h.outputs(Mode::FREE, &y, &mut o);
                for i in 0..2 {
                    out_diff = out_diff.max((out[i] - o[i]).abs());
                    out_size = out_size.max(o[i].abs());
                }
                for i in 0..4 {
                    // Each row against the largest of its terms.
                    let row = (0..4)
                        .map(|j| (split.l[(i, j)] * y[j]).abs())
                        .fold(rhs[i].abs(), f64::max);
                    if row > 0.0 {
                        worst = worst.max((sum[i] - rhs[i]).abs() / row);
                    }
                }
            }
            if out_size > 0.0 {
                worst = worst.max(out_diff / out_size);
            }
            Some(worst)
        }

        fn refused(self, _: NoFlight) -> Option<f64> {
            None
        }
    }

    fn devices() -> Vec<Device> {
        let root = env!("CARGO_MANIFEST_DIR");
        let mut files = vec![
            format!("{root}/data/prototype1.toml"),
            format!("{root}/data/prototype2.toml"),
        ];
        for dir in ["data/examples", "data/validation"] {
            for e in std::fs::read_dir(format!("{root}/{dir}")).unwrap() {
                let p = e.unwrap().path();
                if p.extension().is_some_and(|x| x == "toml") {
                    files.push(p.to_string_lossy().into_owned());
                }
            }
        }
        files.sort();
        files
            .iter()
            .map(|f| Device::from_toml_str(&std::fs::read_to_string(f).unwrap(), f).unwrap())
            .collect()
    }

    /// `L y + R(y)` is the free flight's right-hand side to rounding (1e-12 of the largest
    /// term of each row: a few ulps of the terms that cancel), and the outputs the remainder
    /// hands back are the model's to 1e-12 relatively (the paper's pair computes its node
    /// voltages in closed form), on every device of the data directory that assembles into a
    /// one-mass harvester of four states and splits its flight (the assembly decides: a device
    /// of several masses assembles into `masses::MassChain`, a circuit into another dimension).
    #[test]
    fn the_split_sums_to_the_free_flight() {
        let mut checked = 0;
        for d in devices() {
            let Ok(h) = Harvester::<4>::new(&d) else {
                continue;
            };
            if let Some(worst) = h.visit_flight(1e-5, Check { h: &h }) {
                assert!(worst < 1e-12, "{}: {worst:e}", d.name);
                checked += 1;
            }
        }
        assert!(checked > 10, "{checked} devices checked");
    }
}
