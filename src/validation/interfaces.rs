//! The interface circuits against their closed forms ([`crate::physics::interface_closed_forms`]):
//! the standard bridge (Shu and Lien, Smart Mater. Struct. 15 (2006) 1499), parallel SSHI
//! (Guyomar et al., IEEE Trans. Ultrason. Ferroelectr. Freq. Control 52 (2005) 584), series SSHI
//! and SECE (Lefeuvre et al., Sens. Actuators A 126 (2006) 405), on a weakly coupled linear
//! piezoelectric harvester without stops (`data/validation/piezo_bridge.toml`), each closed form
//! fed with the simulated displacement's fundamental amplitude; the difference as the coupling
//! shrinks; and the standard bridge with strong coupling against the first-harmonic balance.

use std::f64::consts::PI;

use crate::device::{Device, Interface, Inversion, Rectifier, Transducer};
use crate::drive::Sine;
use crate::physics::interface_closed_forms::{standard_coupled, Element};
use crate::study::periodic::{steady_state_from_rest, PeriodicState as IfSteady, SteadySettings};
use crate::validation::{Check, Group, Measure, ValidationError};

/// The sine of the checks (g rms), at the suspension's resonance.
pub const ACCEL_RMS_G: f64 = 0.1;
/// The switches' quality factor (gamma = exp(-pi / 6) = 0.59).
pub const QUALITY_FACTOR: f64 = 3.0;
/// The coupling factors (times the file's theta) of the shrinking and strong-coupling rows.
pub const COUPLING_FACTORS: [f64; 4] = [30.0, 10.0, 3.16, 1.0];

const WEAK_REASON: &str = "the closed form holds the storage voltage constant: its ripple, \
    about T / (2 R Cs), is below 7e-4 of it at these loads; the displacement's distortion adds \
    less (see the coupling rows)";

fn err(e: impl std::fmt::Display) -> ValidationError {
    ValidationError::Device(e.to_string())
}

/// The element, drive and settings of a device's checks.
struct Case {
    device: Device,
    rect: Rectifier,
    element: Element,
    sine: Sine,
    settings: SteadySettings,
}

impl Case {
    fn of(device: &Device) -> Result<Self, ValidationError> {
        let (Transducer::Piezoelectric(p), Interface::FullBridge(rect)) =
            (&device.transducer, &device.interface)
        else {
            return Err(err(
                "the interface checks take a piezoelectric device with a full bridge",
            ));
        };
        if device.stops.present().next().is_some() {
            return Err(err("the interface checks take a device without stops"));
        }
        let f = device.suspension_omega_rad_s() / (2.0 * PI);
        let vf = match rect.diode {
            crate::device::Diode::PiecewiseLinear { forward_drop_v, .. } => forward_drop_v,
            _ => return Err(err("the interface checks take piecewise-linear diodes")),
        };
        Ok(Self {
            device: device.clone(),
            rect: rect.clone(),
            element: Element {
                theta: p.coupling_n_per_v,
                cp: p.capacitance_f,
                w: 2.0 * PI * f,
                vf,
            },
            sine: Sine::from_rms_g(ACCEL_RMS_G, f),
            settings: SteadySettings::default(),
        })
    }

    fn run(&self, interface: Interface) -> Result<IfSteady, ValidationError> {
        let mut d = self.device.clone();
        d.interface = interface;
        steady_state_from_rest(&d, self.sine, &self.settings).map_err(err)
    }
}

/// The closed-form checks in the weakly coupled limit: the standard bridge at three loads and
/// with a forward drop, its largest power; parallel and series SSHI at their optimal loads and
/// parallel SSHI's gain; SECE at two loads.
pub fn weak_coupling_checks(device: &Device) -> Result<Vec<Check>, ValidationError> {
    let c = Case::of(device)?;
    let e = c.element;
    let mut g = Group::new("interface circuits, weak coupling");
    let std_ref = "Shu and Lien 2006, standard interface: V = R theta w u_M / (R Cp w + pi/2)";
    let ropt = e.standard_optimal_load();
    let bridge = |r: f64| Interface::FullBridge(c.rect.clone()).with_load_resistance(r);
    let mut p_std_max = 0.0;
    for k in [0.3, 1.0, 3.0] {
        let s = c.run(bridge(k * ropt))?;
        g.add(
            std_ref,
            &format!("V_DC (V) at R = {k} x pi/(2 w Cp)"),
            e.standard_vdc(s.x1_m, k * ropt),
            s.vdc_v,
            Measure::Relative,
            1e-3,
            WEAK_REASON,
        );
        if k == 1.0 {
            g.add(
                "Shu and Lien 2006: P_max = theta^2 w u_M^2 / (2 pi Cp)",
                "P_DC (W) at the optimal load",
                e.standard_max_power(s.x1_m),
                s.p_dc_w,
                Measure::Relative,
                2e-3,
                WEAK_REASON,
            );
            p_std_max = s.p_dc_w / (s.x1_m * s.x1_m);
        }
    }
    // A forward drop of a tenth of the optimum's voltage.
    let vf = 0.1 * e.theta * c.run(bridge(ropt))?.x1_m / (2.0 * e.cp);
    let mut rect = c.rect.clone();
    rect.diode = crate::device::Diode::PiecewiseLinear {
        forward_drop_v: vf,
        on_resistance_ohm: 0.0,
    };
    let s = c.run(Interface::FullBridge(rect).with_load_resistance(ropt))?;
    g.add(
        "Shu and Lien 2006 with the drops in the charge balance: Cp V -> Cp (V + 2 V_F)",
        &format!("V_DC (V) at the optimal load, V_F = {vf:.4} V"),
        Element { vf, ..e }.standard_vdc(s.x1_m, ropt),
        s.vdc_v,
        Measure::Relative,
        1e-3,
        WEAK_REASON,
    );
    let inv = Inversion::QualityFactor(QUALITY_FACTOR);
    // A quality factor always gives a factor; a NaN would fail every row that uses it.
    let gamma = inv.gamma().unwrap_or(f64::NAN);
    let r_par = e.parallel_sshi_optimal_load(gamma);
    let s = c.run(Interface::ParallelSshi(c.rect.clone(), inv).with_load_resistance(r_par))?;
    let par_ref =
        "Guyomar et al. 2005, parallel SSHI: V = 2 R theta w u_M / (pi + R Cp w (1 - gamma))";
    g.add(
        par_ref,
        &format!("V_DC (V) at R = pi / (w Cp (1 - gamma)), gamma = {gamma:.4}"),
        e.parallel_sshi_vdc(s.x1_m, r_par, gamma),
        s.vdc_v,
        Measure::Relative,
        1e-3,
        WEAK_REASON,
    );
    g.add(
        "Guyomar et al. 2005: gain 2 / (1 - gamma) over the standard maximum",
        "P_DC / u_M^2 of parallel SSHI over that of the standard bridge, both at their optima",
        2.0 / (1.0 - gamma),
        s.p_dc_w / (s.x1_m * s.x1_m) / p_std_max,
        Measure::Relative,
        3e-3,
        WEAK_REASON,
    );
    let r_ser = e.series_sshi_optimal_load(gamma);
    let s = c.run(Interface::SeriesSshi(c.rect.clone(), inv).with_load_resistance(r_ser))?;
    g.add(
        "Lefeuvre et al. 2006, series SSHI: V = 2 R w (1 + gamma) theta u_M / (pi (1 - gamma) + 2 R Cp w (1 + gamma))",
        &format!("V_DC (V) at R = pi (1 - gamma) / (2 w Cp (1 + gamma)), gamma = {gamma:.4}"),
        e.series_sshi_vdc(s.x1_m, r_ser, gamma),
        s.vdc_v,
        Measure::Relative,
        1e-3,
        "as above, and the transfer charges the series capacitance Cp Cs / (Cp + Cs), 1e-4 \
         below the closed form's Cp",
    );
    for k in [1.0, 4.0] {
        let s = c.run(
            Interface::Sece {
                storage_capacitance_f: c.rect.storage_capacitance_f,
                load: c.rect.load.clone(),
                efficiency: 1.0,
            }
            .with_load_resistance(k * ropt),
        )?;
        g.add(
            "Lefeuvre et al. 2006, SECE: P = 2 theta^2 w u_M^2 / (pi Cp), any load",
            &format!("P_DC (W) at R = {k} x pi/(2 w Cp), efficiency 1"),
            e.sece_power(s.x1_m, 1.0),
            s.p_dc_w,
            Measure::Relative,
            2e-3,
            WEAK_REASON,
        );
    }
    Ok(g.into_checks())
}

/// One coupling's standard bridge at the optimal load: the steady state and the closed forms.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct CouplingRow {
    /// The coupling factor k^2 = theta^2 / (km Cp).
    pub k2: f64,
    /// Simulated DC power (W).
    pub p_dc_w: f64,
    /// The uncoupled closed form's power at the simulated fundamental amplitude (W).
    pub p_closed_w: f64,
    /// The same closed form at the simulated excursion, the largest `|x|` (W): the bridge
    /// charges on the excursion, the closed form on the amplitude it is given.
    pub p_closed_excursion_w: f64,
    /// The first-harmonic balance's power (W).
    pub p_coupled_w: f64,
    /// The displacement's distortion.
    pub x_distortion: f64,
    /// The displacement's fundamental amplitude (m).
    pub x1_m: f64,
    /// The displacement's largest `|x|` (m).
    pub x_peak_m: f64,
    /// The storage ripple the closed form neglects, `2 Cp / Cs` of V at the optimum.
    pub ripple_rel: f64,
}

/// The standard bridge at the optimal load for each of [`COUPLING_FACTORS`], with the storage
/// ten times larger than the file's so that its ripple stays below the distortion.
pub fn coupling_rows(device: &Device) -> Result<Vec<CouplingRow>, ValidationError> {
    let c = Case::of(device)?;
    let m = &device.mechanics;
    let mut rows = Vec::new();
    for k in COUPLING_FACTORS {
        let theta = k * c.element.theta;
        let d = device
            .with_param("transducer.coupling_n_per_v", theta)
            .and_then(|d| {
                d.with_param(
                    "interface.storage_capacitance_f",
                    10.0 * c.rect.storage_capacitance_f,
                )
            })
            .map_err(err)?;
        let e = Element { theta, ..c.element };
        let r = e.standard_optimal_load();
        let mut dd = d.clone();
        dd.interface = d.interface.with_load_resistance(r);
        let s = steady_state_from_rest(&dd, c.sine, &c.settings).map_err(err)?;
        let (_, v) = standard_coupled(
            &e,
            m.mass_kg,
            m.stiffness_n_per_m,
            m.damping_n_s_per_m,
            c.sine.amplitude_m_s2,
            r,
        );
        rows.push(CouplingRow {
            k2: theta * theta / (m.stiffness_n_per_m * e.cp),
            p_dc_w: s.p_dc_w,
            p_closed_w: e.standard_vdc(s.x1_m, r).powi(2) / r,
            p_closed_excursion_w: e.standard_vdc(s.x_peak_m, r).powi(2) / r,
            p_coupled_w: v * v / r,
            x_distortion: s.x_distortion,
            x1_m: s.x1_m,
            x_peak_m: s.x_peak_m,
            ripple_rel: 2.0 * e.cp / (10.0 * c.rect.storage_capacitance_f),
        });
    }
    Ok(rows)
}

/// The relative floor below which the closed forms' residuals are not resolved: the storage
/// ripple the closed forms neglect (`2 Cp / Cs`, [`CouplingRow::ripple_rel`]) plus ten times
/// the steady state's convergence tolerance (its section state's scaled residual, which moves
/// the period's power by about as much).
fn floor(r: &CouplingRow) -> f64 {
    r.ripple_rel + 10.0 * SteadySettings::default().tol
}

/// How far the closed form moves when it is given the excursion instead of the fundamental
/// (relative): the part of its residual the displacement's distortion makes.
fn excursion_term(r: &CouplingRow) -> f64 {
    (r.p_closed_excursion_w / r.p_closed_w - 1.0).abs()
}

/// The coupling checks (each bound derived from what the closed form leaves out, not from the
/// rows):
///
/// - **the uncoupled closed form at the simulated excursion**: over each half period the bridge
///   passes the charge `theta (x_max - x_min) - 2 Cp V` (the element's voltage swings from `-V`
///   to `V` first), so it charges on the displacement's excursion, which the closed form takes
///   to be the fundamental `u_M`. Given the simulated excursion (the largest `|x|`, the same on
///   both sides without stops), it leaves out only the storage ripple and the steady state's
///   convergence (`floor`);
/// - **the uncoupled closed form's residual at `u_M` shrinks with the coupling**: that residual
///   is the closed form's change from the excursion to `u_M` (`excursion_term`), which the
///   coupling makes through the displacement's distortion; for each pair of
///   neighbouring couplings whose stronger one's residual stands at least ten times above the
///   floor (below it the residual is the floor's, and a shrinking cannot be seen), the weaker
///   coupling's residual is not above the stronger one's;
/// - **the first-harmonic balance**: it computes the fundamental from the drive with the
///   bridge's fundamental force and charges the storage on it: besides the excursion term, its
///   fundamental is off by the change of the bridge force's fundamental with the displacement's
///   shape, at most the distortion `d` of a force at most the drive's at these loads, and the
///   power by twice that: the excursion term, `2 d` and the floor.
pub fn coupling_checks(rows: &[CouplingRow]) -> Vec<Check> {
    let mut g = Group::new("interface circuits, coupling");
    // Strongest coupling first, whatever the order given: the shrinking is judged between
    // neighbours in the coupling.
    let mut rows = rows.to_vec();
    rows.sort_by(|a, b| b.k2.total_cmp(&a.k2));
    let rows = &rows[..];
    let rel = |r: &CouplingRow| (r.p_dc_w - r.p_closed_w).abs() / r.p_closed_w;
    for r in rows {
        g.add(
            "Shu and Lien 2006 standard interface, at the simulated excursion",
            &format!(
                "P_DC (W) at resonance and the optimal load, k^2 = {:.2e} (excursion {:.3e} of \
                 u_M beyond it)",
                r.k2,
                r.x_peak_m / r.x1_m - 1.0
            ),
            r.p_closed_excursion_w,
            r.p_dc_w,
            Measure::Relative,
            floor(r),
            "the bridge charges on the excursion: given it, the closed form leaves out the \
             storage ripple 2 Cp / Cs and the steady state's convergence",
        );
    }
    for w in rows.windows(2) {
        if rel(&w[0]) < 10.0 * floor(&w[0]) {
            continue;
        }
        g.add(
            "Shu and Lien 2006 standard interface, at the simulated u_M",
            &format!(
                "|P - P_closed(u_M)| / P_closed at k^2 = {:.2e}, not above that at k^2 = {:.2e}",
                w[1].k2, w[0].k2
            ),
            rel(&w[0]),
            rel(&w[1]),
            Measure::NotAbove,
            0.0,
            "the residual is the closed form's change from the excursion to u_M, which the \
             coupling makes; judged only where the stronger coupling's residual stands ten \
             times above the floor",
        );
    }
    for r in rows {
        g.add(
            "first-harmonic balance of the standard bridge (after Shu and Lien 2006)",
            &format!(
                "P_DC (W) at resonance and the optimal load, k^2 = {:.2e} (distortion {:.2e})",
                r.k2, r.x_distortion
            ),
            r.p_coupled_w,
            r.p_dc_w,
            Measure::Relative,
            excursion_term(r) + 2.0 * r.x_distortion + floor(r),
            "the balance keeps the fundamental: the excursion term, 2 d from the bridge force's \
             change with the displacement's shape (distortion d), and the floor",
        );
    }
    g.into_checks()
}
