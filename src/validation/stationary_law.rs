//! The exact stationary law of random vibration, against random ensembles.
//!
//! For `m x'' + c x' + U'(x) = -m a(t)` with `a` white of two-sided density `S` (in
//! (m/s^2)^2/Hz over all frequencies, `S = 9.81^2` times the project's two-sided level in
//! g^2/Hz), velocity-proportional damping only and any confining potential `U`, the stationary
//! Fokker-Planck equation is solved by
//! `p(x, v) = C exp(-(m v^2 / 2 + U(x)) / theta)` with `theta = m^2 S / (2 c)` (Caughey, "Nonlinear
//! theory of random vibrations", Adv. Appl. Mech. 11, 1971, 209-253; Lin and Cai,
//! Probabilistic Structural Dynamics, McGraw-Hill 1995, ch. 5). The velocity is Gaussian with
//! `E[v^2] = theta / m` whatever `U`, and the displacement density is `exp(-U / theta)`
//! normalised.
//!
//! In this model `c` is the suspension's damping plus an electromagnetic transducer's without
//! inductance, whose force `Phi i = Phi^2 v / (Rc + R)` is viscous; the load then takes
//! `R Phi^2 E[v^2] / (Rc + R)^2` ([`StationaryLaw::load_power_w`]; not a row of the checks:
//! it is the `E[v^2]` row times a constant, sample by sample). `U` is the suspension's potential plus the stops' elastic
//! energies ([`crate::laws::suspension::potential_j`]): any suspension form, and stops with
//! linear, Hertz line or Hertz point springs and no contact damping. Devices outside this
//! class (a capacitive or piezoelectric transducer, a coil with inductance, contact damping,
//! rigid stops with `e < 1`) are refused.
//!
//! **The band.** The records' noise is flat up to `B` (10 kHz) and zero above. The content it
//! lacks, beyond `B`, far above the device's frequencies, drives only the velocity's fast part:
//! the velocity variance falls short of white noise's by the fraction
//! [`crate::validation::random_law::band_deficit`] (`c / (m pi^2 B)`, derived there; applied to
//! `E[v^2]` here), while the displacement keeps white noise's `theta` (for a linear oscillator
//! the band removes `int_{|f|>B} |H|^2`, of order `(f_0 / B)^3` of the variance, against the
//! velocity's `f_0 / B`). The density here is `exp(-U / theta)` with white noise's `theta`:
//! the barrier passages of a double well, whose rate goes as `exp(-dU / theta)` and so magnifies
//! an error of `theta` by `dU / theta`, show it ([`crate::validation::kramers`]: with the
//! deficit applied to the density as well, they exceed Rice's count by about `dU / theta` times
//! the deficit, well outside their interval on a device whose deficit is a few per cent).
//!
//! **The checks** ([`checks`]). Every ensemble quantity is a mean over independent records
//! with its interval across records, so the correlation of samples within a record is
//! accounted for. The family of checks per device is about ten, so each interval is a
//! two-sided 99.9 % Student-t interval (a false alarm in a family about 1 %). The histogram is
//! tested as a whole by Hotelling's T^2 on [`GOF_BINS`] bins of about equal exact probability
//! (the records' bin shares are the observations, their sample covariance the test's
//! covariance, one bin dropped for the shares' sum of one): the statistic, scaled to
//! Fisher's F with `(p, R - p)` degrees of freedom, must not exceed its 99 % quantile.

use nalgebra::{DMatrix, DVector};
use statrs::distribution::{ContinuousCDF, FisherSnedecor, StudentsT};

use crate::device::{Device, StopLaw, Transducer};
use crate::laws::contact::StopModel;
use crate::laws::suspension::{potential_j, Polynomial};
use crate::study::displacement::{DisplacementBins, DisplacementEnsemble, RecordDisplacement};
use crate::study::record::RecordSpec;
use crate::validation::random_law::band_deficit;
use crate::validation::{Check, Group, Measure, ValidationError};

/// Bins of the goodness-of-fit test (fewer than the records).
pub const GOF_BINS: usize = 10;

/// The stationary law of one device under one level.
#[derive(Debug, Clone)]
pub struct StationaryLaw {
    /// `theta = m^2 S / (2 c)` (J): the displacement density's temperature (see the module
    /// docs on the band).
    pub theta_j: f64,
    /// The total viscous damping `c` (N s/m).
    pub damping_n_s_per_m: f64,
    /// The band's deficit of the velocity variance (relative).
    pub band_deficit: f64,
    mass_kg: f64,
    poly: Polynomial,
    upper: Option<StopModel>,
    lower: Option<StopModel>,
    /// `R Phi^2 / (Rc + R)^2` (N^2 s^2/ ... : load power per unit `E[v^2]`, kg/s).
    load_per_v2: f64,
    lo_m: f64,
    hi_m: f64,
    u_min: f64,
}

impl StationaryLaw {
    /// The law of `device` under the records of `spec`, or why the device is outside it.
    pub fn of(device: &Device, spec: &RecordSpec) -> Result<Self, ValidationError> {
        let m = &device.mechanics;
        let (c_e, load_per_v2) = match &device.transducer {
            Transducer::Electromagnetic(e) if e.coil_inductance_h == 0.0 => {
                let rt = e.coil_resistance_ohm + e.load_resistance_ohm;
                let phi2 = e.transduction_n_per_a * e.transduction_n_per_a;
                (phi2 / rt, e.load_resistance_ohm * phi2 / (rt * rt))
            }
            t => {
                return Err(ValidationError::Device(format!(
                    "the exact stationary law needs viscous damping only: transducer `{}` is \
                     not an electromagnetic one without inductance",
                    t.key()
                )))
            }
        };
        for (side, s) in device.stops.present() {
            let lossless = match s.law {
                StopLaw::HertzLine(_) | StopLaw::Linear { .. } | StopLaw::HertzPoint(_) => {
                    s.damping_n_s_per_m == 0.0
                }
                StopLaw::Restitution { coefficient } => coefficient == 1.0,
                StopLaw::HuntCrossley { .. } => false,
            };
            if !lossless {
                return Err(ValidationError::Device(format!(
                    "the exact stationary law needs lossless stops: {} is not",
                    device.stop_path(side)
                )));
            }
        }
        let c = m.damping_n_s_per_m + c_e;
        let deficit = band_deficit(m.mass_kg, c, 0.0, 0.0, spec.noise.bandwidth_hz);
        let theta = m.mass_kg * m.mass_kg * spec.noise.psd_si() / (2.0 * c);
        let mut law = Self {
            theta_j: theta,
            damping_n_s_per_m: c,
            band_deficit: deficit,
            mass_kg: m.mass_kg,
            poly: device.restoring_polynomial(),
            upper: device.stops.upper.as_ref().map(StopModel::of),
            lower: device.stops.lower.as_ref().map(StopModel::of),
            load_per_v2,
            lo_m: 0.0,
            hi_m: 0.0,
            u_min: 0.0,
        };
        // The support: out from the lowest equilibrium until U exceeds its minimum by 60
        // theta (a density below e^-60 of its peak), or to a rigid stop.
        let eq = crate::physics::statics::equilibria(device);
        let u_min = eq
            .iter()
            .map(|e| e.energy_j)
            .fold(f64::INFINITY, f64::min)
            .min(0.0);
        law.u_min = u_min;
        let x0 = eq.iter().fold(0.0f64, |a, e| a.max(e.x_m.abs()));
        let scale = (theta / m.stiffness_n_per_m).sqrt().max(x0).max(1e-300);
        let reach = |sign: f64| {
            let mut d = scale;
            for _ in 0..200 {
                let u = law.potential_j(sign * (x0 + d));
                if !u.is_finite() || u - u_min > 60.0 * theta {
                    break;
                }
                d *= 1.5;
            }
            let gap = if sign > 0.0 {
                law.upper.map_or(f64::INFINITY, |s| s.gap())
            } else {
                law.lower.map_or(f64::INFINITY, |s| s.gap())
            };
            let rigid = |s: Option<StopModel>| matches!(s, Some(StopModel::Rigid { .. }));
            let limit = if (sign > 0.0 && rigid(law.upper)) || (sign < 0.0 && rigid(law.lower)) {
                gap
            } else {
                f64::INFINITY
            };
            (x0 + d).min(limit)
        };
        let (hi, lo) = (reach(1.0), -reach(-1.0));
        law.hi_m = hi;
        law.lo_m = lo;
        Ok(law)
    }

    /// `U(x)` (J).
    pub fn potential_j(&self, x: f64) -> f64 {
        potential_j(&self.poly, self.upper.as_ref(), self.lower.as_ref(), x)
    }

    /// The unnormalised density `exp(-(U - U_min) / theta)`.
    fn weight(&self, x: f64) -> f64 {
        (-(self.potential_j(x) - self.u_min) / self.theta_j).exp()
    }

    /// The support `[lo, hi]` outside which the density is below e^-60 of its peak (m).
    pub fn support_m(&self) -> (f64, f64) {
        (self.lo_m, self.hi_m)
    }

    /// `int_a^b f(x) w(x) dx` by 5-point Gauss-Legendre on panels that break at the stops'
    /// contact points (where `U` has a kink in a higher derivative).
    fn integrate(&self, a: f64, b: f64, f: &dyn Fn(f64) -> f64) -> f64 {
        if b <= a {
            return 0.0;
        }
        let mut cuts = vec![a, b];
        for s in [self.upper.map(|s| s.gap()), self.lower.map(|s| -s.gap())]
            .into_iter()
            .flatten()
        {
            if s > a && s < b {
                cuts.push(s);
            }
        }
        cuts.sort_by(f64::total_cmp);
        let mut total = 0.0;
        for w in cuts.windows(2) {
            let panels = 400;
            let h = (w[1] - w[0]) / panels as f64;
            for i in 0..panels {
                let mid = w[0] + (i as f64 + 0.5) * h;
                for &(x, wt) in &crate::ode::GAUSS_LEGENDRE_5 {
                    let xx = mid + 0.5 * h * x;
                    total += 0.5 * h * wt * f(xx) * self.weight(xx);
                }
            }
        }
        total
    }

    /// `E[f(x)]` under the stationary density.
    pub fn expect(&self, f: &dyn Fn(f64) -> f64) -> f64 {
        self.integrate(self.lo_m, self.hi_m, f) / self.integrate(self.lo_m, self.hi_m, &|_| 1.0)
    }

    /// The probability of `[a, b]`.
    pub fn probability(&self, a: f64, b: f64) -> f64 {
        let z = self.integrate(self.lo_m, self.hi_m, &|_| 1.0);
        self.integrate(a.max(self.lo_m), b.min(self.hi_m), &|_| 1.0) / z
    }

    /// The density at `x` (1/m).
    pub fn density(&self, x: f64) -> f64 {
        self.weight(x) / self.integrate(self.lo_m, self.hi_m, &|_| 1.0)
    }

    /// `E[v^2] = theta (1 - deficit) / m` (m^2/s^2): white noise's `theta / m` less the band's
    /// deficit.
    pub fn v2_m2_s2(&self) -> f64 {
        self.theta_j * (1.0 - self.band_deficit) / self.mass_kg
    }

    /// The load power `R Phi^2 E[v^2] / (Rc + R)^2` (W).
    pub fn load_power_w(&self) -> f64 {
        self.load_per_v2 * self.v2_m2_s2()
    }

    /// `GOF_BINS` + 1 edges of bins of about equal probability over the support.
    pub fn equal_probability_edges(&self, n: usize) -> Vec<f64> {
        let grid = 4000;
        let h = (self.hi_m - self.lo_m) / grid as f64;
        let mut cum = vec![0.0];
        for i in 0..grid {
            let a = self.lo_m + i as f64 * h;
            cum.push(cum[i] + self.integrate(a, a + h, &|_| 1.0));
        }
        let total = cum[grid];
        let mut edges = vec![self.lo_m];
        let mut next = 1;
        for (i, c) in cum.iter().enumerate().skip(1) {
            if next < n && *c >= total * next as f64 / n as f64 {
                edges.push(self.lo_m + i as f64 * h);
                next += 1;
            }
        }
        edges.push(self.hi_m);
        edges
    }
}

/// Hotelling's T^2 of the records' bin shares against exact probabilities, scaled to
/// Fisher's F: `(F, F_0.99(p, R - p), p, R)`, with `p` the bins less one.
pub fn hotelling(shares: &[Vec<f64>], exact: &[f64]) -> (f64, f64, usize, usize) {
    let r = shares.len();
    let p = exact.len() - 1;
    let mean = DVector::from_fn(p, |i, _| {
        shares.iter().map(|s| s[i]).sum::<f64>() / r as f64
    });
    let mut cov = DMatrix::<f64>::zeros(p, p);
    for s in shares {
        let d = DVector::from_fn(p, |i, _| s[i] - mean[i]);
        cov += &d * d.transpose();
    }
    cov /= (r - 1) as f64;
    let diff = DVector::from_fn(p, |i, _| mean[i] - exact[i]);
    let t2 = match cov.clone().cholesky() {
        Some(ch) => r as f64 * diff.dot(&ch.solve(&diff)),
        None => f64::INFINITY,
    };
    let f = t2 * (r - p) as f64 / (p as f64 * (r - 1) as f64);
    let crit = FisherSnedecor::new(p as f64, (r - p) as f64)
        .map(|d| d.inverse_cdf(0.99))
        .unwrap_or(f64::NAN);
    (f, crit, p, r)
}

/// The half-width of the two-sided 99.9 % Student-t interval of a mean over `n` records with
/// sample standard deviation `std`.
pub(crate) fn ci999(std: f64, n: usize) -> f64 {
    let t = StudentsT::new(0.0, 1.0, (n - 1) as f64)
        .map(|d| d.inverse_cdf(0.9995))
        .unwrap_or(f64::NAN);
    t * std / (n as f64).sqrt()
}

/// The checks of one ensemble against the law (see the module docs).
pub fn checks(
    device: &Device,
    spec: &RecordSpec,
    ensemble: &DisplacementEnsemble,
    bins: &DisplacementBins,
) -> Result<Vec<Check>, ValidationError> {
    let law = StationaryLaw::of(device, spec)?;
    let mut g = Group::new(&format!("exact stationary law: {}", device.name));
    let src = "exp(-U/theta) normalised, theta = m^2 S / (2 c) (Caughey 1971; Lin and Cai 1995)";
    let why = "the ensemble's 99.9 % interval across records (Student's t)";
    let n = ensemble.records.len();
    // Goodness of fit on bins of about equal exact probability, regrouped from the records'
    // fine histogram: each coarse bin is a run of fine bins.
    let coarse = law.equal_probability_edges(GOF_BINS);
    let fine = &ensemble.edges_m;
    let group_of = |x: f64| {
        coarse
            .partition_point(|&e| e <= x)
            .clamp(1, coarse.len() - 1)
            - 1
    };
    let mut groups: Vec<(f64, f64)> = Vec::new();
    let mut assign = Vec::new();
    for i in 0..fine.len() - 1 {
        let gi = group_of(0.5 * (fine[i] + fine[i + 1]));
        if groups.len() <= gi {
            groups.resize(gi + 1, (f64::INFINITY, f64::NEG_INFINITY));
        }
        groups[gi].0 = groups[gi].0.min(fine[i]);
        groups[gi].1 = groups[gi].1.max(fine[i + 1]);
        assign.push(gi);
    }
    let groups: Vec<(f64, f64)> = groups.into_iter().filter(|g| g.0 < g.1).collect();
    let shares: Vec<Vec<f64>> = ensemble
        .shares()
        .iter()
        .map(|s| {
            let mut out = vec![0.0; groups.len()];
            for (i, v) in s.iter().enumerate() {
                out[assign[i].min(groups.len() - 1)] += v;
            }
            out
        })
        .collect();
    let exact: Vec<f64> = groups
        .iter()
        .map(|(a, b)| law.probability(*a, *b))
        .collect();
    let (f, crit, p, r) = hotelling(&shares, &exact);
    g.add(
        "Fisher's F, 99 % quantile",
        &format!(
            "{}: displacement histogram, Hotelling's T^2 as F({p}, {}) over {r} records",
            device.name,
            r - p
        ),
        crit,
        f,
        Measure::NotAbove,
        0.0,
        "the records' bin shares are independent vectors: their covariance holds the \
         within-record correlation",
    );
    // A mean over records against the law: relative for moments and power, absolute for
    // shares of time (which may be near zero).
    let add = |g: &mut Group,
               what: &str,
               theirs: f64,
               measure: Measure,
               f: &dyn Fn(&RecordDisplacement) -> f64| {
        let ci = ensemble.stat(f);
        let tol = ci999(ci.std, n);
        let tol = match measure {
            Measure::Relative => tol / theirs.abs(),
            _ => tol,
        };
        g.add(
            src,
            &format!("{}: {what}", device.name),
            theirs,
            ci.mean,
            measure,
            tol,
            why,
        );
    };
    let rel = |g: &mut Group, what: &str, theirs: f64, f: &dyn Fn(&RecordDisplacement) -> f64| {
        add(g, what, theirs, Measure::Relative, f)
    };
    let abs = |g: &mut Group, what: &str, theirs: f64, f: &dyn Fn(&RecordDisplacement) -> f64| {
        add(g, what, theirs, Measure::Absolute, f)
    };
    rel(&mut g, "E[x^2] (m^2)", law.expect(&|x| x * x), &|r| {
        r.x2_mean_m2
    });
    rel(&mut g, "E[v^2] (m^2/s^2)", law.v2_m2_s2(), &|r| {
        r.v2_mean_m2_s2
    });
    // No load-power row: a coil without inductance carries `Phi v / (Rc + R)` at every
    // instant, so the load takes `R Phi^2 v^2 / (Rc + R)^2` sample by sample and its mean is
    // the E[v^2] row times a constant; a second row would count one check twice.
    if let Some(s) = &device.stops.upper {
        abs(
            &mut g,
            "share of time past the upper stop",
            law.probability(s.gap_m, f64::INFINITY),
            &|r| r.upper_contact_share,
        );
    }
    if let Some(s) = &device.stops.lower {
        abs(
            &mut g,
            "share of time past the lower stop",
            law.probability(f64::NEG_INFINITY, -s.gap_m),
            &|r| r.lower_contact_share,
        );
    }
    if let Some((_, barrier)) = bins.wells {
        abs(
            &mut g,
            "share of time in the upper well",
            law.probability(barrier, f64::INFINITY),
            &|r| r.upper_well_share,
        );
    }
    Ok(g.into_checks())
}
