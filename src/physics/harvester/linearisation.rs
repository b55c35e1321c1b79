//! The harvester's linearisation: the Jacobian of the right-hand side in each mode, which the
//! variational equations integrate ([`crate::model::tangent`]), and the affine form of each
//! mode that is linear, which the exact propagators use ([`crate::study::flow`]).
//!
//! A mode is affine when the suspension is linear, the transducer is linear (piezoelectric,
//! electromagnetic, or none, with its loads; behind a circuit, a piezoelectric element or a
//! coil with piecewise-linear diodes), and the contact adds no nonlinear force: free flight, a
//! tension-free stop's clipped phase when its bracket is linear, and contact with a linear
//! spring and a viscous damper. Its matrix is the Jacobian at rest (the dynamics only where no
//! force is nonlinear); its constant term comes from a linear contact's spring, pressed in from
//! the gap, and from a conducting bridge's drop or a battery's voltage (read off the
//! right-hand side at rest).

use nalgebra::{SMatrix, SVector};

use super::circuits::DiodeLaw;
use crate::laws::contact::{ContactDamping, ContactLaw, Side, StopModel};
use crate::model::{Affine, AffineGuard, Contact, Mode};
use crate::physics::transducer::TransducerModel;

use super::circuits::{Bridge, CircuitKind, CircuitMode, Element};
use super::port::{head, Port};
use super::stops::{contact_of, FrameStops};
use super::{Harvester, STOP_GUARDS};

impl<const N: usize> Harvester<N> {
    /// The Jacobian of the right-hand side with respect to the state, in a mode (the drive
    /// enters additively and does not appear).
    ///
    /// A pair's part is [`crate::physics::transducer::CapacitorPair::gradients`], the other
    /// loaded transducers' their linear coefficients, a circuit's its own
    /// ([`super::circuits::Circuit::jacobian`]); in contact the end-stop force adds the bracket's
    /// derivatives (a tension-free contact whose force is clipped adds nothing); resting on a
    /// stop, x and v do not move.
    pub fn linearised(&self, mode: Mode, y: &SVector<f64, N>) -> SMatrix<f64, N, N> {
        let m = self.mass_kg;
        let km = self.restoring_stiffness(y[0]);
        let (mut dfim_dx, mut dfim_dv) = (0.0, 0.0);
        if let Some((side, Contact::Pressed)) = FrameStops::touching(mode) {
            if let Some(s) = self.stop(side) {
                if !s.tension_free() || self.stops.bracket(side, y[0], y[1]) > 0.0 {
                    (dfim_dx, dfim_dv) =
                        s.bracket_gradient(self.penetration(side, y[0]), side.sign() * y[1]);
                }
            }
        }
        let resting = FrameStops::resting(mode).is_some();
        let mut j = SMatrix::<f64, N, N>::zeros();
        match &self.port {
            Port::Loaded(t) => {
                j[(0, 1)] = 1.0;
                match *t {
                    TransducerModel::Pair(p) => {
                        let el = p.electrical(&head(y));
                        let g = p.gradients(y[0], &el);
                        j[(1, 0)] = (-km + g.df_dx - dfim_dx) / m;
                        j[(1, 1)] = (-self.damping - dfim_dv) / m;
                        j[(1, 2)] = g.df_ds[0] / m;
                        j[(1, 3)] = g.df_ds[1] / m;
                        j[(2, 0)] = g.rate_dx[0];
                        j[(2, 2)] = g.rate_ds[0];
                        j[(3, 0)] = g.rate_dx[1];
                        j[(3, 3)] = g.rate_ds[1];
                    }
                    TransducerModel::None => {
                        j[(1, 0)] = (-km - dfim_dx) / m;
                        j[(1, 1)] = (-self.damping - dfim_dv) / m;
                    }
                    TransducerModel::Piezo { theta, cp, r } => {
                        j[(1, 0)] = (-km - dfim_dx) / m;
                        j[(1, 1)] = (-self.damping - dfim_dv) / m;
                        j[(1, 2)] = theta / m;
                        j[(2, 1)] = -theta / cp;
                        j[(2, 2)] = -1.0 / (r * cp);
                    }
                    TransducerModel::Electromagnetic { phi, rc, l, r } => {
                        j[(1, 0)] = (-km - dfim_dx) / m;
                        if l > 0.0 {
                            j[(1, 1)] = (-self.damping - dfim_dv) / m;
                            j[(1, 2)] = -phi / m;
                            j[(2, 1)] = phi / l;
                            j[(2, 2)] = -(rc + r) / l;
                        } else {
                            j[(1, 1)] = (-self.damping - phi * phi / (rc + r) - dfim_dv) / m;
                        }
                    }
                }
            }
            Port::Circuit(_) => {
                if !resting {
                    j[(0, 1)] = 1.0;
                    j[(1, 0)] = (-km - dfim_dx) / m;
                    j[(1, 1)] = (-self.damping - dfim_dv) / m;
                }
                let scales = self.scales;
                self.port
                    .circuit_jacobian(mode.circuit(0), y, m, &scales, &mut j);
            }
        }
        if resting {
            for c in 0..N {
                j[(0, c)] = 0.0;
                j[(1, c)] = 0.0;
            }
        }
        j
    }

    /// True when the port is linear in every mode: a loaded piezoelectric element, coil or no
    /// transducer; behind a circuit, a piezoelectric element or a coil with piecewise-linear
    /// diodes.
    pub(super) fn port_is_affine(&self) -> bool {
        match &self.port {
            Port::Loaded(t) => !matches!(t, TransducerModel::Pair(_)),
            Port::Circuit(c) => {
                !matches!(c.element, Element::Pair(_))
                    && matches!(c.diode, DiodeLaw::PiecewiseLinear { .. })
            }
        }
    }

    /// The affine form of `mode` (see the module docs), or `None` where it is not affine.
    pub fn affine_form(&self, mode: Mode) -> Option<Affine<N>> {
        if !self.port_is_affine() || self.spring.nonlinear {
            return None;
        }
        let m = self.mass_kg;
        let rest = SVector::<f64, N>::zeros();
        let touching = FrameStops::touching(mode);
        if matches!(touching, Some((_, Contact::Resting))) {
            return None;
        }
        let free_mode = mode.without_contacts();
        let free = self.linearised(free_mode, &rest);
        let gap_guard = |index: usize, side: Side, sign: f64| {
            self.stop(side).map(|s| {
                let mut n = SVector::<f64, N>::zeros();
                // sign * (side.sign() x - gap)
                n[0] = sign * side.sign();
                AffineGuard {
                    index,
                    n,
                    g0: -sign * s.gap(),
                }
            })
        };
        let mut guards = Vec::new();
        let (l, mut d) = match touching {
            None => {
                guards.extend(gap_guard(0, Side::Upper, 1.0));
                guards.extend(gap_guard(2, Side::Lower, 1.0));
                (free, SVector::<f64, N>::zeros())
            }
            Some((side, c)) => {
                let Some(&StopModel::Compliant {
                    gap,
                    law: ContactLaw::Linear(k),
                    damping: ContactDamping::Viscous(b),
                    tension_free,
                }) = self.stop(side)
                else {
                    return None;
                };
                let s = side.sign();
                let base = 2 * contact_of(side);
                // The bracket k delta + b delta' = k (s x - gap) + b s v as an affine function.
                let bracket = |sign: f64| {
                    let mut n = SVector::<f64, N>::zeros();
                    n[0] = sign * k * s;
                    n[1] = sign * b * s;
                    AffineGuard {
                        index: base + 1,
                        n,
                        g0: -sign * k * gap,
                    }
                };
                guards.extend(gap_guard(base, side, -1.0));
                if c == Contact::Pressed {
                    let mut l = free;
                    l[(1, 0)] -= k / m;
                    l[(1, 1)] -= b / m;
                    let mut d = SVector::<f64, N>::zeros();
                    d[1] = s * k * gap / m;
                    if tension_free {
                        guards.push(bracket(-1.0));
                    }
                    (l, d)
                } else {
                    guards.push(bracket(1.0));
                    (free, SVector::<f64, N>::zeros())
                }
            }
        };
        if let Port::Circuit(circuit) = &self.port {
            // The circuit's constant terms (the drop, a battery) from the right-hand side at
            // rest with no drive; its guards' affine pieces.
            let f0 = self.rhs_at_rest(free_mode);
            for i in 2..N {
                d[i] += f0[i];
            }
            d[1] += f0[1];
            let cm = CircuitMode::of(mode.circuit(0));
            guards.extend(self.circuit_guard_pieces(circuit, cm));
        }
        let mut c = SVector::<f64, N>::zeros();
        c[1] = 1.0;
        Some(Affine { l, c, d, guards })
    }

    /// The right-hand side at the zero state with no drive, in a mode.
    fn rhs_at_rest(&self, mode: Mode) -> SVector<f64, N> {
        use crate::model::Model;
        self.rhs(mode, &SVector::zeros(), 0.0)
    }

    /// The affine pieces of a circuit's guard in a mode (each one fires the guard), in the
    /// state's units: the conduction threshold's two signs while the bridge is off, the
    /// current's zero while it conducts, and the extremum's velocity.
    pub(super) fn circuit_guard_pieces(
        &self,
        circuit: &super::circuits::Circuit,
        cm: CircuitMode,
    ) -> Vec<AffineGuard<N>> {
        let index = STOP_GUARDS;
        let mut out = Vec::new();
        let unit = |i: usize, w: f64| {
            let mut n = SVector::<f64, N>::zeros();
            n[i] = w;
            n
        };
        let (e, vs) = (circuit.e, circuit.vs);
        if let Some(piece) = circuit.kind.guard_piece(circuit, cm.bridge, index) {
            // The kind's own phase guards it in place of the bridge's conduction (during an
            // inductor's transfer the bridge blocks).
            out.push(piece);
        } else if circuit.has_conduction_events() {
            let drop = circuit.path_drop();
            let drive = match circuit.element {
                Element::Piezo { .. } => unit(e, 1.0),
                Element::Coil { phi, .. } => unit(1, phi),
                Element::Pair(_) => return Vec::new(),
            };
            match cm.bridge {
                Bridge::Off => {
                    for sign in [1.0, -1.0] {
                        // sign * drive - Vs - drop > 0
                        out.push(AffineGuard {
                            index,
                            n: drive * sign - unit(vs, 1.0),
                            g0: -drop,
                        });
                    }
                }
                b => {
                    let s = b.sign();
                    match circuit.element {
                        Element::Coil { l, .. } if l > 0.0 => out.push(AffineGuard {
                            index,
                            n: unit(e, -s),
                            g0: 0.0,
                        }),
                        Element::Piezo { .. } if circuit.ron() == 0.0 => {
                            // The bridge current falling to zero, from the rates at rest
                            // and the velocity's column.
                            let cur = self.bridge_current_row(circuit, b);
                            out.push(AffineGuard {
                                index,
                                n: -cur.0,
                                g0: -cur.1,
                            });
                        }
                        _ => out.push(AffineGuard {
                            index,
                            n: -(drive * s - unit(vs, 1.0)),
                            g0: drop,
                        }),
                    }
                }
            }
        }
        if circuit.kind.acts_at_extrema() {
            let sign = match cm.heading {
                super::circuits::Heading::Up => -1.0,
                super::circuits::Heading::Down => 1.0,
            };
            out.push(AffineGuard {
                index,
                n: unit(1, sign),
                g0: 0.0,
            });
        }
        out
    }

    /// The bridge current of a conducting mode as an affine function `n . y + g0` (read off the
    /// current at the zero state and at unit states: it is affine in a linear mode).
    fn bridge_current_row(
        &self,
        circuit: &super::circuits::Circuit,
        b: Bridge,
    ) -> (SVector<f64, N>, f64) {
        let zero = SVector::<f64, N>::zeros();
        let g0 = circuit.bridge_current(b, &zero);
        let sc = self.scales;
        let mut n = SVector::<f64, N>::zeros();
        for i in 0..N {
            let mut u = zero;
            u[i] = sc[i];
            n[i] = (circuit.bridge_current(b, &u) - g0) / sc[i];
        }
        (n, g0)
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Matrix4;

    use super::*;
    use crate::device::{Device, StopLaw};
    use crate::drive::{Excitation, Sine};
    use crate::model::Model;
    use crate::physics::transducer::State;

    /// The analytic Jacobian equals central differences of the right-hand side on the paper's
    /// prototype 1 (its comb pair with charged nodes), in free flight and
    /// pressed into a stop under both spring laws: the file's Hertz stops and the linear fit of
    /// eq 19.
    #[test]
    fn jacobian_matches_central_differences_of_the_rhs() {
        let text = include_str!("../../../data/prototype1.toml");
        let base = Device::from_toml_str(text, "prototype1.toml").unwrap();
        // The drive at t = 0.1 s.
        let a = Sine::from_rms_g(5.5, 1300.0).accel(0.1);
        // The file's Hertz stops (b_im = 1.5 N s/m), then the same with the linear fit of eq 19.
        for linear_fit in [false, true] {
            let mut d = base.clone();
            d.stops.for_each_mut(|s| {
                if let StopLaw::HertzLine(h) = &mut s.law {
                    h.linear_fit = linear_fit;
                }
            });
            let h = Harvester::<4>::new(&d).unwrap();
            let sc = h.scales();
            // A state 0.2 um into the upper stop, moving, with charged nodes.
            let y = State::new(h.gap(Side::Upper) + 0.2e-6, 0.3, 0.4 * sc[2], -0.3 * sc[3]);
            let pressed = Mode::FREE.with_contact(contact_of(Side::Upper), Contact::Pressed);
            for mode in [Mode::FREE, pressed] {
                let j = h.jacobian(mode, &y);
                // Columns scaled by the state scales, so that every entry is the change of a
                // derivative over a typical change of the state; compared per row against the
                // row's largest entry.
                let mut fd = Matrix4::zeros();
                for c in 0..4 {
                    // Steps of 1e-5 of each scale: truncation ~1e-10 of the row, rounding
                    // ~1e-11 of it.
                    let e = 1e-5 * sc[c];
                    let (mut yp, mut ym) = (y, y);
                    yp[c] += e;
                    ym[c] -= e;
                    let col = (h.rhs(mode, &yp, a) - h.rhs(mode, &ym, a)) * (sc[c] / (2.0 * e));
                    fd.set_column(c, &col);
                }
                for r in 0..4 {
                    let row_max = (0..4).map(|c| fd[(r, c)].abs()).fold(0.0, f64::max);
                    for c in 0..4 {
                        let an = j[(r, c)] * sc[c];
                        assert!(
                            (fd[(r, c)] - an).abs() <= 1e-6 * row_max,
                            "linear fit {linear_fit} {mode:?} d f{r}/d y{c}: {an} vs {}",
                            fd[(r, c)]
                        );
                    }
                }
            }
        }
    }
}
