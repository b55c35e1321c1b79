//! Property tests of bad input: generated device files, measured records and `endstop`
//! command lines (every subcommand) never make the library or the tool panic. A device file or a record either
//! loads or is refused with an error that names its source; a command line either runs or
//! exits with a message, never a panic, an abort, or a run past its time limit.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use endstop::device::Device;
use endstop::drive::measured::{MeasuredRecord, Position};
use endstop_experiments::reports::measured_io::read_csv;
use proptest::prelude::*;
use proptest::sample::select;

const BIN: &str = env!("CARGO_BIN_EXE_endstop");

/// The device files a generated file starts from: the paper's two and every example.
const DEVICE_FILES: [&str; 8] = [
    "data/prototype1.toml",
    "data/prototype2.toml",
    "data/examples/my_harvester.toml",
    "data/examples/piezo_cantilever.toml",
    "data/examples/em_asymmetric.toml",
    "data/examples/rigid_restitution.toml",
    "data/examples/piezo_bridge.toml",
    "data/examples/em_bridge.toml",
];

fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(rel)
}

/// Every leaf of a TOML table as a dotted path.
fn leaves(t: &toml::Table, prefix: &str, out: &mut Vec<String>) {
    for (k, v) in t {
        let path = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        match v {
            toml::Value::Table(sub) => leaves(sub, &path, out),
            _ => out.push(path),
        }
    }
}

/// The table holding a dotted path's leaf, and the leaf's key.
fn parent_mut<'a>(t: &'a mut toml::Table, path: &str) -> (&'a mut toml::Table, String) {
    let mut parts: Vec<&str> = path.split('.').collect();
    let key = parts.pop().unwrap().to_string();
    let mut cur = t;
    for p in parts {
        cur = cur.get_mut(p).unwrap().as_table_mut().unwrap();
    }
    (cur, key)
}

/// One edit of a device file.
#[derive(Debug, Clone)]
enum Edit {
    /// A leaf takes another value.
    Set(usize, toml::Value),
    /// A leaf is removed.
    Remove(usize),
    /// A key nobody knows is added beside a leaf.
    Unknown(usize),
}

fn value() -> impl Strategy<Value = toml::Value> {
    prop_oneof![
        any::<f64>().prop_map(toml::Value::Float),
        select(vec![
            0.0,
            -0.0,
            -1.0,
            1e-300,
            1e300,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            0.5,
            1.0,
            1.5,
            2.0
        ])
        .prop_map(toml::Value::Float),
        any::<i64>().prop_map(toml::Value::Integer),
        "[a-z_]{0,12}".prop_map(toml::Value::String),
        any::<bool>().prop_map(toml::Value::Boolean),
        Just(toml::Value::Array(vec![])),
    ]
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        4 => (any::<usize>(), value()).prop_map(|(i, v)| Edit::Set(i, v)),
        1 => any::<usize>().prop_map(Edit::Remove),
        1 => any::<usize>().prop_map(Edit::Unknown),
    ]
}

/// A device file: one of [`DEVICE_FILES`] with up to four edits.
fn device_text() -> impl Strategy<Value = String> {
    (0..DEVICE_FILES.len(), prop::collection::vec(edit(), 0..4)).prop_map(|(f, edits)| {
        let text = std::fs::read_to_string(repo(DEVICE_FILES[f])).unwrap();
        let mut table: toml::Table = toml::from_str(&text).unwrap();
        for e in edits {
            let mut paths = Vec::new();
            leaves(&table, "", &mut paths);
            if paths.is_empty() {
                break;
            }
            let pick = |i: usize| paths[i % paths.len()].clone();
            match e {
                Edit::Set(i, v) => {
                    let (t, k) = parent_mut(&mut table, &pick(i));
                    t.insert(k, v);
                }
                Edit::Remove(i) => {
                    let (t, k) = parent_mut(&mut table, &pick(i));
                    t.remove(&k);
                }
                Edit::Unknown(i) => {
                    let (t, _) = parent_mut(&mut table, &pick(i));
                    t.insert("surplus_key_m".into(), toml::Value::Float(1.0));
                }
            }
        }
        toml::to_string(&table).unwrap()
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    /// A generated device file loads, or is refused naming the file; a loaded one gives the
    /// linear quantities every study starts from without a panic.
    #[test]
    fn a_device_file_loads_or_is_refused_naming_it(text in device_text()) {
        match Device::from_toml_str(&text, "gen.toml") {
            Ok(d) => {
                let f0 = endstop::physics::linear::open_circuit_resonance_hz(&d);
                let _ = endstop::physics::linear::open_circuit_qm(&d);
                let _ = endstop::study::record::transient_s(&d);
                let lin = endstop::physics::linear::LinearResponse::of(&d);
                let _ = lin.output_psd_w_per_hz(1.0, f0);
                // Its assembled model (behind an interface circuit, too), and its right-hand
                // side and guards at rest; a device whose parts do not combine is refused with
                // an error.
                let a = endstop::drive::Excitation::accel(&endstop::drive::Sine::from_rms_g(0.1, f0), 0.0);
                let _: Result<(), endstop::physics::harvester::AssemblyError> =
                    endstop::with_harvester!(&d, |m| {
                        use endstop::model::Model;
                        let y = m.rest_state();
                        let mode = m.mode_of(&y);
                        let _ = m.rhs(mode, &y, a);
                        let mut g = vec![0.0; m.guard_count()];
                        m.guards(mode, &y, || a, &mut g);
                        Ok(())
                    });
            }
            Err(e) => prop_assert!(e.to_string().contains("gen.toml"), "{e}"),
        }
    }

    /// Text that is not a device file at all is refused naming the file.
    #[test]
    fn any_text_is_refused_or_loads(text in "\\PC{0,200}") {
        if let Err(e) = Device::from_toml_str(&text, "gen.toml") {
            prop_assert!(e.to_string().contains("gen.toml"), "{e}");
        }
    }

    /// A generated CSV record (any header, steps and values) loads, or is refused naming the
    /// file; a loaded one checks any band and resamples to any rate without a panic.
    #[test]
    fn a_csv_record_loads_or_is_refused_naming_it(
        header in select(vec!["time_s,accel_g", "time_ms,accel_m_per_s2", "t,a", "time_s",
                              "accel_g,time_s", "", "time_s,time_s"]),
        n in 0usize..80,
        dt in select(vec![1e-3, 0.0, -1e-3, 1e-300, f64::NAN, 1e300]),
        jitter in prop::collection::vec(select(vec![0.0, 0.0, 0.0, 0.5, -2.0, f64::NAN]), 80),
        accel in prop::collection::vec(select(vec![0.0, 1.0, -3.0, f64::NAN, f64::INFINITY, 1e308]), 80),
        band in (select(vec![1.0, 0.0, -1.0, f64::NAN, 1e9]), select(vec![10.0, 100.0, 0.5, f64::INFINITY])),
        rate in select(vec![1e3, 0.0, -1.0, f64::NAN, 1e-9, 2e3]),
    ) {
        let mut text = format!("{header}\n");
        for k in 0..n {
            let t = (k as f64 + jitter[k]) * dt;
            text.push_str(&format!("{t},{}\n", accel[k]));
        }
        match read_csv(&text, "rec.csv") {
            Ok(r) => {
                let _ = r.check_band(band.0, band.1, 0.01);
                let _ = r.resampled(rate);
            }
            Err(e) => prop_assert!(e.to_string().contains("rec.csv"), "{e}"),
        }
    }

    /// Rows given directly to the record check (any positions, times and values).
    #[test]
    fn rows_load_or_are_refused_naming_the_source(
        rows in prop::collection::vec((any::<f64>(), any::<f64>()), 0..64),
    ) {
        let rows: Vec<(Position, f64, f64)> = rows
            .into_iter()
            .enumerate()
            .map(|(k, (t, a))| (Position::Line(k + 2), t, a))
            .collect();
        if let Err(e) = MeasuredRecord::from_times("rows", &rows) {
            prop_assert!(e.to_string().contains("rows"), "{e}");
        }
    }
}

/// An option with a value from a pool whose first value is valid (and cheap): that value in
/// three cases of four, so that whole command lines run as well as fail, another of the pool
/// (mostly invalid) otherwise, or rarely absent.
fn opt(name: &'static str, pool: Vec<&'static str>) -> impl Strategy<Value = Vec<String>> {
    let valid = pool[0];
    let value = prop_oneof![3 => Just(valid), 1 => select(pool)];
    prop::option::weighted(0.95, value)
        .prop_map(move |v| v.map_or_else(Vec::new, |v| vec![name.to_string(), v.to_string()]))
}

/// A command line of the `endstop` tool: every subcommand (`sweep`, `response`, `random`,
/// `fit`, `charge`, `basins`) and an unknown one, a device (an example, a missing file, a
/// directory, a file that is not TOML, a device the subcommand does not take) and each option
/// valid, invalid or absent.
fn command_line() -> impl Strategy<Value = Vec<String>> {
    let device = select(vec![
        "data/examples/piezo_cantilever.toml",
        "data/examples/em_asymmetric.toml",
        "data/examples/rigid_restitution.toml",
        "data/no_such_device.toml",
        "data",
        "data/examples/machine_record.wav",
    ]);
    let range = (
        opt(
            "--from",
            vec!["100", "600", "45", "0", "-1", "nan", "1e300", "x", ""],
        ),
        opt("--to", vec!["110", "610", "50", "1e-300", "inf", "100"]),
        opt(
            "--step",
            vec!["5", "2", "0", "-2", "1e-300", "1e300", "nan"],
        ),
        opt(
            "--accel-rms-g",
            vec!["0.3", "0", "-1", "nan", "1e300", "1e-300"],
        ),
        prop::option::weighted(0.2, select(vec!["10", "-5", "nan", "1e300"]))
            .prop_map(|v| v.map_or_else(Vec::new, |v| vec!["--bias-v".into(), v.into()])),
    );
    let random = (
        opt("--psd", vec!["1e-4", "0", "-1", "nan", "1e300", "x"]),
        opt(
            "--records",
            vec!["1", "0", "-1", "x", "18446744073709551616"],
        ),
        opt(
            "--duration-s",
            vec!["0.2", "0", "-1", "nan", "1e-9", "1e12"],
        ),
        opt("--seed", vec!["0", "18446744073709551615", "-1"]),
        prop::option::weighted(
            0.3,
            select(vec![
                "data/examples/machine_record.wav",
                "data/examples/piezo_cantilever.toml",
                "data/no_such_record.csv",
            ]),
        )
        .prop_map(|v| v.map_or_else(Vec::new, |v| vec!["--accel-file".into(), v.into()])),
        opt("--accel-scale", vec!["20", "0", "-1", "nan", "1e300"]),
        opt("--sample-rate-hz", vec!["1e5", "1e15", "0", "nan", "10"]),
    );
    // `fit`: measured files (a small valid one first) and free parameters, valid or not.
    let fit = (
        opt(
            "--up-sweep",
            vec![
                "experiments/tests/fixtures/fit_small_up.csv",
                "data/no_such_sweep.csv",
                "data",
                "data/examples/machine_record.wav",
                "data/examples/piezo_cantilever.toml",
            ],
        ),
        prop::option::weighted(
            0.2,
            select(vec![
                "experiments/tests/fixtures/fit_small_up.csv",
                "data/no_such_sweep.csv",
            ]),
        )
        .prop_map(|v| v.map_or_else(Vec::new, |v| vec!["--down-sweep".into(), v.into()])),
        opt(
            "--free",
            vec![
                "mechanics.damping_n_s_per_m=0.01..1",
                "stops.upper.gap_m=0.05e-3..0.3e-3",
                "stops.both.gap_m=4e-6..9.9e-6",
                "mechanics.no_such_key=1..2",
                "stops.upper.gap_m=0.3e-3..0.05e-3",
                "stops.upper.gap_m=nan..1",
                "drive.accel_scale=0..2",
                "drive.accel_scale=0.5..2",
                "x",
                "",
            ],
        ),
        prop::option::weighted(
            0.3,
            select(vec![
                "drive.accel_scale=0.5..2",
                "mechanics.damping_n_s_per_m=0.01..1",
                "stops.upper.damping_n_s_per_m=1e300..1e301",
            ]),
        )
        .prop_map(|v| v.map_or_else(Vec::new, |v| vec!["--free".into(), v.into()])),
    );
    // `charge`: a device with an interface (the examples with a bridge), one without, a
    // missing file; the sine, the storage's start and target voltages, the ramp and the
    // longest simulated time, each valid, invalid or absent.
    let charge = (
        select(vec![
            "data/examples/piezo_bridge.toml",
            "data/examples/em_bridge.toml",
            "data/examples/piezo_cantilever.toml",
            "data/no_such_device.toml",
        ]),
        opt("--freq-hz", vec!["120", "0", "-1", "nan", "1e300", "x"]),
        opt("--accel-rms-g", vec!["0.3", "0", "-1", "nan", "1e300"]),
        opt("--start-v", vec!["0", "-1", "nan", "1e300", "inf"]),
        opt("--target-v", vec!["0.2", "0", "-1", "nan", "1e300", "inf"]),
        opt("--ramp-periods", vec!["0", "10", "-1", "nan", "1e300"]),
        opt("--t-max-s", vec!["0.2", "0", "-1", "nan", "1e9", "inf"]),
    );
    // `basins`: the bistable example (a valid grid is 5 by 5 cells of at most 50 periods),
    // a device without wells, a missing file; the sine, the grid, the ranges, the settling and
    // the seeds, each valid, invalid or absent.
    let basins = (
        select(vec![
            "data/examples/bistable_stops_em.toml",
            "data/examples/piezo_cantilever.toml",
            "data/no_such_device.toml",
        ]),
        opt("--freq", vec!["30", "0", "-1", "nan", "1e300"]),
        opt("--accel-rms-g", vec!["0.05", "0", "-1", "nan", "1e300"]),
        // 502 is past the largest grid; the largest itself (501) is not generated: with valid
        // settings it is a run of tens of minutes, past RUN_LIMIT.
        opt("--cells", vec!["5", "0", "1", "502", "-1", "x"]),
        opt(
            "--x-range",
            vec![
                "-7.5e-4,7.5e-4",
                "1,-1",
                "nan,1",
                "0,0",
                "-1e300,1e300",
                "1",
            ],
        ),
        opt(
            "--v-range",
            vec!["-0.1,0.1", "0.1,-0.1", "nan,0", "-inf,inf"],
        ),
        opt("--max-periods", vec!["50", "0", "1000000000", "-1"]),
        opt("--settle-tol", vec!["1e-3", "0", "-1", "nan", "1e300"]),
        opt("--seeds-per-side", vec!["2", "0", "100", "-1"]),
    );
    (
        select(vec![
            "sweep", "response", "random", "random", "fit", "fit", "charge", "charge", "basins",
            "basins", "bogus",
        ]),
        device,
        range,
        random,
        fit,
        (charge, basins),
        any::<bool>(),
    )
        .prop_map(|(study, device, r, x, f, (c, b), surplus)| {
            let device = match study {
                "charge" => c.0,
                "basins" => b.0,
                _ => device,
            };
            let mut args = vec![study.to_string(), "--device".into(), device.into()];
            if study == "fit" {
                for o in [f.0, f.1, f.2, f.3] {
                    args.extend(o);
                }
            } else if study == "random" {
                for o in [x.0, x.1, x.2, x.3, x.4, x.5, x.6, r.4] {
                    args.extend(o);
                }
            } else if study == "charge" {
                for o in [c.1, c.2, c.3, c.4, c.5, c.6] {
                    args.extend(o);
                }
            } else if study == "basins" {
                for o in [b.1, b.2, b.3, b.4, b.5, b.6, b.7, b.8, r.4] {
                    args.extend(o);
                }
            } else {
                for o in [r.0, r.1, r.2, r.3, r.4] {
                    args.extend(o);
                }
                // Steps taken at once: the default phase-continuous ramps move at a rate set by
                // the half-power width, so a valid sweep far from resonance (e.g. 100-610 Hz on
                // the 50 Hz electromagnetic example) takes minutes, past RUN_LIMIT. The ramps
                // are exercised by the library's sweep tests and the book's jobs.
                args.push("--steps-at-once".into());
            }
            if surplus {
                args.push("--surplus".into());
            }
            args
        })
}

/// How long one generated command may run: its valid runs are a few sweep steps, a short
/// record, a charge over 0.2 s or a 5 by 5 basin grid, seconds each.
const RUN_LIMIT: Duration = Duration::from_secs(120);

proptest! {
    // A fixed seed: each command runs for up to RUN_LIMIT, so the cases are the same on
    // every run (proptest draws a fresh seed by default).
    #![proptest_config(ProptestConfig {
        cases: 48,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0),
        ..ProptestConfig::default()
    })]

    /// A generated command line runs or exits with a message: exit status 0, 1 (a named
    /// error) or 2 (a usage error), never a panic (101) or a signal, within [`RUN_LIMIT`].
    #[test]
    fn a_command_line_runs_or_exits_with_a_message(args in command_line()) {
        let out = std::env::temp_dir().join(format!("endstop-props-{}", std::process::id()));
        let log = out.with_extension("stderr");
        let mut child = Command::new(BIN)
            .args(&args)
            .args(["--out".as_ref(), out.as_os_str()])
            .current_dir(repo(""))
            .stdout(Stdio::null())
            .stderr(std::fs::File::create(&log).unwrap())
            .spawn()
            .unwrap();
        let start = Instant::now();
        let status = loop {
            if let Some(s) = child.try_wait().unwrap() {
                break s;
            }
            if start.elapsed() > RUN_LIMIT {
                child.kill().unwrap();
                child.wait().unwrap();
                prop_assert!(false, "`endstop {}` ran past {RUN_LIMIT:?}", args.join(" "));
            }
            std::thread::sleep(Duration::from_millis(20));
        };
        let stderr = std::fs::read_to_string(&log).unwrap_or_default();
        eprintln!("endstop {} -> {status}", args.join(" "));
        let _ = std::fs::remove_file(&log);
        let _ = std::fs::remove_dir_all(&out);
        prop_assert!(
            matches!(status.code(), Some(0..=2)) && !stderr.contains("panicked"),
            "`endstop {}` exited with {status}: {stderr}",
            args.join(" ")
        );
        if status.code() == Some(1) {
            prop_assert!(stderr.contains("error"), "`endstop {}`: {stderr}", args.join(" "));
        }
    }
}
