//! The tables of `endstop design`: its designs as Parquet rows, and the power maps as a table
//! for `numbers.md`: the power against the first range (the stop gap in the design chapter's
//! example), each interface's best over the second range at each of its values, with the value
//! that gives it and the impact speed there (the displacement under a noise or a record,
//! which measure no impact speed).

use anyhow::Result;
use endstop::design::{Evaluated, Problem};
use endstop_experiments::io::frame::frame;
use endstop_experiments::{fmt_sig, row};

/// The table of the maps (`maps[i] = (interface, n x n grid)`, the grid's index
/// `k * n + j` for the `k`-th value of the first range and the `j`-th of the second, as
/// [`Problem::grid`] lays it out); empty without maps.
pub(crate) fn first_range_table(p: &Problem, maps: &[(usize, Vec<Evaluated>)]) -> String {
    let Some((_, first)) = maps.first() else {
        return String::new();
    };
    let n = (first.len() as f64).sqrt().round() as usize;
    let (x, y) = (&p.ranges[0].path, &p.ranges[1].path);
    let (what, head) = if p.measures_impacts() {
        ("impact speed", "impact speed [m/s]")
    } else {
        ("displacement", "displacement [um]")
    };
    let mut md = format!(
        "\nPower against `{x}` from the maps ({n} x {n} points): at each value, each \
         interface's largest power over `{y}`, the value of `{y}` that gives it, and the \
         largest {what} there (- where no design of the row could be evaluated).\n\n| `{x}` |"
    );
    let mut rule = String::from("|---|");
    for (i, _) in maps {
        let key = p.interfaces[*i].key();
        md.push_str(&format!(" `{key}`: power [uW] | at `{y}` | {head} |"));
        rule.push_str("---|---|---|");
    }
    md.push('\n');
    md.push_str(&rule);
    md.push('\n');
    for k in 0..n {
        md.push_str(&format!("| {} |", fmt_sig(first[k * n].values[0], 3)));
        for (_, grid) in maps {
            let best = grid[k * n..(k + 1) * n]
                .iter()
                .filter_map(|e| e.result.as_ref().ok().map(|q| (e, q)))
                .max_by(|a, b| a.1.power_w.total_cmp(&b.1.power_w));
            match best {
                Some((e, q)) => md.push_str(&format!(
                    " {} | {} | {} |",
                    fmt_sig(q.power_w * 1e6, 4),
                    fmt_sig(e.values[1], 3),
                    fmt_sig(
                        if p.measures_impacts() {
                            q.impact_speed_m_s
                        } else {
                            q.displacement_m * 1e6
                        },
                        3
                    )
                )),
                None => md.push_str(" - | - | - |"),
            }
        }
        md.push('\n');
    }
    md
}

/// One row per evaluated design.
pub(crate) fn design_rows(
    p: &Problem,
    evals: &[Evaluated],
    source: &str,
) -> Result<polars::prelude::DataFrame> {
    let names: Vec<&'static str> = p
        .ranges
        .iter()
        .map(|r| &*Box::leak(r.path.clone().into_boxed_str()))
        .collect();
    let rows = evals.iter().map(|e| {
        let perf = e.result.as_ref().ok();
        let mut r = row![
            "source" => source,
            "interface" => p.interfaces[e.interface].key(),
            "evaluated" => perf.is_some(),
            "feasible" => e.feasible(),
            "violation" => e.violation,
            "power_w" => perf.map(|q| q.power_w),
            "worst_freq_hz" => perf.map(|q| q.worst_freq_hz),
            "impact_speed_m_s" => perf.map(|q| q.impact_speed_m_s),
            "contact_force_n" => perf.map(|q| q.contact_force_n),
            "displacement_m" => perf.map(|q| q.displacement_m),
            "impacts_per_s" => perf.map(|q| q.impacts_per_s),
            "error" => e.result.as_ref().err().cloned().unwrap_or_default(),
        ];
        for (n, v) in names.iter().zip(&e.values) {
            r.push((*n, (*v).into()));
        }
        r
    });
    frame(rows)
}
