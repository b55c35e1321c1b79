//! The model's linearisation: the Jacobian of the right-hand side in each mode and the reset
//! Jacobian of each switch, which the variational equations of periodic orbits integrate
//! ([`crate::study::orbit`]).

use nalgebra::Matrix4;

use super::{Harvester, State, SwitchKind};
use crate::drive::Excitation;
use crate::physics::contact::Mode;
use crate::physics::transducer::TransducerModel;

impl<E: Excitation> Harvester<E> {
    /// The Jacobian of the right-hand side with respect to the state, in a mode (the drive
    /// enters additively and does not appear). Used by the variational equations of periodic
    /// orbits ([`crate::study::orbit`]).
    ///
    /// The transducer's part is [`crate::physics::transducer::CapacitorPair::gradients`] for a
    /// pair and the linear coefficients of the other transducers; in contact the end-stop force
    /// adds the bracket's derivatives (a tension-free contact whose force is clipped adds
    /// nothing); stuck on a stop, x and v do not move.
    pub fn jacobian(&self, mode: Mode, y: &State) -> Matrix4<f64> {
        let m = self.mass_kg;
        let km = self.restoring_stiffness(y[0]);
        let (mut dfim_dx, mut dfim_dv) = (0.0, 0.0);
        if let Mode::Contact(side) = mode {
            if let Some(s) = self.stop(side) {
                if !s.tension_free() || self.contact_bracket(side, y) > 0.0 {
                    (dfim_dx, dfim_dv) =
                        s.bracket_gradient(self.penetration(side, y[0]), side.sign() * y[1]);
                }
            }
        }
        let mut j = match self.transducer {
            TransducerModel::Pair(p) => {
                let el = p.electrical(y);
                let g = p.gradients(y[0], &el);
                Matrix4::new(
                    0.0,
                    1.0,
                    0.0,
                    0.0,
                    (-km + g.df_dx - dfim_dx) / m,
                    (-self.damping - dfim_dv) / m,
                    g.df_ds[0] / m,
                    g.df_ds[1] / m,
                    g.rate_dx[0],
                    0.0,
                    g.rate_ds[0],
                    0.0,
                    g.rate_dx[1],
                    0.0,
                    0.0,
                    g.rate_ds[1],
                )
            }
            TransducerModel::None => {
                let mut j = Matrix4::zeros();
                j[(0, 1)] = 1.0;
                j[(1, 0)] = (-km - dfim_dx) / m;
                j[(1, 1)] = (-self.damping - dfim_dv) / m;
                j
            }
            TransducerModel::Piezo { theta, cp, r } => {
                let mut j = Matrix4::zeros();
                j[(0, 1)] = 1.0;
                j[(1, 0)] = (-km - dfim_dx) / m;
                j[(1, 1)] = (-self.damping - dfim_dv) / m;
                j[(1, 2)] = theta / m;
                j[(2, 1)] = -theta / cp;
                j[(2, 2)] = -1.0 / (r * cp);
                j
            }
            TransducerModel::Electromagnetic { phi, rc, l, r } => {
                let mut j = Matrix4::zeros();
                j[(0, 1)] = 1.0;
                j[(1, 0)] = (-km - dfim_dx) / m;
                if l > 0.0 {
                    j[(1, 1)] = (-self.damping - dfim_dv) / m;
                    j[(1, 2)] = -phi / m;
                    j[(2, 1)] = phi / l;
                    j[(2, 2)] = -(rc + r) / l;
                } else {
                    j[(1, 1)] = (-self.damping - phi * phi / (rc + r) - dfim_dv) / m;
                }
                j
            }
        };
        if let Mode::Stuck(_) = mode {
            for c in 0..4 {
                j[(0, c)] = 0.0;
                j[(1, c)] = 0.0;
            }
        }
        j
    }
}

/// The reset Jacobian of a switch, `d y+ / d y-` (the identity but for a rebound's or a
/// stick's velocity reset; the projections onto the stop are within the event tolerance and
/// are not differentiated).
pub fn reset_jacobian(from: Mode, to: Mode, restitution: f64) -> Matrix4<f64> {
    let mut d = Matrix4::identity();
    match SwitchKind::of(from, to) {
        SwitchKind::Rebound => d[(1, 1)] = -restitution,
        SwitchKind::Stick => d[(1, 1)] = 0.0,
        _ => {}
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device::{Device, StopLaw};
    use crate::drive::Sine;
    use crate::ode::HybridSystem;
    use crate::physics::contact::Side;

    /// The analytic Jacobian equals central differences of the right-hand side, in free
    /// flight and in contact under both spring laws.
    #[test]
    fn jacobian_matches_central_differences_of_the_rhs() {
        let text = include_str!("../../../data/prototype1.toml");
        let base = Device::from_toml_str(text, "prototype1.toml").unwrap();
        // The file's Hertz stops (b_im = 1.5 N s/m), then the same with the linear fit of eq 19.
        for linear_fit in [false, true] {
            let mut d = base.clone();
            d.stops.for_each_mut(|s| {
                if let StopLaw::HertzLine(h) = &mut s.law {
                    h.linear_fit = linear_fit;
                }
            });
            let h = Harvester::new(&d, Sine::from_rms_g(5.5, 1300.0));
            let sc = h.scales();
            // A state 0.2 um into the upper stop, moving, with charged nodes.
            let y = State::new(h.gap(Side::Upper) + 0.2e-6, 0.3, 0.4 * sc[2], -0.3 * sc[3]);
            for mode in [Mode::Free, Mode::Contact(Side::Upper)] {
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
                    let col = (h.rhs(mode, 0.1, &yp) - h.rhs(mode, 0.1, &ym)) * (sc[c] / (2.0 * e));
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
