//! The `endstop` tool on devices of other kinds than the paper's (the shipped examples of
//! `data/examples/`) and on measured acceleration records: one-load transducers write zero
//! second-load columns, a record is refused with the file, the line and the valid range and
//! nothing written, and a good record is resampled and analysed beside its spectrum.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::cli_common::{read_parquet, run, BIN};

fn data(rel: &str) -> String {
    format!("{}/../data/{rel}", env!("CARGO_MANIFEST_DIR"))
}

fn tmp(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("endstop-clidev-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// Writes a CSV record of `n` rows at `dt` with header `time_s,accel_m_per_s2`, with `edit`
/// applied to the rows (a dropped row, a NaN).
fn csv(dir: &Path, n: usize, dt: f64, edit: impl Fn(&mut Vec<String>)) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let mut rows: Vec<String> = (0..n)
        .map(|k| {
            let t = k as f64 * dt;
            format!("{t:.7},{}", (2.0 * std::f64::consts::PI * 120.0 * t).sin())
        })
        .collect();
    edit(&mut rows);
    let p = dir.join("rec.csv");
    std::fs::write(&p, format!("time_s,accel_m_per_s2\n{}\n", rows.join("\n"))).unwrap();
    p
}

#[test]
fn a_one_load_device_sweeps_with_zero_second_load_columns() {
    let out = tmp("sweep");
    let o = run(&[
        "sweep",
        "--device",
        &data("examples/piezo_cantilever.toml"),
        "--from",
        "110",
        "--to",
        "120",
        "--step",
        "5",
        "--accel-rms-g",
        "0.1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let df = read_parquet(&out.join("sweep.parquet"));
    let v1 = df.column("v1_rms_v").unwrap().f64().unwrap().clone();
    let v2 = df.column("v2_rms_v").unwrap().f64().unwrap().clone();
    assert!(v1.into_iter().all(|v| v.unwrap() > 0.0));
    assert!(v2.into_iter().all(|v| v.unwrap() == 0.0));
    // No bias voltage, so the column is null; --bias-v is refused for such a device.
    assert_eq!(df.column("bias_v").unwrap().null_count(), df.height());
    let o = run(&[
        "sweep",
        "--device",
        &data("examples/piezo_cantilever.toml"),
        "--from",
        "110",
        "--to",
        "120",
        "--accel-rms-g",
        "0.1",
        "--bias-v",
        "5",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        err.contains("--bias-v") && err.contains("piezoelectric"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(out);
}

/// A bad record: its name, the edit of a good record's lines, and the messages expected.
type BadRecordCase = (
    &'static str,
    Box<dyn Fn(&mut Vec<String>)>,
    &'static [&'static str],
);

#[test]
fn a_bad_record_is_refused_naming_file_line_and_range_and_nothing_is_written() {
    let dir = tmp("bad");
    let out = dir.join("out");
    let piezo = data("examples/piezo_cantilever.toml");
    let cases: [BadRecordCase; 3] = [
        (
            "gap",
            Box::new(|r: &mut Vec<String>| {
                r.remove(1000);
            }),
            // Word for word as the book's "Model your own harvester" chapter quotes it.
            &[
                "rec.csv: line 1002: time step 2.0000e-4 s is not uniform: must be between \
               9.9000e-5 and 1.0100e-4 s (the record's median step 1.0000e-4 s within 1 %)",
            ],
        ),
        (
            "nan",
            Box::new(|r: &mut Vec<String>| r[500] = "0.0500000,NaN".into()),
            &["line 502", "accel = NaN", "not a finite number"],
        ),
        (
            "short",
            Box::new(|r: &mut Vec<String>| r.truncate(2000)),
            &["too short", "must be at least"],
        ),
    ];
    for (tag, edit, needles) in cases {
        let rec = csv(&dir.join(tag), 40000, 1e-4, edit);
        let o = run(&[
            "random",
            "--device",
            &piezo,
            "--accel-file",
            rec.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{tag}: {err}");
        assert!(err.contains("rec.csv"), "{tag}: {err}");
        for n in needles {
            assert!(err.contains(n), "{tag}: `{n}` not in {err}");
        }
        assert!(!out.exists(), "{tag}: output written for a refused record");
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_measured_record_drives_a_device_with_its_spectrum_beside() {
    let out = tmp("measured");
    let o = run(&[
        "random",
        "--device",
        &data("examples/piezo_cantilever.toml"),
        "--accel-file",
        &data("examples/machine_record.wav"),
        "--accel-scale",
        "20",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let df = read_parquet(&out.join("output_psd.parquet"));
    for c in [
        "freq_hz",
        "out_psd_uw_per_hz",
        "linear_psd_uw_per_hz",
        "psd_g2_per_hz",
    ] {
        assert!(df.column(c).is_ok(), "missing column {c}");
    }
    // The drive's spectrum peaks at the machine's third harmonic, 3 x 39.5 Hz, the
    // strongest line of the synthetic record (data/examples/make_machine_record.py).
    let f = df.column("freq_hz").unwrap().f64().unwrap().clone();
    let s = df.column("psd_g2_per_hz").unwrap().f64().unwrap().clone();
    let (peak_f, _) = f
        .into_iter()
        .zip(&s)
        .map(|(f, s)| (f.unwrap(), s.unwrap()))
        .fold((0.0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
    assert!(
        (peak_f - 118.5).abs() < 2.0,
        "drive PSD peaks at {peak_f} Hz"
    );
    assert!(out.join("endstop-random.svg").exists());
    let _ = std::fs::remove_dir_all(out);
}

/// The book quotes this message word for word.
#[test]
fn a_restitution_coefficient_above_one_is_refused_with_the_books_message() {
    let dir = tmp("coef");
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(data("examples/rigid_restitution.toml"))
        .unwrap()
        .replace("coefficient = 0.6", "coefficient = 1.2")
        .replace("[stops.both]", "[stops.upper]");
    std::fs::write(dir.join("my.toml"), text).unwrap();
    let o = Command::new(BIN)
        .current_dir(&dir)
        .args(["random", "--device", "my.toml", "--psd", "1e-3"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        err.contains(
            "my.toml: field `stops.upper.coefficient` = 1.2e0 is out of range: must be between \
             0 and 1"
        ),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// `--sine-g` drives a device with a sine for a fixed time and writes what `--accel-file`
/// writes: the drive's spectrum peaks in the Welch bin nearest the sine's frequency, its RMS is the amplitude over
/// root two (to 1e-4: the analysed window holds a whole number of cycles to within one sample
/// of 167, and the mean of the sampled sin^2 differs from 1/2 by far less), and the same
/// samples written to a CSV file give the same record (power, RMS displacement and RMS drive
/// to 1e-9 relatively: the file's rate equals the integrator's, so nothing is resampled, and
/// the CSV holds each sample to the last bit).
#[test]
fn a_sine_drive_for_a_fixed_time_writes_what_a_measured_record_writes() {
    let dir = tmp("sine");
    let piezo = data("examples/piezo_cantilever.toml");
    let (amplitude_g, freq_hz, fs, duration_s) = (0.2, 120.0, 20e3, 2.0);
    let sine_out = dir.join("sine");
    let o = run(&[
        "random",
        "--device",
        &piezo,
        "--sine-g",
        "0.2",
        "--freq-hz",
        "120",
        "--duration-s",
        "2",
        "--sample-rate-hz",
        "20000",
        "--out",
        sine_out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (peak_f, bin_hz) = drive_psd_peak(&sine_out);
    // The Welch bin nearest the sine.
    assert!(
        (peak_f - freq_hz).abs() <= 0.5 * bin_hz,
        "drive PSD peaks at {peak_f} Hz (bins of {bin_hz} Hz)"
    );
    let (p, x, a) = first_record(&sine_out);
    assert!(
        (a / (amplitude_g / 2f64.sqrt()) - 1.0).abs() < 1e-4,
        "RMS drive {a} g"
    );
    // The same samples as a measured record.
    let text = std::fs::read_to_string(&piezo).unwrap();
    let device = endstop::device::Device::from_toml_str(&text, &piezo).unwrap();
    let preroll = endstop::study::record::transient_s(&device);
    let n = ((preroll + duration_s) * fs).round() as usize;
    let g = endstop::G;
    let w = 2.0 * std::f64::consts::PI * freq_hz / fs;
    let accel: Vec<f64> = (0..=n)
        .map(|k| amplitude_g * g * (w * k as f64).sin())
        .collect();
    same_record_from_file(&dir, &piezo, "sine", &accel, fs, (p, x, a));
    let _ = std::fs::remove_dir_all(dir);
}

/// `--chirp-to-hz` sweeps the sine after the pre-roll and writes what `--accel-file` writes:
/// the same samples (`endstop::drive::swept_sine_samples`, whose phase is checked against the
/// chirp's closed form in its own tests) written to a CSV file give the same record (power,
/// RMS displacement and RMS drive to 1e-9 relatively, as for the steady sine: equal rates, so
/// nothing is resampled, and each sample written to the last bit), and the drive's spectrum
/// peaks inside the swept band (to the Welch bin nearest its edges).
#[test]
fn a_chirp_drive_writes_what_a_measured_record_writes() {
    let dir = tmp("chirp");
    let piezo = data("examples/piezo_cantilever.toml");
    let (amplitude_g, f0, f1, fs, duration_s) = (0.2, 100.0, 140.0, 20e3, 2.0);
    let chirp_out = dir.join("chirp");
    let o = run(&[
        "random",
        "--device",
        &piezo,
        "--sine-g",
        "0.2",
        "--freq-hz",
        "100",
        "--chirp-to-hz",
        "140",
        "--duration-s",
        "2",
        "--sample-rate-hz",
        "20000",
        "--out",
        chirp_out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (peak_f, bin_hz) = drive_psd_peak(&chirp_out);
    // Inside the band, to the Welch bin nearest its edges.
    assert!(
        (f0 - 0.5 * bin_hz..=f1 + 0.5 * bin_hz).contains(&peak_f),
        "drive PSD peaks at {peak_f} Hz (bins of {bin_hz} Hz)"
    );
    let (p, x, a) = first_record(&chirp_out);
    let text = std::fs::read_to_string(&piezo).unwrap();
    let device = endstop::device::Device::from_toml_str(&text, &piezo).unwrap();
    let preroll = endstop::study::record::transient_s(&device);
    let (hold, n) = (
        (preroll * fs).round() as usize,
        ((preroll + duration_s) * fs).round() as usize,
    );
    let accel = endstop::drive::swept_sine_samples(amplitude_g * endstop::G, f0, f1, fs, hold, n);
    same_record_from_file(&dir, &piezo, "chirp", &accel, fs, (p, x, a));
    let _ = std::fs::remove_dir_all(dir);
}

/// The drive spectrum's peak frequency in a `random` run's `output_psd.parquet` and the Welch
/// bin width (Hz).
fn drive_psd_peak(out: &Path) -> (f64, f64) {
    let df = read_parquet(&out.join("output_psd.parquet"));
    let f = df.column("freq_hz").unwrap().f64().unwrap().clone();
    let s = df.column("psd_g2_per_hz").unwrap().f64().unwrap().clone();
    let bin_hz = f.get(1).unwrap() - f.get(0).unwrap();
    let (peak_f, _) = f
        .into_iter()
        .zip(&s)
        .map(|(f, s)| (f.unwrap(), s.unwrap()))
        .fold((0.0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
    (peak_f, bin_hz)
}

/// The first record's power (W), RMS displacement (m) and RMS drive (g) of a `random` run.
fn first_record(out: &Path) -> (f64, f64, f64) {
    let r = read_parquet(&out.join("records.parquet"));
    let col = |c: &str| r.column(c).unwrap().f64().unwrap().get(0).unwrap();
    (col("p_w"), col("x_rms_m"), col("accel_rms_g"))
}

/// Writes `accel` (m/s^2, sampled at `fs` Hz from t = 0) to `<dir>/<name>.csv`, runs `random
/// --accel-file` on it at the same rate, and asserts the record's power, RMS displacement and
/// RMS drive equal `expected` to 1e-9 relatively (equal rates: nothing is resampled, and each
/// sample is written to the last bit).
fn same_record_from_file(
    dir: &Path,
    device: &str,
    name: &str,
    accel: &[f64],
    fs: f64,
    expected: (f64, f64, f64),
) {
    let mut csv_text = String::from("time_s,accel_m_per_s2\n");
    for (k, acc) in accel.iter().enumerate() {
        let t = k as f64 / fs;
        csv_text.push_str(&format!("{t:e},{acc:e}\n"));
    }
    std::fs::create_dir_all(dir).unwrap();
    let file = dir.join(format!("{name}.csv"));
    std::fs::write(&file, csv_text).unwrap();
    let file_out = dir.join(format!("{name}_file"));
    let o = run(&[
        "random",
        "--device",
        device,
        "--accel-file",
        file.to_str().unwrap(),
        "--sample-rate-hz",
        &format!("{fs}"),
        "--out",
        file_out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (p, x, a) = expected;
    let (pf, xf, af) = first_record(&file_out);
    let rel = |u: f64, v: f64| (u - v).abs() / v.abs();
    assert!(rel(p, pf) < 1e-9, "power {p:e} vs {pf:e}");
    assert!(rel(x, xf) < 1e-9, "x rms {x:e} vs {xf:e}");
    assert!(rel(a, af) < 1e-9, "accel rms {a:e} vs {af:e}");
}

/// A device whose resonance lies below the record's frequency resolution (the rigid-stop
/// oscillator of the validation chapter, 0.16 Hz, against Welch bins about 1.5 Hz apart) has
/// no bin in its analysis band: a named error before any record runs, and nothing written.
#[test]
fn random_on_a_resonance_below_the_resolution_is_refused_and_writes_nothing() {
    let out = tmp("empty-band");
    let o = run(&[
        "random",
        "--device",
        &data("validation/grazing_rigid.toml"),
        "--psd",
        "1e-4",
        "--records",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("analysis_band_hz"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(!out.exists(), "nothing written");
}
