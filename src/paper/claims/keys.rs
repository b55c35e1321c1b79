//! The key of every number the paper claims, said once: the figures build their values from
//! these constants, the experiments and tests look claims up by them, and a test checks that
//! they are exactly the claims of `data/claims.toml`, in its order. A renamed quantity is then
//! one edit here and one in the file, and a key that matches no claim cannot be written.

use std::fmt;

/// One number of a claim: the claim's id and the quantity's key, as in `data/claims.toml`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ClaimKey {
    /// Claim id, e.g. `F8-c`.
    pub id: &'static str,
    /// Quantity key within the claim, e.g. `jump_hertz_bim1p5_hz`.
    pub quantity: &'static str,
}

impl fmt::Display for ClaimKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "({}, {})", self.id, self.quantity)
    }
}

macro_rules! claim_keys {
    ($($(#[$doc:meta])* $name:ident = ($id:literal, $quantity:literal);)*) => {
        $(
            $(#[$doc])*
            pub const $name: ClaimKey = ClaimKey { id: $id, quantity: $quantity };
        )*
        /// Every key, in the order of `data/claims.toml`.
        pub const ALL: &[ClaimKey] = &[$($name),*];
    };
}

claim_keys! {
    /// Figure 5: delta0 = t²/R of prototype 1 (um).
    F5A_DELTA0_P1 = ("F5-a", "delta0_p1_um");
    /// Figure 5: delta0 = t²/R of prototype 2 (um).
    F5A_DELTA0_P2 = ("F5-a", "delta0_p2_um");
    /// Eq 19's coefficient of the linear end-stop stiffness.
    F5B_EQ19_COEFFICIENT = ("F5-b", "eq19_coefficient");
    /// Table 3: k^2 of prototype 1 (%).
    T3A_K2_P1 = ("T3-a", "k2_pct_p1");
    /// Table 3: Qm of prototype 1.
    T3A_QM_P1 = ("T3-a", "qm_p1");
    /// Table 3: k^2 Qm of prototype 1.
    T3A_K2QM_P1 = ("T3-a", "k2qm_p1");
    /// Table 3: k^2 of prototype 2 (%).
    T3B_K2_P2 = ("T3-b", "k2_pct_p2");
    /// Table 3: Qm of prototype 2.
    T3B_QM_P2 = ("T3-b", "qm_p2");
    /// Table 3: k^2 Qm of prototype 2.
    T3B_K2QM_P2 = ("T3-b", "k2qm_p2");
    /// Figure 8: no impact at 4.1 g (yes/no).
    F8A_NO_IMPACT = ("F8-a", "no_impact_4p1g");
    /// Figure 8: the impact onset at 5.5 g (Hz).
    F8B_ONSET = ("F8-b", "impact_onset_5p5g_hz");
    /// Figure 8: the jump with Hertz contact, b_im = 1.5 N s/m (Hz).
    F8C_JUMP_HERTZ_BIM1P5 = ("F8-c", "jump_hertz_bim1p5_hz");
    /// Figure 8: the jump with Hertz contact, no end-stop damping (Hz).
    F8D_JUMP_HERTZ_BIM0 = ("F8-d", "jump_hertz_bim0_hz");
    /// Figure 8: the jump with Hertz contact, b_im = 10 N s/m (Hz).
    F8E_JUMP_HERTZ_BIM10 = ("F8-e", "jump_hertz_bim10_hz");
    /// Figure 8: the jumps fall as b_im grows (yes/no).
    F8E_JUMP_ORDER = ("F8-e", "jump_order_by_bim");
    /// Figure 8: the jump with the linear law of eq 19, b_im = 2 N s/m (Hz).
    F8F_JUMP_LINEAR_BIM2 = ("F8-f", "jump_linear_bim2_hz");
    /// Figure 9: the impact onset at 20 V (g).
    F9A_ONSET_20V = ("F9-a", "onset_g_20v");
    /// Figure 9: the impact onset at 30 V (g).
    F9A_ONSET_30V = ("F9-a", "onset_g_30v");
    /// Figure 9: the impact onset at 40 V (g).
    F9A_ONSET_40V = ("F9-a", "onset_g_40v");
    /// Figure 9: the onsets are the same for every bias (yes/no).
    F9A_ONSET_SAME = ("F9-a", "onset_same_all_vb");
    /// Figure 9: the saturated power at 20 V (nW).
    F9B_P_SAT_20V = ("F9-b", "p_sat_20v_nw");
    /// Figure 9: the saturated power at 40 V (nW).
    F9B_P_SAT_40V = ("F9-b", "p_sat_40v_nw");
    /// Figure 9: the saturated power at 40 V over that at 20 V.
    F9B_P_SAT_RATIO = ("F9-b", "p_sat_ratio_40v_20v");
    /// Figure 10: the level of the generated excitation (g²/Hz).
    F10_LEVEL = ("F10", "excitation_psd_g2_per_hz");
    /// Figure 10: the band of the generated excitation (Hz).
    F10_BAND = ("F10", "excitation_band_hz");
    /// Figure 11: the 3 dB width at 3.49e-4 over that at 4.42e-6 g²/Hz.
    F11_BW_RATIO = ("F11", "bw_ratio_3p49e-4_over_4p42e-6");
    /// Figure 11: no impact at any level (yes/no).
    F11_NO_IMPACT = ("F11", "linear_regime_no_impact");
    /// Figure 12: the 3 dB width at 7.4e-3 g²/Hz (Hz).
    F12_BW_LOW = ("F12", "bw_7p4e-3_hz");
    /// Figure 12: the 3 dB width at 2.85e-2 g²/Hz (Hz).
    F12_BW_HIGH = ("F12", "bw_2p85e-2_hz");
    /// Figure 12: the 3 dB width at 2.85e-2 over that at 7.4e-3 g²/Hz.
    F12_BW_RATIO = ("F12", "bw_ratio_2p85e-2_over_7p4e-3");
    /// Figure 13: no impact at 0.12 g (yes/no).
    F13_NO_IMPACT = ("F13", "no_impact_0p12g");
    /// Figure 13: impacts and a jump at 0.31 g (yes/no).
    F13_JUMP = ("F13", "jump_0p31g");
    /// Figure 13: the Hertz and linear laws agree (yes/no).
    F13_HERTZ_LINEAR_AGREE = ("F13", "hertz_linear_agree");
    /// Figure 14: eq 21's efficiency of prototype 2 (%).
    F14A_EFF_EQ21 = ("F14-a", "eff_eq21_pct");
    /// Figure 14: the simulated efficiency in the linear regime (%).
    F14A_EFF_SIM_LINEAR = ("F14-a", "eff_sim_linear_pct");
    /// Figure 14: the efficiency at 1.69e-3 g²/Hz (%).
    F14B_EFF = ("F14-b", "eff_1p69e-3_pct");
    /// Figure 14: the power grows sublinearly with impacts (yes/no).
    F14B_SUBLINEAR = ("F14-b", "sublinear_power_growth");
    /// Figure 15: the peak of the output PSD at 0.34e-3 g²/Hz (Hz).
    F15A_PEAK = ("F15-a", "peak_0p34e-3_hz");
    /// Figure 15: the 3 dB width at 0.34e-3 g²/Hz (Hz).
    F15A_BW = ("F15-a", "bw_0p34e-3_hz");
    /// Figure 15: the 3 dB width at 0.55e-3 over that at 0.34e-3 g²/Hz.
    F15B_BW_RATIO = ("F15-b", "bw_ratio_0p55e-3_over_0p34e-3");
    /// Figure 15: the response widens towards higher frequencies at 1.69e-3 g²/Hz (yes/no).
    F15C_WIDENING_UP = ("F15-c", "widening_up_1p69e-3");
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::paper::claims::Claims;

    #[test]
    fn the_keys_are_the_claims_file_in_its_order() {
        let c = Claims::bundled().expect("data/claims.toml parses");
        let file: Vec<(&str, &str)> = c
            .claims
            .iter()
            .map(|c| (c.id.as_str(), c.quantity.as_str()))
            .collect();
        let keys: Vec<(&str, &str)> = ALL.iter().map(|k| (k.id, k.quantity)).collect();
        assert_eq!(keys, file);
    }
}
