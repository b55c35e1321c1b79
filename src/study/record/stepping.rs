//! The record's loop: from one sample instant to the next, by a fast step where one applies
//! (the exponential free flight, an affine mode's exact step), else by [`Dopri5`] with its
//! events, collecting the outputs, the contact statistics and the continuous books (see the
//! parent module).

use nalgebra::SVector;

use crate::drive::Sampled;
use crate::model::{Driven, Layout, Load, Mode, Model, SwitchKind, MAX_OUTPUTS};
use crate::ode::{Dopri5, Observer, Step};
use crate::study::mass_peaks::MassPeaks;

use super::books::{Books, Found};
use super::{
    Fallback, FreeFlightPath, Record, RecordError, RecordObserver, RecordSummary, SampledDrive,
    STORAGE,
};

/// The first mass's position and velocity in a model's state: its first two components (as
/// [`Model::static_state`] and [`crate::model::Layout::new`] have them).
pub(super) const POSITION: usize = 0;
/// See [`POSITION`].
pub(super) const VELOCITY: usize = 1;

/// What advances a sample interval without Dormand-Prince. The loop is compiled for each
/// implementation, so that a fast path's inner loop is its own.
pub(super) trait FastPath<M: Model<N>, const N: usize> {
    /// Right-hand-side evaluations a fast interval counts as in the record's statistics.
    const RHS_EVALS: u64;

    /// How the record's free flight is integrated.
    fn path(&self) -> FreeFlightPath;

    /// The record starts at `y` in `mode`.
    fn start(&mut self, _model: &M, _y: &SVector<f64, N>, _mode: Mode) {}

    /// The state one sample interval after `y` in `mode` (from `t0`, the input `a0` and `a1`
    /// at its ends), with whether the model's outputs there were written into `outputs`; or
    /// `None` to hand the interval to Dormand-Prince. Books, when kept, take the interval's
    /// integrals.
    #[allow(clippy::too_many_arguments)]
    fn step(
        &mut self,
        model: &M,
        t0: f64,
        y: &SVector<f64, N>,
        mode: Mode,
        a: [f64; 2],
        outputs: &mut [f64; MAX_OUTPUTS],
        books: Option<&mut Books<N>>,
    ) -> Option<(SVector<f64, N>, bool)>;

    /// The rebounds off rigid stops inside the last fast interval: the time into it (s) and
    /// |x| there (m).
    fn rebounds(&self) -> &[(f64, f64)] {
        &[]
    }

    /// The states at those rebounds, before each one's reset (empty where the fast path does
    /// not keep them): a model of several masses takes each mass's peaks there, since the
    /// impact's speed is met between samples.
    fn rebound_states(&self) -> &[SVector<f64, N>] {
        &[]
    }

    /// The mode at the last fast interval's end and the time it spent in contact (s), where
    /// switches inside it changed its mode on the exact solution (a contact came to rest or
    /// was released); its impacts are then all among [`Self::rebounds`]. `None`: the interval
    /// ended in the mode it started in, in contact throughout or not at all.
    fn inside(&self) -> Option<(Mode, f64)> {
        None
    }

    /// A Dormand-Prince interval ended at `y` in `mode`; `switched` when a mode switch
    /// happened inside it.
    fn after_dopri(&mut self, _model: &M, _y: &SVector<f64, N>, _mode: Mode, _switched: bool) {}

    /// Adds the integrals the fast path holds apart into `books`.
    fn flush(&mut self, _books: &mut Books<N>) {}
}

/// No fast path: Dormand-Prince throughout, for the stated reason.
pub(super) struct NoFast(pub(super) Fallback);

impl<M: Model<N>, const N: usize> FastPath<M, N> for NoFast {
    const RHS_EVALS: u64 = 0;

    fn path(&self) -> FreeFlightPath {
        FreeFlightPath::Dopri5(self.0)
    }

    #[inline(always)]
    fn step(
        &mut self,
        _: &M,
        _: f64,
        _: &SVector<f64, N>,
        _: Mode,
        _: [f64; 2],
        _: &mut [f64; MAX_OUTPUTS],
        _: Option<&mut Books<N>>,
    ) -> Option<(SVector<f64, N>, bool)> {
        None
    }
}

/// The record's loop for one model and fast path (see the parent module): the record, with
/// what its books found when it kept them.
///
/// From rest, each sample interval is advanced by the fast path where it takes it, else by
/// Dormand-Prince ([`Walk::interval`]); the books open at the first analysed sample; each
/// analysed sample's outputs are kept ([`Samples`]); the record and its summary are read off
/// at the end ([`Walk::record`]).
pub(super) fn run<M: Model<N>, O: RecordObserver, F: FastPath<M, N>, const N: usize>(
    model: &M,
    drive: &SampledDrive,
    rtol: f64,
    fast: F,
    observer: &mut O,
    mut books: Option<Books<N>>,
) -> Result<(Record, Option<Found>), RecordError> {
    let accel = &drive.accel;
    let n_tr = drive.transient_samples;
    let n = accel.len() - n_tr;
    let (mut walk, mut y, mut mode) = Walk::start(model, drive, rtol, fast);
    let mut samples = Samples::new(model.layout(), walk.n_out, n);
    let mut out = [0.0; MAX_OUTPUTS];
    for k in 0..n_tr + n {
        // Whether the fast step wrote the outputs at sample k.
        let mut have_out = false;
        if k > 0 {
            if k - 1 == n_tr {
                if let Some(b) = books.as_mut() {
                    walk.fast.flush(b);
                    b.open(model, mode, &y);
                    b.split(mode, &y);
                }
            }
            let a = [accel[k - 1], accel[k]];
            have_out = walk.interval(k, a, (&mut y, &mut mode), &mut out, &mut books)?;
        }
        if k >= n_tr {
            observer.sample(y.as_slice(), mode);
            if !have_out {
                model.outputs(mode, &y, &mut out);
            }
            samples.push(&out, y[POSITION], accel[k]);
        }
    }
    let found = books.map(|mut b| {
        walk.fast.flush(&mut b);
        b.found(model)
    });
    let record = walk.record(samples, found.as_ref());
    Ok((record, found))
}

/// The record's walk from sample to sample: the integrator that takes the intervals the fast
/// path does not, and the contact statistics so far. The state and mode at the current sample
/// stay with the loop, in its registers.
struct Walk<'m, M: Model<N>, F, const N: usize> {
    model: &'m M,
    /// The model under the sampled drive, for Dormand-Prince.
    sys: Driven<'m, M, Sampled, N>,
    fast: F,
    ode: Dopri5<Driven<'m, M, Sampled, N>>,
    /// Whether `ode` holds the state at the current sample (it does after a Dormand-Prince
    /// interval, not after a fast step).
    ode_current: bool,
    stats: Contacts,
    /// Intervals the fast path took.
    fast_steps: u64,
    /// Samples of the pre-roll, and the first analysed sample's time (s).
    n_tr: usize,
    t_start: f64,
    /// The sample interval (s) and rate (Hz).
    dt: f64,
    fs: f64,
    /// The model's outputs kept (at most [`MAX_OUTPUTS`]).
    n_out: usize,
}

impl<'m, M: Model<N>, F: FastPath<M, N>, const N: usize> Walk<'m, M, F, N> {
    /// The walk of `model` under `drive`, with the state it starts from: rest, and its mode.
    fn start(
        model: &'m M,
        drive: &SampledDrive,
        rtol: f64,
        mut fast: F,
    ) -> (Self, SVector<f64, N>, Mode) {
        let fs = drive.sample_rate_hz;
        let sampled = Sampled::new(drive.accel.clone(), fs);
        let (dt, t_start) = (sampled.dt_s, sampled.time_of(drive.transient_samples));
        let layout = model.layout();
        let y = model.rest_state();
        let mode = model.mode_of(&y);
        let ode = Dopri5::new(0.0, y, mode, model.solver_options(rtol));
        fast.start(model, &y, mode);
        let walk = Self {
            model,
            sys: Driven::new(model, sampled),
            fast,
            ode,
            ode_current: true,
            stats: Contacts {
                peaks: MassPeaks::of(layout),
                ..Contacts::default()
            },
            fast_steps: 0,
            n_tr: drive.transient_samples,
            t_start,
            dt,
            fs,
            n_out: layout.outputs.len().min(MAX_OUTPUTS),
        };
        (walk, y, mode)
    }

    /// Advances `(y, mode)` over the interval that ends at sample `k`, with the drive `a` at
    /// its ends: by the fast path where it takes it (then `true` when it wrote the outputs at
    /// sample `k` into `out`), else by Dormand-Prince.
    #[inline(always)]
    fn interval(
        &mut self,
        k: usize,
        a: [f64; 2],
        (y, mode): (&mut SVector<f64, N>, &mut Mode),
        out: &mut [f64; MAX_OUTPUTS],
        books: &mut Option<Books<N>>,
    ) -> Result<bool, RecordError> {
        let analysed = k > self.n_tr;
        let t0 = self.sys.drive.time_of(k - 1);
        let Some((next, wrote)) = self
            .fast
            .step(self.model, t0, y, *mode, a, out, books.as_mut())
        else {
            (*y, *mode) = self.dopri(k, t0, (*y, *mode), books.as_mut())?;
            return Ok(false);
        };
        *y = next;
        self.ode_current = false;
        self.fast_steps += 1;
        let s = &mut self.stats;
        match self.fast.inside() {
            Some((end, contact_s)) => {
                *mode = end;
                s.switched_inside(analysed, mode.in_contact(), contact_s, y[POSITION]);
            }
            None => s.fast(analysed, mode.in_contact(), self.dt, y[POSITION]),
        }
        if analysed && s.peaks.len > 0 {
            s.peaks.see(self.model.layout(), y.as_slice());
        }
        let from = self.t_start - 0.5 * self.dt;
        for &(tau, x) in self.fast.rebounds() {
            s.rebound(t0 + tau >= from, x);
        }
        if s.peaks.len > 0 {
            let rebounds = self.fast.rebounds().iter();
            for (&(tau, _), at) in rebounds.zip(self.fast.rebound_states()) {
                if t0 + tau >= from {
                    s.peaks.see(self.model.layout(), at.as_slice());
                }
            }
        }
        Ok(wrote)
    }

    /// The state and mode at sample `k`, from `(y, mode)` at `t0` by Dormand-Prince with its
    /// events, restarted there after fast steps.
    fn dopri(
        &mut self,
        k: usize,
        t0: f64,
        (y, mode): (SVector<f64, N>, Mode),
        books: Option<&mut Books<N>>,
    ) -> Result<(SVector<f64, N>, Mode), RecordError> {
        if !self.ode_current {
            self.ode.restart_with_step(t0, y, mode, self.dt);
            self.ode_current = true;
        }
        let events = self.ode.stats().events;
        let mut watch = Watch {
            model: self.model,
            analysed_from: self.t_start - 0.5 * self.dt,
            stats: &mut self.stats,
            ix: POSITION,
            books,
        };
        let t1 = self.sys.drive.time_of(k);
        self.ode.integrate_observed(&self.sys, t1, &mut watch)?;
        let (y, mode) = (self.ode.y(), self.ode.mode());
        let switched = self.ode.stats().events != events;
        self.fast.after_dopri(self.model, &y, mode, switched);
        Ok((y, mode))
    }

    /// The record of the finished walk: the kept outputs, their loads' powers, and the
    /// summary, with the storage's and the drive's terms where the books `found` them.
    fn record(self, samples: Samples, found: Option<&Found>) -> Record {
        let layout = self.model.layout();
        let Samples {
            v1,
            v2,
            more,
            sx2,
            sa2,
            n,
            ..
        } = samples;
        let nf = n as f64;
        // An output the model holds at zero keeps no samples: its power is zero (an empty
        // sum is -0.0, which the sum of the zeros is not).
        let power = |i: usize, v: &[f64]| match layout.outputs.get(i).and_then(|s| s.load) {
            _ if v.is_empty() => 0.0,
            Some(Load::Resistor(r)) => v.iter().map(|v| v * v).sum::<f64>() / nf / r,
            Some(load) => {
                let sum = v.iter().sum::<f64>();
                let squares = v.iter().map(|v| v * v).sum::<f64>();
                load.mean_power(sum / nf, squares / nf)
            }
            None => 0.0,
        };
        let (p1_w, p2_w) = (power(0, &v1), power(1, &v2));
        let duration = (n.saturating_sub(1)) as f64 * self.dt;
        let analysed_s = (n.saturating_sub(1)) as f64 / self.fs;
        let (mut p_drive_w, mut p_dc_w, mut vdc_v) = (None, None, None);
        if let Some(f) = found {
            let drive_term = self
                .model
                .ledger_terms()
                .iter()
                .position(|t| t.name == "drive");
            p_drive_w = drive_term.map(|i| f.analysed.energy_j[i] / analysed_s);
            if let Some(i) = layout.output(STORAGE) {
                let (mean, square) = (f.integrals[i] / analysed_s, f.squares[i] / analysed_s);
                vdc_v = Some(mean);
                p_dc_w = layout.outputs[i].load.map(|l| l.mean_power(mean, square));
            }
        }
        let stats = self.stats;
        let summary = RecordSummary {
            p1_w,
            p2_w,
            x_rms_m: (sx2 / nf).sqrt(),
            x_peak_m: stats.x_peak,
            mass_peaks: stats.peaks,
            contact_fraction: if duration > 0.0 {
                stats.contact_time / duration
            } else {
                0.0
            },
            impacts: stats.impacts,
            accel_mean_square_si: sa2 / nf,
            stats: {
                // A fast step counts as an accepted step (with its remainder's evaluation).
                let mut st = self.ode.stats();
                st.accepted += self.fast_steps;
                st.rhs_evals += F::RHS_EVALS * self.fast_steps;
                st
            },
            exponential_steps: self.fast_steps,
            free_flight: self.fast.path(),
            p_drive_w,
            p_dc_w,
            vdc_v,
        };
        Record {
            sample_rate_hz: self.fs,
            samples: n,
            v1_v: if self.n_out >= 1 { v1 } else { Vec::new() },
            v2_v: if self.n_out >= 2 { v2 } else { Vec::new() },
            more_v: more,
            outputs: layout.outputs.clone(),
            ledger: found.map(|f| f.analysed.clone()),
            summary,
        }
    }
}

/// The outputs at the analysed samples, and the sums of squares of the position and the
/// drive there. An output the model holds at zero keeps no samples (its vector stays empty,
/// without room).
struct Samples {
    v1: Vec<f64>,
    v2: Vec<f64>,
    more: Vec<Vec<f64>>,
    /// Whether the first two outputs' samples are kept.
    keep: [bool; 2],
    sx2: f64,
    sa2: f64,
    /// Analysed samples so far.
    n: usize,
}

impl Samples {
    /// Room for `n` samples of `n_out` outputs of `layout` (the first two kept unless the
    /// model holds them at zero).
    fn new(layout: &Layout, n_out: usize, n: usize) -> Self {
        let keep = [!layout.held_at_zero(0), !layout.held_at_zero(1)];
        let room = |kept: bool| Vec::with_capacity(if kept { n } else { 0 });
        Self {
            v1: room(keep[0]),
            v2: room(keep[1]),
            more: (2..n_out.max(2)).map(|_| Vec::with_capacity(n)).collect(),
            keep,
            sx2: 0.0,
            sa2: 0.0,
            n: 0,
        }
    }

    /// A sample: the outputs `out`, the position `x` (m) and the drive `a` (m/s^2).
    #[inline(always)]
    fn push(&mut self, out: &[f64; MAX_OUTPUTS], x: f64, a: f64) {
        if self.keep[0] {
            self.v1.push(out[0]);
        }
        if self.keep[1] {
            self.v2.push(out[1]);
        }
        self.n += 1;
        for (o, v) in self.more.iter_mut().zip(&out[2..]) {
            o.push(*v);
        }
        self.sx2 += x * x;
        self.sa2 += a * a;
    }
}

/// The contact statistics over the analysed window: contact time, impacts (contact entries,
/// and rebounds off rigid stops, which have no contact phase) and the peak displacement.
#[derive(Debug, Default)]
struct Contacts {
    contact_time: f64,
    impacts: u64,
    x_peak: f64,
    /// Each mass's peaks (a model of several masses).
    peaks: MassPeaks,
    in_contact: bool,
}

impl Contacts {
    /// A fast step of `dt` that ends at the position `x`, in contact or not.
    #[inline(always)]
    fn fast(&mut self, analysed: bool, now: bool, dt: f64, x: f64) {
        if analysed {
            if now {
                self.contact_time += dt;
                if !self.in_contact {
                    self.impacts += 1;
                }
            }
            self.x_peak = self.x_peak.max(x.abs());
        }
        self.in_contact = now;
    }
}

impl Contacts {
    /// A fast step that ends at the position `x`, in contact or not, after `contact_s` in
    /// contact; its impacts come as rebounds ([`Self::rebound`]).
    #[inline(always)]
    fn switched_inside(&mut self, analysed: bool, now: bool, contact_s: f64, x: f64) {
        if analysed {
            self.contact_time += contact_s;
            self.x_peak = self.x_peak.max(x.abs());
        }
        self.in_contact = now;
    }

    /// A rebound off a rigid stop at the position `x`, in the analysed window or not.
    #[inline(always)]
    fn rebound(&mut self, analysed: bool, x: f64) {
        if analysed {
            self.impacts += 1;
            self.x_peak = self.x_peak.max(x.abs());
        }
    }
}

/// What the Dormand-Prince intervals of a record show: the contact statistics from every
/// accepted step, and the steps to the books.
struct Watch<'a, M, const N: usize> {
    model: &'a M,
    analysed_from: f64,
    stats: &'a mut Contacts,
    ix: usize,
    books: Option<&'a mut Books<N>>,
}

impl<M: Model<N>, const N: usize> Observer<SVector<f64, N>, Mode> for Watch<'_, M, N> {
    #[inline(always)]
    fn step(&mut self, step: &Step<SVector<f64, N>>, mode: Mode) {
        if let Some(b) = self.books.as_mut() {
            b.open(self.model, mode, &step.y0);
            b.add_nodes(self.model, mode, step.t0, step.h, |i| {
                step.at_theta(crate::ode::GAUSS_LEGENDRE_3[i].0)
            });
            b.close(mode, &step.y1);
        }
        let s = &mut *self.stats;
        let now = mode.in_contact();
        if step.t0 >= self.analysed_from {
            if now {
                s.contact_time += step.h;
                if !s.in_contact {
                    s.impacts += 1;
                }
            }
            s.x_peak = s.x_peak.max(step.y1[self.ix].abs());
            if s.peaks.len > 0 {
                s.peaks.see(self.model.layout(), step.y1.as_slice());
            }
        }
        s.in_contact = now;
    }

    fn switched(&mut self, t: f64, from: Mode, to: Mode) {
        if let Some(b) = self.books.as_mut() {
            b.switched(to);
        }
        if t >= self.analysed_from && SwitchKind::between(from, to) == SwitchKind::Rebound {
            self.stats.impacts += 1;
        }
    }
}
