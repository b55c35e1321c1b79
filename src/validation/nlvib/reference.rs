//! NLvib's stored numbers (`data/references/nlvib/`): the harmonic-balance branches and folds,
//! the exact shooting's orbits and fold, and the AFT sampling check, parsed from the text the
//! caller gives.

use serde::Deserialize;

use super::HARMONICS;
use crate::validation::ValidationError;

/// One point of a harmonic-balance branch (`nlvib_hb_HNN.csv`; the other columns are not read).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
pub struct HbPoint {
    /// Index along the branch.
    pub point: usize,
    /// Omega (rad/s).
    pub omega_rad_s: f64,
    /// First-harmonic amplitude sqrt(Qc1^2 + Qs1^2) (m).
    pub a1_amplitude_m: f64,
}

/// A turning point of a harmonic-balance branch (`nlvib_folds.csv`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct HbFold {
    /// H.
    #[serde(rename = "harmonics_H")]
    pub harmonics: usize,
    /// `fold_max_omega` or `fold_min_omega`.
    pub kind: String,
    /// Omega at the turning point (rad/s).
    pub omega_rad_s: f64,
    /// Index of the branch point nearest the turning point.
    pub point: usize,
}

/// One orbit of the exact shooting (`shooting_branch.csv`).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
pub struct ExactPoint {
    /// 0: from Omega = 0.5 over the fold and down the overhang; 1: the non-impacting orbits
    /// from Omega = 2.5 down.
    pub segment: u32,
    /// Omega (rad/s).
    pub omega_rad_s: f64,
    /// q(0) (m) at the cosine's phase zero.
    pub x0_m: f64,
    /// q'(0) (m/s).
    pub v0_m_s: f64,
    /// First-harmonic amplitude (m).
    pub a1_amplitude_m: f64,
    /// Impacts per period.
    pub impacts_per_period: u32,
    /// Largest multiplier modulus (central differences of the period map).
    pub max_floquet_modulus: f64,
    /// Largest multiplier modulus (variational equations).
    pub max_floquet_modulus_variational: f64,
    /// Largest modulus below one.
    pub stable: bool,
}

/// The exact fold and the grazing points (`shooting_folds.csv`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct ExactFold {
    /// `fold_max_omega` or `grazing`.
    pub kind: String,
    /// How it was solved.
    pub method: String,
    /// Omega (rad/s).
    pub omega_rad_s: f64,
    /// First-harmonic amplitude (m).
    pub a1_amplitude_m: f64,
}

/// NLvib's H = 40 amplitudes re-solved with four times finer AFT sampling
/// (`nlvib_aft_check_H40.csv`).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
pub struct AftCheck {
    /// Omega (rad/s).
    pub omega_rad_s: f64,
    /// As stored (4096 samples per period).
    pub a1_amplitude_m: f64,
    /// With 16384 samples.
    pub a1_amplitude_m_fine: f64,
}

/// Every reference table of the problem.
#[derive(Debug, Clone, PartialEq)]
pub struct Reference {
    /// Each harmonic-balance branch with its H, in [`HARMONICS`] order.
    pub hb: Vec<(usize, Vec<HbPoint>)>,
    /// The turning points of the harmonic-balance branches.
    pub hb_folds: Vec<HbFold>,
    /// The exact shooting's orbits.
    pub exact: Vec<ExactPoint>,
    /// The exact fold and grazing points.
    pub exact_folds: Vec<ExactFold>,
    /// The AFT sampling check.
    pub aft: Vec<AftCheck>,
    /// The turning points of the fine-step H = 5 branch (`fine_H05/nlvib_folds.csv`).
    pub fine_h05_folds: Vec<HbFold>,
}

fn parse<T: for<'de> Deserialize<'de>>(file: &str, text: &str) -> Result<Vec<T>, ValidationError> {
    csv::Reader::from_reader(text.as_bytes())
        .deserialize()
        .collect::<Result<Vec<T>, _>>()
        .map_err(|e| ValidationError::Reference {
            file: file.to_string(),
            message: e.to_string(),
        })
}

impl Reference {
    /// The file names of the reference, relative to its directory.
    pub fn files() -> Vec<String> {
        let mut f: Vec<String> = HARMONICS
            .iter()
            .map(|h| format!("nlvib_hb_H{h:02}.csv"))
            .collect();
        f.extend(
            [
                "nlvib_folds.csv",
                "shooting_branch.csv",
                "shooting_folds.csv",
                "nlvib_aft_check_H40.csv",
                "fine_H05/nlvib_folds.csv",
            ]
            .map(String::from),
        );
        f
    }

    /// Parses the reference from the text of its files, which `read(name)` returns for each
    /// name of [`Reference::files`] (reading them is the caller's job).
    pub fn parse(
        mut read: impl FnMut(&str) -> Result<String, ValidationError>,
    ) -> Result<Self, ValidationError> {
        let mut hb = Vec::new();
        for h in HARMONICS {
            let name = format!("nlvib_hb_H{h:02}.csv");
            hb.push((h, parse(&name, &read(&name)?)?));
        }
        let mut table = |name: &str| read(name).map(|t| (name.to_string(), t));
        let (n, t) = table("nlvib_folds.csv")?;
        let hb_folds = parse(&n, &t)?;
        let (n, t) = table("shooting_branch.csv")?;
        let exact = parse(&n, &t)?;
        let (n, t) = table("shooting_folds.csv")?;
        let exact_folds = parse(&n, &t)?;
        let (n, t) = table("nlvib_aft_check_H40.csv")?;
        let aft = parse(&n, &t)?;
        let (n, t) = table("fine_H05/nlvib_folds.csv")?;
        let fine_h05_folds = parse(&n, &t)?;
        Ok(Self {
            hb,
            hb_folds,
            exact,
            exact_folds,
            aft,
            fine_h05_folds,
        })
    }

    /// The exact fold's frequency (rad/s).
    pub fn exact_fold_rad_s(&self) -> Result<f64, ValidationError> {
        self.exact_folds
            .iter()
            .find(|f| f.kind == "fold_max_omega")
            .map(|f| f.omega_rad_s)
            .ok_or_else(|| missing("shooting_folds.csv", "no fold_max_omega row"))
    }

    /// The fold of the harmonic-balance branch of H harmonics: its turning point of largest
    /// frequency (rad/s), and the index of the branch point nearest it.
    pub fn hb_fold(&self, harmonics: usize) -> Result<(f64, usize), ValidationError> {
        self.hb_folds
            .iter()
            .filter(|f| f.harmonics == harmonics && f.kind == "fold_max_omega")
            .max_by(|a, b| a.omega_rad_s.total_cmp(&b.omega_rad_s))
            .map(|f| (f.omega_rad_s, f.point))
            .ok_or_else(|| missing("nlvib_folds.csv", &format!("no fold for H = {harmonics}")))
    }

    /// The lower turning point of the harmonic-balance branch of H harmonics (where the
    /// overhang ends): the index of its branch point.
    pub(super) fn hb_lower_turn(&self, harmonics: usize) -> Result<usize, ValidationError> {
        self.hb_folds
            .iter()
            .filter(|f| f.harmonics == harmonics && f.kind == "fold_min_omega")
            .min_by(|a, b| a.omega_rad_s.total_cmp(&b.omega_rad_s))
            .map(|f| f.point)
            .ok_or_else(|| {
                missing(
                    "nlvib_folds.csv",
                    &format!("no lower turning point for H = {harmonics}"),
                )
            })
    }

    /// The AFT sampling floor: the largest change of a stored H = 40 amplitude with four
    /// times finer sampling (m); NaN without a stored point (a floor of nothing would pass
    /// as zero).
    pub fn aft_floor_m(&self) -> f64 {
        self.aft
            .iter()
            .map(|a| (a.a1_amplitude_m - a.a1_amplitude_m_fine).abs())
            .reduce(f64::max)
            .unwrap_or(f64::NAN)
    }
}

impl Reference {
    /// The floor of a harmonic-balance fold frequency set by the sampled contact force: the
    /// deepest micro turning point (a turning point of largest frequency and the next one of
    /// smallest) of the fine-step H = 5 branch below its fold (rad/s); NaN without one. The
    /// branch of the sampled force is piecewise smooth and zigzags in frequency at that scale
    /// for every H.
    pub fn fold_floor_rad_s(&self) -> f64 {
        let mut turns: Vec<&HbFold> = self.fine_h05_folds.iter().collect();
        turns.sort_by_key(|f| f.point);
        let top = turns
            .iter()
            .filter(|f| f.kind == "fold_max_omega")
            .map(|f| f.omega_rad_s)
            .fold(f64::NEG_INFINITY, f64::max);
        turns
            .windows(2)
            .filter(|w| w[0].kind == "fold_max_omega" && w[1].kind == "fold_min_omega")
            // Near the fold only (the lower turning point ends the overhang far below).
            .filter(|w| top - w[1].omega_rad_s < 0.01)
            .map(|w| w[0].omega_rad_s - w[1].omega_rad_s)
            .reduce(f64::max)
            .unwrap_or(f64::NAN)
    }
}

pub(super) fn missing(file: &str, message: &str) -> ValidationError {
    ValidationError::Reference {
        file: file.to_string(),
        message: message.to_string(),
    }
}
