//! The record's loop: from one sample instant to the next, by one exponential step where the
//! mass flies free and clear of the stops, else by [`Dopri5`] with its events, collecting the
//! node voltages and the contact statistics (see the parent module).

use crate::drive::{Excitation, Sampled};
use crate::ode::exponential::{resolves, ExpAdams, History};
use crate::ode::{Dopri5, Observer, Step};
use crate::physics::contact::{Mode, Side};
use crate::physics::free_flight::FreeFlight;
use crate::physics::free_flight::Remainder;
use crate::physics::harvester::{Harvester, State, SwitchKind};
use crate::physics::transducer::{PairGeometry, TransducerModel};

use super::{
    Fallback, FreeFlightPath, Record, RecordError, RecordObserver, RecordSummary, SampledDrive,
    EXPONENTIAL_ORDER, STOP_MARGIN,
};

/// The record's loop for one kind of free flight `R` (monomorphised, so that the paper's pair
/// runs its own inner loop).
pub(super) fn run<O: RecordObserver, R: Remainder>(
    model: &Harvester<Sampled>,
    drive: &SampledDrive,
    rtol: f64,
    flight: Result<FastFlight<R>, Fallback>,
    observer: &mut O,
) -> Result<Record, RecordError> {
    let accel = &drive.accel;
    let fs = drive.sample_rate_hz;
    let n_tr = drive.transient_samples;
    let n = accel.len() - n_tr;
    let dt = model.excitation.dt_s;
    let t_start = model.excitation.time_of(n_tr);
    let free_flight = match &flight {
        Ok(_) => FreeFlightPath::Exponential,
        Err(reason) => FreeFlightPath::Dopri5(*reason),
    };
    let flight = flight.ok();

    let mut ode = Dopri5::new(
        0.0,
        model.rest_state(),
        Mode::Free,
        model.solver_options(rtol),
    );
    // The state at the current sample instant, and whether `ode` holds it (it does after a
    // Dormand-Prince interval, not after an exponential step).
    let (mut y, mut mode, mut ode_current) = (model.rest_state(), Mode::Free, true);
    let mut history = History::default();
    if let Some(f) = &flight {
        history.push(f.model.remainder(&y));
    }
    let mut v1 = Vec::with_capacity(n);
    let mut v2 = Vec::with_capacity(n);
    let (mut contact_time, mut impacts, mut x_peak) = (0.0f64, 0u64, 0.0f64);
    let mut in_contact = false;
    let (mut sx2, mut sa2) = (0.0f64, 0.0f64);
    let mut exponential_steps = 0u64;

    for k in 0..n_tr + n {
        // The node voltages at sample k, when the exponential step computed them.
        let mut volts = None;
        if k > 0 {
            let analysed = k > n_tr;
            let fast = flight.as_ref().and_then(|f| {
                (mode == Mode::Free && history.is_full())
                    .then(|| f.step(&y, accel[k - 1], accel[k], &history))
                    .flatten()
            });
            if let (Some(next), Some(f)) = (fast, &flight) {
                observer.exponential(
                    model,
                    model.excitation.time_of(k - 1),
                    &y,
                    &next,
                    accel[k - 1],
                    accel[k],
                    &history,
                );
                y = next;
                let (r, v) = f.model.remainder_and_voltages(&y);
                history.push(r);
                volts = Some(v);
                ode_current = false;
                exponential_steps += 1;
                in_contact = false;
                if analysed {
                    x_peak = x_peak.max(y[0].abs());
                }
            } else {
                if !ode_current {
                    ode.restart_with_step(model.excitation.time_of(k - 1), y, mode, dt);
                    ode_current = true;
                }
                let events = ode.stats().events;
                let mut watch = Watch {
                    model,
                    observer: &mut *observer,
                    analysed_from: t_start - 0.5 * dt,
                    contact_time: &mut contact_time,
                    impacts: &mut impacts,
                    x_peak: &mut x_peak,
                    in_contact: &mut in_contact,
                };
                ode.integrate_observed(model, model.excitation.time_of(k), &mut watch)?;
                (y, mode) = (ode.y(), ode.mode());
                if let Some(f) = &flight {
                    // The remainder is smooth only between mode switches.
                    if ode.stats().events != events {
                        history.clear();
                    }
                    if mode == Mode::Free {
                        history.push(f.model.remainder(&y));
                    } else {
                        history.clear();
                    }
                }
            }
        }
        if k >= n_tr {
            observer.sample(&y, mode);
            let [a, b] = volts.unwrap_or_else(|| model.electrical(&y).v);
            v1.push(a);
            v2.push(b);
            sx2 += y[0] * y[0];
            sa2 += accel[k] * accel[k];
        }
    }

    let nf = n as f64;
    let rl = model.load_resistance();
    let p1_w = v1.iter().map(|v| v * v).sum::<f64>() / nf / rl;
    let p2_w = v2.iter().map(|v| v * v).sum::<f64>() / nf / rl;
    let duration = (n.saturating_sub(1)) as f64 * dt;
    let summary = RecordSummary {
        p1_w,
        p2_w,
        x_rms_m: (sx2 / nf).sqrt(),
        x_peak_m: x_peak,
        contact_fraction: if duration > 0.0 {
            contact_time / duration
        } else {
            0.0
        },
        impacts,
        accel_mean_square_si: sa2 / nf,
        stats: {
            // An exponential step evaluates the remainder once, as a right-hand side.
            let mut st = ode.stats();
            st.accepted += exponential_steps;
            st.rhs_evals += exponential_steps;
            st
        },
        exponential_steps,
        free_flight,
    };
    Ok(Record {
        sample_rate_hz: fs,
        v1_v: v1,
        v2_v: v2,
        summary,
    })
}

/// What the Dormand-Prince intervals of a record show: contact time, impacts (contact
/// entries, and rebounds off rigid stops, which have no contact phase) and the peak
/// displacement over the analysed window, and every step to the record's observer.
struct Watch<'a, O> {
    model: &'a Harvester<Sampled>,
    observer: &'a mut O,
    analysed_from: f64,
    contact_time: &'a mut f64,
    impacts: &'a mut u64,
    x_peak: &'a mut f64,
    in_contact: &'a mut bool,
}

impl<O: RecordObserver> Observer<State, Mode> for Watch<'_, O> {
    #[inline(always)]
    fn step(&mut self, step: &Step<State>, mode: Mode) {
        self.observer.dopri(self.model, step, mode);
        let now = mode.in_contact();
        if step.t0 >= self.analysed_from {
            if now {
                *self.contact_time += step.h;
                if !*self.in_contact {
                    *self.impacts += 1;
                }
            }
            *self.x_peak = self.x_peak.max(step.y1[0].abs());
        }
        *self.in_contact = now;
    }

    fn switched(&mut self, t: f64, from: Mode, to: Mode) {
        if t >= self.analysed_from && SwitchKind::of(from, to) == SwitchKind::Rebound {
            *self.impacts += 1;
        }
    }
}

/// The exponential free-flight step of [`Scheme::Exponential`](super::Scheme::Exponential) for one device and sample
/// interval, with its check against the stops.
pub(super) struct FastFlight<R: Remainder> {
    model: R,
    method: ExpAdams<4, EXPONENTIAL_ORDER>,
    /// Largest x an exponential step may reach: the upper gap less [`STOP_MARGIN`] of it
    /// (infinite without a stop).
    upper: f64,
    /// Largest -x an exponential step may reach.
    lower: f64,
}

impl<R: Remainder> FastFlight<R> {
    /// The fast path of a device, or why the record goes to [`Dopri5`] throughout: the free
    /// flight could reach an inadmissible state that only [`Dopri5`] checks (a capacitance
    /// plus Cp not positive before a stop, or a capacitor pair without a stop on one side), or
    /// the free flight is nonlinear and the sample interval does not resolve its dynamics
    /// ([`resolves`]). A linear free flight is integrated exactly whatever its time constants
    /// ([`ExpAdams::new`]).
    pub(super) fn new<E: Excitation>(
        model: &Harvester<E>,
        dt: f64,
        flight: &FreeFlight,
        remainder: R,
    ) -> Result<Self, Fallback> {
        if let TransducerModel::Pair(p) = model.transducer {
            for side in Side::BOTH {
                let gap = model.gap(side);
                if !gap.is_finite() {
                    return Err(Fallback::UnboundedPair);
                }
                if let PairGeometry::AreaOverlap { x0 } = p.geometry {
                    if p.c0 * gap / x0 >= p.c0 + p.cp {
                        return Err(Fallback::CapacitanceVanishes);
                    }
                }
            }
        }
        let (l, c) = flight.linear();
        if !flight.is_linear() && !resolves(&l, dt, &model.scales()) {
            return Err(Fallback::Unresolved);
        }
        let method = ExpAdams::new(&l, &c, dt, &model.scales());
        // A nonlinear suspension bounds the step's reach like a stop (see `Spring`).
        let reach = model.spring.fast_path_reach_m(model.km, model.mass_kg, dt);
        if reach <= model.spring.well_m.abs() {
            return Err(Fallback::StiffSuspension);
        }
        Ok(Self {
            model: remainder,
            method,
            upper: (model.gap(Side::Upper) * (1.0 - STOP_MARGIN)).min(reach),
            lower: (model.gap(Side::Lower) * (1.0 - STOP_MARGIN)).min(reach),
        })
    }

    /// The state one sample later, or None if the step may come near a stop.
    ///
    /// Forced inline, with the exponential step and the stop check it calls: this is the
    /// record's inner loop, and with the loop generic over its observer (the energy ledger's
    /// or none) the compiler does not inline them on its own, which costs 14 to 16 % of a
    /// record (measured; the profile shows them as functions of their own).
    #[inline(always)]
    fn step(
        &self,
        y: &State,
        a0: f64,
        a1: f64,
        history: &History<4, EXPONENTIAL_ORDER>,
    ) -> Option<State> {
        let next = self.method.step(y, a0, a1, history);
        let h = self.method.h;
        hermite_within(y[0], h * y[1], next[0], h * next[1], self.upper, self.lower).then_some(next)
    }
}

/// Checks that the cubic Hermite interpolant of x over a step (end values `x0`, `x1`, end
/// slopes times the step `m0`, `m1`) stays below `upper` and above `-lower`.
///
/// The Hermite basis functions of the slopes are at most 4/27 in absolute value and those of
/// the values are non-negative and sum to one, so `max(x0, x1) + 4/27 (|m0| + |m1|)` bounds
/// the cubic from above (and its mirror from below); most steps stop at that test. Otherwise
/// the cubic's interior extrema (the roots of its derivative) are checked.
#[inline(always)]
fn hermite_within(x0: f64, m0: f64, x1: f64, m1: f64, upper: f64, lower: f64) -> bool {
    let slack = 4.0 / 27.0 * (m0.abs() + m1.abs());
    let (hi, lo) = (max2(x0, x1), -max2(-x0, -x1));
    if hi + slack < upper && -lo + slack < lower {
        return true;
    }
    // p(θ) = x0 + m0 θ + b θ² + c θ³.
    let b = 3.0 * (x1 - x0) - 2.0 * m0 - m1;
    let c = 2.0 * (x0 - x1) + m0 + m1;
    let p = |th: f64| x0 + th * (m0 + th * (b + th * c));
    let (mut max, mut min) = (hi, lo);
    // p'(θ) = m0 + 2 b θ + 3 c θ².
    let (qa, qb, qc) = (3.0 * c, 2.0 * b, m0);
    let mut consider = |th: f64| {
        if th > 0.0 && th < 1.0 {
            let v = p(th);
            max = max.max(v);
            min = min.min(v);
        }
    };
    if qa == 0.0 {
        if qb != 0.0 {
            consider(-qc / qb);
        }
    } else {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc >= 0.0 {
            let q = -0.5 * (qb + qb.signum() * disc.sqrt());
            consider(q / qa);
            if q != 0.0 {
                consider(qc / q);
            }
        }
    }
    max < upper && -min < lower
}

/// The larger of two values by plain comparison.
#[inline(always)]
fn max2(a: f64, b: f64) -> f64 {
    if a > b {
        a
    } else {
        b
    }
}
