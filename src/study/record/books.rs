//! A record's continuous books: the integral over time of each of the model's energy-ledger
//! powers ([`Model::ledger_terms`]), of each of its outputs and of each output's square, from
//! rest to the record's end and over its analysed window, with what the mode switches moved.
//!
//! Each way of advancing an interval adds its own integrals:
//!
//! * a Dormand-Prince step, and an exponential step through its dense output
//!   ([`crate::ode::exponential::ExpAdams::dense`], which continues the step's own formula
//!   inside the interval): 3-point Gauss-Legendre (degree 5) on the step's interpolant, the
//!   input read by linear interpolation inside the sample interval as both schemes read it. The
//!   rule's relative error on a power oscillating at 2f (a motion at f) is about
//!   5e-7 (4πf h)^6: 1e-11 at prototype 1's 1.3 kHz resonance sampled every 10 us;
//! * an exact step of an affine mode: its integrals exactly, by the mode's Gram sums
//!   (`affine.rs`), added when they are folded in.
//!
//! A change of the state or mode between one interval's end and the next one's start (a switch:
//! a projection onto a stop, a rebound, a circuit's reset) is booked by the model
//! ([`Model::book_switch`]); switches at one instant that end in the mode they left are booked
//! as their first (a rebound off a rigid stop keeps the mode; a pair of circuit switches that
//! undo each other's modes is not an impact). The window's books are the whole record's less those booked before
//! the window's first sample instant, with the stored energy and the sources' work counted from
//! the state there.

use nalgebra::SVector;

use crate::drive::{Excitation, Sampled};
use crate::model::{Ledger, Mode, Model, MAX_OUTPUTS};
use crate::ode::GAUSS_LEGENDRE_3;

/// The books of one record (see the module docs).
#[derive(Debug, Clone)]
pub(super) struct Books<const N: usize> {
    drive: Sampled,
    terms: usize,
    outputs: usize,
    /// The ledger terms' energies (J), then each output's integral, then its square's.
    sums: Vec<f64>,
    first: Option<(Mode, SVector<f64, N>)>,
    last: Option<(Mode, SVector<f64, N>)>,
    /// The sums and the state at the analysed window's start.
    split: Option<(Vec<f64>, Mode, SVector<f64, N>)>,
    /// The mode the first switch since the last interval closed went to.
    via: Option<Mode>,
    values: Vec<f64>,
}

/// What a record's books found: the ledger from rest and over the analysed window, and the
/// integrals over the window of each output and of its square.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Found {
    /// From rest to the record's end.
    pub(crate) whole: Ledger,
    /// Over the analysed window.
    pub(crate) analysed: Ledger,
    /// `∫ o dt` of each output over the window.
    pub(crate) integrals: Vec<f64>,
    /// `∫ o² dt` of each output over the window.
    pub(crate) squares: Vec<f64>,
}

impl Default for Found {
    /// Empty books of a model without ledger terms or outputs.
    fn default() -> Self {
        Self {
            whole: Ledger::new(&[]),
            analysed: Ledger::new(&[]),
            integrals: Vec::new(),
            squares: Vec::new(),
        }
    }
}

/// The integrands of a model's books at a state: its ledger powers, then its outputs, then
/// their squares, into `values` (of length [`Books::integrands`]).
#[inline]
pub(super) fn integrands<M: Model<N>, const N: usize>(
    model: &M,
    mode: Mode,
    y: &SVector<f64, N>,
    a: f64,
    values: &mut [f64],
) {
    let terms = model.ledger_terms().len();
    let n = model.layout().outputs.len();
    model.powers(mode, y, a, &mut values[..terms]);
    let mut out = [0.0; MAX_OUTPUTS];
    model.outputs(mode, y, &mut out);
    for (i, o) in out.iter().take(n).enumerate() {
        values[terms + i] = *o;
        values[terms + n + i] = o * o;
    }
}

impl<const N: usize> Books<N> {
    /// Empty books of `model` under `drive`.
    pub(super) fn new<M: Model<N>>(model: &M, drive: Sampled) -> Self {
        let terms = model.ledger_terms().len();
        let outputs = model.layout().outputs.len().min(MAX_OUTPUTS);
        let size = terms + 2 * outputs;
        Self {
            drive,
            terms,
            outputs,
            sums: vec![0.0; size],
            first: None,
            last: None,
            split: None,
            via: None,
            values: vec![0.0; size],
        }
    }

    /// The number of integrands ([`integrands`]).
    pub(super) fn integrands(&self) -> usize {
        self.sums.len()
    }

    /// Opens an interval from `y` in `mode`: books what a switch moved since the last interval
    /// ended.
    #[inline]
    pub(super) fn open<M: Model<N>>(&mut self, model: &M, mode: Mode, y: &SVector<f64, N>) {
        match self.last {
            None => {
                if self.first.is_none() {
                    self.first = Some((mode, *y));
                }
            }
            Some((m, prev)) => {
                if m != mode || prev != *y {
                    // Switches at one instant that come back to the mode they left (a rebound
                    // off a rigid stop, or a pair that undo each other's modes) are booked as
                    // their first: its kind tells the model what moved the energy.
                    let to = if m == mode {
                        self.via.unwrap_or(mode)
                    } else {
                        mode
                    };
                    model.book_switch(m, to, &prev, y, &mut self.sums[..self.terms]);
                    self.last = Some((mode, *y));
                }
            }
        }
    }

    /// Closes an interval at `y` in `mode`.
    #[inline(always)]
    pub(super) fn close(&mut self, mode: Mode, y: &SVector<f64, N>) {
        self.last = Some((mode, *y));
        self.via = None;
    }

    /// A switch into `to` since the last interval closed.
    #[inline]
    pub(super) fn switched(&mut self, to: Mode) {
        if self.via.is_none() {
            self.via = Some(to);
        }
    }

    /// Adds `h` times the Gauss sum of the integrands over an interval from `t0` in `mode`,
    /// with `at(i)` the state at the rule's node `i`.
    #[inline]
    pub(super) fn add_nodes<M: Model<N>>(
        &mut self,
        model: &M,
        mode: Mode,
        t0: f64,
        h: f64,
        at: impl Fn(usize) -> SVector<f64, N>,
    ) {
        for (i, (x, w)) in GAUSS_LEGENDRE_3.iter().enumerate() {
            let a = self.drive.accel(t0 + x * h);
            integrands(model, mode, &at(i), a, &mut self.values);
            for (s, v) in self.sums.iter_mut().zip(&self.values) {
                *s += w * h * v;
            }
        }
    }

    /// Adds integrals computed elsewhere (an affine mode's Gram sums), in the order of
    /// [`integrands`].
    pub(super) fn add(&mut self, integrals: &[f64]) {
        for (s, v) in self.sums.iter_mut().zip(integrals) {
            *s += v;
        }
    }

    /// Marks the start of the analysed window at the state `y` in `mode` (opened already).
    pub(super) fn split(&mut self, mode: Mode, y: &SVector<f64, N>) {
        self.split = Some((self.sums.clone(), mode, *y));
    }

    /// The ledgers and the window's output integrals (see [`Found`]).
    pub(super) fn found<M: Model<N>>(&self, model: &M) -> Found {
        let terms = model.ledger_terms();
        let (k, n) = (self.terms, self.outputs);
        let ledger = |from: Option<(&[f64], Mode, SVector<f64, N>)>| {
            let mut l = Ledger::new(terms);
            if let (Some((before, ma, a)), Some((mb, b))) = (from, self.last) {
                for ((e, s), p) in l.energy_j.iter_mut().zip(&self.sums).zip(before) {
                    *e = s - p;
                }
                l.source_j = model.source_work(&b) - model.source_work(&a);
                l.stored_change_j = model.stored_energy(mb, &b) - model.stored_energy(ma, &a);
            }
            l
        };
        let zeros = vec![0.0; self.sums.len()];
        let start = self.first.map(|(m, y)| (&zeros[..], m, y));
        let whole = ledger(start);
        let (analysed, window) = match &self.split {
            Some((sums, m, y)) => (
                ledger(Some((&sums[..], *m, *y))),
                self.sums.iter().zip(sums).map(|(a, b)| a - b).collect(),
            ),
            // No interval reached the window: it is the whole record.
            None => (whole.clone(), self.sums.clone()),
        };
        Found {
            whole,
            analysed,
            integrals: window[k..k + n].to_vec(),
            squares: window[k + n..k + 2 * n].to_vec(),
        }
    }
}
