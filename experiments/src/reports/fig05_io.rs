//! Figure 5's outputs (the figure itself is `endstop::paper::figures::fig05`): the normalised
//! Hertz law and the eq 19 fits as Parquet, the numbers of the summary, the book's tables
//! (scales, fits, sensitivity to the elastic constants) and the plot of one run.

use anyhow::Result;
use endstop::paper::claims::{keys, Claims};
use endstop::paper::figures::fig05::{self, FIT_READINGS};
use endstop::paper::setups::ParamSet;

use crate::io::frame::frame;
use crate::io::md::Table;
use crate::io::plot::{LinePlot, Series, Style, PALETTE};
use crate::{fmt_sig, row, Experiment};

/// Writes everything of one run of Figure 5: the Parquet tables, the numbers of the summary,
/// the book's tables and the plot.
pub fn write(mut exp: Experiment, run: &fig05::Run, claims: &Claims) -> Result<()> {
    let published = ParamSet::Published.label();
    let [q1, q2] = &run.prototypes;

    let curve = run.curve.iter().map(|&(d, f)| {
        row![
            "delta_over_delta0" => d,
            "force_over_f0" => f,
            "series" => "hertz eq 6",
            "params" => published,
        ]
    });
    exp.write_parquet("fig05_curve", &mut frame(curve)?, published)?;

    let mut md = Table::new([
        "device",
        "t (um)",
        "R (um)",
        "delta0 = t^2/R (um)",
        "F0 = t^3/(2 lambda R) (N)",
        "0.5 um in units of delta0",
    ]);
    let mut fits = Table::new(["device", "fit", "c", "k_im (N/m) at E = 169 GPa, nu = 0.22"]);
    let mut fit_rows = Vec::new();
    for q in &run.prototypes {
        let h = &q.hertz;
        md.row([
            q.label.to_string(),
            fmt_sig(h.length_m * 1e6, 3),
            fmt_sig(h.radius_m * 1e6, 3),
            fmt_sig(h.delta_scale_m() * 1e6, 4),
            fmt_sig(h.force_scale_n(), 4),
            fmt_sig(q.fit_range_over_delta0(), 3),
        ]);
        for (label, coefficient) in FIT_READINGS {
            let c = coefficient(&q.fits);
            let k = q.stiffness_of_coefficient(c);
            fits.row([
                q.label.to_string(),
                label.to_string(),
                fmt_sig(c, 4),
                fmt_sig(k, 4),
            ]);
            fit_rows.push(row![
                "device" => q.label,
                "fit" => label,
                "coefficient" => c,
                "k_im_n_per_m" => k,
                "params" => published,
            ]);
        }
    }
    exp.write_parquet("fig05_fits", &mut frame(fit_rows)?, published)?;
    exp.number("eq19_coefficient_p1_through_origin", q1.fits.through_origin);
    exp.number("eq19_coefficient_p1_with_intercept", q1.fits.with_intercept);
    exp.number("eq19_coefficient_p1_secant", q1.fits.secant);
    exp.number("eq19_coefficient_p1_force_sampled", q1.fits.force_sampled);
    exp.number("eq19_coefficient_p2_through_origin", q2.fits.through_origin);
    exp.number("delta0_p1_m", q1.hertz.delta_scale_m());
    exp.number("delta0_p2_m", q2.hertz.delta_scale_m());
    exp.number("k_im_eq19_p1_n_per_m", q1.k_im_n_per_m);
    exp.number("k_im_eq19_p2_n_per_m", q2.k_im_n_per_m);

    let printed = claims
        .claim(keys::F5B_EQ19_COEFFICIENT)
        .map_or(f64::NAN, |c| c.paper.to_f64());
    let mut text = md.render();
    text.push_str(&format!(
        "\n**Eq 19 coefficient c** in k_im = c pi E t/(1 - nu^2), from {} readings of \
         \"least-squares fit over 0-0.5 um\" (the paper prints {printed}). The coefficient does \
         not depend on E or nu, only on the fit range in units of delta0.\n\n",
        FIT_READINGS.len()
    ));
    text.push_str(&fits.render());
    text.push_str(&format!(
        "\n**Sensitivity to the elastic constants** (eq 19 with the printed c = {printed}, \
         prototype 1): k_im scales as E/(1 - nu^2).\n\n"
    ));
    let mut sens = Table::new(["E (GPa)", "nu", "k_im (N/m)", "relative to default"]);
    for s in &run.sensitivity {
        sens.row([
            (s.youngs_modulus_pa / 1e9).to_string(),
            s.poisson_ratio.to_string(),
            fmt_sig(s.k_im_n_per_m, 4),
            fmt_sig(s.relative, 3),
        ]);
    }
    text.push_str(&sens.render());
    exp.write_numbers_md(&text)?;

    // Figure: the normalised law with the eq 19 line of the printed coefficient over each
    // prototype's fit range.
    let line = |q: &fig05::Prototype| q.normalised_eq19_line(printed).to_vec();
    let plot = LinePlot::new(
        "Figure 5: Hertz line contact, normalised (eq 6)",
        "relative displacement delta/delta0",
        "normalised impact force F/F0",
        vec![
            Series::new(
                "eq 6: d = f (1 - ln f)",
                run.curve.clone(),
                PALETTE[0],
                Style::Line,
            ),
            Series::new(
                &format!("eq 19 (c = {printed}), 0..0.5 um of prototype 1"),
                line(q1),
                PALETTE[1],
                Style::Dashed,
            ),
            Series::new(
                &format!("eq 19 (c = {printed}), 0..0.5 um of prototype 2"),
                line(q2),
                PALETTE[2],
                Style::Dashed,
            ),
        ],
    )
    .x(0.0, 0.1)
    .y(0.0, 0.02)
    .legend(crate::io::plot::LegendPos::LowerRight);
    exp.write_plot(&plot)?;
    exp.finish()
}
