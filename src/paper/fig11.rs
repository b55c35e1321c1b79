//! Figure 11: prototype 1 at 30 V under low-level random vibration (claim F11).

/// Figure 11's levels (g²/Hz).
pub const FIG11_LEVELS: [f64; 3] = [4.42e-6, 1.12e-4, 3.49e-4];

/// Records per level in Figure 11 (prototype 1 is broad-band, Qm = 5.7: a 10 s record spans
/// thousands of correlation times, so a few records give width CIs of a few per cent).
pub const FIG11_REALISATIONS: usize = 6;
