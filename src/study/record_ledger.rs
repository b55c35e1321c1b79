//! The energy balance of a random-vibration record as
//! [`simulate_record`](crate::study::record::simulate_record) integrates it.
//!
//! [`crate::physics::energy::EnergyAudit`] checks Dormand-Prince by integrating the work of
//! every force beside the state. A record is integrated mostly by the exponential
//! Adams-Bashforth step ([`crate::ode::exponential`]), which advances the state only, so
//! [`record_ledger`] books the work of every force interval by interval, with the same
//! 3-point Gauss-Legendre rule (degree 5) on each scheme's own interpolant:
//!
//! * an exponential step: its dense output ([`ExpAdams::dense`]) at the three nodes, which
//!   continues the step's own formula (exact linear part and input, the remainder's
//!   extrapolating polynomial) inside the interval;
//! * a Dormand-Prince step: its dense output ([`crate::ode::Step::at_theta`]).
//!
//! The input is read by linear interpolation inside a sample interval, as both schemes read
//! it. A change of the state between one interval's end and the next one's start (the
//! projection onto a stop at a mode switch) is booked as the stored energy it moves, by
//! [`EnergyLedger::book_switch`] as the audit books it. The residual of
//! the [`EnergyLedger`] then measures the integration of the record and the quadrature. The
//! rule's relative error on a power oscillating at 2f (a motion at f) is about
//! 5e-7 (4πf h)^6: 1e-11 at prototype 1's 1.3 kHz resonance sampled every 10 us.

use crate::device::Device;
use crate::drive::Sampled;
use crate::ode::exponential::{ExpAdams, History};
use crate::ode::{Step, GAUSS_LEGENDRE_3};
use crate::physics::contact::Mode;
use crate::physics::energy::{EnergyLedger, PowerTerms};
use crate::physics::harvester::{Harvester, State};
use crate::study::record::{
    simulate_observed, Record, RecordError, RecordObserver, RecordSpec, EXPONENTIAL_ORDER,
};

/// Simulates a record exactly as [`crate::study::record::simulate_record`] does (the same
/// samples) and books its energy balance from rest to the record's end (pre-roll included).
pub fn record_ledger(
    device: &Device,
    spec: &RecordSpec,
    seed: u64,
    stream: u64,
) -> Result<(Record, EnergyLedger), RecordError> {
    let mut books = Books::default();
    let record = simulate_observed(device, spec, seed, stream, &mut books)?;
    Ok((record, books.ledger()))
}

/// The energy balance of a record from rest to its end ([`record_ledger`]'s) and over its
/// analysed window alone, from the first analysed sample instant (the end of the pre-roll) to
/// the end: the window's terms are the whole record's less those booked before the window,
/// and its stored-energy change and source work are counted from the state at the window's
/// start. Over a stationary window the drive's work and the dissipation grow with its length
/// while the stored energy only fluctuates, so the window's mean powers estimate the
/// stationary ones without the ring-up's bias.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RecordLedgers {
    /// From rest to the record's end (pre-roll included).
    pub whole: EnergyLedger,
    /// Over the analysed window.
    pub analysed: EnergyLedger,
    /// Length of the analysed window (s).
    pub analysed_s: f64,
}

/// Simulates a record exactly as [`crate::study::record::simulate_record`] does and books its
/// energy balance from rest and over its analysed window ([`RecordLedgers`]).
pub fn record_ledgers(
    device: &Device,
    spec: &RecordSpec,
    seed: u64,
    stream: u64,
) -> Result<(Record, RecordLedgers), RecordError> {
    let split_s = spec.transient_samples() as f64 / spec.noise.sample_rate_hz;
    let mut books = Books {
        split_s: Some(split_s),
        ..Books::default()
    };
    let record = simulate_observed(device, spec, seed, stream, &mut books)?;
    let whole = books.ledger();
    let analysed = match (books.at_split, books.last) {
        (Some((before, start)), Some(end)) => {
            let mut l = EnergyLedger {
                source: books.vb * (end.charge_c - start.charge_c),
                stored_change: end.stored_j - start.stored_j,
                ..EnergyLedger::default()
            };
            l.excitation = books.ledger.excitation - before.excitation;
            l.mech_damping = books.ledger.mech_damping - before.mech_damping;
            l.stop_damping = books.ledger.stop_damping - before.stop_damping;
            l.loads = books.ledger.loads - before.loads;
            l.clip_losses = books.ledger.clip_losses - before.clip_losses;
            l.reengagement_gains = books.ledger.reengagement_gains - before.reengagement_gains;
            l.projections = books.ledger.projections - before.projections;
            l.impact_losses = books.ledger.impact_losses - before.impact_losses;
            l.internal = books.ledger.internal - before.internal;
            l
        }
        // A record without a pre-roll: the window is the whole record.
        _ => whole,
    };
    let analysed_s = (record.v1_v.len().saturating_sub(1)) as f64 / record.sample_rate_hz;
    Ok((
        record,
        RecordLedgers {
            whole,
            analysed,
            analysed_s,
        },
    ))
}

/// The exponential step's dense output at the Gauss nodes.
type DenseNodes = [ExpAdams<4, EXPONENTIAL_ORDER>; 3];

/// What the ledger needs of one instant: the mode, the state, the stored energy and the bias
/// source's charge.
#[derive(Debug, Clone, Copy)]
struct Moment {
    mode: Mode,
    y: State,
    stored_j: f64,
    charge_c: f64,
}

impl Moment {
    fn of(model: &Harvester<Sampled>, mode: Mode, y: &State) -> Self {
        Self {
            mode,
            y: *y,
            stored_j: model.stored_energy(mode, y),
            charge_c: model.source_charge(y),
        }
    }
}

#[derive(Debug, Default)]
struct Books {
    dense: Option<DenseNodes>,
    vb: f64,
    first: Option<Moment>,
    last: Option<Moment>,
    ledger: EnergyLedger,
    /// Where the analysed window starts (s), if it is booked apart.
    split_s: Option<f64>,
    /// The terms booked before the window and the state at its start.
    at_split: Option<(EnergyLedger, Moment)>,
}

impl Books {
    /// The start of an interval: books the rest state once, and the stored energy a switch
    /// moved since the last interval ended.
    fn open(&mut self, model: &Harvester<Sampled>, t0: f64, mode: Mode, y: &State) {
        let last = match self.last {
            Some(last) => last,
            None => {
                self.vb = model.transducer.bias_v();
                let start = Moment::of(model, mode, y);
                self.first = Some(start);
                start
            }
        };
        if last.mode != mode || last.y != *y {
            self.ledger.book_switch(
                last.mode,
                mode,
                last.stored_j - model.stored_energy(mode, y),
            );
        }
        // The first interval that starts at the window's start (a sample instant, which
        // every interval and every Dormand-Prince step of the record starts from exactly or
        // after) splits the books.
        if let Some(split) = self.split_s {
            if self.at_split.is_none() && t0 >= split - 1e-9 * model.excitation.dt_s {
                self.at_split = Some((self.ledger, Moment::of(model, mode, y)));
            }
        }
    }

    /// Adds `h` times the Gauss sum of the power terms at the nodes.
    fn add_work(&mut self, h: f64, at_nodes: [PowerTerms; 3]) {
        let l = &mut self.ledger;
        for ((_, w), q) in GAUSS_LEGENDRE_3.iter().zip(at_nodes) {
            l.excitation += w * h * q.excitation;
            l.mech_damping += w * h * q.mech_damping;
            l.stop_damping += w * h * q.stop_damping;
            l.loads += w * h * q.load;
            l.internal += w * h * q.internal;
        }
    }

    fn close(&mut self, model: &Harvester<Sampled>, mode: Mode, y: &State) {
        self.last = Some(Moment::of(model, mode, y));
    }

    /// The balance from the first interval's start to the last one's end.
    fn ledger(&self) -> EnergyLedger {
        let mut l = self.ledger;
        if let (Some(a), Some(b)) = (self.first, self.last) {
            l.source = self.vb * (b.charge_c - a.charge_c);
            l.stored_change = b.stored_j - a.stored_j;
        }
        l
    }
}

impl RecordObserver for Books {
    fn exponential(
        &mut self,
        model: &Harvester<Sampled>,
        t0: f64,
        y0: &State,
        y1: &State,
        a0: f64,
        a1: f64,
        history: &History<4, EXPONENTIAL_ORDER>,
    ) {
        self.open(model, t0, Mode::Free, y0);
        let h = model.excitation.dt_s;
        let dense = self.dense.get_or_insert_with(|| {
            let (l, c) = model.free_flight().linear();
            let scales = model.scales();
            GAUSS_LEGENDRE_3.map(|(x, _)| ExpAdams::dense(&l, &c, h, x, &scales))
        });
        let work = std::array::from_fn(|i| {
            let y = dense[i].step(y0, a0, a1, history);
            model.power_terms(Mode::Free, t0 + GAUSS_LEGENDRE_3[i].0 * h, &y)
        });
        self.add_work(h, work);
        self.close(model, Mode::Free, y1);
    }

    fn dopri(&mut self, model: &Harvester<Sampled>, step: &Step<State>, mode: Mode) {
        self.open(model, step.t0, mode, &step.y0);
        let work = GAUSS_LEGENDRE_3
            .map(|(x, _)| model.power_terms(mode, step.t0 + x * step.h, &step.at_theta(x)));
        self.add_work(step.h, work);
        self.close(model, mode, &step.y1);
    }
}
