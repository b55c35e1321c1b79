//! How prototype 1's 3 dB width depends on the Welch segment length, and the bias of the
//! width estimator measured where the true width is known.
//!
//! Prototype 1's response is broad (a linear half-power width of about 220 Hz), and its
//! spectra are read with segments of [`P1_NPERSEG`](crate::paper::ensembles::P1_NPERSEG) samples (24.4 Hz bins). The width of a
//! Welch estimate is biased by the window (a periodic Hann of `nperseg` samples smooths the
//! spectrum over about two bins, which widens the peak) and by reading the half-power
//! crossings between bins. This study runs the same records (Figure 11's lowest level, where
//! the mass never reaches a stop and the model is linear to a few parts in a million, and
//! Figure 12's lowest level, 7.4e-3 g²/Hz) and reads the width of the ensemble-mean PSD at
//! every segment length of [`NPERSEGS`]. At the linear level the exact width is the half-power
//! width of the linearised output PSD ([`linear_widths`]), so `width - exact` is the
//! estimator's bias, measured; at 7.4e-3 the same bias applies, and what remains is the
//! end-stop's widening.

use rayon::prelude::*;

use crate::device::Device;
use crate::num::stats::Jackknife;
use crate::paper::ensembles::P1_BAND_HZ;
use crate::paper::figures::{fig11, fig12};
use crate::paper::setups::{paper_record, prototype1_setup};
use crate::physics::linear::linear_widths;
use crate::progress::Progress;
use crate::signal::bandwidth::mean_psd;
use crate::signal::{self, Psd, WelchOptions};
use crate::study::ensemble::{first_stream_for_level, DEFAULT_SEED};
use crate::study::record::{output_psd, simulate_record, RecordError};

/// Segment lengths of the study (samples; 2^10 to 2^15, bins of 97.7 Hz down to 3.05 Hz).
pub const NPERSEGS: [usize; 6] = [1 << 10, 1 << 11, 1 << 12, 1 << 13, 1 << 14, 1 << 15];

/// The levels of the study (g²/Hz): Figure 11's lowest (linear) and Figure 12's lowest.
pub const LEVELS: [f64; 2] = [
    fig11::FIG11_LEVELS[fig11::LOW],
    fig12::FIG12_LEVELS[fig12::LOW],
];

/// Records per level: as many as the figures' ensembles (their first records).
pub const RECORDS: usize = fig11::FIG11_REALISATIONS;

/// Index in [`LEVELS`] of the linear level.
pub const LINEAR: usize = 0;

/// Index in [`NPERSEGS`] of the figures' segment length [`P1_NPERSEG`](crate::paper::ensembles::P1_NPERSEG).
pub const FIGURES_NPERSEG: usize = 2;

/// The width at one level and segment length.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Row {
    /// Index in [`LEVELS`].
    pub level: usize,
    /// Index in [`NPERSEGS`].
    pub nperseg: usize,
    /// Bin spacing (Hz).
    pub bin_hz: f64,
    /// Half-power width of the ensemble-mean PSD, with its jackknife interval over records (Hz).
    pub width: Jackknife,
}

/// The study: the exact linear width and a row per level and segment length.
#[derive(Debug, Clone, PartialEq)]
pub struct Study {
    /// Half-power width of the linearised output PSD (Hz).
    pub exact_hz: f64,
    /// Records per level.
    pub records: usize,
    /// Rows, level-major, in the order of [`LEVELS`] and [`NPERSEGS`].
    pub rows: Vec<Row>,
}

impl Study {
    /// The row of a level and segment length (indices into [`LEVELS`] and [`NPERSEGS`]).
    pub fn row(&self, level: usize, nperseg: usize) -> &Row {
        &self.rows[level * NPERSEGS.len() + nperseg]
    }

    /// The estimator's bias at a segment length: the width at the linear level less the
    /// exact width (Hz).
    pub fn bias_hz(&self, nperseg: usize) -> f64 {
        self.row(LINEAR, nperseg).width.estimate - self.exact_hz
    }
}

/// Runs the study on the published prototype 1 ([`prototype1_setup`] is applied here) with
/// the first `records` records of Figures 11 and 12 (the same seed and streams), calling
/// `progress` after each record.
pub fn run(
    published: &Device,
    records: usize,
    progress: &dyn Progress,
) -> Result<Study, RecordError> {
    let dev = prototype1_setup(published);
    let rl = dev.transducer.load_resistance_ohm();
    let (lo, hi) = P1_BAND_HZ;
    let jobs: Vec<(usize, usize)> = (0..LEVELS.len())
        .flat_map(|l| (0..records).map(move |i| (l, i)))
        .collect();
    // spectra[job][nperseg]: the output power PSD of one record at each segment length.
    let spectra: Vec<Vec<Psd>> = jobs
        .par_iter()
        .map(|&(l, i)| {
            let sa = LEVELS[l];
            let spec = paper_record(&dev, sa);
            let stream = first_stream_for_level(sa) + i as u64;
            let rec = simulate_record(&dev, &spec, DEFAULT_SEED, stream)?;
            let out = NPERSEGS
                .iter()
                .map(|&n| {
                    let cfg = WelchOptions::half_overlap(n);
                    Ok(output_psd(&rec, rl, &cfg)?.restrict(lo, hi).total)
                })
                .collect::<Result<Vec<_>, RecordError>>();
            progress.tick();
            out
        })
        .collect::<Result<_, _>>()?;
    let mut rows = Vec::new();
    for level in 0..LEVELS.len() {
        for nperseg in 0..NPERSEGS.len() {
            let psds: Vec<&Psd> = spectra[level * records..(level + 1) * records]
                .iter()
                .map(|s| &s[nperseg])
                .collect();
            rows.push(Row {
                level,
                nperseg,
                bin_hz: psds[0].df(),
                width: mean_width(&psds),
            });
        }
    }
    Ok(Study {
        exact_hz: linear_widths(&dev, lo, hi).bw3db_hz(),
        records,
        rows,
    })
}

/// Half-power width of the mean of `psds` with its delete-one jackknife over them (Hz).
fn mean_width(psds: &[&Psd]) -> Jackknife {
    let width = |p: &Psd| signal::width_at_fraction(p, 0.5).map_or(f64::NAN, |b| b.width_hz);
    let n = psds.len();
    let sum = mean_psd(psds.iter().copied());
    let mut p = sum.clone();
    Jackknife::of(n, width(&sum), |i| {
        for ((d, m), x) in p.density.iter_mut().zip(&sum.density).zip(&psds[i].density) {
            *d = (n as f64 * m - x) / (n - 1) as f64;
        }
        width(&p)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_figures_segment_length_is_in_the_study() {
        assert_eq!(
            NPERSEGS[FIGURES_NPERSEG],
            crate::paper::ensembles::P1_NPERSEG
        );
    }
}
