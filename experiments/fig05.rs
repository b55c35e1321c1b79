//! Figure 5: the Hertz line-contact law (eq 6) in normalised form, delta0 for both prototypes
//! (claim F5-a), and the linear end-stop stiffness of eq 19 (claim F5-b).

use endstop_experiments as common;

use anyhow::Result;
use common::plot::{LinePlot, Series, Style, PALETTE};
use common::{fmt_sig, load_device, Experiment};
use endstop::physics::hertz::normalised_delta;
use endstop::physics::hertz::HertzLine;
use endstop::physics::hertz::LinearFits;
use endstop::physics::hertz::EQ19_FIT_RANGE_M as FIT_RANGE_M;
use endstop::physics::hertz::EQ19_FIT_SAMPLES as FIT_SAMPLES;
use polars::prelude::*;

fn main() {
    common::run_main("fig05", run);
}

fn run() -> Result<()> {
    let mut exp = Experiment::start("fig05");
    let p1 = load_device("prototype1")?;
    let p2 = load_device("prototype2")?;
    exp.uses(&p1, "published");
    exp.uses(&p2, "published");

    // The normalised curve d = f (1 - ln f) of Figure 5, sampled in f.
    let n = 2001;
    let f: Vec<f64> = (0..n).map(|i| 0.02 * i as f64 / (n - 1) as f64).collect();
    let d: Vec<f64> = f.iter().map(|&f| normalised_delta(f)).collect();
    let mut curve = df!(
        "delta_over_delta0" => &d,
        "force_over_f0" => &f,
        "series" => vec!["hertz eq 6"; n],
        "params" => vec!["published"; n],
    )?;
    exp.write_parquet("fig05_curve", &mut curve, "published")?;

    let mut rows: Vec<(String, &str, f64, f64)> = Vec::new();
    let mut md = String::new();
    md.push_str("| device | t (um) | R (um) | delta0 = t^2/R (um) | F0 = t^3/(2 lambda R) (N) | 0.5 um in units of delta0 |\n|---|---|---|---|---|---|\n");
    let mut fits: Vec<(String, HertzLine, LinearFits)> = Vec::new();
    for (name, dev) in [("prototype 1", &p1), ("prototype 2", &p2)] {
        let h = HertzLine::of(&dev.device);
        let d0 = h.delta_scale_m();
        md.push_str(&format!(
            "| {name} | {} | {} | {} | {} | {} |\n",
            fmt_sig(h.length_m * 1e6, 3),
            fmt_sig(h.radius_m * 1e6, 3),
            fmt_sig(d0 * 1e6, 4),
            fmt_sig(h.force_scale_n(), 4),
            fmt_sig(FIT_RANGE_M / d0, 3)
        ));
        let fit = h.linear_fits(FIT_RANGE_M, FIT_SAMPLES);
        for (label, c) in [
            (
                "least squares through origin, uniform in delta",
                fit.through_origin,
            ),
            ("least squares with intercept (slope)", fit.with_intercept),
            ("secant F(0.5 um)/0.5 um", fit.secant),
            (
                "least squares through origin, uniform in force",
                fit.force_sampled,
            ),
            ("least squares of delta on F (errors in delta)", fit.inverse),
        ] {
            rows.push((name.to_string(), label, c, c * h.length_m / h.lambda_per_pa));
        }
        fits.push((name.to_string(), h, fit));
    }
    let (h1, fit1) = (fits[0].1, fits[0].2);
    let h2 = fits[1].1;
    exp.claim(
        "F5-a",
        "delta0_p1_um",
        "published",
        h1.delta_scale_m() * 1e6,
    );
    exp.claim(
        "F5-a",
        "delta0_p2_um",
        "published",
        h2.delta_scale_m() * 1e6,
    );
    // Our reading of "least-squares fit" (eq 19): a line through the origin, F = k delta,
    // fitted to eq 6 sampled uniformly in delta over 0..0.5 um, for prototype 1 (whose Figure
    // 8 first used it). The other readings are shown beside it.
    exp.claim(
        "F5-b",
        "eq19_coefficient",
        "published",
        fit1.paper_reading(),
    );
    exp.number("eq19_coefficient_p1_through_origin", fit1.through_origin);
    exp.number("eq19_coefficient_p1_with_intercept", fit1.with_intercept);
    exp.number("eq19_coefficient_p1_secant", fit1.secant);
    exp.number("eq19_coefficient_p1_force_sampled", fit1.force_sampled);
    exp.number(
        "eq19_coefficient_p2_through_origin",
        fits[1].2.through_origin,
    );
    exp.number("delta0_p1_m", h1.delta_scale_m());
    exp.number("delta0_p2_m", h2.delta_scale_m());
    exp.number(
        "k_im_eq19_p1_n_per_m",
        p1.device.linear_endstop_stiffness_n_per_m(),
    );
    exp.number(
        "k_im_eq19_p2_n_per_m",
        p2.device.linear_endstop_stiffness_n_per_m(),
    );

    md.push_str("\n**Eq 19 coefficient c** in k_im = c pi E t/(1 - nu^2), from four readings of \"least-squares fit over 0-0.5 um\" (the paper prints 0.058). The coefficient does not depend on E or nu, only on the fit range in units of delta0.\n\n| device | fit | c | k_im (N/m) at E = 169 GPa, nu = 0.22 |\n|---|---|---|---|\n");
    for (dev, label, c, k) in &rows {
        md.push_str(&format!(
            "| {dev} | {label} | {} | {} |\n",
            fmt_sig(*c, 4),
            fmt_sig(*k, 4)
        ));
    }
    let mut fit_df = df!(
        "device" => rows.iter().map(|r| r.0.clone()).collect::<Vec<_>>(),
        "fit" => rows.iter().map(|r| r.1.to_string()).collect::<Vec<_>>(),
        "coefficient" => rows.iter().map(|r| r.2).collect::<Vec<_>>(),
        "k_im_n_per_m" => rows.iter().map(|r| r.3).collect::<Vec<_>>(),
        "params" => vec!["published"; rows.len()],
    )?;
    exp.write_parquet("fig05_fits", &mut fit_df, "published")?;

    // Sensitivity of the eq 19 stiffness to E and nu (not given in the paper).
    md.push_str("\n**Sensitivity to the elastic constants** (eq 19 with the printed c = 0.058, prototype 1): k_im scales as E/(1 - nu^2).\n\n| E (GPa) | nu | k_im (N/m) | relative to default |\n|---|---|---|---|\n");
    let k_ref = p1.device.linear_endstop_stiffness_n_per_m();
    for (e, nu) in [
        (130e9, 0.28),
        (150e9, 0.17),
        (169e9, 0.22),
        (169e9, 0.064),
        (188e9, 0.26),
    ] {
        let mut d = p1.device.clone();
        d.material.youngs_modulus_pa = e;
        d.material.poisson_ratio = nu;
        let k = d.linear_endstop_stiffness_n_per_m();
        md.push_str(&format!(
            "| {} | {} | {} | {} |\n",
            e / 1e9,
            nu,
            fmt_sig(k, 4),
            fmt_sig(k / k_ref, 3)
        ));
    }
    exp.write_numbers_md(&md)?;

    // Figure: normalised law with the two prototypes' relevant ranges and the eq 19 line.
    let curve_pts: Vec<(f64, f64)> = d.iter().copied().zip(f.iter().copied()).collect();
    let lin = |c: f64, dmax: f64| -> Vec<(f64, f64)> {
        // k = c pi E t/(1-nu^2) = c t / lambda; in normalised units f = (2 c) d.
        vec![(0.0, 0.0), (dmax, 2.0 * c * dmax)]
    };
    let d1 = FIT_RANGE_M / h1.delta_scale_m();
    let d2 = FIT_RANGE_M / h2.delta_scale_m();
    let plot = LinePlot::new(
        "Figure 5: Hertz line contact, normalised (eq 6)",
        "relative displacement delta/delta0",
        "normalised impact force F/F0",
        vec![
            Series::new("eq 6: d = f (1 - ln f)", curve_pts, PALETTE[0], Style::Line),
            Series::new(
                "eq 19 (c = 0.058), 0..0.5 um of prototype 1",
                lin(0.058, d1),
                PALETTE[1],
                Style::Dashed,
            ),
            Series::new(
                "eq 19 (c = 0.058), 0..0.5 um of prototype 2",
                lin(0.058, d2),
                PALETTE[2],
                Style::Dashed,
            ),
        ],
    )
    .x(0.0, 0.1)
    .y(0.0, 0.02)
    .legend(common::plot::LegendPos::LowerRight);
    exp.write_plot(&plot)?;
    exp.finish()
}
