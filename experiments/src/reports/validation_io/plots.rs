//! The validation chapter's plots: our one-sided spring branch against NLvib-py's harmonic
//! balance, and the linear harvesters' closed-form response against the time-domain one.

use anyhow::Result;
use endstop::device::Device;
use endstop::validation::cases;
use endstop::validation::linear_harvesters::{response_curve, ClosedForm};
use endstop::validation::nlvib::{self, Reference};

use crate::io::plot::{LegendPos, LinePlot, Series, Style, PALETTE};

pub(super) fn nlvib_plot(samples: &[nlvib::BranchSample], reference: &Reference) -> LinePlot {
    let mut series = Vec::new();
    // Our branch in runs of equal stability: solid where stable, dashed where not.
    let mut run: Vec<(f64, f64)> = Vec::new();
    let mut labelled = [false, false];
    let flush = |run: &mut Vec<(f64, f64)>,
                 stable: bool,
                 labelled: &mut [bool; 2],
                 series: &mut Vec<Series>| {
        if run.len() > 1 {
            let k = usize::from(!stable);
            let label = if labelled[k] {
                ""
            } else if stable {
                "ours, stable"
            } else {
                "ours, unstable"
            };
            labelled[k] = true;
            series.push(Series::new(
                label,
                std::mem::take(run),
                PALETTE[0],
                if stable { Style::Line } else { Style::Dashed },
            ));
        }
        run.clear();
    };
    let mut last: Option<bool> = None;
    for s in samples {
        if let Some(l) = last {
            if l != s.stable {
                let keep = run.last().copied();
                flush(&mut run, l, &mut labelled, &mut series);
                run.extend(keep);
            }
        }
        run.push((s.omega_rad_s, s.a1_amplitude_m));
        last = Some(s.stable);
    }
    if let Some(l) = last {
        flush(&mut run, l, &mut labelled, &mut series);
    }
    let ours = series.len();
    for (k, (h, points)) in reference
        .hb
        .iter()
        .filter(|(h, _)| [3, 40].contains(h))
        .enumerate()
    {
        series.push(Series::new(
            &format!("NLvib-py harmonic balance, H = {h}"),
            points
                .iter()
                .step_by(4)
                .map(|p| (p.omega_rad_s, p.a1_amplitude_m))
                .collect(),
            PALETTE[1 + k],
            Style::Points,
        ));
    }
    // Our branch drawn last, over NLvib-py's crosses: under them its stable and unstable
    // stretches, which the crosses follow, would not show.
    series.rotate_left(ours);
    LinePlot::new(
        "One-sided spring oscillator: first-harmonic amplitude (ours and NLvib-py)",
        "Omega [rad/s]",
        "first-harmonic amplitude [m]",
        series,
    )
    .x(0.5, 2.5)
    .legend(LegendPos::UpperRight)
}

pub(super) fn linear_plot(piezo: &Device, em: &Device) -> Result<LinePlot> {
    let mut series = Vec::new();
    for (k, d) in [piezo, em].into_iter().enumerate() {
        let at = cases::response_frequencies_hz(d)?;
        let (lo, hi) = (0.8 * at[0], 1.1 * at[at.len() - 1]);
        let grid: Vec<f64> = (0..=400)
            .map(|i| lo + (hi - lo) * i as f64 / 400.0)
            .collect();
        let (closed, ours) = response_curve(d, cases::LINEAR_ACCEL_RMS_G, &grid, &at)?;
        let label = match ClosedForm::of(d)? {
            ClosedForm::Piezoelectric(_) => "piezoelectric",
            ClosedForm::Electromagnetic(_) => "electromagnetic",
        };
        series.push(Series::new(
            &format!("{label}: closed form"),
            closed.iter().map(|(f, v)| (*f, v.norm())).collect(),
            PALETTE[2 * k],
            Style::Line,
        ));
        series.push(Series::new(
            &format!("{label}: time-domain steady state"),
            ours.iter().map(|(f, v)| (*f, v.norm())).collect(),
            PALETTE[2 * k + 1],
            Style::Points,
        ));
    }
    let (lo, hi) = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.1))
        .fold((f64::MAX, f64::MIN), |(a, b), y| (a.min(y), b.max(y)));
    Ok(LinePlot::new(
        "Linear harvesters: load voltage per base acceleration",
        "frequency [Hz]",
        "|V/A| [V s^2/m]",
        series,
    )
    .y(0.5 * lo, 3.0 * hi)
    .log(false, true)
    .legend(LegendPos::UpperRight))
}
