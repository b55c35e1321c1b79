//! Shooting: the period map of one model, its linearisation, Newton's method for a periodic
//! orbit, and the move of an orbit's section into free flight.

use nalgebra::{SMatrix, SVector};

use crate::drive::Sine;
use crate::model::tangent::{tangent_options, Tangents};
use crate::model::{ContactGeometry, Mode, Model};
use crate::ode::{Observer, SolverError, Stats, Step, Steps, Tangent, Unseen};
use crate::study::flow::{Engine, SineFlow};

use super::period_sums::Accumulator;
use super::CHORD_STEPS;
use super::{multipliers, Forcing, Orbit, OrbitError, OrbitSummary, Parameter, ShootingOptions};

/// The period map and its derivatives at one point: P(y), M = dP/dy and dP/dp (physical
/// units).
#[derive(Debug, Clone, Copy)]
pub struct Linearised<const N: usize> {
    /// P(y).
    pub end: SVector<f64, N>,
    /// dP/dy.
    pub monodromy: SMatrix<f64, N, N>,
    /// dP/dp.
    pub dp: SVector<f64, N>,
}

/// Shooting for periodic orbits of one model.
#[derive(Debug, Clone)]
pub struct Shooter<'a, M, const N: usize> {
    /// The model.
    pub base: &'a M,
    /// Settings.
    pub cfg: ShootingOptions,
    scales: SVector<f64, N>,
    /// The contacts whose reach an orbit's summary measures (`None`: the model's own).
    measured: Option<Vec<ContactGeometry>>,
}

impl<'a, M: Model<N>, const N: usize> Shooter<'a, M, N> {
    /// Shooting on `base` with settings `cfg`.
    pub fn new(base: &'a M, cfg: ShootingOptions) -> Self {
        Self::with_scales(base, cfg, base.scales())
    }

    /// Shooting with given state scales (e.g. those of another model of the same device).
    pub fn with_scales(base: &'a M, cfg: ShootingOptions, scales: SVector<f64, N>) -> Self {
        Self {
            base,
            cfg,
            scales,
            measured: None,
        }
    }

    /// The same shooter with the summaries' reach measured for `contacts` (those of another
    /// model of the same device, e.g. the device with its stops, on the flow without them).
    #[must_use]
    pub fn measuring(mut self, contacts: Vec<ContactGeometry>) -> Self {
        self.measured = Some(contacts);
        self
    }

    /// The state scales of the scaled coordinates.
    pub fn scales(&self) -> SVector<f64, N> {
        self.scales
    }

    /// The scaled Euclidean norm of a state.
    pub fn norm(&self, y: &SVector<f64, N>) -> f64 {
        y.component_div(&self.scales).norm()
    }

    pub(crate) fn solver_err(&self, p: Parameter, forcing: &Forcing, e: SolverError) -> OrbitError {
        OrbitError::Solver {
            what: p.label(),
            param: forcing.get(p),
            source: e,
        }
    }

    /// Integrates from `y` at drive phase `phase_rad` for `duration_s`, calling `observer`
    /// with every accepted step; returns the final state and mode and the counters.
    pub fn flow<O: FnMut(&Step<SVector<f64, N>>, Mode)>(
        &self,
        forcing: &Forcing,
        phase_rad: f64,
        y: SVector<f64, N>,
        duration_s: f64,
        observer: O,
    ) -> Result<(SVector<f64, N>, Mode, Stats), SolverError> {
        self.run(forcing, phase_rad, y, duration_s, &mut Steps(observer))
    }

    /// As [`Shooter::flow`], showing nothing (the same steps, without the dense output an
    /// observer would see).
    pub fn advance(
        &self,
        forcing: &Forcing,
        phase_rad: f64,
        y: SVector<f64, N>,
        duration_s: f64,
    ) -> Result<(SVector<f64, N>, Mode, Stats), SolverError> {
        self.run(forcing, phase_rad, y, duration_s, &mut Unseen)
    }

    fn run<O: Observer<SVector<f64, N>, Mode>>(
        &self,
        forcing: &Forcing,
        phase_rad: f64,
        y: SVector<f64, N>,
        duration_s: f64,
        observer: &mut O,
    ) -> Result<(SVector<f64, N>, Mode, Stats), SolverError> {
        let sine = forcing.sine(phase_rad);
        let mut ode = SineFlow::new(
            self.base,
            sine,
            0.0,
            y,
            self.base.mode_of(&y),
            self.cfg.rtol,
        );
        ode.integrate_observed(duration_s, observer)?;
        Ok((ode.y(), ode.mode(), ode.stats()))
    }

    /// The plain period map P(y).
    pub fn period_map(
        &self,
        forcing: &Forcing,
        phase_rad: f64,
        y: SVector<f64, N>,
    ) -> Result<SVector<f64, N>, SolverError> {
        self.advance(forcing, phase_rad, y, forcing.period_s())
            .map(|r| r.0)
    }

    /// P(y), dP/dy and dP/dp by the variational equations (see the module docs); `stats`
    /// accumulates the integrator's counters.
    pub fn linearise(
        &self,
        forcing: &Forcing,
        param: Parameter,
        phase_rad: f64,
        y: SVector<f64, N>,
        stats: &mut Stats,
    ) -> Result<Linearised<N>, SolverError> {
        self.linearise_over(forcing, param, phase_rad, y, forcing.period_s(), stats)
    }

    /// As [`Shooter::linearise`] for the flow over `duration_s` instead of one period (the
    /// half-period map of a symmetric orbit): the end state, its derivative with respect to
    /// the start state, and with respect to the parameter (for the frequency at a fixed
    /// fraction of the period, `duration_s * f` fixed).
    pub fn linearise_over(
        &self,
        forcing: &Forcing,
        param: Parameter,
        phase_rad: f64,
        y: SVector<f64, N>,
        duration_s: f64,
        stats: &mut Stats,
    ) -> Result<Linearised<N>, SolverError> {
        let p_ref = forcing.get(param).abs().max(1e-300);
        self.linearise_with(forcing.sine(phase_rad), param, p_ref, y, duration_s, stats)
    }

    /// As [`Shooter::linearise_over`] under the sine `sine` itself.
    pub fn linearise_sine(
        &self,
        sine: Sine,
        param: Parameter,
        y: SVector<f64, N>,
        duration_s: f64,
        stats: &mut Stats,
    ) -> Result<Linearised<N>, SolverError> {
        let p_ref = match param {
            Parameter::Frequency => sine.freq_hz,
            Parameter::Amplitude => sine.amplitude_m_s2 / (std::f64::consts::SQRT_2 * crate::G),
        }
        .abs()
        .max(1e-300);
        self.linearise_with(sine, param, p_ref, y, duration_s, stats)
    }

    /// The linearisation under `sine` with the parameter's scale `p_ref` (for the parameter
    /// column's tolerance).
    fn linearise_with(
        &self,
        sine: Sine,
        param: Parameter,
        p_ref: f64,
        y: SVector<f64, N>,
        duration_s: f64,
        stats: &mut Stats,
    ) -> Result<Linearised<N>, SolverError> {
        let sys = Tangents::new(self.base, sine, param);
        let opts = tangent_options(self.base, &self.scales, self.cfg.rtol, p_ref);
        let mut ode = Engine::new(
            sys,
            0.0,
            Tangent::start(y),
            self.base.mode_of(&y),
            opts,
            true,
        );
        let period = sine.period_s();
        ode.integrate_observed(
            duration_s,
            &mut crate::ode::Steps(|_: &Step<Tangent<N>>, _| {}),
        )?;
        *stats += ode.stats();
        let z = ode.z();
        let end = z.y;
        let mut monodromy = z.phi;
        self.drop_unused(&mut monodromy);
        let mut dp = z.dp;
        if param == Parameter::Frequency {
            // The end time t = c/f moves with the frequency: + f(y(t)) dt/df, dt/df = -t T.
            let a = crate::drive::Excitation::accel(&sine, duration_s);
            let f_end = self.base.rhs(ode.mode(), &end, a);
            dp -= f_end * (duration_s * period);
        }
        Ok(Linearised { end, monodromy, dp })
    }

    /// The monodromy matrix in scaled coordinates by central differences of the plain period
    /// map, with steps of `eps` in each scaled coordinate (the check of the variational one).
    pub fn monodromy_fd(
        &self,
        forcing: &Forcing,
        phase_rad: f64,
        y: SVector<f64, N>,
        eps: f64,
    ) -> Result<SMatrix<f64, N, N>, SolverError> {
        let mut m = SMatrix::<f64, N, N>::zeros();
        for c in 0..N {
            let h = eps * self.scales[c];
            let (mut yp, mut ym) = (y, y);
            yp[c] += h;
            ym[c] -= h;
            let pp = self.period_map(forcing, phase_rad, yp)?;
            let pm = self.period_map(forcing, phase_rad, ym)?;
            let col = (pp - pm).component_div(&self.scales) / (2.0 * eps);
            m.set_column(c, &col);
        }
        self.drop_unused(&mut m);
        Ok(m)
    }

    /// Replaces the trivial multiplier 1 of each state component the model leaves unused
    /// (held at zero; its row and column of the monodromy are those of the identity) by 0, so
    /// that Newton's matrix M - I is regular and the Floquet tests see only the device's
    /// multipliers.
    fn drop_unused(&self, m: &mut SMatrix<f64, N, N>) {
        for &i in self.base.unused() {
            m[(i, i)] = 0.0;
        }
    }

    /// Scales a physical monodromy to the scaled coordinates: D^-1 M D.
    pub fn scaled_monodromy(&self, m: &SMatrix<f64, N, N>) -> SMatrix<f64, N, N> {
        let mut out = *m;
        for i in 0..N {
            for j in 0..N {
                out[(i, j)] *= self.scales[j] / self.scales[i];
            }
        }
        out
    }

    /// One period of the plain map from `y` with the orbit's whole-period measures; returns
    /// (P(y), summary).
    pub fn measure(
        &self,
        forcing: &Forcing,
        phase_rad: f64,
        y: SVector<f64, N>,
        stats: &mut Stats,
    ) -> Result<(SVector<f64, N>, OrbitSummary), SolverError> {
        self.measure_periods(forcing, phase_rad, y, 1, stats)
    }

    /// As [`Shooter::measure`] over `periods` drive periods (the map and measures of an
    /// orbit of that many periods).
    pub fn measure_periods(
        &self,
        forcing: &Forcing,
        phase_rad: f64,
        y: SVector<f64, N>,
        periods: usize,
        stats: &mut Stats,
    ) -> Result<(SVector<f64, N>, OrbitSummary), SolverError> {
        let sine = forcing.sine(phase_rad);
        let outputs = self.base.layout().outputs.len();
        let peaks = crate::study::mass_peaks::MassPeaks::of(self.base.layout());
        let contacts = self
            .measured
            .clone()
            .unwrap_or_else(|| self.base.contacts());
        let mut acc = Accumulator::new(self.base, outputs, peaks, contacts);
        let mut ode = SineFlow::new(
            self.base,
            sine,
            0.0,
            y,
            self.base.mode_of(&y),
            self.cfg.rtol,
        );
        let period = periods as f64 * forcing.period_s();
        ode.integrate_observed(period, &mut acc)?;
        let (end, st) = (ode.y(), ode.stats());
        *stats += st;
        Ok((end, OrbitSummary::of(self.base.layout(), &acc.sums, period)))
    }

    /// Newton's method for the periodic orbit of `forcing` with section at `phase_rad`, from
    /// `guess`; `param` names the parameter in errors (and is the one whose sensitivity is
    /// computed alongside). The orbit is accepted when the plain period map's residual is
    /// below [`ShootingOptions::residual_tol`].
    ///
    /// A piezoelectric cantilever below its stopper is linear, `y' = L y + c a`: its
    /// multipliers are those of `exp(L T)`, whose product is `exp(T trace L)` (Liouville's
    /// formula), with `trace L = -b/m - 1/(R Cp)`.
    ///
    /// ```
    /// use endstop::device::Device;
    /// use endstop::model::Model;
    /// use endstop::ode::Stats;
    /// use endstop::study::orbit::{Forcing, Parameter, Shooter, ShootingOptions};
    /// use nalgebra::Complex;
    ///
    /// let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/examples/piezo_cantilever.toml"));
    /// let device = Device::from_toml_str(text, "piezo_cantilever.toml")?;
    /// let forcing = Forcing { freq_hz: 115.0, accel_rms_g: 0.01 };
    /// let orbit = endstop::with_harvester!(&device, |h| {
    ///     let shooter = Shooter::new(&h, ShootingOptions::default());
    ///     let mut stats = Stats::default();
    ///     shooter.solve(&forcing, Parameter::Frequency, 0.0, h.rest_state(), &mut stats)
    /// })?;
    /// assert!(orbit.is_stable() && !orbit.is_impacting());
    /// // The unused component's multiplier is 0 and is left out of the product.
    /// let product = orbit
    ///     .multipliers
    ///     .iter()
    ///     .filter(|m| m.norm() > 0.0)
    ///     .fold(Complex::new(1.0, 0.0), |p, m| p * m);
    /// let (mass, b, cp, r) = (5e-3, 0.0754, 50e-9, 26.5e3);
    /// let liouville = ((-b / mass - 1.0 / (r * cp)) / forcing.freq_hz).exp();
    /// // The variational equations are integrated at rtol 1e-10; 1e-6 relative leaves room
    /// // for the error of the matrix's entries amplified by the eigenvalue product.
    /// assert!((product.re / liouville - 1.0).abs() < 1e-6 && product.im.abs() < 1e-6 * liouville);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn solve(
        &self,
        forcing: &Forcing,
        param: Parameter,
        phase_rad: f64,
        guess: SVector<f64, N>,
        stats: &mut Stats,
    ) -> Result<Orbit, OrbitError> {
        self.solve_periods(forcing, param, phase_rad, guess, 1, stats)
    }

    /// As [`Shooter::solve`] for an orbit of `periods` drive periods: Newton's method on the
    /// map over that many periods (whose fixed points include the orbits of every divisor of
    /// `periods`: the caller tells them apart).
    pub fn solve_periods(
        &self,
        forcing: &Forcing,
        param: Parameter,
        phase_rad: f64,
        guess: SVector<f64, N>,
        periods: usize,
        stats: &mut Stats,
    ) -> Result<Orbit, OrbitError> {
        if periods == 0 {
            return Err(OrbitError::Invalid(
                "an orbit spans at least one drive period".into(),
            ));
        }
        let err = |e| self.solver_err(param, forcing, e);
        let duration_s = periods as f64 * forcing.period_s();
        let mut y = guess;
        let mut residual = f64::INFINITY;
        for it in 0..=self.cfg.max_newton {
            let lin = self
                .linearise_over(forcing, param, phase_rad, y, duration_s, stats)
                .map_err(err)?;
            let g = (lin.end - y).component_div(&self.scales);
            residual = g.norm() / self.norm(&y).max(1e-300);
            let m = self.scaled_monodromy(&lin.monodromy);
            let lu = crate::num::dense::Lu::of(&(m - SMatrix::<f64, N, N>::identity()));
            if residual < self.cfg.residual_tol {
                // The fixed point of the variational integration; polish it on the plain
                // period map (the one every reported residual refers to) by chord steps
                // with the same matrix: the two integrations differ by their global error,
                // a few rtol.
                for _ in 0..CHORD_STEPS {
                    let (end, summary) = self
                        .measure_periods(forcing, phase_rad, y, periods, stats)
                        .map_err(err)?;
                    let gp = (end - y).component_div(&self.scales);
                    let plain = gp.norm() / self.norm(&y).max(1e-300);
                    if plain < self.cfg.residual_tol {
                        let mut o =
                            self.orbit(forcing, param, phase_rad, y, m, plain, it, summary)?;
                        o.periods = periods;
                        return Ok(o);
                    }
                    residual = plain;
                    let Some(dz) = lu.solve(&(-gp)) else { break };
                    y += dz.component_mul(&self.scales);
                }
                break;
            }
            if it == self.cfg.max_newton {
                break;
            }
            let Some(dz) = lu.solve(&(-g)) else {
                break;
            };
            y += dz.component_mul(&self.scales);
        }
        Err(OrbitError::NoConvergence {
            what: param.label(),
            param: forcing.get(param),
            iterations: self.cfg.max_newton,
            residual,
        })
    }

    /// Builds an orbit of one drive period from a converged state.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn orbit(
        &self,
        forcing: &Forcing,
        param: Parameter,
        phase_rad: f64,
        y: SVector<f64, N>,
        monodromy: SMatrix<f64, N, N>,
        residual: f64,
        iterations: usize,
        summary: OrbitSummary,
    ) -> Result<Orbit, OrbitError> {
        let multipliers = multipliers(&monodromy).ok_or(OrbitError::Eigenvalues {
            what: param.label(),
            param: forcing.get(param),
        })?;
        Ok(Orbit {
            forcing: *forcing,
            phase_rad,
            periods: 1,
            state: nalgebra::DVector::from_column_slice(y.as_slice()),
            monodromy: nalgebra::DMatrix::from_column_slice(N, N, monodromy.as_slice()),
            multipliers,
            residual,
            iterations,
            summary,
        })
    }

    /// True when the orbit's section lies well inside free flight: with every mass's
    /// displacement doubled, no contact's guard of free flight fires (for a mass between two
    /// stops: at most half the gap from rest towards either).
    pub fn section_is_free(&self, orbit: &Orbit) -> bool {
        let mut probe: SVector<f64, N> = orbit.state_n();
        for &(x, _) in &self.base.layout().masses {
            probe[x] *= 2.0;
        }
        let mut g = vec![0.0; self.base.guard_count()];
        self.base.guards(Mode::FREE, &probe, || 0.0, &mut g);
        g[..self.base.contact_guards()].iter().all(|h| *h <= 0.0)
    }

    /// The same orbit cut at the drive phase where x crosses zero upwards (see the module
    /// docs), polished by Newton at the new section. Returns the orbit unchanged when it has
    /// no upward zero crossing.
    pub fn reanchor(
        &self,
        orbit: &Orbit,
        param: Parameter,
        stats: &mut Stats,
    ) -> Result<Orbit, OrbitError> {
        let Some(t) = orbit.summary.upcrossing_s else {
            return Ok(orbit.clone());
        };
        let f = &orbit.forcing;
        let (y, _, st) = self
            .advance(f, orbit.phase_rad, orbit.state_n(), t)
            .map_err(|e| self.solver_err(param, f, e))?;
        *stats += st;
        let w = 2.0 * std::f64::consts::PI * f.freq_hz;
        let phase = (orbit.phase_rad + w * t).rem_euclid(2.0 * std::f64::consts::PI);
        self.solve_periods(f, param, phase, y, orbit.periods, stats)
    }

    /// The state of an orbit at drive phase `phase_rad` (integrated from its section).
    pub fn state_at_phase(
        &self,
        orbit: &Orbit,
        phase_rad: f64,
    ) -> Result<SVector<f64, N>, SolverError> {
        let f = &orbit.forcing;
        let w = 2.0 * std::f64::consts::PI * f.freq_hz;
        let dphi = (phase_rad - orbit.phase_rad).rem_euclid(2.0 * std::f64::consts::PI);
        let t = dphi / w;
        if t == 0.0 {
            return Ok(orbit.state_n());
        }
        self.advance(f, orbit.phase_rad, orbit.state_n(), t)
            .map(|r| r.0)
    }
}
