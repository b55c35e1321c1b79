//! Figure 12: prototype 1 at 30 V under high-level random vibration (claim F12).

/// Figure 12's levels (g²/Hz).
pub const FIG12_LEVELS: [f64; 3] = [7.4e-3, 1.31e-2, 2.85e-2];

/// Records per level in Figure 12 (as Figure 11; the contact statistics need a few more).
pub const FIG12_REALISATIONS: usize = 8;
