//! Where new branches begin: at the grazings of the non-impacting orbit, at the ends of other
//! branches (an impact lost or gained), at a symmetry-breaking pitchfork or a period doubling,
//! and at the orbit reached from rest at either end of the range.

use nalgebra::{DMatrix, DVector};

use nalgebra::SVector;

use crate::laws::contact::Side;
use crate::model::{Driven, Mode, Model, SwitchKind};
use crate::ode::{Dopri5, Observer, Step};
use crate::study::continuation::first_orbit;
use crate::study::orbit::{Orbit, OrbitError, Shooter};

use super::build::{Builder, From, Start};
use super::bvp::{live_components, side_stops, Closure, ImpactSequence, Problem};
use super::follow::{Found, Node};
use super::segment::fly;
use super::{EndKind, EventKind};

/// The impacts of one period, recorded as they happen.
struct ImpactLog<const N: usize> {
    /// The state at the end of the last step (before a switch, the state at impact).
    last: SVector<f64, N>,
    impacts: Vec<(f64, SVector<f64, N>)>,
    /// A switch that is not a rebound (sticking): no chain of flights holds it.
    other: bool,
}

impl<const N: usize> Observer<SVector<f64, N>, Mode> for ImpactLog<N> {
    fn step(&mut self, st: &Step<SVector<f64, N>>, _mode: Mode) {
        self.last = st.y1;
    }

    fn switched(&mut self, t: f64, from: Mode, to: Mode) {
        match SwitchKind::between(from, to) {
            SwitchKind::Rebound => self.impacts.push((t, self.last)),
            _ => self.other = true,
        }
    }
}

impl<M: Model<N> + Clone, const N: usize> Builder<'_, M, N> {
    /// The impacting orbit reached from rest at parameter value `at` (a transient, then
    /// Newton on the period map of the device with its stops), as a start to follow both
    /// ways; `None` when it does not impact, Newton does not converge, or it sticks to a stop
    /// (which no chain of flights holds).
    pub(super) fn seed_from_rest(&mut self, at: f64) -> Option<Start> {
        let param = self.param();
        let shooter = Shooter::new(self.h, self.settings.shooting);
        let f = self.start.with(param, at);
        let o = first_orbit(
            &shooter,
            &f,
            param,
            self.h.rest_state(),
            self.options.transient_periods,
            &mut self.stats,
        )
        .ok()?;
        if !o.is_impacting() {
            return None;
        }
        let (seq, z) = self.chain_of(&o)?;
        Some(Start {
            seq,
            forcing: o.forcing,
            z,
            dirs: None,
            from: From::Rest,
            kind: EndKind::Rest,
        })
    }

    /// The impact sequence and the chain's unknowns of a period-one orbit of the device.
    fn chain_of(&mut self, o: &Orbit) -> Option<(ImpactSequence, DVector<f64>)> {
        let f = &o.forcing;
        let model = Driven::new(self.h, f.sine(o.phase_rad));
        let y0: SVector<f64, N> = o.state_n();
        let mut log = ImpactLog {
            last: y0,
            impacts: Vec::new(),
            other: false,
        };
        let mut ode = Dopri5::new(
            0.0,
            y0,
            self.h.mode_of(&y0),
            self.h.solver_options(self.settings.shooting.rtol),
        );
        ode.integrate_observed(&model, f.period_s(), &mut log)
            .ok()?;
        self.stats += ode.stats();
        if log.other || log.impacts.is_empty() {
            return None;
        }
        let seq = ImpactSequence {
            sides: log
                .impacts
                .iter()
                .map(|(_, y)| if y[0] > 0.0 { Side::Upper } else { Side::Lower })
                .collect(),
            closure: Closure::Periodic(1),
        };
        let problem = Problem::new(
            self.h,
            seq.clone(),
            self.param(),
            self.settings.shooting.rtol,
        )
        .ok()?;
        let w = 2.0 * std::f64::consts::PI * f.freq_hz;
        let mut z = DVector::zeros(seq.len() * problem.d);
        for (k, (t, y)) in log.impacts.iter().enumerate() {
            problem.pack(&mut z, k, o.phase_rad + w * t, y);
        }
        Some((seq, z))
    }

    /// The impacting branches that begin at a grazing of the non-impacting orbit: one impact
    /// at each stop it grazes, and the symmetric orbit where it grazes both of a symmetric
    /// device.
    pub(super) fn grazing_starts(&mut self, node: usize, g: &Orbit) -> Result<(), OrbitError> {
        let param = self.param();
        let f = g.forcing;
        let w = 2.0 * std::f64::consts::PI * f.freq_hz;
        let free = self.h.without_contacts();
        let fl = fly(
            &free,
            f.sine(g.phase_rad),
            param,
            g.state_n(),
            f.period_s(),
            self.settings.shooting.rtol,
            &self.h.scales(),
            &[],
            &mut self.stats,
        )
        .map_err(|e| OrbitError::Solver {
            what: param.label(),
            param: g.param(param),
            source: e,
        })?;
        let top = fl
            .extrema
            .iter()
            .filter(|x| x.maximum)
            .max_by(|a, b| a.state[0].total_cmp(&b.state[0]));
        let bottom = fl
            .extrema
            .iter()
            .filter(|x| !x.maximum)
            .min_by(|a, b| a.state[0].total_cmp(&b.state[0]));
        let tol = 1e-6 * self.h.scales()[0];
        let [(g_up, _), (g_lo, _)] = side_stops(self.h);
        let mut grazed = Vec::new();
        if let Some(x) = top.filter(|x| (x.state[0] - g_up).abs() <= tol) {
            grazed.push((Side::Upper, *x));
        }
        if let Some(x) = bottom.filter(|x| (-x.state[0] - g_lo).abs() <= tol) {
            grazed.push((Side::Lower, *x));
        }
        for (side, x) in &grazed {
            let seq = ImpactSequence {
                sides: vec![*side],
                closure: Closure::Periodic(1),
            };
            let mut z = DVector::zeros(live_components(self.h));
            let problem = Problem::new(self.h, seq.clone(), param, self.settings.shooting.rtol)
                .map_err(OrbitError::Invalid)?;
            problem.pack(&mut z, 0, g.phase_rad + w * x.t, &x.state);
            self.queue.push_back(Start {
                seq,
                forcing: f,
                z,
                dirs: None,
                from: From::Grazing(node),
                kind: EndKind::Grazing,
            });
        }
        if grazed.len() == 2 && self.sym.is_some() {
            let (side, x) = grazed[0];
            let seq = ImpactSequence {
                sides: vec![side],
                closure: Closure::Mirror,
            };
            let problem = Problem::new(self.h, seq.clone(), param, self.settings.shooting.rtol)
                .map_err(OrbitError::Invalid)?;
            let mut z = DVector::zeros(live_components(self.h));
            problem.pack(&mut z, 0, g.phase_rad + w * x.t, &x.state);
            self.queue.push_back(Start {
                seq,
                forcing: f,
                z,
                dirs: None,
                from: From::Grazing(node),
                kind: EndKind::Grazing,
            });
        }
        Ok(())
    }

    /// The branch a smooth event leads to: the asymmetric pair at a symmetry-breaking
    /// pitchfork, the period-two branch at a period doubling.
    pub(super) fn starts_at_event(&mut self, idx: usize, problem: &Problem<'_, M, N>, e: &Found) {
        let n = &e.node;
        let seq = &problem.seq;
        let (new_seq, z, both) = match (e.kind, seq.closure) {
            (EventKind::SymmetryBreaking, Closure::Mirror) => {
                let s = self.sym.expect("a symmetric chain has the mirror");
                let mut sides = seq.sides.clone();
                sides.extend(seq.sides.iter().map(|x| match x {
                    Side::Upper => Side::Lower,
                    Side::Lower => Side::Upper,
                }));
                let new_seq = ImpactSequence {
                    sides,
                    closure: Closure::Periodic(1),
                };
                let k = seq.len();
                let mut z = DVector::zeros(2 * n.z.len());
                let Ok(full) = Problem::new(self.h, new_seq.clone(), self.param(), problem.rtol)
                else {
                    return;
                };
                for i in 0..k {
                    let y = problem.pre_state(&n.z, i);
                    let ph = problem.phase(&n.z, i);
                    full.pack(&mut z, i, ph, &y);
                    full.pack(&mut z, i + k, ph + std::f64::consts::PI, &(s * y));
                }
                (new_seq, z, true)
            }
            (EventKind::PeriodDoubling, Closure::Periodic(1)) if self.options.period_two => {
                let mut sides = seq.sides.clone();
                sides.extend(seq.sides.iter().copied());
                let new_seq = ImpactSequence {
                    sides,
                    closure: Closure::Periodic(2),
                };
                let k = seq.len();
                let mut z = DVector::zeros(2 * n.z.len());
                let Ok(full) = Problem::new(self.h, new_seq.clone(), self.param(), problem.rtol)
                else {
                    return;
                };
                for i in 0..k {
                    let y = problem.pre_state(&n.z, i);
                    let ph = problem.phase(&n.z, i);
                    full.pack(&mut z, i, ph, &y);
                    full.pack(&mut z, i + k, ph + 2.0 * std::f64::consts::PI, &y);
                }
                (new_seq, z, false)
            }
            _ => return,
        };
        let Ok(full) = Problem::new(self.h, new_seq.clone(), self.param(), problem.rtol) else {
            return;
        };
        let Ok(ev) = full.evaluate(&n.forcing, &z, &mut self.stats) else {
            return;
        };
        let Some(w) = null_vector(&ev.jz) else { return };
        let mut d = DVector::zeros(z.len() + 1);
        d.rows_mut(0, z.len()).copy_from(&w);
        let dirs = if both { vec![d.clone(), -d] } else { vec![d] };
        self.queue.push_back(Start {
            seq: new_seq,
            forcing: n.forcing,
            z,
            dirs: Some(dirs),
            from: From::Inside(idx),
            kind: EndKind::Bifurcation,
        });
    }

    /// The branch the end of branch `idx` leads to.
    pub(super) fn starts_at_end(
        &mut self,
        idx: usize,
        problem: &Problem<'_, M, N>,
        last: &Node,
        kind: EndKind,
    ) {
        let seq = &problem.seq;
        let param = self.param();
        let n = seq.len();
        let d = problem.d;
        match kind {
            EndKind::Grazing if n == 1 => {
                // The orbit loses its only impact: the non-impacting orbit's grazing.
                let p = last.forcing.get(param);
                let near = self
                    .grazings
                    .iter()
                    .enumerate()
                    .min_by(|a, b| (a.1.param - p).abs().total_cmp(&(b.1.param - p).abs()));
                if let Some((g, node)) = near {
                    if (node.param - p).abs() <= self.settings.max_param_step {
                        self.grazings[g].impacting.push(idx);
                        let ni = self.grazings[g].branch;
                        self.branches[idx].end.meets.push(ni);
                    }
                }
            }
            EndKind::Grazing => {
                let k = (0..n)
                    .min_by(|a, b| last.info.speeds_m_s[*a].total_cmp(&last.info.speeds_m_s[*b]))
                    .expect("a chain has an impact");
                // Without the impact whose speed vanished: its flight now touches the stop
                // there, so the new branch starts at a new contact.
                let mut sides = seq.sides.clone();
                sides.remove(k);
                let new_seq = ImpactSequence {
                    sides,
                    closure: seq.closure,
                };
                let mut z = DVector::zeros((n - 1) * d);
                let mut j = 0;
                for i in 0..n {
                    if i == k {
                        continue;
                    }
                    z.rows_mut(j * d, d).copy_from(&last.z.rows(i * d, d));
                    j += 1;
                }
                self.queue.push_back(Start {
                    seq: new_seq,
                    forcing: last.forcing,
                    z,
                    dirs: None,
                    from: From::Branch(idx),
                    kind: EndKind::NewContact,
                });
            }
            EndKind::NewContact => {
                let Some((k, t, side, y)) = last.info.excursion_at.clone() else {
                    return;
                };
                let y = SVector::<f64, N>::from_column_slice(y.as_slice());
                // With an impact where the flight touches the stop, at zero speed: the new
                // branch starts at a grazing impact.
                let w = 2.0 * std::f64::consts::PI * last.forcing.freq_hz;
                let mut sides = seq.sides.clone();
                sides.insert(k + 1, side);
                let new_seq = ImpactSequence {
                    sides,
                    closure: seq.closure,
                };
                let Ok(p2) = Problem::new(self.h, new_seq.clone(), param, problem.rtol) else {
                    return;
                };
                let mut z = DVector::zeros((n + 1) * d);
                let mut j = 0;
                for i in 0..n {
                    z.rows_mut(j * d, d).copy_from(&last.z.rows(i * d, d));
                    j += 1;
                    if i == k {
                        p2.pack(&mut z, j, problem.phase(&last.z, k) + w * t, &y);
                        j += 1;
                    }
                }
                self.queue.push_back(Start {
                    seq: new_seq,
                    forcing: last.forcing,
                    z,
                    dirs: None,
                    from: From::Branch(idx),
                    kind: EndKind::Grazing,
                });
            }
            EndKind::Symmetric => {
                // Back on the symmetric orbits: their branch, if not followed yet.
                let h = n / 2;
                let new_seq = ImpactSequence {
                    sides: seq.sides[..h].to_vec(),
                    closure: Closure::Mirror,
                };
                let z = last.z.rows(0, h * d).into_owned();
                self.queue.push_back(Start {
                    seq: new_seq,
                    forcing: last.forcing,
                    z,
                    dirs: None,
                    from: From::Branch(idx),
                    kind: EndKind::Bifurcation,
                });
            }
            _ => {}
        }
    }
}

/// The unit vector spanning the (numerical) kernel of a square matrix: the right singular
/// vector of its smallest singular value.
fn null_vector(j: &DMatrix<f64>) -> Option<DVector<f64>> {
    let svd = j.clone().svd(false, true);
    let v_t = svd.v_t?;
    let (k, _) = svd
        .singular_values
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(b.1))?;
    Some(v_t.row(k).transpose().normalize())
}
