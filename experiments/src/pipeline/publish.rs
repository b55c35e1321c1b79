//! What the book takes from results besides the scorecard and the provenance page: the
//! own-device runs' numbers and plots, and the deviations study's placeholders where the study
//! has not run.

use anyhow::Result;

use crate::pipeline::jobs::JOBS;

/// Copies the own-device runs' numbers and plots into the book's generated directory, with
/// the curve drawn from several of them ([`crate::pipeline::noise_curve`]).
pub fn publish_own_device() -> Result<()> {
    let dst = crate::book_generated_root().join("own_device");
    for job in JOBS.iter().filter(|j| j.is_tool_run()) {
        let src = job.dir();
        let stem = job.name.trim_start_matches("own_device_");
        // The tool names its files after its study, the job's first argument.
        let tool = format!("endstop-{}", job.args.first().copied().unwrap_or(stem));
        for (from, to) in [
            ("numbers.md".to_string(), format!("{stem}.md")),
            (format!("{tool}.svg"), format!("{stem}.svg")),
            (format!("{tool}.png"), format!("{stem}.png")),
        ] {
            if let Ok(bytes) = std::fs::read(src.join(&from)) {
                crate::write_atomic(&dst.join(to), &bytes)?;
            }
        }
        // The caption, with the image pointing at the copy above.
        if let Ok(md) = std::fs::read_to_string(src.join(format!("{tool}.figure.md"))) {
            let md = match (md.find("]("), md.find(".svg)")) {
                (Some(a), Some(b)) if a < b => {
                    format!("{}](generated/own_device/{stem}{}", &md[..a], &md[b..])
                }
                _ => md,
            };
            crate::write_atomic(&dst.join(format!("{stem}.figure.md")), md.as_bytes())?;
        }
    }
    // The bistable example's power and transition rate against the noise level, from its
    // random jobs' summaries.
    crate::pipeline::noise_curve::publish(&crate::results_root(), &dst)
}

/// The study is not one of `reproduce`'s jobs: until `just deviations` has run, its chapter
/// includes a note in place of its answer, numbers, recorded match and heat map.
pub fn deviations_placeholder() -> Result<()> {
    let dir = crate::book_generated_root().join(crate::pipeline::jobs::DEVIATIONS.name);
    if !dir.join("numbers.md").exists() {
        let note = "*Not run in this build: the study is not part of `reproduce`; run \
                    `just deviations` (or `cargo run --release --bin deviations`) and rebuild the book.*\n";
        crate::write_atomic(&dir.join("numbers.md"), note.as_bytes())?;
    }
    for (file, note) in [
        ("answer.md", "*The study of why the paper deviates has not run in this build (`just deviations`).*\n"),
        ("recorded.md", "*(the study has not run in this build)*\n"),
    ] {
        if !dir.join(file).exists() {
            crate::write_atomic(&dir.join(file), note.as_bytes())?;
        }
    }
    let path = dir.join("deviations.figure.md");
    if !path.exists() {
        crate::write_atomic(&path, b"*(no plot: the study has not run)*\n")?;
    }
    Ok(())
}
