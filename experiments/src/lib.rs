//! Shared edge of the experiment binaries: loading parameter files, writing Parquet with
//! provenance metadata, plots (SVG + PNG with a bundled font), `summary.json`, and the
//! generated snippets the book includes. The physics lives in the `endstop` library; nothing
//! here computes a result.
//!
//! Every file is written to a temporary name in the same directory and renamed, so a failed
//! run never leaves a partial output behind.
//!
//! The modules are in three rooms by job, each using only the rooms listed after it and this
//! crate root:
//!
//! * [`pipeline`]: what the `reproduce` driver alone uses (its jobs, when a job may be
//!   skipped, the answer boxes, the book's build);
//! * [`reports`]: the outputs of each figure, study and `endstop` command (Parquet rows,
//!   plots, the book's tables and sentences), and the readers of measured files;
//! * [`io`]: the helpers every report uses (plots, data frames, Markdown tables, progress bars);
//!
//! and [`ngspice`], the runner of the external circuit simulator, [`commit`], the commit
//! every output names, and [`usage`], the processor time and memory a run reports of itself.
pub mod commit;
pub mod io;
pub mod ngspice;
pub mod pipeline;
pub mod reports;
pub mod time_split;
pub mod usage;

pub use commit::{git_commit, git_commit_in_background};
pub use io::progress::{progress, with_progress, Bar};
pub use reports::calibration_io::{calibrated_prototype1, prototype1_both_sets};
pub use usage::{children_cpu_time_s, cpu_time_s, own_cpu_time_s, own_memory, Memory};

/// Every experiment binary allocates through mimalloc: a record's 10^6-sample vectors are
/// freed and allocated again record after record, and the system allocator returns them to
/// the kernel and faults them in afresh each time (measured in the book's Performance
/// chapter). The allocator does not touch the arithmetic: every number is the same.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};
use std::time::Instant;

use anyhow::{Context, Result};
use endstop::device::Device;
use endstop::paper::claims::{Claims, Value};
use endstop::paper::setups::ParamSet;
use endstop::paper::Figure;
use polars::prelude::*;
use serde::Serialize;

/// Project root (found from this package's manifest, never from the working directory): the
/// workspace root, one level above `experiments/`.
pub fn root() -> PathBuf {
    let manifest = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    manifest.parent().map_or(manifest.clone(), PathBuf::from)
}

/// Where results go: `data/results/`, or `$ENDSTOP_OUTPUT_DIR` when set (used by tests that
/// must not overwrite the user's results).
pub fn results_root() -> PathBuf {
    match std::env::var_os("ENDSTOP_OUTPUT_DIR") {
        Some(d) => PathBuf::from(d),
        None => root().join("data/results"),
    }
}

/// Where the generated book snippets go: `book/src/generated/`, or
/// `$ENDSTOP_OUTPUT_DIR/book-generated` when that variable is set.
pub fn book_generated_root() -> PathBuf {
    match std::env::var_os("ENDSTOP_OUTPUT_DIR") {
        Some(d) => PathBuf::from(d).join("book-generated"),
        None => root().join("book/src/generated"),
    }
}

/// A loaded, validated parameter file.
#[derive(Debug, Clone)]
pub struct LoadedDevice {
    /// The device.
    pub device: Device,
    /// File name relative to the project root, e.g. `data/prototype1.toml`.
    pub file: String,
    /// The file's text, recorded in every output's metadata.
    pub text: String,
}

/// Loads and validates `data/<name>.toml` (or `$ENDSTOP_DATA_DIR/<name>.toml` when that
/// variable is set); the error names the file and the field.
pub fn load_device(name: &str) -> Result<LoadedDevice> {
    let (rel, path) = match std::env::var_os("ENDSTOP_DATA_DIR") {
        Some(dir) => {
            let p = PathBuf::from(dir).join(format!("{name}.toml"));
            (p.display().to_string(), p)
        }
        None => {
            let rel = format!("data/{name}.toml");
            (rel.clone(), root().join(&rel))
        }
    };
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("cannot read parameter file {}", path.display()))?;
    let device = Device::from_toml_str(&text, &rel)?;
    Ok(LoadedDevice {
        device,
        file: rel,
        text,
    })
}

/// Loads and validates a device file given by path (the `endstop` command-line tool).
pub fn load_device_file(path: &Path) -> Result<LoadedDevice> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read device file {}", path.display()))?;
    let file = path.display().to_string();
    let device = Device::from_toml_str(&text, &file)?;
    Ok(LoadedDevice { device, file, text })
}

/// Writes `bytes` to `path` atomically (temporary file in the same directory, then rename).
///
/// After [`git_commit_in_background`] it first waits for the commit, so that the provenance
/// describes the tree before the run wrote into it.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    commit::await_background();
    let dir = path.parent().context("output path has no parent")?;
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let tmp = dir.join(format!(
        ".{}.tmp",
        path.file_name().unwrap_or_default().to_string_lossy()
    ));
    {
        let mut f = std::fs::File::create(&tmp)
            .with_context(|| format!("cannot create {}", tmp.display()))?;
        f.write_all(bytes)?;
        f.sync_all()?;
    }
    std::fs::rename(&tmp, path).with_context(|| format!("cannot rename to {}", path.display()))?;
    Ok(())
}

/// A figure rendered and not yet written: its title, SVG text and PNG bytes.
pub struct RenderedPlot {
    title: String,
    svg: String,
    png: Vec<u8>,
}

impl RenderedPlot {
    /// Renders `fig` ([`io::plot::render`]); it touches no file, so it may run on any thread.
    pub fn of<F: io::plot::Chart>(fig: &F) -> Result<Self> {
        let (svg, png) = io::plot::render(fig)?;
        Ok(Self {
            title: fig.title(),
            svg,
            png,
        })
    }
}

/// One experiment's output directory and provenance.
pub struct Experiment {
    /// Experiment name (`fig08`).
    pub name: String,
    /// `data/results/<name>/`.
    pub dir: PathBuf,
    /// `book/src/generated/<name>/`.
    pub book_dir: PathBuf,
    /// Parameter files used: (file, parameter set label, text).
    pub params: Vec<(String, String, String)>,
    /// Seed of the random streams, if any.
    pub seed: Option<u64>,
    values: Vec<Value>,
    numbers: BTreeMap<String, f64>,
    /// The run's settings, by key, for `summary.json`: what a run needs besides its parameter
    /// files and seed to be repeated.
    settings: serde_json::Map<String, serde_json::Value>,
    /// Parquet files written: (path, parameter set). (Behind a lock so that writing keeps
    /// taking `&self`.)
    parquet: Mutex<Vec<(PathBuf, String)>>,
    /// Plots written: (file stem, title).
    plots: Mutex<Vec<(String, String)>>,
    started: Instant,
    /// This process's processor time when the experiment started (s).
    cpu_started: Option<f64>,
    /// Further wall-clock figures for `timing.json` (a run's time split,
    /// [`time_split::TimeSplit`]), by key.
    timing_extra: serde_json::Map<String, serde_json::Value>,
}

#[derive(Serialize)]
struct Summary<'a> {
    experiment: &'a str,
    commit: String,
    crate_version: &'static str,
    seed: Option<u64>,
    params: Vec<(String, String)>,
    values: &'a [Value],
    numbers: &'a BTreeMap<String, f64>,
    #[serde(skip_serializing_if = "serde_json::Map::is_empty")]
    settings: &'a serde_json::Map<String, serde_json::Value>,
}

impl Experiment {
    /// Starts an experiment: prints its name and prepares its directories.
    pub fn start(name: &str) -> Self {
        // After `git_commit_in_background` the commit is still being read: the line that ends
        // the run names it.
        if commit::in_background() {
            eprintln!("[{name}] running");
        } else {
            eprintln!("[{name}] running (commit {})", git_commit());
        }
        Self {
            name: name.to_string(),
            dir: results_root().join(name),
            book_dir: book_generated_root().join(name),
            params: Vec::new(),
            seed: None,
            values: Vec::new(),
            numbers: BTreeMap::new(),
            settings: serde_json::Map::new(),
            parquet: Mutex::new(Vec::new()),
            plots: Mutex::new(Vec::new()),
            started: Instant::now(),
            cpu_started: cpu_time_s(),
            timing_extra: serde_json::Map::new(),
        }
    }

    /// Starts a run whose outputs all go to `dir` (data, plot, summary and the markdown
    /// snippet), for the `endstop` command-line tool.
    pub fn start_in(name: &str, dir: PathBuf) -> Self {
        let mut e = Self::start(name);
        e.book_dir = dir.clone();
        e.dir = dir;
        e
    }

    /// Records a parameter file used by this experiment under a set label.
    pub fn uses(&mut self, dev: &LoadedDevice, set: &str) {
        self.params
            .push((dev.file.clone(), set.to_string(), dev.text.clone()));
    }

    /// Loads the parameter file of `name` ([`load_device`]) and records it under the
    /// published set.
    pub fn load_published(&mut self, name: &str) -> Result<LoadedDevice> {
        let dev = load_device(name)?;
        self.uses(&dev, ParamSet::Published.label());
        Ok(dev)
    }

    /// Records our values for claims (scorecard input), as the paper layer's `claims`
    /// functions return them.
    pub fn claims(&mut self, values: impl IntoIterator<Item = Value>) {
        self.values.extend(values);
    }

    /// Runs the figure `F` on `setup` under a progress bar, records its claim values, and
    /// returns the run with them.
    pub fn run_figure<F: Figure>(
        &mut self,
        setup: &F::Setup,
        claims: &Claims,
    ) -> Result<(F::Run, Vec<Value>)> {
        let run = with_progress(F::work(setup), F::NAME, |tick| F::run(setup, tick))?;
        let values = F::claims(&run, claims)?;
        self.claims(values.clone());
        Ok((run, values))
    }

    /// Records a named number for the summary (not a claim).
    pub fn number(&mut self, key: &str, value: f64) {
        self.numbers.insert(key.to_string(), value);
    }

    /// Records a setting of the run under `key` for `summary.json` (with the seed and the
    /// parameter files, what repeats the run).
    pub fn setting(&mut self, key: &str, value: serde_json::Value) {
        self.settings.insert(key.to_string(), value);
    }

    /// Records a figure of time under `key` in `timing.json` (wall-clock content, kept out of
    /// `summary.json`).
    pub fn timing(&mut self, key: &str, value: serde_json::Value) {
        self.timing_extra.insert(key.to_string(), value);
    }

    /// Key-value metadata written into every Parquet file.
    fn metadata(&self, set: &str) -> Vec<(String, String)> {
        let mut kv = vec![
            ("experiment".to_string(), self.name.clone()),
            ("git_commit".to_string(), git_commit()),
            (
                "crate_version".to_string(),
                env!("CARGO_PKG_VERSION").to_string(),
            ),
            (
                "seed".to_string(),
                self.seed.map(|s| s.to_string()).unwrap_or("none".into()),
            ),
            ("params".to_string(), set.to_string()),
        ];
        for (file, label, text) in &self.params {
            kv.push((format!("param_file:{file}:{label}"), text.clone()));
        }
        kv
    }

    /// Writes a data frame to `<dir>/<stem>.parquet` with provenance metadata; `set` names the
    /// parameter set(s) in it (`published`, `calibrated`, `published+calibrated`).
    pub fn write_parquet(&self, stem: &str, df: &mut DataFrame, set: &str) -> Result<PathBuf> {
        let path = self.dir.join(format!("{stem}.parquet"));
        let mut buf = Vec::new();
        ParquetWriter::new(&mut buf)
            .with_key_value_metadata(Some(KeyValueMetadata::from_static(self.metadata(set))))
            .set_parallel(false)
            .finish(df)
            .with_context(|| format!("writing {}", path.display()))?;
        write_atomic(&path, &buf)?;
        lock(&self.parquet).push((path.clone(), set.to_string()));
        Ok(path)
    }

    /// Renders a figure as `<dir>/<name>.svg` and `.png`, and copies both for the book;
    /// [`Experiment::finish`] writes its caption (`<name>.figure.md`).
    pub fn write_plot<F: io::plot::Chart>(&self, fig: &F) -> Result<()> {
        let stem = self.name.clone();
        self.write_extra_plot(&stem, fig)
    }

    /// Renders an extra figure under another file stem (e.g. `fig08_convergence`), with its
    /// caption as [`Experiment::write_plot`].
    pub fn write_extra_plot<F: io::plot::Chart>(&self, stem: &str, fig: &F) -> Result<()> {
        self.write_rendered_plot(stem, RenderedPlot::of(fig)?)
    }

    /// Writes a figure rendered beforehand ([`RenderedPlot::of`], e.g. on a thread beside
    /// the data files' writing) as [`Experiment::write_extra_plot`] writes it.
    pub fn write_rendered_plot(&self, stem: &str, plot: RenderedPlot) -> Result<()> {
        let RenderedPlot { title, svg, png } = plot;
        // The `endstop` tool's runs write the book's copy into their own directory: once.
        let dirs = if self.book_dir == self.dir {
            vec![&self.dir]
        } else {
            vec![&self.dir, &self.book_dir]
        };
        for dir in dirs {
            write_atomic(&dir.join(format!("{stem}.svg")), svg.as_bytes())?;
            write_atomic(&dir.join(format!("{stem}.png")), &png)?;
        }
        lock(&self.plots).push((stem.to_string(), title));
        Ok(())
    }

    /// The book's Markdown for the plot `stem`: the image and a caption naming the program and
    /// paper-layer file that made it, the parameter files with their sets, and the Parquet
    /// files the experiment wrote, each linked (paths relative to the book's pages in
    /// `book/build/`). Deterministic: the same run gives the same bytes.
    pub fn figure_markdown(&self, stem: &str, title: &str) -> String {
        let link = |rel: &str| format!("[`{rel}`](../../{rel})");
        // The experiment's own binary where it has one (Figure 15's outputs are also written
        // by Figure 14's), else the program that ran (the `endstop` tool).
        let program = if root()
            .join(format!("experiments/{}.rs", self.name))
            .exists()
        {
            self.name.clone()
        } else {
            std::env::current_exe()
                .ok()
                .and_then(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
                .unwrap_or_else(|| self.name.clone())
        };
        let mut made_by = Vec::new();
        let source = format!("experiments/{program}.rs");
        if root().join(&source).exists() {
            made_by.push(link(&source));
        }
        let paper = format!("src/paper/figures/{program}.rs");
        if root().join(&paper).exists() {
            made_by.push(format!("the paper layer {}", link(&paper)));
        }
        let made_by = if made_by.is_empty() {
            format!("`{program}`")
        } else {
            made_by.join(" and ")
        };
        let rel = |p: &Path| -> String {
            p.strip_prefix(root())
                .unwrap_or(p)
                .to_string_lossy()
                .replace('\\', "/")
        };
        let params: Vec<String> = self
            .params
            .iter()
            .map(|(file, set, _)| format!("{} ({set} parameters)", link(file)))
            .collect();
        let data: Vec<String> = lock(&self.parquet)
            .iter()
            .map(|(path, set)| {
                let r = rel(path);
                if path.starts_with(root()) {
                    format!("{} ({set})", link(&r))
                } else {
                    format!("`{r}` ({set})")
                }
            })
            .collect();
        let image_dir = rel(&self.book_dir);
        let image_dir = image_dir
            .strip_prefix("book/src/")
            .unwrap_or(&image_dir)
            .to_string();
        let alt = if title.is_empty() { stem } else { title };
        let mut md = format!("![{alt}]({image_dir}/{stem}.svg)\n\n*Made by {made_by}");
        if !params.is_empty() {
            md.push_str(&format!(" from {}", params.join(", ")));
        }
        md.push_str(if data.is_empty() {
            "; no data file.*\n"
        } else {
            "; data: "
        });
        if !data.is_empty() {
            md.push_str(&data.join(", "));
            md.push_str(".*\n");
        }
        md
    }

    /// Writes the generated markdown the book includes (`book/src/generated/<name>/numbers.md`).
    pub fn write_numbers_md(&self, markdown: &str) -> Result<()> {
        write_atomic(&self.book_dir.join("numbers.md"), markdown.as_bytes())
    }

    /// Writes `summary.json` (deterministic: no wall-clock content), `timing.json`, and the
    /// caption of every plot (`<stem>.figure.md`, which the book includes in place of the
    /// image).
    pub fn finish(self) -> Result<()> {
        for (stem, title) in lock(&self.plots).iter() {
            write_atomic(
                &self.book_dir.join(format!("{stem}.figure.md")),
                self.figure_markdown(stem, title).as_bytes(),
            )?;
        }
        let summary = Summary {
            experiment: &self.name,
            commit: git_commit(),
            crate_version: env!("CARGO_PKG_VERSION"),
            seed: self.seed,
            params: self
                .params
                .iter()
                .map(|(f, l, _)| (f.clone(), l.clone()))
                .collect(),
            values: &self.values,
            numbers: &self.numbers,
            settings: &self.settings,
        };
        let json = serde_json::to_string_pretty(&summary)?;
        write_atomic(&self.dir.join("summary.json"), json.as_bytes())?;
        let secs = self.started.elapsed().as_secs_f64();
        // Provenance of the book's numbers: which program, parameter files, seed and commit
        // produced them, and how long it took (the book only; the data files stay free of
        // wall-clock content so that they are byte-identical between runs).
        let snippet = self.book_dir.join("numbers.md");
        if let Ok(mut md) = std::fs::read_to_string(&snippet) {
            let files: Vec<String> = self
                .params
                .iter()
                .map(|(f, l, _)| format!("`{f}` ({l})"))
                .collect();
            md.push_str(&format!(
                "\n*Produced by `{}` from {}; seed {}; commit `{}`; {:.2} s wall time.*\n",
                self.name,
                if files.is_empty() {
                    "no parameter file".to_string()
                } else {
                    files.join(", ")
                },
                self.seed.map_or("none".to_string(), |s| s.to_string()),
                git_commit(),
                secs
            ));
            write_atomic(&snippet, md.as_bytes())?;
        }
        // The processor time since the start: a process that writes two experiments (Figure
        // 14's writes Figure 15's from the same records) counts each second once.
        let cpu = cpu_time_s().zip(self.cpu_started).map(|(now, t0)| now - t0);
        let mut timing = serde_json::json!({
            "experiment": self.name,
            "wall_time_s": secs,
            "cpu_time_s": cpu,
        });
        if let Some(t) = timing.as_object_mut() {
            t.extend(self.timing_extra.clone());
        }
        write_atomic(
            &self.dir.join("timing.json"),
            serde_json::to_string_pretty(&timing)?.as_bytes(),
        )?;
        eprintln!(
            "[{}] wrote {} ({:.2} s, commit {})",
            self.name,
            self.dir.strip_prefix(root()).unwrap_or(&self.dir).display(),
            secs,
            git_commit()
        );
        Ok(())
    }
}

/// Locks a mutex, also after a panic elsewhere (the data are append-only lists).
fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// Formats a number with `sig` significant digits for generated prose.
pub fn fmt_sig(x: f64, sig: usize) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let mag = x.abs().log10().floor() as i32;
    let decimals = (sig as i32 - 1 - mag).max(0) as usize;
    format!("{x:.decimals$}")
}

/// Runs an experiment's body, printing the error chain and exiting non-zero on failure.
pub fn run_main(name: &str, body: impl FnOnce() -> Result<()>) {
    if let Err(e) = body() {
        eprintln!("[{name}] error: {e:#}");
        std::process::exit(1);
    }
}

#[cfg(test)]
mod caption_tests {
    use super::*;

    #[test]
    fn caption_shows_the_image_and_links_parameter_files_and_parquet() {
        let mut exp = Experiment::start("figxx");
        exp.params.push((
            "data/prototype2.toml".into(),
            ParamSet::Published.label().into(),
            String::new(),
        ));
        lock(&exp.parquet).push((
            root().join("data/results/figxx/figxx.parquet"),
            ParamSet::Published.label().into(),
        ));
        let md = exp.figure_markdown("figxx", "Figure XX");
        assert!(
            md.starts_with("![Figure XX](generated/figxx/figxx.svg)\n\n*Made by "),
            "{md}"
        );
        assert!(
            md.contains(
                "from [`data/prototype2.toml`](../../data/prototype2.toml) (published parameters)"
            ),
            "{md}"
        );
        assert!(
            md.ends_with(
                "; data: [`data/results/figxx/figxx.parquet`]\
                 (../../data/results/figxx/figxx.parquet) (published).*\n"
            ),
            "{md}"
        );
    }
}
