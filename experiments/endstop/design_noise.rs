//! `endstop design --psd`: the noise objective's options, and the answer confirmed on a fresh
//! seed ([`endstop::design::noise`]).

use anyhow::{bail, Result};
use endstop::design::{NoiseObjective, Problem, Study};
use endstop_experiments::{fmt_sig, Experiment};

/// The noise objective's options.
#[derive(clap::Args, Debug, Clone)]
pub struct NoiseArgs {
    /// Two-sided density of band-limited white noise (g^2/Hz), in place of --freq-hz and
    /// --accel-rms-g: the objective is then the mean DC power over --records records, the same
    /// records for every design (common random numbers), and the answer is measured again on
    /// fresh records (--noise-seed + 1) with its 95 % interval.
    #[arg(long, conflicts_with_all = ["freqs_hz", "accel_rms_g"], allow_hyphen_values = true)]
    pub(crate) psd: Option<f64>,
    /// Records per design under --psd.
    #[arg(long, default_value_t = 8, requires = "psd")]
    pub(crate) records: u64,
    /// Analysed length of each record under --psd (s).
    #[arg(
        long,
        default_value_t = 2.0,
        requires = "psd",
        allow_hyphen_values = true
    )]
    pub(crate) duration_s: f64,
    /// Upper edge of the noise's flat band under --psd (Hz); sampled at ten times this.
    #[arg(
        long,
        default_value_t = 10e3,
        requires = "psd",
        allow_hyphen_values = true
    )]
    pub(crate) noise_band_hz: f64,
    /// Seed of the search's records under --psd (record i is stream i).
    #[arg(long, default_value_t = 2012, requires = "psd")]
    pub(crate) noise_seed: u64,
}

impl NoiseArgs {
    /// The noise objective, if --psd is given (its pre-roll is the problem's to set).
    pub(crate) fn objective(&self) -> Result<Option<NoiseObjective>> {
        let Some(psd) = self.psd else {
            return Ok(None);
        };
        let n = NoiseObjective {
            psd_g2_per_hz: psd,
            bandwidth_hz: self.noise_band_hz,
            records: self.records,
            duration_s: self.duration_s,
            seed: self.noise_seed,
            transient_s: 0.0,
        };
        if let Err(e) = n.check() {
            bail!("--psd, --records, --duration-s, --noise-band-hz, --noise-seed: {e}");
        }
        Ok(Some(n))
    }
}

/// The RMS acceleration (g) of the noise objective's records, `sqrt(2 B Sa)`.
pub(crate) fn noise_rms_g(n: &NoiseObjective) -> f64 {
    (2.0 * n.bandwidth_hz * n.psd_g2_per_hz).sqrt()
}

/// Under noise: the answer's power measured again on fresh records
/// ([`NoiseObjective::fresh_seed`]), recorded as
/// `power_confirmed_w` and `power_confirmed_ci95_w`, and the lines for `numbers.md`; nothing
/// without a noise objective.
pub(crate) fn confirm(exp: &mut Experiment, p: &Problem, study: &Study) -> Result<String> {
    let Some(n) = p.noise else {
        return Ok(String::new());
    };
    let Some(fresh) = n.fresh_seed() else {
        return Ok(String::new());
    };
    let Some(c) = p.confirm(&study.answer.design, fresh) else {
        return Ok(String::new());
    };
    let c = c?;
    exp.number("power_confirmed_w", c.mean);
    exp.number("power_confirmed_ci95_w", c.ci95);
    Ok(format!(
        "- the answer's power on fresh records (seed {fresh}, {} records of {} s): {} W ± {} W \
         (95 %); the search's value, on the records it chose by, is biased up by that choice\n",
        n.records,
        fmt_sig(n.duration_s, 3),
        fmt_sig(c.mean, 4),
        fmt_sig(c.ci95, 2)
    ))
}

/// The opening of `numbers.md` under noise: the question.
pub(crate) fn question(n: &NoiseObjective) -> String {
    format!(
        "under band-limited white noise of two-sided density {} g^2/Hz up to {} Hz ({} g rms; \
         the objective is the mean DC power over {} records of {} s, seed {}, the same records \
         for every design)",
        n.psd_g2_per_hz,
        fmt_sig(n.bandwidth_hz, 4),
        fmt_sig(noise_rms_g(n), 4),
        n.records,
        fmt_sig(n.duration_s, 3),
        n.seed
    )
}
