//! Escape over the barrier of a double well: the two counts of [`crate::validation::escapes`],
//! each against the theory of what it counts, in the damping regime it holds in.
//!
//! The mass moves in `U = dU ((x/x_w)^2 - 1)^2` (measured from a well's bottom) with viscous
//! damping `gamma = c / m` under white noise of temperature `theta`
//! ([`crate::validation::stationary_law`], with the band's deficit); `w_0` is the
//! small-oscillation frequency in a well, `w_b = w_0 / sqrt 2` that of the inverted barrier.
//! The theories are those reviewed by Haenggi, Talkner and Borkovec (Rev. Mod. Phys. 62, 251,
//! 1990: section IV for the weak- and moderate-friction rates and the turnover).
//!
//! **Barrier passages** ([`EscapeTheory::passage_rate_per_s`]). The stationary law is exact for
//! any damping, and with it Rice's count of level crossings: the mass crosses the barrier's top
//! `2 p(0) sqrt(E[v^2] / (2 pi))` times a second (`p(0)` the exact density there, the velocity
//! Gaussian with variance `E[v^2] = theta / m`, less the band's deficit, and independent of
//! `x`). This is also the transition-state
//! rate of one well (the one-way flux over the barrier over a well's population, one half). The
//! records count crossings between samples `h = 1/f_s` apart, and miss a pair when the mass
//! turns back within one: a crossing with `|v| < |a| h`, of flux-weighted probability
//! `m h^2 E[a^2] / (2 theta)`; with the noise's `E[a^2] = 2 B S` and `theta = m^2 S / (2 c)` the
//! passages fall short by at most `4 gamma B h^2` ([`EscapeTheory::passage_undercount`]).
//!
//! **Settled escapes, moderate damping: Kramers.** Kramers (Physica 7, 284, 1940) found for
//! moderate to strong friction the transition-state rate times the transmission factor
//! `kappa = (sqrt(gamma^2/4 + w_b^2) - gamma/2) / w_b` of the recrossings at a parabolic
//! barrier. In a symmetric double well every escape at this rate settles in the other well, so
//! the records' settled escapes per second (from either well, each well holding half the time)
//! are `kappa` times the passage rate above ([`EscapeTheory::kramers_per_s`]: the exact
//! transition-state rate in place of its harmonic value `(w_0 / 2 pi) exp(-dU/theta)`; Kramers'
//! formula as written, [`EscapeTheory::kramers_harmonic_per_s`], differs by the wells'
//! anharmonicity, about `0.19 theta / dU` and more). The theory's own error, the parts it
//! neglects ([`EscapeTheory::own_error`]):
//! - the turnover: an escaping mass must lose energy to settle; with the energy `Delta theta`
//!   it loses over one swing through a well at the barrier's energy (`Delta = gamma I_b /
//!   theta`, `I_b` that orbit's action), Mel'nikov and Meshkov's depopulation factor
//!   `A(Delta) = exp((1/pi) int_0^inf ln(1 - exp(-Delta (l^2 + 1/4))) / (l^2 + 1/4) dl)` (HTB
//!   eq. 4.55) makes the double well's rate `A(Delta)^2 / A(2 Delta)` of Kramers' (Mel'nikov,
//!   Phys. Rep. 209, 1, 1991): the term `1 - A(Delta)^2 / A(2 Delta)`;
//! - the barrier's anharmonicity: `kappa` is decided within the thermal width
//!   `x^2 = theta / (m w_b^2)` of the barrier, over which the quartic's curvature changes by
//!   `3 x^2 / x_w^2 = 3 theta / (4 dU)`; the term is that change times `|d ln kappa / d ln
//!   w_b^2|`;
//! - the count's definition: a mass settled `theta` above a well's bottom is carried back over
//!   the barrier before it relaxes with a chance of the order of `exp(-(dU - theta) / theta)`.
//!
//! **Settled escapes, light damping: the energy-diffusion limit.** For `Delta << 1` the energy
//! changes little over a swing and diffuses: `d_t P = d_E [gamma I(E) (1 + theta d_E)
//! (w(E) / 2 pi) P]` (Kramers 1940; HTB section IV.A), which follows from the Langevin equation
//! with `I(E) = oint p dx`: its drift `gamma (theta - I w / 2 pi)` and diffusion `gamma theta I w
//! / 2 pi` are the orbit averages of `gamma (theta - m v^2)` and `gamma theta m v^2`. Its
//! stationary flux from a well's bottom to the barrier's energy `E_b`, over the well's
//! population, is the rate of reaching `E_b`:
//! `k = gamma theta / int_0^E_b exp(E / theta) Z(E) / I(E) dE`, with `Z(E)` the well's phase-space
//! integral of `exp(-H / theta)` below `E` ([`EscapeTheory::diffusion_escape_per_s`]; computed for
//! the quartic well itself, so it carries no harmonic approximation; for a high barrier it is
//! `gamma (I_b / theta) (w_0 / 2 pi) exp(-dU / theta)`). A mass at `E_b` swings over both wells
//! and settles in either with the same chance, so the settled escapes per second are `k / 2`.
//! Its own error is the turnover, `1 - A(Delta)^2 / (A(2 Delta) Delta / 2)` (the depopulation
//! factor's next order, about `0.8 sqrt(Delta)`), and the count's definition term.
//!
//! Between the regimes (`0.3 < Delta < 10`) neither asymptotic theory holds to a useful
//! accuracy and the settled escapes are not judged ([`Regime::of`]).
//!
//! **The checks** ([`checks`]). At each level both counts against their theories, each within
//! its own error plus the ensemble's two-sided 99.9 % Student-t interval across records (a
//! family of a few rows per device, as the stationary law's).

use crate::device::Device;
use crate::study::record::RecordSpec;
use crate::validation::escapes::{double_well, EscapeEnsemble, SETTLED_WITHIN_THETA};
use crate::validation::stationary_law::{ci999, StationaryLaw};
use crate::validation::{Check, Group, Measure, ValidationError};

/// Kramers' moderate-friction rate is used for `Delta` at or above this (its turnover term,
/// `1 - A^2(Delta) / A(2 Delta)`, is then below 5 %).
pub const KRAMERS_MIN_LOSS: f64 = 10.0;
/// The energy-diffusion limit is used for `Delta` at or below this (its turnover term is then
/// below 25 %).
pub const DIFFUSION_MAX_LOSS: f64 = 0.3;

/// The damping regime of an escape, by the energy `Delta theta` lost over one swing at the
/// barrier's energy.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Regime {
    /// `Delta >= KRAMERS_MIN_LOSS`: Kramers' rate.
    Moderate,
    /// `Delta <= DIFFUSION_MAX_LOSS`: the energy-diffusion limit.
    Light,
}

impl Regime {
    /// The regime of `Delta`, `None` between them.
    pub fn of(loss: f64) -> Option<Self> {
        if loss >= KRAMERS_MIN_LOSS {
            Some(Regime::Moderate)
        } else if loss <= DIFFUSION_MAX_LOSS {
            Some(Regime::Light)
        } else {
            None
        }
    }

    /// The name of the theory in the tables.
    pub fn theory(self) -> &'static str {
        match self {
            Regime::Moderate => "Kramers' rate (moderate damping; Kramers 1940, HTB 1990)",
            Regime::Light => {
                "the energy-diffusion limit, half of it to the other well (light damping; \
                 Kramers 1940, HTB 1990)"
            }
        }
    }
}

/// The theories of one device at one level (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct EscapeTheory {
    /// The barrier over the temperature, `dU / theta`.
    pub barrier_over_theta: f64,
    /// `gamma = c / m` (1/s).
    pub gamma_per_s: f64,
    /// `Delta = gamma I_b / theta`.
    pub loss: f64,
    /// Rice's barrier passages per second on the exact law.
    pub passage_rate_per_s: f64,
    /// The passages' largest relative shortfall from sampling, `4 gamma B h^2`.
    pub passage_undercount: f64,
    /// Kramers' transmission factor times the passage rate (settled escapes per second).
    pub kramers_per_s: f64,
    /// Kramers' formula as written, with the harmonic transition-state rate.
    pub kramers_harmonic_per_s: f64,
    /// The energy-diffusion limit's rate of reaching the barrier's energy from a well (1/s).
    pub diffusion_escape_per_s: f64,
    /// The regime, if any.
    pub regime: Option<Regime>,
    /// Mel'nikov and Meshkov's depopulation factor `A(Delta)`.
    pub depopulation: f64,
    /// The turnover term of the regime's theory (relative).
    pub turnover_term: f64,
    /// The barrier anharmonicity term (relative; Kramers' only).
    pub barrier_term: f64,
    /// The count's definition term (relative).
    pub settle_term: f64,
}

impl EscapeTheory {
    /// The theories for a `bistable` device without stops under the records of `spec`.
    pub fn of(device: &Device, spec: &RecordSpec) -> Result<Self, ValidationError> {
        let (well_m, barrier_j) = double_well(device)?;
        let law = StationaryLaw::of(device, spec)?;
        let m = device.mechanics.mass_kg;
        let theta = law.theta_j;
        let w0 = (8.0 * barrier_j / (m * well_m * well_m)).sqrt();
        let wb = w0 / std::f64::consts::SQRT_2;
        let gamma = law.damping_n_s_per_m / m;
        let well = QuarticWell {
            mass_kg: m,
            well_m,
            barrier_j,
        };
        let loss = gamma * well.action_j_s(barrier_j) / theta;
        let beta = barrier_j / theta;
        // The density with white noise's theta, the velocity with the band's deficit
        // (`StationaryLaw`'s module docs).
        let passage =
            2.0 * law.density(0.0) * (law.v2_m2_s2() / (2.0 * std::f64::consts::PI)).sqrt();
        let h = 1.0 / spec.noise.sample_rate_hz;
        let g = gamma / (2.0 * wb);
        let kappa = (1.0 + g * g).sqrt() - g;
        let dlnk_dlnwb2 = 0.5 * g * (1.0 - g / (1.0 + g * g).sqrt()) / kappa;
        let a1 = depopulation(loss);
        let a2 = depopulation(2.0 * loss);
        let regime = Regime::of(loss);
        let turnover_term = match regime {
            Some(Regime::Moderate) | None => (1.0 - a1 * a1 / a2).abs(),
            Some(Regime::Light) => (1.0 - a1 * a1 / (a2 * 0.5 * loss)).abs(),
        };
        Ok(Self {
            barrier_over_theta: beta,
            gamma_per_s: gamma,
            loss,
            passage_rate_per_s: passage,
            passage_undercount: 4.0 * gamma * spec.noise.bandwidth_hz * h * h,
            kramers_per_s: kappa * passage,
            kramers_harmonic_per_s: kappa * w0 / (2.0 * std::f64::consts::PI) * (-beta).exp(),
            diffusion_escape_per_s: well.diffusion_escape_per_s(gamma, theta),
            regime,
            depopulation: a1,
            turnover_term,
            barrier_term: match regime {
                Some(Regime::Moderate) => 0.75 / beta * dlnk_dlnwb2,
                _ => 0.0,
            },
            settle_term: (-(beta - SETTLED_WITHIN_THETA)).exp(),
        })
    }

    /// Settled escapes per second by the regime's theory (NaN between the regimes).
    pub fn settled_reference_per_s(&self) -> f64 {
        match self.regime {
            Some(Regime::Moderate) => self.kramers_per_s,
            Some(Regime::Light) => 0.5 * self.diffusion_escape_per_s,
            None => f64::NAN,
        }
    }

    /// The regime's theory's own error (relative): the sum of the terms it neglects.
    pub fn own_error(&self) -> f64 {
        self.turnover_term + self.barrier_term + self.settle_term
    }
}

/// Mel'nikov and Meshkov's depopulation factor `A(Delta)` (HTB 1990 eq. 4.55), by the
/// substitution `l = tan(phi) / 2`: `(2/pi) int_0^(pi/2) ln(1 - exp(-Delta / (4 cos^2 phi))) dphi`
/// in the exponent, Gauss-Legendre on 400 panels (the integrand is smooth and bounded; it
/// vanishes at `pi/2`).
pub fn depopulation(loss: f64) -> f64 {
    let ln1m_exp = |u: f64| {
        if u < 0.5 {
            (-(-u).exp_m1()).ln()
        } else {
            (-(-u).exp()).ln_1p()
        }
    };
    let s = gauss_legendre(0.0, std::f64::consts::FRAC_PI_2, 400, &|phi: f64| {
        let c = phi.cos();
        if c <= 0.0 {
            0.0
        } else {
            ln1m_exp(loss / (4.0 * c * c))
        }
    });
    (2.0 / std::f64::consts::PI * s).exp()
}

/// `int_a^b f` by 5-point Gauss-Legendre on `panels` equal panels.
fn gauss_legendre(a: f64, b: f64, panels: usize, f: &dyn Fn(f64) -> f64) -> f64 {
    let h = (b - a) / panels as f64;
    let mut total = 0.0;
    for i in 0..panels {
        let mid = a + (i as f64 + 0.5) * h;
        for &(x, w) in &crate::ode::GAUSS_LEGENDRE_5 {
            total += 0.5 * h * w * f(mid + 0.5 * h * x);
        }
    }
    total
}

/// One well of the quartic double well, energies measured from its bottom.
#[derive(Debug, Clone, Copy)]
struct QuarticWell {
    mass_kg: f64,
    well_m: f64,
    barrier_j: f64,
}

impl QuarticWell {
    /// `U(x) = dU ((x/x_w)^2 - 1)^2` (J).
    fn potential_j(&self, x: f64) -> f64 {
        let q = (x / self.well_m).powi(2) - 1.0;
        self.barrier_j * q * q
    }

    /// `int_{x1}^{x2} f(x) dx` between the turning points of energy `e` (`0 < e <= dU`), by the
    /// substitution `x = mid - half cos(phi)`, which makes the square roots at the turning points
    /// smooth.
    fn over_orbit(&self, e: f64, f: &dyn Fn(f64) -> f64) -> f64 {
        let r = (e / self.barrier_j).clamp(0.0, 1.0).sqrt();
        let x1 = self.well_m * (1.0 - r).max(0.0).sqrt();
        let x2 = self.well_m * (1.0 + r).sqrt();
        let (mid, half) = (0.5 * (x1 + x2), 0.5 * (x2 - x1));
        gauss_legendre(0.0, std::f64::consts::PI, 64, &|phi| {
            f(mid - half * phi.cos()) * half * phi.sin()
        })
    }

    /// The action `I(E) = oint m v dx` of the orbit of energy `e` in the well (J s).
    fn action_j_s(&self, e: f64) -> f64 {
        let m = self.mass_kg;
        2.0 * self.over_orbit(e, &|x| {
            (2.0 * m * (e - self.potential_j(x)).max(0.0)).sqrt()
        })
    }

    /// `Z(E)`: `int int exp(-H / theta) dx dp` over the well's states with `H <= e`, the
    /// momentum integrated in closed form, `sqrt(2 pi m theta) erf(sqrt((e - U) / theta))`.
    fn phase_integral(&self, e: f64, theta: f64) -> f64 {
        let c = (2.0 * std::f64::consts::PI * self.mass_kg * theta).sqrt();
        c * self.over_orbit(e, &|x| {
            let u = self.potential_j(x);
            (-u / theta).exp() * statrs::function::erf::erf(((e - u).max(0.0) / theta).sqrt())
        })
    }

    /// The energy-diffusion limit's rate of reaching the barrier's energy from the well (see
    /// the module docs): `gamma theta / int_0^dU exp(E/theta) Z(E) / I(E) dE`, the integrand
    /// finite at both ends (`Z / I -> 1` at the bottom).
    fn diffusion_escape_per_s(&self, gamma: f64, theta: f64) -> f64 {
        let integral = gauss_legendre(0.0, self.barrier_j, 200, &|e| {
            (e / theta).exp() * self.phase_integral(e, theta) / self.action_j_s(e)
        });
        gamma * theta / integral
    }
}

/// The action `oint m v dx` of the orbit at the barrier's energy in one well of the quartic
/// double well of mass `mass_kg`, wells at `+-well_m` and barrier `barrier_j` (J s; in closed
/// form `(8/3) x_w sqrt(m dU)`, here by quadrature).
pub fn barrier_action_j_s(mass_kg: f64, well_m: f64, barrier_j: f64) -> f64 {
    QuarticWell {
        mass_kg,
        well_m,
        barrier_j,
    }
    .action_j_s(barrier_j)
}

/// The energy-diffusion limit's rate of reaching the barrier's energy from a well of the
/// quartic double well (1/s; see the module docs), for damping rate `gamma` (1/s) and
/// temperature `theta` (J).
pub fn energy_diffusion_escape_per_s(
    mass_kg: f64,
    well_m: f64,
    barrier_j: f64,
    gamma: f64,
    theta: f64,
) -> f64 {
    QuarticWell {
        mass_kg,
        well_m,
        barrier_j,
    }
    .diffusion_escape_per_s(gamma, theta)
}

/// One level's ensemble beside its theories.
#[derive(Debug, Clone)]
pub struct EscapeLevel {
    /// The theories.
    pub theory: EscapeTheory,
    /// The counts.
    pub ensemble: EscapeEnsemble,
}

/// The checks over levels (see the module docs): at each level the barrier passages against
/// Rice's count on the exact law, and the settled escapes against the regime's theory (none
/// between the regimes).
pub fn checks(device: &Device, levels: &[EscapeLevel]) -> Vec<Check> {
    let mut g = Group::new(&format!("escape over the barrier: {}", device.name));
    for l in levels {
        let t = &l.theory;
        let n = l.ensemble.records.len();
        let p = l.ensemble.passage_rate();
        g.add(
            "Rice's crossings on the exact stationary law, 2 p(0) sqrt(E[v^2] / (2 pi))",
            &format!(
                "{}: barrier passages per second at dU/theta = {:.2} ({} passages)",
                device.name,
                t.barrier_over_theta,
                l.ensemble.passages()
            ),
            t.passage_rate_per_s,
            p.mean,
            Measure::Relative,
            t.passage_undercount + ci999(p.std, n) / t.passage_rate_per_s,
            "exact for any damping: the passages the samples miss (at most 4 gamma B h^2) and \
             the ensemble's 99.9 % interval across records",
        );
        let Some(regime) = t.regime else {
            continue;
        };
        let s = l.ensemble.settled_rate();
        let reference = t.settled_reference_per_s();
        let extra = match regime {
            Regime::Moderate => format!(
                "; Kramers' formula as written {:.4e}",
                t.kramers_harmonic_per_s
            ),
            Regime::Light => format!(
                "; passages {:.1} times the settled escapes",
                p.mean / s.mean
            ),
        };
        g.add(
            regime.theory(),
            &format!(
                "{}: settled escapes per second at dU/theta = {:.2}, Delta = {:.3} ({} escapes{extra})",
                device.name,
                t.barrier_over_theta,
                t.loss,
                l.ensemble.settled()
            ),
            reference,
            s.mean,
            Measure::Relative,
            t.own_error() + ci999(s.std, n) / reference,
            &format!(
                "the theory's own error, {:.1e} (turnover {:.1e}, barrier anharmonicity {:.1e}, \
                 the count's definition {:.1e}), and the ensemble's 99.9 % interval across records",
                t.own_error(),
                t.turnover_term,
                t.barrier_term,
                t.settle_term
            ),
        );
    }
    g.into_checks()
}
