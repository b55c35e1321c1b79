//! The finite-difference rows of a stepped-sweep fit's Jacobian: how much of the information
//! about one parameter comes from steps whose response does not settle (a sample of an
//! irregular response, whose value jitters from one run to the next) and from points a jump
//! crosses, against the rows of the settled steps.
//!
//! At recovery-family case 21's optimum, as its fit finds it (a rigid stop; the steps at
//! 116-120 Hz do not settle, the branch ends near 154 Hz), the damping's derivative is taken
//! by forward differences of several relative sizes, in standard deviations of each point per unit
//! relative change. A smooth model's rows do not depend on the step; the printed rows of the
//! unsettled steps and of the jump do, and they make the sum `J^T J` that an interval is
//! computed from.
//!
//! Usage: `cargo run --release --example stepped_rows` (the fit itself first, some 15 s).

use endstop::fit::family::recovery_family;
use endstop::fit::{fit, model_values, FitSettings};

/// The parameter whose rows are shown.
const DAMPING: &str = "mechanics.damping_n_s_per_m";

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let case = &recovery_family()[20];
    let data = case.data()?;
    let report = fit(
        &case.start_device()?,
        &data,
        &case.free,
        &FitSettings::default(),
    )?;
    let fitted = report
        .params
        .iter()
        .find(|p| p.path == DAMPING)
        .ok_or("case 21 fits the damping")?;
    println!(
        "case {}: fitted damping {:.6e}, 95 % {:.6e} .. {:.6e} (standard error {:.2e} of it)",
        case.name,
        fitted.value,
        fitted.interval.0,
        fitted.interval.1,
        fitted.std_err / fitted.value
    );
    let base = &report.device;
    let values = |damping_factor: f64| -> Result<Vec<f64>, Box<dyn std::error::Error>> {
        let d = base.with_params(&[(DAMPING, fitted.value * damping_factor)])?;
        Ok(model_values(&d, report.accel_scale, &data[0])?)
    };
    let at = values(1.0)?;
    let points = &data[0].points;
    println!("the damping's rows (sigmas per unit relative change):");
    for rel in [1e-4, 1e-3, 2.75e-3, 5.5e-3, 1.1e-2] {
        let moved = values(1.0 + rel)?;
        let (mut all, mut unsettled, mut jump) = (0.0, 0.0, 0.0);
        let mut rows = String::new();
        for ((p, a), b) in points.iter().zip(&at).zip(&moved) {
            let sigma = p.sigma.ok_or("the family's points have sigmas")?;
            let d = (b - a) / rel / sigma;
            all += d * d;
            if (115.0..=121.0).contains(&p.freq_hz) {
                unsettled += d * d;
            } else if (150.0..=158.0).contains(&p.freq_hz) {
                jump += d * d;
            }
            if d.abs() > 3.0 {
                rows += &format!(" {} Hz: {d:.3e};", p.freq_hz);
            }
        }
        let rest = all - unsettled - jump;
        println!(
            "step {rel:.2e}: J^T J {all:.3e} (116-120 Hz {unsettled:.3e}, 150-158 Hz {jump:.3e}, \
             the rest {rest:.3e}); standard error of the relative damping from all rows {:.2e}, \
             from the rest {:.2e};{rows}",
            all.sqrt().recip(),
            rest.sqrt().recip()
        );
    }
    Ok(())
}
