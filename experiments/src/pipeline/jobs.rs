//! The jobs `reproduce` runs: what each one executes, which data files it reads (for its
//! freshness key, see [`crate::pipeline::freshness`]), and when it runs.
//!
//! The module reads better whole: it is the one list of everything `reproduce` runs, in the
//! book's order, and a reader who looks for what a chapter's plot comes from finds its job
//! here beside the others; most of its length is that list's arguments, one per line.

use std::path::PathBuf;

/// When a job runs relative to the others.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Alone, before everything else (its output is read by later jobs).
    First,
    /// With the other jobs of this phase, `--jobs` at a time.
    Parallel,
    /// Alone, after everything else (a benchmark must not compete for the cores).
    Last,
}

/// One job of `reproduce`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Job {
    /// Name: the results directory under `data/results/` and the label in logs.
    pub name: &'static str,
    /// The binary next to `reproduce` that runs it.
    pub program: &'static str,
    /// Arguments (an `--out <results dir>` is appended for the `endstop` tool).
    pub args: &'static [&'static str],
    /// Data files it reads, relative to the project root (besides the code and
    /// `data/claims.toml`, which every job's key holds).
    pub reads: &'static [&'static str],
    /// True when it reads the calibrated prototype 1 (the `calibrate` job's artefact).
    pub reads_calibration: bool,
    /// When it runs.
    pub phase: Phase,
    /// True when its numbers feed the scorecard (its `summary.json` holds claim values).
    pub scored: bool,
    /// The other experiments it writes, each to its own results directory (`fig14` writes
    /// `fig15` from the same records).
    pub also: &'static [&'static str],
}

const P1: &str = "data/prototype1.toml";
const P2: &str = "data/prototype2.toml";
const EXAMPLE: &str = "data/examples/my_harvester.toml";
const FIG08_MEASURED: &str = "data/measured/fig08_paper.csv";
const PIEZO: &str = "data/examples/piezo_cantilever.toml";
const PIEZO_BRIDGE: &str = "data/examples/piezo_bridge.toml";
const EM: &str = "data/examples/em_asymmetric.toml";
const RIGID: &str = "data/examples/rigid_restitution.toml";
const RECORD: &str = "data/examples/machine_record.wav";
const HARDENING: &str = "data/examples/hardening_em.toml";
const BISTABLE: &str = "data/examples/bistable_stops_em.toml";
const DESIGN_INTERFACES: &str = "data/design/interfaces.toml";
const EM_BRIDGE: &str = "data/examples/em_bridge.toml";
const UPCONVERTER: &str = "data/examples/upconverter.toml";
const UP_DIRECT: &str = "data/upconversion/direct.toml";
const UP_GENERATOR: &str = "data/upconversion/generator_alone.toml";
const UPCONVERTER_BRIDGE: &str = "data/upconversion/upconverter_bridge.toml";
const UP_DIRECT_BRIDGE: &str = "data/upconversion/direct_bridge.toml";

/// A job of the up-conversion chapter ([`crate::pipeline::upconversion`]): a sweep of a device
/// over 10-40 Hz in 0.5 Hz steps at an RMS acceleration (g), or its charging from 0 to 0.5 V
/// at 20 Hz and 0.2 g.
macro_rules! up_job {
    (sweep $name:literal, $device:expr, $g:literal) => {
        tool_run(
            $name,
            &[
                "sweep",
                "--device",
                $device,
                "--from",
                "10",
                "--to",
                "40",
                "--step",
                "0.5",
                "--accel-rms-g",
                $g,
            ],
            &[$device],
        )
    };
    (charge $name:literal, $device:expr) => {
        tool_run(
            $name,
            &[
                "charge",
                "--device",
                $device,
                "--freq-hz",
                "20",
                "--accel-rms-g",
                "0.2",
                "--target-v",
                "0.5",
            ],
            &[$device],
        )
    };
}

/// A job of the design chapter's example devices: `endstop design` on `$device` at one
/// frequency (Hz) and RMS acceleration (g) over the ranges, with the options after them.
macro_rules! design_job {
    ($name:literal, $device:expr, $freq:literal, $g:literal, [$($arg:expr),* $(,)?]) => {
        tool_run(
            $name,
            &["design", "--device", $device, "--freq-hz", $freq, "--accel-rms-g", $g, $($arg),*],
            &[$device],
        )
    };
}

/// A run of the `endstop` tool for the "Model your own harvester" chapter: `own_device_<stem>`,
/// its arguments, and the files it reads.
const fn tool_run(
    name: &'static str,
    args: &'static [&'static str],
    reads: &'static [&'static str],
) -> Job {
    Job {
        name,
        program: "endstop",
        args,
        reads,
        reads_calibration: false,
        phase: Phase::Parallel,
        scored: false,
        also: &[],
    }
}

const fn experiment(name: &'static str, reads: &'static [&'static str], cal: bool) -> Job {
    Job {
        name,
        program: name,
        args: &[],
        reads,
        reads_calibration: cal,
        phase: Phase::Parallel,
        scored: true,
        also: &[],
    }
}

/// The calibration of prototype 1: runs first; fig08, fig09, fig11, fig12 and bench read it.
pub const CALIBRATE: &str = "calibrate";
/// The ngspice cross-check: ngspice's numbers from their recording (CI runs ngspice again).
pub const CROSSCHECK: &str = "crosscheck";
/// The benchmark (its short form, `bench --quick`): runs last and alone.
pub const BENCH: &str = "bench";

/// Every job, in the order of the paper and then the extras.
pub const JOBS: &[Job] = &[
    Job {
        name: CALIBRATE,
        program: CALIBRATE,
        args: &[],
        reads: &[P1],
        reads_calibration: false,
        phase: Phase::First,
        scored: false,
        also: &[],
    },
    experiment("fig05", &[P1, P2], false),
    experiment("table3", &[P1, P2], false),
    experiment("fig08", &[P1], true),
    experiment("fig09", &[P1], true),
    experiment("fig10", &[], false),
    experiment("fig11", &[P1], true),
    experiment("fig12", &[P1], true),
    experiment("fig13", &[P2], false),
    Job {
        also: &["fig15"],
        ..experiment("fig14", &[P2], false)
    },
    Job {
        name: "response",
        program: "response",
        args: &[],
        reads: &[P1, P2],
        reads_calibration: true,
        phase: Phase::Parallel,
        scored: false,
        also: &[],
    },
    tool_run(
        "own_device_sweep",
        &[
            "sweep",
            "--device",
            EXAMPLE,
            "--from",
            "500",
            "--to",
            "800",
            "--accel-rms-g",
            "0.3",
        ],
        &[EXAMPLE],
    ),
    tool_run(
        "own_device_random",
        &[
            "random",
            "--device",
            EXAMPLE,
            "--psd",
            "1e-4",
            "--records",
            "4",
        ],
        &[EXAMPLE],
    ),
    tool_run(
        "own_device_piezo_response",
        &[
            "response",
            "--device",
            PIEZO,
            "--from",
            "100",
            "--to",
            "200",
            "--accel-rms-g",
            "0.5",
            "--sweep-rate",
            "5",
        ],
        &[PIEZO],
    ),
    tool_run(
        "own_device_piezo_bridge_response",
        &[
            "response",
            "--device",
            PIEZO_BRIDGE,
            "--from",
            "110",
            "--to",
            "300",
            "--step",
            "2",
            "--accel-rms-g",
            "1",
        ],
        &[PIEZO_BRIDGE],
    ),
    tool_run(
        "own_device_piezo_bridge_random",
        &[
            "random",
            "--device",
            PIEZO_BRIDGE,
            "--psd",
            "1e-4",
            "--records",
            "4",
            "--duration-s",
            "4",
        ],
        &[PIEZO_BRIDGE],
    ),
    tool_run(
        "own_device_piezo_random",
        &[
            "random",
            "--device",
            PIEZO,
            "--psd",
            "1e-3",
            "--records",
            "4",
            "--duration-s",
            "4",
        ],
        &[PIEZO],
    ),
    tool_run(
        "own_device_piezo_measured",
        &[
            "random",
            "--device",
            PIEZO,
            "--accel-file",
            RECORD,
            "--accel-scale",
            "20",
        ],
        &[PIEZO, RECORD],
    ),
    tool_run(
        "own_device_em_response",
        &[
            "response",
            "--device",
            EM,
            "--from",
            "44",
            "--to",
            "60",
            "--accel-rms-g",
            "0.2",
        ],
        &[EM],
    ),
    tool_run(
        "own_device_em_random",
        &[
            "random",
            "--device",
            EM,
            "--psd",
            "1e-3",
            "--records",
            "4",
            "--duration-s",
            "4",
        ],
        &[EM],
    ),
    tool_run(
        "own_device_rigid_response",
        &[
            "response",
            "--device",
            RIGID,
            "--from",
            "550",
            "--to",
            "750",
            "--accel-rms-g",
            "0.3",
            "--step-study",
        ],
        &[RIGID],
    ),
    tool_run(
        "own_device_rigid_random",
        &[
            "random",
            "--device",
            RIGID,
            "--psd",
            "1e-4",
            "--records",
            "4",
            "--duration-s",
            "4",
        ],
        &[RIGID],
    ),
    tool_run(
        "own_device_springs_hardening_response",
        &[
            "response",
            "--device",
            HARDENING,
            "--from",
            "80",
            "--to",
            "140",
            "--step",
            "1",
            "--accel-rms-g",
            "0.1",
        ],
        &[HARDENING],
    ),
    tool_run(
        "own_device_springs_hardening_random",
        &[
            "random",
            "--device",
            HARDENING,
            "--psd",
            "1e-4",
            "--records",
            "8",
            "--duration-s",
            "10",
        ],
        &[HARDENING],
    ),
    tool_run(
        "own_device_springs_bistable_response",
        &[
            "response",
            "--device",
            BISTABLE,
            "--from",
            "20",
            "--to",
            "70",
            "--step",
            "1",
            "--accel-rms-g",
            "0.5",
        ],
        &[BISTABLE],
    ),
    tool_run(
        "own_device_springs_bistable_basins",
        &[
            "basins",
            "--device",
            BISTABLE,
            "--freq",
            "55",
            "--accel-rms-g",
            "0.5",
            "--cells",
            "31",
        ],
        &[BISTABLE],
    ),
    tool_run(
        "own_device_springs_bistable_random_low",
        &[
            "random",
            "--device",
            BISTABLE,
            "--psd",
            "1e-4",
            "--records",
            "8",
            "--duration-s",
            "10",
        ],
        &[BISTABLE],
    ),
    tool_run(
        "own_device_springs_bistable_random",
        &[
            "random",
            "--device",
            BISTABLE,
            "--psd",
            "3e-4",
            "--records",
            "8",
            "--duration-s",
            "10",
        ],
        &[BISTABLE],
    ),
    tool_run(
        "own_device_springs_bistable_random_high",
        &[
            "random",
            "--device",
            BISTABLE,
            "--psd",
            "1e-3",
            "--records",
            "8",
            "--duration-s",
            "10",
        ],
        &[BISTABLE],
    ),
    // The up-conversion chapter: the up-converter against one mass at 20 Hz and against its
    // generator alone, at two levels, and the charging of the first two.
    up_job!(sweep "own_device_upconversion_upconverter_low", UPCONVERTER, "0.05"),
    up_job!(sweep "own_device_upconversion_direct_low", UP_DIRECT, "0.05"),
    up_job!(sweep "own_device_upconversion_generator_low", UP_GENERATOR, "0.05"),
    up_job!(sweep "own_device_upconversion_upconverter_high", UPCONVERTER, "0.2"),
    up_job!(sweep "own_device_upconversion_direct_high", UP_DIRECT, "0.2"),
    up_job!(sweep "own_device_upconversion_generator_high", UP_GENERATOR, "0.2"),
    up_job!(charge "own_device_upconversion_charge_upconverter", UPCONVERTER_BRIDGE),
    up_job!(charge "own_device_upconversion_charge_direct", UP_DIRECT_BRIDGE),
    // The design chapter's power against the stop gap, per interface, with the load chosen.
    tool_run(
        "own_device_design_gap",
        &[
            "design",
            "--device",
            PIEZO_BRIDGE,
            "--range",
            "stops.upper.gap_m=4e-5..1.6e-4",
            "--range",
            "load.resistance_ohm=3e3..1e6",
            "--freq-hz",
            "120",
            "--accel-rms-g",
            "0.3",
            "--interfaces",
            DESIGN_INTERFACES,
            "--max-impact-speed-m-s",
            "0.015",
        ],
        &[PIEZO_BRIDGE, DESIGN_INTERFACES],
    ),
    // The design chapter's example devices, each over its load (or its battery's voltage) and
    // its stop gap where it has one, at its resonance.
    design_job!(
        "own_device_design_cantilever",
        PIEZO,
        "120",
        "0.3",
        [
            "--range",
            "load.resistance_ohm=3e3..3e5",
            "--range",
            "stops.upper.gap_m=3e-5..3e-4",
            "--max-impact-speed-m-s",
            "0.08",
        ]
    ),
    design_job!(
        "own_device_design_em",
        EM,
        "50",
        "0.2",
        [
            "--range",
            "load.resistance_ohm=40..4000",
            "--range",
            "stops.upper.gap_m=6e-4..2e-3",
            "--max-contact-force-n",
            "0.02",
        ]
    ),
    design_job!(
        "own_device_design_em_bridge",
        EM_BRIDGE,
        "50",
        "0.2",
        [
            "--range",
            "interface.load.voltage_v=0.5..5",
            "--range",
            "stops.upper.gap_m=6e-4..2e-3",
            "--max-contact-force-n",
            "0.02",
        ]
    ),
    design_job!(
        "own_device_design_electrostatic",
        EXAMPLE,
        "616",
        "0.3",
        [
            "--range",
            "load.resistance_ohm=1e6..1e8",
            "--range",
            "stops.both.gap_m=5e-6..1.5e-5",
        ]
    ),
    design_job!(
        "own_device_design_hardening",
        HARDENING,
        "110",
        "0.1",
        ["--range", "load.resistance_ohm=10..1000",]
    ),
    design_job!(
        "own_device_design_bistable",
        BISTABLE,
        "55",
        "0.5",
        [
            "--range",
            "load.resistance_ohm=10..1000",
            "--range",
            "stops.both.gap_m=6e-4..1.2e-3",
            "--max-impact-speed-m-s",
            "0.15",
        ]
    ),
    Job {
        name: "own_device_fit",
        program: "endstop",
        args: &[
            "fit",
            "--device",
            P1,
            "--up-sweep",
            FIG08_MEASURED,
            "--free",
            "stops.both.gap_m=4e-6..9.9e-6",
            "--free",
            "stops.both.damping_n_s_per_m=0.1..20",
        ],
        reads: &[P1, FIG08_MEASURED],
        reads_calibration: false,
        phase: Phase::Parallel,
        scored: false,
        also: &[],
    },
    Job {
        name: "validation",
        program: "validation",
        args: &[],
        reads: &[
            "data/validation/piezo_linear.toml",
            "data/validation/em_linear.toml",
            "data/validation/em_linear_no_inductance.toml",
            "data/validation/grazing_rigid.toml",
            "data/validation/random_linear_piezo.toml",
            "data/validation/random_hertz_em.toml",
            "data/validation/random_restitution.toml",
            "data/validation/nlvib_sdof.toml",
            "data/validation/random_duffing_em.toml",
            "data/validation/random_bistable_stops_em.toml",
            "data/validation/random_linear_asym_stops_em.toml",
            "data/validation/kramers_bistable_em.toml",
            "data/validation/kramers_light_em.toml",
            "data/references/rigid_band_limit/cells.csv",
            "data/validation/nlvib_duffing.toml",
            "data/references/nlvib_duffing/nlvib_hb_H01.csv",
            "data/references/nlvib_duffing/nlvib_hb_H03.csv",
            "data/references/nlvib_duffing/nlvib_hb_H05.csv",
            "data/references/nlvib_duffing/nlvib_hb_H07.csv",
            "data/references/nlvib_duffing/nlvib_hb_H10.csv",
            "data/references/nlvib_duffing/nlvib_hb_H15.csv",
            "data/validation/piezo_bridge.toml",
            "data/references/nlvib/nlvib_hb_H01.csv",
            "data/references/nlvib/nlvib_hb_H03.csv",
            "data/references/nlvib/nlvib_hb_H05.csv",
            "data/references/nlvib/nlvib_hb_H10.csv",
            "data/references/nlvib/nlvib_hb_H20.csv",
            "data/references/nlvib/nlvib_hb_H40.csv",
            "data/references/nlvib/nlvib_folds.csv",
            "data/references/nlvib/shooting_branch.csv",
            "data/references/nlvib/shooting_folds.csv",
            "data/references/nlvib/nlvib_aft_check_H40.csv",
            "data/references/nlvib/fine_H05/nlvib_folds.csv",
        ],
        reads_calibration: false,
        phase: Phase::Parallel,
        scored: false,
        also: &[],
    },
    Job {
        name: "interfaces",
        program: "interfaces",
        args: &[],
        reads: &[
            "data/examples/piezo_bridge.toml",
            "data/examples/em_bridge.toml",
            "data/examples/piezo_cantilever.toml",
        ],
        reads_calibration: false,
        phase: Phase::Parallel,
        scored: false,
        also: &[],
    },
    Job {
        name: CROSSCHECK,
        program: CROSSCHECK,
        args: &[],
        reads: &[
            P1,
            P2,
            "data/validation/piezo_bridge_spice.toml",
            "data/validation/piezo_bridge_spice_stop.toml",
            "data/recorded/ngspice/crosscheck.json",
        ],
        reads_calibration: false,
        phase: Phase::Parallel,
        scored: false,
        also: &[],
    },
    // The short benchmark: `just bench` runs the whole one.
    Job {
        name: BENCH,
        program: BENCH,
        args: &["--quick"],
        reads: &[
            P1,
            P2,
            BISTABLE,
            "data/recorded/bench/full.md",
            "data/recorded/bench/interfaces.md",
        ],
        reads_calibration: true,
        phase: Phase::Last,
        scored: false,
        also: &[],
    },
];

/// The job of this name.
pub fn job(name: &str) -> Option<&'static Job> {
    JOBS.iter().find(|j| j.name == name)
}

/// The job that writes the experiment `name` (its own, or one it writes besides).
pub fn job_writing(name: &str) -> Option<&'static Job> {
    JOBS.iter().find(|j| j.experiments().any(|e| e == name))
}

/// Every experiment the jobs write, in the order of [`JOBS`].
pub fn experiment_names() -> Vec<&'static str> {
    JOBS.iter().flat_map(Job::experiments).collect()
}

/// The results directory of an experiment (under the results root).
pub fn experiment_dir(name: &str) -> PathBuf {
    crate::results_root().join(name)
}

impl Job {
    /// The experiments it writes: its own, then [`Job::also`].
    pub fn experiments(&self) -> impl Iterator<Item = &'static str> {
        std::iter::once(self.name).chain(self.also.iter().copied())
    }

    /// The experiments it writes with their results directories.
    pub fn outputs(&self) -> impl Iterator<Item = (&'static str, PathBuf)> + '_ {
        std::iter::once((self.name, self.dir()))
            .chain(self.also.iter().map(|e| (*e, experiment_dir(e))))
    }

    /// True for a run of the `endstop` tool (its outputs all go to its results directory).
    pub fn is_tool_run(&self) -> bool {
        self.program == "endstop"
    }

    /// Its results directory (the calibration's is its artefact's directory).
    pub fn dir(&self) -> PathBuf {
        if self.name == CALIBRATE {
            crate::reports::calibration_io::calibration_dir()
        } else {
            crate::results_root().join(self.name)
        }
    }

    /// The arguments to run it with.
    pub fn command_args(&self) -> Vec<String> {
        let mut a: Vec<String> = self.args.iter().map(|s| s.to_string()).collect();
        if self.is_tool_run() {
            a.push("--out".into());
            a.push(self.dir().display().to_string());
        }
        a
    }

    /// The output whose presence (with `summary.json`) says a past run completed.
    pub fn completion_marker(&self) -> PathBuf {
        if self.name == CALIBRATE {
            self.dir().join(crate::reports::calibration_io::DEVICE_FILE)
        } else if self.is_tool_run() {
            self.dir().join("numbers.md")
        } else {
            crate::book_generated_root()
                .join(self.name)
                .join("numbers.md")
        }
    }
}

/// Why the paper deviates: the sensitivity study and multi-claim calibration (`just deviations`): cached by content hash
/// like the jobs of [`JOBS`], but not one of them (it does not fit `reproduce`'s budget).
pub const DEVIATIONS: Job = Job {
    name: "deviations",
    program: "deviations",
    args: &[],
    reads: &[P1, P2, "data/sensitivity.toml"],
    reads_calibration: false,
    phase: Phase::Last,
    scored: false,
    also: &[],
};
