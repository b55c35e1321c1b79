//! What the book takes from results besides the scorecard and the provenance page: the
//! own-device runs' numbers and plots, and the reduced deviations study's placeholders where
//! it has not run.

use anyhow::Result;

use crate::pipeline::jobs::JOBS;

/// Copies the own-device runs' numbers and plots into the book's generated directory, with
/// the curve and the comparison drawn from several of them ([`crate::pipeline::noise_curve`],
/// [`crate::pipeline::upconversion`]).
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
    write_device_count(&crate::root().join("book/src/own_device.md"), &dst)?;
    write_intro_example(&dst)?;
    // The bistable example's power and transition rate against the noise level, from its
    // random jobs' summaries; the up-converter against one mass, from its sweeps and charges.
    crate::pipeline::noise_curve::publish(&crate::results_root(), &dst)?;
    crate::pipeline::upconversion::publish(&crate::results_root(), &dst)?;
    // The Design chapter's choice of optimiser, from its recorded comparison.
    crate::pipeline::design_optimisers::publish(&crate::root(), &dst)
}

/// The device files of the tool runs whose outputs the chapter `chapter` includes
/// (`generated/own_device/<stem>...`), in the order the chapter first includes them.
pub fn chapter_devices(chapter: &str) -> Vec<&'static str> {
    let mut devices = Vec::new();
    for job in JOBS.iter().filter(|j| j.is_tool_run()) {
        let stem = job.name.trim_start_matches("own_device_");
        let Some(at) = chapter.find(&format!("generated/own_device/{stem}.")) else {
            continue;
        };
        if let Some(d) = arg(job, "--device") {
            devices.push((at, d));
        }
    }
    devices.sort_by_key(|(at, _)| *at);
    let mut out: Vec<&'static str> = Vec::new();
    for (_, d) in devices {
        if !out.contains(&d) {
            out.push(d);
        }
    }
    out
}

/// A count in words, for prose ("four example devices").
pub fn count_words(n: usize) -> String {
    const WORDS: [&str; 13] = [
        "no", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine", "ten",
        "eleven", "twelve",
    ];
    WORDS.get(n).map_or(n.to_string(), |w| w.to_string())
}

/// `devices.md`: how many example devices the own-device chapter runs, counted from the runs
/// its pages include, with their files.
fn write_device_count(chapter: &std::path::Path, dst: &std::path::Path) -> Result<()> {
    let text = std::fs::read_to_string(chapter).unwrap_or_default();
    let devices = chapter_devices(&text);
    let names: Vec<String> = devices.iter().map(|d| format!("`{d}`")).collect();
    let md = format!(
        "This chapter runs {} example devices of different kinds, shipped in `data/examples/` \
         ({}).",
        count_words(devices.len()),
        names.join(", ")
    );
    crate::write_atomic(&dst.join("devices.md"), md.as_bytes())
}

/// The reduced history match (the `deviations` experiment) is an option, not one of
/// `reproduce`'s jobs: until `just deviations` has run, its section of the chapter says how to
/// run it, in place of its numbers and heat map. The chapter's answer is the recorded
/// definitive match's ([`crate::pipeline::recorded_history`]), present in every build.
pub fn deviations_placeholder() -> Result<()> {
    let dir = crate::book_generated_root().join(crate::pipeline::jobs::DEVIATIONS.name);
    if !dir.join("numbers.md").exists() {
        let note = "*Optional, not run in this build: the reduced match takes longer than \
                    `reproduce`'s budget allows. Run `just deviations` (or `cargo run --release \
                    --bin deviations`) and rebuild the book to see it here.*\n";
        crate::write_atomic(&dir.join("numbers.md"), note.as_bytes())?;
    }
    let path = dir.join("deviations.figure.md");
    if !path.exists() {
        crate::write_atomic(
            &path,
            b"*(The heat map of the reduced match's Sobol indices appears here once \
              `just deviations` has run; the recorded match's indices are in \
              `data/recorded/history/sobol.parquet`.)*\n",
        )?;
    }
    Ok(())
}

/// The tool run the introduction shows: the up-sweep of the example device of the paper's kind.
pub const INTRO_JOB: &str = "own_device_sweep";

/// `intro_example.md`: the introduction's one result, the command of the [`INTRO_JOB`] run
/// and what it found (impact onset, the end of the impacting branch, the largest power), each
/// number read from the run's `summary.json`, with its plot; a note where it has not run.
fn write_intro_example(dst: &std::path::Path) -> Result<()> {
    let Some(job) = crate::pipeline::jobs::job(INTRO_JOB) else {
        return Ok(());
    };
    // Two lines, so that the command fits the page's width.
    let command = format!(
        "cargo run --release --bin endstop -- {} \\\n    {}",
        job.args.first().copied().unwrap_or_default(),
        job.args.get(1..).unwrap_or_default().join(" ")
    );
    let summary = std::fs::read_to_string(job.dir().join("summary.json"))
        .ok()
        .and_then(|s| serde_json::from_str::<serde_json::Value>(&s).ok());
    let number = |k: &str| summary.as_ref().and_then(|s| s["numbers"][k].as_f64());
    let md = match (
        number("impact_onset_hz"),
        number("branch_end_hz"),
        number("power_max_w"),
    ) {
        (Some(onset), Some(end), Some(p)) => format!(
            "```sh\n{command}\n```\n\n![Up-sweep of the example device](generated/own_device/sweep.svg)\n\n\
             *The example device of the paper's kind (`{device}`), swept up at {accel} g rms: \
             its proof mass starts to hit the stops at **{onset} Hz**, rides the impacting \
             branch up to **{end} Hz** and then jumps down; the loads take at most \
             **{p} nW**. Generated by `reproduce` from the run above \
             ([its chapter](own_device.md#5-the-papers-topology-a-frequency-sweep-and-white-noise)).*\n",
            device = arg(job, "--device").unwrap_or("?"),
            accel = arg(job, "--accel-rms-g").unwrap_or("?"),
            onset = crate::fmt_sig(onset, 4),
            end = crate::fmt_sig(end, 4),
            p = crate::fmt_sig(p * 1e9, 3),
        ),
        _ => format!(
            "```sh\n{command}\n```\n\n*(Its result appears here once `reproduce` has run the \
             job `{INTRO_JOB}`.)*\n"
        ),
    };
    crate::write_atomic(&dst.join("intro_example.md"), md.as_bytes())
}

/// The value after `flag` in a job's arguments.
fn arg(job: &crate::pipeline::jobs::Job, flag: &str) -> Option<&'static str> {
    job.args.windows(2).find(|w| w[0] == flag).map(|w| w[1])
}
