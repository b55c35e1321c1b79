//! The boxes that open the book's figure chapters with the answer: for each chapter, the
//! paper's claims beside our values and verdicts, taken from the scorecard's rows, written to
//! `generated/<chapter>/answer.md`; for the whole-response chapter, the jump claims beside the
//! upper folds of the continued orbits (`generated/response/answer.md`).
//!
//! A box is a Markdown block quote. The chapter includes it and continues the quote with its
//! one sentence of why (a `>` line after the include), so the numbers come from the run and
//! only the explanation is written by hand.

use std::collections::BTreeMap;

use anyhow::Result;
use endstop::paper::claims::{Answer, Row, Verdict};
use endstop::paper::setups::ParamSet;

use crate::{book_generated_root, fmt_sig, write_atomic};

/// The chapter directory of a claim (`F8-c` is Figure 8's, `T3-a` Table 3's): `fig08`,
/// `table3`; None for an id of another form.
pub fn chapter_of(claim: &str) -> Option<String> {
    let head = claim.split('-').next()?;
    let (kind, number) = head.split_at(1);
    let n: u32 = number.parse().ok()?;
    match kind {
        "F" => Some(format!("fig{n:02}")),
        "T" => Some(format!("table{n}")),
        _ => None,
    }
}

/// A value in the row's unit: yes/no for a yes/no claim, else four significant digits with
/// the unit.
fn value(v: Answer, unit: &str) -> String {
    match (v, unit) {
        (Answer::YesNo(yes), _) => (if yes { "yes" } else { "no" }).to_string(),
        (Answer::Number(v), "") => fmt_sig(v, 4),
        (Answer::Number(v), _) => format!("{} {unit}", fmt_sig(v, 4)),
    }
}

/// Our value of a row with its uncertainty and verdict (and its note), as a table cell.
fn ours(r: &Row) -> String {
    let Some(v) = r.ours else {
        return "not yet".into();
    };
    let mut s = match (v, r.uncertainty, r.unit.as_str()) {
        (Answer::Number(v), Some(u), "") => format!("{} ± {}", fmt_sig(v, 4), fmt_sig(u, 2)),
        (Answer::Number(v), Some(u), unit) => {
            format!("{} ± {} {unit}", fmt_sig(v, 4), fmt_sig(u, 2))
        }
        (_, _, unit) => value(v, unit),
    };
    s.push_str(match r.verdict {
        Verdict::Reproduced => ", **reproduced**",
        Verdict::Deviates => ", *deviates*",
        Verdict::NotYet => ", not yet",
        Verdict::Open => ", open question",
    });
    if !r.note.is_empty() {
        s.push_str(&format!(" ({})", r.note));
    }
    s
}

/// Text safe inside a table cell.
fn cell(s: &str) -> String {
    s.replace('|', "\\|")
}

/// The box of one chapter's rows (in the scorecard's order).
fn chapter_box(rows: &[&Row]) -> String {
    // One line per claim number, a column per parameter set that has values.
    let mut sets: Vec<ParamSet> = Vec::new();
    for r in rows {
        if !sets.contains(&r.set) {
            sets.push(r.set);
        }
    }
    let mut md = String::from(
        "> **The answer.** The paper's numbers for this chapter beside ours, from the \
         [scorecard](scorecard.md):\n>\n> | claim | what the paper says | paper |",
    );
    for s in &sets {
        md.push_str(&format!(" ours, {s} set |"));
    }
    md.push_str("\n> |---|---|---|");
    md.push_str(&"---|".repeat(sets.len()));
    md.push('\n');
    let mut seen: Vec<(&str, &str)> = Vec::new();
    for r in rows {
        let key = (r.claim.as_str(), r.quantity.as_str());
        if seen.contains(&key) {
            continue;
        }
        seen.push(key);
        md.push_str(&format!(
            "> | {} | {} | {} |",
            r.claim,
            cell(&r.text),
            value(r.paper, &r.unit)
        ));
        for s in &sets {
            let got = rows
                .iter()
                .find(|x| (x.claim.as_str(), x.quantity.as_str()) == key && x.set == *s);
            md.push_str(&format!(
                " {} |",
                got.map(|x| cell(&ours(x))).unwrap_or_default()
            ));
        }
        md.push('\n');
    }
    let tally: Vec<String> = sets
        .iter()
        .map(|s| {
            let of_set: Vec<&&Row> = rows.iter().filter(|r| r.set == *s).collect();
            let ok = of_set
                .iter()
                .filter(|r| r.verdict == Verdict::Reproduced)
                .count();
            format!("{ok} of {} with the {s} set", of_set.len())
        })
        .collect();
    md.push_str(&format!(">\n> Reproduced: {}.\n", tally.join(", ")));
    md
}

/// The whole-response chapter's box: each jump claim with our sweep's jump and the upper
/// fold of the continued orbits.
fn response_box(rows: &[&Row]) -> String {
    if rows.is_empty() {
        return "> **The answer.** *Not available: the `response` experiment has not run.*\n"
            .into();
    }
    let mut md = String::from(
        "> **The answer.** The paper's jump frequencies are where its up-sweeps fall off the \
         impacting branch. Beside each, our sweep's jump and the upper fold of the continued \
         periodic orbits, where the impacting branch ends:\n>\n\
         > | claim | set | paper (Hz) | our sweep's jump (Hz) | upper fold (Hz) | sweep - fold (Hz) |\n\
         > |---|---|---|---|---|---|\n",
    );
    for r in rows {
        let (Some(jump), Some(fold)) = (r.ours.and_then(Answer::number), r.fold_hz) else {
            continue;
        };
        md.push_str(&format!(
            "> | {} | {} | {} | {jump:.2} | {fold:.2} | {:+.2} |\n",
            r.claim,
            r.set,
            r.paper.to_f64(),
            jump - fold
        ));
    }
    md
}

/// Writes every chapter's box (see the module docs).
pub fn write(rows: &[Row]) -> Result<()> {
    let mut chapters: BTreeMap<String, Vec<&Row>> = BTreeMap::new();
    for r in rows {
        if let Some(ch) = chapter_of(&r.claim) {
            chapters.entry(ch).or_default().push(r);
        }
    }
    let root = book_generated_root();
    for (ch, rows) in &chapters {
        write_atomic(
            &root.join(ch).join("answer.md"),
            chapter_box(rows).as_bytes(),
        )?;
    }
    let folds: Vec<&Row> = rows
        .iter()
        .filter(|r| r.fold_hz.is_some() && r.unit == "Hz")
        .collect();
    write_atomic(
        &root.join("response").join("answer.md"),
        response_box(&folds).as_bytes(),
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn claims_map_to_their_chapters() {
        assert_eq!(chapter_of("F5-a").as_deref(), Some("fig05"));
        assert_eq!(chapter_of("F12").as_deref(), Some("fig12"));
        assert_eq!(chapter_of("T3-b").as_deref(), Some("table3"));
        assert_eq!(chapter_of("X1"), None);
    }
}
