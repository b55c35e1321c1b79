//! The boundary-value problem of an impacting periodic orbit: a chain of free flights, each
//! from one impact to the next, closed after a whole number of drive periods (or, for a
//! symmetric orbit, after half a period and the mirror image).
//!
//! # Unknowns and equations
//! For impacts k = 0..n-1 on sides s_k, the unknowns are the drive phase phi_k of the impact
//! and the state just before it, y_k = (s_k g, u_k, e_k) with the displacement fixed at the
//! stop (u_k the velocity, e_k the live electrical components): d unknowns per impact, d the
//! number of live state components. Flight k starts from the rebound R(y_k) = (s_k g, -e u_k,
//! e_k) at phase phi_k and lasts (phi_{k+1} - phi_k) / w, with phi_n = phi_0 + 2 pi m for an
//! orbit of m periods, or phi_0 + pi for the half of a symmetric orbit; it must end at
//! y_{k+1} (at y_0, or S y_0 for the half orbit): d equations per flight. The system is
//! square, and smooth in every unknown, the impact velocities included, through zero: an
//! impact at zero speed does nothing (R(y) = y), so at u_k = 0 the solution is the orbit
//! without that impact, grazing the stop there. The branch of impacting orbits therefore
//! passes its grazing point as a regular point of this problem, with the impact speed falling
//! linearly to zero, while on the period map it is a square-root singularity (Nordmark's
//! grazing map) at which pseudo-arclength steps collapse. This is the multi-segment problem of
//! COCO's `hspo` toolbox (Dankowicz and Schilder, *Recipes for Continuation*, 2013, chapter
//! 17), with the flights integrated by shooting instead of collocation.
//!
//! An orbit of the problem is an orbit of the device where it is *admissible*: every impact
//! speed s_k u_k positive and no flight past a stop (every interior extremum of x inside the
//! gaps). Where either fails the orbit is virtual, and the branch of real orbits ends there,
//! at a grazing.
//!
//! # Multipliers
//! The monodromy matrix is the product, around the orbit, of each impact's saltation matrix
//! S_k = D + (f+ - D f-) e_x^T / u_k (D = diag(1, -e, 1, 1) the rebound's Jacobian, f- and
//! f+ the vector field before and after it, e_x^T y = x the guard's gradient) and each
//! flight's transition matrix (Kuznetsov; di Bernardo et al. 2008, section 2.5). Its entries
//! grow like 1/u_k as an impact speed vanishes: the multipliers of a rigid-stop orbit diverge
//! at grazing. For the half orbit the product, premultiplied by S, is the half-period map,
//! whose multipliers square to those of the period map.

use nalgebra::{Complex, DMatrix, DVector, SMatrix, SVector};

use crate::drive::{Excitation, Sine};
use crate::laws::contact::Side;
use crate::model::{Mode, Model};
use crate::ode::{SolverError, Stats};
use crate::study::mass_peaks::MassPeaks;
use crate::study::orbit::{multipliers, ContactReach, Extent, Forcing, OrbitSummary, Parameter};

use super::segment::{fly, Flight};

/// An orbit's measures, its section (drive phase, state) if it has one, and its fingerprint.
type Measures<const N: usize> = (
    OrbitSummary,
    Option<(f64, SVector<f64, N>)>,
    SVector<f64, N>,
);

/// How the chain of flights closes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Closure {
    /// After this many drive periods, on the first impact.
    Periodic(u32),
    /// After half a drive period, on the mirror image of the first impact: a symmetric orbit
    /// of a device symmetric under x -> -x, its impacts those listed and their mirror images.
    Mirror,
}

/// The impacts of an orbit in time order (for [`Closure::Mirror`], those of its first half)
/// and how the chain closes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ImpactSequence {
    /// The side of each impact.
    pub sides: Vec<Side>,
    /// How the chain closes.
    pub closure: Closure,
}

impl ImpactSequence {
    /// Impacts in the chain (half of a symmetric orbit's).
    pub fn len(&self) -> usize {
        self.sides.len()
    }

    /// True without impacts (never a valid chain).
    pub fn is_empty(&self) -> bool {
        self.sides.is_empty()
    }

    /// Drive periods of the orbit.
    pub fn periods(&self) -> u32 {
        match self.closure {
            Closure::Periodic(m) => m,
            Closure::Mirror => 1,
        }
    }

    /// The drive phase the chain spans (rad).
    pub(super) fn phase_span(&self) -> f64 {
        match self.closure {
            Closure::Periodic(m) => 2.0 * std::f64::consts::PI * f64::from(m),
            Closure::Mirror => std::f64::consts::PI,
        }
    }

    /// Impacts of the whole orbit on each side (upper, lower).
    pub fn impacts_per_side(&self) -> [usize; 2] {
        let up = self.sides.iter().filter(|s| **s == Side::Upper).count();
        let lo = self.len() - up;
        match self.closure {
            Closure::Periodic(_) => [up, lo],
            Closure::Mirror => [up + lo, up + lo],
        }
    }

    /// Impacts of the whole orbit.
    pub fn impacts(&self) -> usize {
        let [a, b] = self.impacts_per_side();
        a + b
    }

    /// A short description: "symmetric, 2 impacts a period", "1 impact a period (upper)",
    /// "period two, 3 impacts (upper, lower, upper)".
    pub fn describe(&self) -> String {
        let side = |s: &Side| match s {
            Side::Upper => "upper",
            Side::Lower => "lower",
        };
        let list = self.sides.iter().map(side).collect::<Vec<_>>().join(", ");
        let n = self.impacts();
        let plural = if n == 1 { "impact" } else { "impacts" };
        match self.closure {
            Closure::Mirror => format!("symmetric, {n} {plural} a period"),
            Closure::Periodic(1) => format!("{n} {plural} a period ({list})"),
            Closure::Periodic(2) => format!("period two, {n} {plural} ({list})"),
            Closure::Periodic(m) => format!("period {m}, {n} {plural} ({list})"),
        }
    }
}

/// The problem of one impact sequence on one device.
pub(super) struct Problem<'a, M, const N: usize> {
    /// The model.
    pub base: &'a M,
    pub seq: ImpactSequence,
    pub param: Parameter,
    pub scales: SVector<f64, N>,
    pub rtol: f64,
    /// Live state components (the leading ones; the model holds the rest at zero).
    pub d: usize,
    /// The mirror involution (for [`Closure::Mirror`] and symmetry tests).
    pub mirror: Option<SMatrix<f64, N, N>>,
    /// The gap (m) and coefficient of restitution of each side's stop (upper, lower).
    stops: [(f64, f64); 2],
}

/// The problem evaluated at one point.
#[derive(Debug, Clone)]
pub(super) struct Evaluated<const N: usize> {
    /// Residual, scaled by the state scales.
    pub r: DVector<f64>,
    /// d r / d z (z the scaled unknowns).
    pub jz: DMatrix<f64>,
    /// d r / d p (per unit of the parameter).
    pub jp: DVector<f64>,
    /// Each flight.
    pub flights: Vec<Flight<N>>,
}

/// What a solved point of a branch is, besides its unknowns.
#[derive(Debug, Clone)]
pub struct ImpactOrbitInfo {
    /// Each impact's speed (m/s, positive on a real orbit).
    pub speeds_m_s: Vec<f64>,
    /// The largest excursion of an interior extremum of x past its stop (m; negative on a
    /// real orbit): flight, time from its start (s), side and state of that extremum.
    pub excursion_m: f64,
    /// Where the largest excursion is: (flight, time from its start in s, side, state).
    pub excursion_at: Option<(usize, f64, Side, DVector<f64>)>,
    /// Multipliers of the period map (of all the orbit's periods), largest modulus first.
    pub multipliers: Vec<Complex<f64>>,
    /// Multipliers of the half-period map, for a symmetric orbit.
    pub half_multipliers: Option<Vec<Complex<f64>>>,
}

/// The gap of the first mass's stop to the frame on each side (upper, lower; infinite where
/// there is none) and its coefficient of restitution (`None` unless the stop is rigid).
pub(crate) fn side_stops<M: Model<N>, const N: usize>(m: &M) -> [(f64, Option<f64>); 2] {
    let mut out = [(f64::INFINITY, None); 2];
    for c in m.contacts() {
        if c.mass == 0 && c.other.is_none() {
            let k = usize::from(c.side < 0.0);
            out[k] = (c.gap, c.restitution);
        }
    }
    out
}

/// The number of leading components the model does not hold at zero.
pub(super) fn live_components<M: Model<N>, const N: usize>(m: &M) -> usize {
    (0..N).find(|i| m.unused().contains(i)).unwrap_or(N)
}

impl<'a, M: Model<N>, const N: usize> Problem<'a, M, N> {
    pub(super) fn new(
        base: &'a M,
        seq: ImpactSequence,
        param: Parameter,
        rtol: f64,
    ) -> Result<Self, String> {
        let rigid = side_stops(base);
        for s in &seq.sides {
            let k = usize::from(*s == Side::Lower);
            if rigid[k].1.is_none() {
                return Err(format!("no rigid stop on the {s:?} side"));
            }
        }
        let mirror = base.mirror();
        if seq.closure == Closure::Mirror && mirror.is_none() {
            return Err("a symmetric orbit needs a device symmetric under x -> -x".into());
        }
        Ok(Self {
            base,
            seq,
            param,
            scales: base.scales(),
            rtol,
            d: live_components(base),
            mirror,
            stops: rigid.map(|(g, e)| (g, e.unwrap_or(0.0))),
        })
    }

    fn restitution(&self, side: Side) -> f64 {
        self.stops[usize::from(side == Side::Lower)].1
    }

    fn gap(&self, side: Side) -> f64 {
        self.stops[usize::from(side == Side::Lower)].0
    }

    /// The drive phase of impact k (rad).
    pub(super) fn phase(&self, z: &DVector<f64>, k: usize) -> f64 {
        z[k * self.d]
    }

    /// The state just before impact k.
    pub(super) fn pre_state(&self, z: &DVector<f64>, k: usize) -> SVector<f64, N> {
        let side = self.seq.sides[k];
        let mut y = SVector::<f64, N>::zeros();
        y[0] = side.sign() * self.gap(side);
        for i in 1..self.d {
            y[i] = z[k * self.d + i] * self.scales[i];
        }
        y
    }

    /// The scaled unknowns of impact k from its phase and the state before it.
    pub(super) fn pack(&self, z: &mut DVector<f64>, k: usize, phase: f64, y: &SVector<f64, N>) {
        z[k * self.d] = phase;
        for i in 1..self.d {
            z[k * self.d + i] = y[i] / self.scales[i];
        }
    }

    fn rebound(&self, k: usize, y: &SVector<f64, N>) -> SVector<f64, N> {
        let mut r = *y;
        r[1] *= -self.restitution(self.seq.sides[k]);
        r
    }

    /// The drive of flight k: the sine with its phase at the flight's start.
    pub(super) fn drive(&self, forcing: &Forcing, phase: f64) -> Sine {
        forcing.sine(phase)
    }

    /// The phase at which flight k ends.
    fn next_phase(&self, z: &DVector<f64>, k: usize) -> f64 {
        if k + 1 < self.seq.len() {
            self.phase(z, k + 1)
        } else {
            self.phase(z, 0) + self.seq.phase_span()
        }
    }

    /// The residual and its derivatives at `z` and `forcing`.
    pub(super) fn evaluate(
        &self,
        forcing: &Forcing,
        z: &DVector<f64>,
        stats: &mut Stats,
    ) -> Result<Evaluated<N>, SolverError> {
        let (n, d) = (self.seq.len(), self.d);
        let w = 2.0 * std::f64::consts::PI * forcing.freq_hz;
        let sc = &self.scales;
        let mut r = DVector::zeros(n * d);
        let mut jz = DMatrix::zeros(n * d, n * d);
        let mut jp = DVector::zeros(n * d);
        let mut flights = Vec::with_capacity(n);
        for k in 0..n {
            let (p0, p1) = (self.phase(z, k), self.next_phase(z, k));
            let tau = (p1 - p0) / w;
            if !(tau > 0.0 && tau.is_finite()) {
                return Err(SolverError::InvalidState {
                    t: 0.0,
                    message: format!("flight {k} of non-positive duration {tau:e} s"),
                    state: vec![],
                });
            }
            let sine = self.drive(forcing, p0);
            let pre = self.pre_state(z, k);
            let y0 = self.rebound(k, &pre);
            let fl = fly(
                self.base,
                sine,
                self.param,
                y0,
                tau,
                self.rtol,
                sc,
                &[],
                stats,
            )?;
            let last = k + 1 == n;
            let kn = if last { 0 } else { k + 1 };
            let mut target = self.pre_state(z, kn);
            let mut dtarget = SMatrix::<f64, N, N>::identity();
            if last && self.seq.closure == Closure::Mirror {
                let s = self.mirror.expect("checked in new");
                target = s * target;
                dtarget = s;
            }
            let e = self.restitution(self.seq.sides[k]);
            let row = k * d;
            for i in 0..d {
                r[row + i] = (fl.end[i] - target[i]) / sc[i];
                // The phases: the start's enters the drive and the duration, the end's the
                // duration alone.
                jz[(row + i, k * d)] += (fl.dphase[i] - fl.f_end[i] / w) / sc[i];
                jz[(row + i, kn * d)] += (fl.f_end[i] / w) / sc[i];
                // The state before impact k, through the rebound.
                for j in 1..d {
                    let dy0 = if j == 1 { -e } else { 1.0 };
                    jz[(row + i, k * d + j)] += fl.phi[(i, j)] * dy0 * sc[j] / sc[i];
                    jz[(row + i, kn * d + j)] -= dtarget[(i, j)] * sc[j] / sc[i];
                }
                let dur = match self.param {
                    // The duration (p1 - p0) / w moves with the frequency: d tau / df = -tau / f.
                    Parameter::Frequency => -fl.f_end[i] * tau / forcing.freq_hz,
                    Parameter::Amplitude => 0.0,
                };
                jp[row + i] = (fl.dp[i] + dur) / sc[i];
            }
            flights.push(fl);
        }
        Ok(Evaluated { r, jz, jp, flights })
    }

    /// The speeds, excursions and multipliers of a solved point.
    pub(super) fn info(
        &self,
        forcing: &Forcing,
        z: &DVector<f64>,
        ev: &Evaluated<N>,
    ) -> ImpactOrbitInfo {
        let n = self.seq.len();
        let speeds_m_s: Vec<f64> = (0..n)
            .map(|k| self.seq.sides[k].sign() * self.pre_state(z, k)[1])
            .collect();
        let (g_up, g_lo) = (self.gap(Side::Upper), self.gap(Side::Lower));
        let mut excursion_m = f64::NEG_INFINITY;
        let mut excursion_at = None;
        for (k, fl) in ev.flights.iter().enumerate() {
            for x in &fl.extrema {
                let (side, e) = if x.maximum {
                    (Side::Upper, x.state[0] - g_up)
                } else {
                    (Side::Lower, -x.state[0] - g_lo)
                };
                if e > excursion_m {
                    excursion_m = e;
                    excursion_at =
                        Some((k, x.t, side, DVector::from_column_slice(x.state.as_slice())));
                }
            }
        }
        if excursion_at.is_none() {
            // No interior extremum: the flights run from stop to stop monotonically, as far
            // from a new contact as an orbit gets.
            excursion_m = -g_up.min(g_lo);
        }
        let m = self.transfer(forcing, z, ev);
        let scaled = |m: &SMatrix<f64, N, N>| {
            let mut out = *m;
            for i in 0..N {
                for j in 0..N {
                    out[(i, j)] *= self.scales[j] / self.scales[i];
                }
            }
            for i in self.d..N {
                out[(i, i)] = 0.0;
            }
            out
        };
        let nan = vec![Complex::new(f64::NAN, 0.0); N];
        let (mults, half) = match self.seq.closure {
            Closure::Mirror => {
                let h = self.mirror.expect("checked in new") * m;
                let hm = multipliers(&scaled(&h)).unwrap_or(nan);
                let mut pm: Vec<Complex<f64>> = hm.iter().map(|x| x * x).collect();
                pm.sort_by(|a, b| b.norm().total_cmp(&a.norm()));
                (pm, Some(hm))
            }
            Closure::Periodic(_) => (multipliers(&scaled(&m)).unwrap_or(nan), None),
        };
        ImpactOrbitInfo {
            speeds_m_s,
            excursion_m,
            excursion_at,
            multipliers: mults,
            half_multipliers: half,
        }
    }

    /// The product of saltation and transition matrices around the chain, from just before
    /// impact 0 (physical units; for the half orbit, without the final S).
    pub(super) fn transfer(
        &self,
        forcing: &Forcing,
        z: &DVector<f64>,
        ev: &Evaluated<N>,
    ) -> SMatrix<f64, N, N> {
        let mut m = SMatrix::<f64, N, N>::identity();
        for (k, fl) in ev.flights.iter().enumerate() {
            let a = self.drive(forcing, self.phase(z, k)).accel(0.0);
            let pre = self.pre_state(z, k);
            let post = self.rebound(k, &pre);
            let f_minus = self.base.rhs(Mode::FREE, &pre, a);
            let f_plus = self.base.rhs(Mode::FREE, &post, a);
            let mut dmat = SMatrix::<f64, N, N>::identity();
            dmat[(1, 1)] = -self.restitution(self.seq.sides[k]);
            let jump = (f_plus - dmat * f_minus) / pre[1];
            let mut salt = dmat;
            for i in 0..N {
                salt[(i, 0)] += jump[i];
            }
            m = fl.phi * salt * m;
        }
        m
    }

    /// The signed asymmetry of a periodic chain whose second half mirrors its first (sides
    /// s_{k+h} = -s_k): the sum over its first half of the impact speed of each mirror
    /// impact less its own (m/s), zero on a symmetric orbit and of opposite signs on the two
    /// mirror-image asymmetric orbits; NaN for any other chain or device.
    pub(super) fn asymmetry(&self, z: &DVector<f64>) -> f64 {
        let n = self.seq.len();
        let h = n / 2;
        let mirrored = self.mirror.is_some()
            && matches!(self.seq.closure, Closure::Periodic(1))
            && n.is_multiple_of(2)
            && (0..h).all(|k| self.seq.sides[k + h] != self.seq.sides[k]);
        if !mirrored {
            return f64::NAN;
        }
        (0..h)
            .map(|k| self.pre_state(z, k + h)[1].abs() - self.pre_state(z, k)[1].abs())
            .sum()
    }

    /// The whole orbit's measures from its flights (for the half orbit, the mirror half is
    /// flown as well): RMS voltages and power over the orbit, extreme displacements, impacts
    /// and their speeds; the section is the first upward zero crossing of x, returned as
    /// (drive phase, state) with the measures, and the mean of the states at drive phase zero
    /// (the orbit's fingerprint) last.
    pub(super) fn measures(
        &self,
        forcing: &Forcing,
        z: &DVector<f64>,
        ev: &Evaluated<N>,
        stats: &mut Stats,
    ) -> Result<Measures<N>, SolverError> {
        let n = self.seq.len();
        let w = 2.0 * std::f64::consts::PI * forcing.freq_hz;
        let two_pi = 2.0 * std::f64::consts::PI;
        let n_out = self.base.layout().outputs.len();
        let mut out_sq = vec![0.0; n_out];
        let mut out_int = vec![0.0; n_out];
        let mut peaks = MassPeaks::of(self.base.layout());
        let mut x_up = f64::NEG_INFINITY;
        let mut x_lo = f64::INFINITY;
        let mut speed = [0.0f64; 2];
        // The reach of every contact at the states the flights keep: the rebounds and the
        // interior extrema of x (the first mass's stops to the frame are the problem's).
        let contacts = self.base.contacts();
        let mut reach = ContactReach::new(contacts.len());
        let layout = self.base.layout();
        let mut section = None;
        let mut zeros: Vec<SVector<f64, N>> = Vec::new();
        let mirror = self.mirror.unwrap_or_else(SMatrix::<f64, N, N>::identity);
        let halves = if self.seq.closure == Closure::Mirror {
            2
        } else {
            1
        };
        for half in 0..halves {
            for k in 0..n {
                let (p0, p1) = (self.phase(z, k), self.next_phase(z, k));
                let tau = (p1 - p0) / w;
                let pre = self.pre_state(z, k);
                let (pre, phase0) = if half == 0 {
                    (pre, p0)
                } else {
                    (mirror * pre, p0 + std::f64::consts::PI)
                };
                // The multiples of 2 pi inside the flight (the drive's phase zero).
                let marks: Vec<f64> = (0..)
                    .map(|j| ((phase0 / two_pi).ceil() + f64::from(j)) * two_pi)
                    .map(|zero| (zero - phase0) / w)
                    .take_while(|&t| t < tau)
                    .collect();
                let fl = if half == 0 && marks.is_empty() {
                    ev.flights[k].clone()
                } else {
                    // Flown again for the states at phase zero (the evaluation kept none), and
                    // the mirror half for the first time.
                    let sine = self.drive(forcing, phase0);
                    let y0 = self.rebound(k, &pre);
                    fly(
                        self.base,
                        sine,
                        self.param,
                        y0,
                        tau,
                        self.rtol,
                        &self.scales,
                        &marks,
                        stats,
                    )?
                };
                zeros.extend(fl.marked.iter().flatten());
                for i in 0..n_out {
                    out_sq[i] += fl.out_sq[i];
                    out_int[i] += fl.out_int[i];
                }
                peaks.see(self.base.layout(), pre.as_slice());
                peaks = peaks.max(&fl.mass_peaks);
                let side = if pre[0] > 0.0 { 0 } else { 1 };
                speed[side] = speed[side].max(pre[1].abs());
                reach.see(&contacts, layout, pre.as_slice());
                reach.strike(&contacts, layout, pre.as_slice());
                x_up = x_up.max(pre[0]);
                x_lo = x_lo.min(pre[0]);
                for x in &fl.extrema {
                    x_up = x_up.max(x.state[0]);
                    x_lo = x_lo.min(x.state[0]);
                    reach.see(&contacts, layout, x.state.as_slice());
                }
                if section.is_none() {
                    if let Some((t, y)) = fl.upcrossing {
                        section = Some(((phase0 + w * t).rem_euclid(two_pi), y));
                    }
                }
            }
        }
        let period = f64::from(self.seq.periods()) / forcing.freq_hz;
        let summary = OrbitSummary::from_integrals(
            self.base.layout(),
            &out_sq,
            &out_int,
            period,
            Extent {
                x_upper_m: x_up,
                x_lower_m: x_lo,
                mass_peaks: peaks,
                contact_fraction: 0.0,
                impacts: self.seq.impacts() as u32,
                impact_speed_m_s: speed,
                contact_reach: reach,
                upcrossing_s: section.map(|_| 0.0),
            },
        );
        // The mean of the states at phase zero of each period: the same for every choice of
        // the orbit's first period.
        let fingerprint = if zeros.is_empty() {
            self.pre_state(z, 0)
        } else {
            zeros.iter().sum::<SVector<f64, N>>() / zeros.len() as f64
        };
        Ok((summary, section, fingerprint))
    }
}
