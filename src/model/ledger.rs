//! A model's energy ledger over a run: the energy of each of its terms
//! ([`super::Model::ledger_terms`]), the work of its sources and the change of its stored
//! energy, and the observer that books them from an integration's steps and switches.
//!
//! Over any run, the terms that flow in plus the sources' work equal the terms that flow out
//! plus the change of the stored energy; [`Ledger::residual`] is what is left.

use nalgebra::SVector;

use crate::drive::Excitation;
use crate::ode::{Observer, Step, GAUSS_LEGENDRE_3};

use super::{Flow, LedgerTerm, Mode, Model};

/// The energy balance of a run (J): each term's energy as it flows, the sources' work and the
/// change of the stored energy.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Ledger {
    /// The terms, in the model's order.
    pub terms: Vec<LedgerTerm>,
    /// Each term's energy over the run (J, as the term flows).
    pub energy_j: Vec<f64>,
    /// Work of the sources that are functions of the state (a bias source) (J).
    pub source_j: f64,
    /// Change of the stored energy (J).
    pub stored_change_j: f64,
}

impl Ledger {
    /// An empty ledger of a model's terms.
    pub fn new(terms: &[LedgerTerm]) -> Self {
        Self {
            terms: terms.to_vec(),
            energy_j: vec![0.0; terms.len()],
            source_j: 0.0,
            stored_change_j: 0.0,
        }
    }

    /// The energy of the term named `name` (J; zero for a term the model does not have).
    pub fn get(&self, name: &str) -> f64 {
        self.terms
            .iter()
            .position(|t| t.name == name)
            .map_or(0.0, |i| self.energy_j[i])
    }

    /// Energy in minus energy out and stored (J); zero for an exact run.
    pub fn residual(&self) -> f64 {
        let mut r = self.source_j - self.stored_change_j;
        for (t, e) in self.terms.iter().zip(&self.energy_j) {
            match t.flow {
                Flow::In => r += e,
                Flow::Out => r -= e,
            }
        }
        r
    }

    /// The residual divided by the sum of the terms' magnitudes (dividing by the work in alone
    /// would be ill-conditioned for a detuned drive, whose net work passes through zero while
    /// energy sloshes in and out of the resonator).
    pub fn relative_residual(&self) -> f64 {
        let scale = self.source_j.abs()
            + self.stored_change_j.abs()
            + self.energy_j.iter().map(|e| e.abs()).sum::<f64>();
        self.residual() / scale
    }

    /// The ledger less `earlier` (a run's later part), with the stored energy and the sources'
    /// work counted from `earlier`'s end: the caller sets them.
    #[must_use]
    pub fn minus(&self, earlier: &Ledger) -> Ledger {
        Ledger {
            terms: self.terms.clone(),
            energy_j: self
                .energy_j
                .iter()
                .zip(&earlier.energy_j)
                .map(|(a, b)| a - b)
                .collect(),
            source_j: self.source_j - earlier.source_j,
            stored_change_j: self.stored_change_j - earlier.stored_change_j,
        }
    }
}

/// Books a model's ledger from the steps and switches of an integration under the drive
/// `drive` (see the module docs): each step's powers by 3-point Gauss-Legendre on its dense
/// output (degree 5), and what a switch moved between one step's end and the next one's start
///
/// ```
/// use endstop::device::Device;
/// use endstop::drive::Sine;
/// use endstop::model::{Books, Driven, Mode, Model};
/// use endstop::ode::Dopri5;
///
/// let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/examples/piezo_cantilever.toml"));
/// let device = Device::from_toml_str(text, "piezo_cantilever.toml")?;
/// // 0.3 g rms at 120 Hz for 0.1 s from rest: the tip strikes its stopper.
/// let sine = Sine::from_rms_g(0.3, 120.0);
/// let ledger = endstop::with_harvester!(&device, |h| {
///     let sys = Driven::new(&h, sine);
///     let rest = h.rest_state();
///     let mut ode = Dopri5::new(0.0, rest, h.mode_of(&rest), h.solver_options(1e-9));
///     let mut books = Books::new(&h, sine);
///     ode.integrate_observed(&sys, 0.1, &mut books)?;
///     assert!(ode.stats().events > 0);
///     Ok::<_, Box<dyn std::error::Error>>(books.ledger())
/// })?;
/// assert!(ledger.get("drive") > 0.0 && ledger.get("loads") > 0.0);
/// // Energy in = energy out + stored, to the integrator's tolerance (1e-9) times the
/// // energies turned over and the quadrature's error on the dense output: 1e-6 leaves room.
/// assert!(ledger.relative_residual().abs() < 1e-6);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
/// ([`super::Model::book_switch`]).
pub struct Books<'m, M, D, const N: usize> {
    model: &'m M,
    drive: D,
    ledger: Ledger,
    first: Option<(Mode, SVector<f64, N>)>,
    last: Option<(Mode, SVector<f64, N>)>,
    powers: Vec<f64>,
}

impl<'m, M: Model<N>, D: Excitation, const N: usize> Books<'m, M, D, N> {
    /// Empty books of `model` under the drive `drive`.
    pub fn new(model: &'m M, drive: D) -> Self {
        let terms = model.ledger_terms();
        Self {
            model,
            drive,
            ledger: Ledger::new(terms),
            first: None,
            last: None,
            powers: vec![0.0; terms.len()],
        }
    }

    /// The ledger from the first step's start to the last one's end.
    pub fn ledger(&self) -> Ledger {
        let mut l = self.ledger.clone();
        if let (Some((ma, a)), Some((mb, b))) = (self.first, self.last) {
            l.source_j = self.model.source_work(&b) - self.model.source_work(&a);
            l.stored_change_j = self.model.stored_energy(mb, &b) - self.model.stored_energy(ma, &a);
        }
        l
    }

    /// Opens an interval from `y` in `mode` at `t0`: books what a switch moved since the last
    /// interval ended.
    fn open(&mut self, mode: Mode, y: &SVector<f64, N>) {
        match self.last {
            None => self.first = Some((mode, *y)),
            Some((m, prev)) => {
                if m != mode || prev != *y {
                    self.model
                        .book_switch(m, mode, &prev, y, &mut self.ledger.energy_j);
                }
            }
        }
    }

    /// Adds the powers over an interval of length `h` from their values at the Gauss nodes.
    fn add(&mut self, h: f64, at: impl Fn(f64) -> (SVector<f64, N>, f64), mode: Mode) {
        for (x, w) in GAUSS_LEGENDRE_3 {
            let (y, t) = at(x);
            self.model
                .powers(mode, &y, self.drive.accel(t), &mut self.powers);
            for (e, p) in self.ledger.energy_j.iter_mut().zip(&self.powers) {
                *e += w * h * p;
            }
        }
    }
}

impl<M: Model<N>, D: Excitation, const N: usize> Observer<SVector<f64, N>, Mode>
    for Books<'_, M, D, N>
{
    fn step(&mut self, st: &Step<SVector<f64, N>>, mode: Mode) {
        self.open(mode, &st.y0);
        self.add(st.h, |x| (st.at_theta(x), st.t0 + x * st.h), mode);
        self.last = Some((mode, st.y1));
    }
}
