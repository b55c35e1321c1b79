//! Reading a measured acceleration record from a file: a CSV of time and acceleration, or a
//! WAV file with a stated scale. The samples are checked and resampled by the library
//! ([`endstop::drive::measured`]); this module only reads and converts units.
//!
//! **CSV.** Text with a header line naming two columns, a time and an acceleration, each with
//! its unit: `time_s` or `time_ms`, and `accel_m_per_s2` or `accel_g` (g = 9.81 m/s^2), in
//! either order, separated by a comma (spaces around fields are ignored). Blank lines and lines
//! starting with `#` are skipped. Every error names the file and the line.
//!
//! **WAV.** One channel, integer or float samples; an integer sample is read as a fraction of
//! full scale (`sample / 2^(bits-1)`), and `scale_m_per_s2` states the acceleration of full
//! scale (1.0) in m/s^2: a WAV file carries no unit.

use std::path::Path;
use std::sync::Arc;

use endstop::drive::measured::{MeasuredError, MeasuredRecord, Position};
use thiserror::Error;

/// The time columns a CSV header may name, with their factor to seconds.
pub const TIME_COLUMNS: [(&str, f64); 2] = [("time_s", 1.0), ("time_ms", 1e-3)];

/// The acceleration columns a CSV header may name, with their factor to m/s^2.
pub const ACCEL_COLUMNS: [(&str, f64); 2] = [("accel_m_per_s2", 1.0), ("accel_g", endstop::G)];

/// A record file that cannot be read.
#[derive(Debug, Error)]
pub enum RecordFileError {
    /// The file cannot be opened or read.
    #[error("{file}: cannot be read: {message}")]
    Io {
        /// The file.
        file: String,
        /// The operating system's or the decoder's message.
        message: String,
    },
    /// The file's extension is neither `.csv` nor `.wav`.
    #[error("{file}: unknown record format: the name must end in .csv or .wav")]
    Format {
        /// The file.
        file: String,
    },
    /// The CSV header does not name a time and an acceleration column with units.
    #[error(
        "{file}: line {line}: header `{header}` must name two columns, one of {times} and one \
         of {accels}"
    )]
    Header {
        /// The file.
        file: String,
        /// Its line.
        line: usize,
        /// The header as read.
        header: String,
        /// Valid time columns.
        times: String,
        /// Valid acceleration columns.
        accels: String,
    },
    /// A CSV row is not two numbers.
    #[error("{file}: line {line}: `{text}` is not two numbers separated by a comma")]
    Row {
        /// The file.
        file: String,
        /// Its line.
        line: usize,
        /// The line as read.
        text: String,
    },
    /// A WAV file has more than one channel.
    #[error("{file}: field `channels` = {channels}: must be 1 (one acceleration)")]
    Channels {
        /// The file.
        file: String,
        /// Its channel count.
        channels: u16,
    },
    /// A WAV file was given without its scale.
    #[error(
        "{file}: a WAV file carries no unit: give --accel-scale, the acceleration of full \
         scale in m/s^2"
    )]
    NoScale {
        /// The file.
        file: String,
    },
    /// The samples were read but cannot be used.
    #[error(transparent)]
    Samples(#[from] MeasuredError),
}

/// Reads the record at `path`: a CSV (units from its header) or a WAV (`scale_m_per_s2` is the
/// acceleration of full scale, required for WAV and refused for CSV, whose header carries the
/// unit).
pub fn read_record(
    path: &Path,
    scale_m_per_s2: Option<f64>,
) -> Result<MeasuredRecord, RecordFileError> {
    let file = path.display().to_string();
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some("csv") => {
            if let Some(s) = scale_m_per_s2 {
                return Err(MeasuredError::NotPositive {
                    source_name: file,
                    field: "--accel-scale (a CSV header carries its unit; give none)".into(),
                    value: s,
                }
                .into());
            }
            let text = std::fs::read_to_string(path).map_err(|e| RecordFileError::Io {
                file: file.clone(),
                message: e.to_string(),
            })?;
            read_csv(&text, &file)
        }
        Some("wav") => {
            let scale =
                scale_m_per_s2.ok_or_else(|| RecordFileError::NoScale { file: file.clone() })?;
            read_wav(path, &file, scale)
        }
        _ => Err(RecordFileError::Format { file }),
    }
}

/// Reads CSV text (see the module docs); `file` names it in errors.
pub fn read_csv(text: &str, file: &str) -> Result<MeasuredRecord, RecordFileError> {
    let mut lines = content_lines(text);
    let header_err = |line: usize, header: &str| RecordFileError::Header {
        file: file.to_string(),
        line,
        header: header.to_string(),
        times: names(&TIME_COLUMNS),
        accels: names(&ACCEL_COLUMNS),
    };
    let (hline, header) = lines.next().ok_or_else(|| header_err(1, ""))?;
    let cols: Vec<&str> = header.split(',').map(str::trim).collect();
    if cols.len() != 2 {
        return Err(header_err(hline, header));
    }
    let find = |table: &[(&str, f64)], c: &str| table.iter().find(|(n, _)| *n == c).map(|t| t.1);
    let (time_col, time_factor, accel_factor) = match (
        find(&TIME_COLUMNS, cols[0]),
        find(&ACCEL_COLUMNS, cols[1]),
        find(&ACCEL_COLUMNS, cols[0]),
        find(&TIME_COLUMNS, cols[1]),
    ) {
        (Some(t), Some(a), _, _) => (0, t, a),
        (_, _, Some(a), Some(t)) => (1, t, a),
        _ => return Err(header_err(hline, header)),
    };
    // Two columns rather than a vector of rows (half the memory, and fresh memory costs a long
    // file a large share of its reading time), reserved at a guess of the row count (a row is
    // two numbers and a comma, about 30 bytes).
    let guess = text.len() / 24;
    let (mut times, mut accels) = (Vec::with_capacity(guess), Vec::with_capacity(guess));
    let mut push = |first: f64, second: f64| {
        let (t, a) = if time_col == 0 {
            (first, second)
        } else {
            (second, first)
        };
        times.push(t * time_factor);
        accels.push(a * accel_factor);
    };
    // The rows after the header: each line read by `plain_row` in one pass over its bytes
    // where it is a plain row, else (a blank line, a comment, any other spacing or number
    // syntax, a bad row) by `general_row` on the trimmed line, which names a refused row.
    let bytes = text.as_bytes();
    let (mut at, mut line) = (header_end(text, hline), hline + 1);
    while at < bytes.len() {
        let rest = &bytes[at..];
        let end = match plain_row(rest) {
            Some((first, second, used)) => {
                push(first, second);
                at + used
            }
            None => {
                let end = rest
                    .iter()
                    .position(|&b| b == b'\n')
                    .map_or(bytes.len(), |i| at + i);
                let l = text[at..end].trim();
                if !l.is_empty() && !l.starts_with('#') {
                    let (first, second) = general_row(l, line, file)?;
                    push(first, second);
                }
                end
            }
        };
        (at, line) = (end + 1, line + 1);
    }
    // A refused row is named by its line, found again only then: the k-th row after the
    // header.
    let line_of = |k: usize| {
        let line = content_lines(text).nth(k + 1).map_or(0, |(line, _)| line);
        Position::Line(line)
    };
    Ok(MeasuredRecord::from_columns(file, &times, accels, line_of)?)
}

/// The lines of CSV text that carry content, numbered from 1 and trimmed: blank lines and
/// comments (`#`) are skipped.
fn content_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'))
}

/// The byte just past line `line` (numbered from 1) of `text`, or its end.
fn header_end(text: &str, line: usize) -> usize {
    text.match_indices('\n')
        .nth(line - 1)
        .map_or(text.len(), |(i, _)| i + 1)
}

/// A row of two numbers split at its one comma, both parsed by `str::parse` (which refuses
/// what is not a number); `line` and `file` name a refused row.
fn general_row(text: &str, line: usize, file: &str) -> Result<(f64, f64), RecordFileError> {
    let row_err = || RecordFileError::Row {
        file: file.to_string(),
        line,
        text: text.to_string(),
    };
    // The comma by its byte (a char pattern compares each candidate through `memcmp`);
    // an ASCII byte is a character boundary, so the halves are valid `str`s.
    let bytes = text.as_bytes();
    let (first, second) = match bytes.iter().position(|&b| b == b',') {
        Some(c) if !bytes[c + 1..].contains(&b',') => (text[..c].trim(), text[c + 1..].trim()),
        _ => return Err(row_err()),
    };
    let parse = |s: &str| s.parse::<f64>().map_err(|_| row_err());
    Ok((parse(first)?, parse(second)?))
}

/// The two numbers of a plain row at the start of `rest`, read in one pass over its bytes,
/// and the length of its line (up to its newline or the end): spaces, tabs or carriage
/// returns around each field, one comma between them, each a decimal number that starts with
/// a digit, a sign or a point. `None` for anything else, which [`general_row`] reads. The
/// parser (`fast-float2`) rounds correctly, as `str::parse` does: a plain row gives the same
/// bits either way.
fn plain_row(rest: &[u8]) -> Option<(f64, f64, usize)> {
    let space = |b: &u8| matches!(b, b' ' | b'\t' | b'\r');
    let skip = |at: usize| at + rest[at..].iter().take_while(|b| space(b)).count();
    let number = |at: usize| -> Option<(f64, usize)> {
        match rest.get(at) {
            Some(b'0'..=b'9' | b'-' | b'+' | b'.') => {
                let (v, used) = fast_float2::parse_partial::<f64, _>(&rest[at..]).ok()?;
                Some((v, at + used))
            }
            _ => None,
        }
    };
    let (first, at) = number(skip(0))?;
    let at = skip(at);
    if rest.get(at) != Some(&b',') {
        return None;
    }
    let (second, at) = number(skip(at + 1))?;
    let at = skip(at);
    matches!(rest.get(at), None | Some(b'\n')).then_some((first, second, at))
}

fn read_wav(path: &Path, file: &str, scale: f64) -> Result<MeasuredRecord, RecordFileError> {
    if !(scale.is_finite() && scale > 0.0) {
        return Err(MeasuredError::NotPositive {
            source_name: file.to_string(),
            field: "--accel-scale".into(),
            value: scale,
        }
        .into());
    }
    let io = |e: hound::Error| RecordFileError::Io {
        file: file.to_string(),
        message: e.to_string(),
    };
    // The whole file in memory: hound reads the header, and the samples of a plain layout
    // are decoded from the bytes in one pass (hound's iterator reads each sample through its
    // own call on the reader, the larger part of a long file's reading time).
    let bytes = std::fs::read(path).map_err(|e| io(hound::Error::IoError(e)))?;
    let reader = hound::WavReader::new(std::io::Cursor::new(bytes.as_slice())).map_err(io)?;
    let spec = reader.spec();
    if spec.channels != 1 {
        return Err(RecordFileError::Channels {
            file: file.to_string(),
            channels: spec.channels,
        });
    }
    let samples = match plain_samples(&bytes, reader, scale) {
        Some(samples) => samples,
        None => hound_samples(&bytes, scale).map_err(io)?,
    };
    Ok(MeasuredRecord::from_uniform(
        file,
        f64::from(spec.sample_rate),
        samples,
    )?)
}

/// The samples (m/s^2) of a WAV file's bytes read by hound's iterator, each a fraction of full
/// scale times `scale`: the reader of every layout, and the one that names a bad sample.
fn hound_samples(bytes: &[u8], scale: f64) -> Result<Arc<[f64]>, hound::Error> {
    let mut reader = hound::WavReader::new(std::io::Cursor::new(bytes))?;
    let spec = reader.spec();
    match spec.sample_format {
        hound::SampleFormat::Float => reader
            .samples::<f32>()
            .map(|s| s.map(|v| f64::from(v) * scale))
            .collect(),
        hound::SampleFormat::Int => {
            let full = 2f64.powi(i32::from(spec.bits_per_sample) - 1);
            reader
                .samples::<i32>()
                .map(|s| s.map(|v| f64::from(v) / full * scale))
                .collect()
        }
    }
}

/// The samples of `reader` (positioned at its data, over `bytes`) decoded from the bytes, the
/// same values as [`hound_samples`]: for the layouts hound decodes (8-bit unsigned; 16-, 24-
/// and 32-bit signed, 24 bits also in 4 bytes; 32-bit float), little-endian, with every
/// sample present. `None` for any other layout or a short data chunk, which hound reads and
/// refuses.
fn plain_samples(
    bytes: &[u8],
    reader: hound::WavReader<std::io::Cursor<&[u8]>>,
    scale: f64,
) -> Option<Arc<[f64]>> {
    let (spec, n) = (reader.spec(), reader.len() as usize);
    let start = usize::try_from(reader.into_inner().position()).ok()?;
    // The data chunk's length (the 4 bytes before its data) is `n` samples of its width.
    let len_bytes: [u8; 4] = bytes.get(start.checked_sub(4)?..start)?.try_into().ok()?;
    let width = (u32::from_le_bytes(len_bytes) as usize).checked_div(n)?;
    let data = bytes.get(start..start.checked_add(n.checked_mul(width)?)?)?;
    let full = 2f64.powi(i32::from(spec.bits_per_sample) - 1);
    let int = |v: i32| f64::from(v) / full * scale;
    // Collected straight into the shared samples the record keeps (an iterator of known
    // length fills one allocation), not into a vector copied after.
    fn each(data: &[u8], width: usize, f: impl Fn(&[u8]) -> f64) -> Option<Arc<[f64]>> {
        Some(data.chunks_exact(width).map(f).collect())
    }
    match (spec.sample_format, width, spec.bits_per_sample) {
        (hound::SampleFormat::Float, 4, 32) => each(data, width, |b| {
            f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])) * scale
        }),
        (hound::SampleFormat::Int, 1, 8) => each(data, width, |b| int(i32::from(b[0]) - 128)),
        (hound::SampleFormat::Int, 2, 16) => each(data, width, |b| {
            int(i32::from(i16::from_le_bytes([b[0], b[1]])))
        }),
        // A 24-bit sample in the high bytes of an `i32`, shifted back with its sign.
        (hound::SampleFormat::Int, 3 | 4, 24) => each(data, width, |b| {
            int(i32::from_le_bytes([0, b[0], b[1], b[2]]) >> 8)
        }),
        (hound::SampleFormat::Int, 4, 32) => each(data, width, |b| {
            int(i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        }),
        _ => None,
    }
}

fn names(table: &[(&str, f64)]) -> String {
    table
        .iter()
        .map(|(n, _)| format!("`{n}`"))
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A record of `n` rows, time first (or acceleration first when the header names it
    /// first).
    fn csv(header: &str, n: usize, dt: f64) -> String {
        let accel_first = header.starts_with("accel");
        let mut s = format!("# a test record\n{header}\n");
        for k in 0..n {
            let (t, a) = (
                format!("{:.9}", k as f64 * dt),
                (k as f64).sin().to_string(),
            );
            if accel_first {
                s.push_str(&format!("{a}, {t}\n"));
            } else {
                s.push_str(&format!("{t}, {a}\n"));
            }
        }
        s
    }

    #[test]
    fn units_in_the_header_convert() {
        let r = read_csv(&csv("time_ms,accel_g", 100, 0.1), "a.csv").unwrap();
        assert!((r.sample_rate_hz - 1e4).abs() < 1e-6);
        assert!((r.accel_si[1] - 1f64.sin() * endstop::G).abs() < 1e-12);
        let r = read_csv(&csv("accel_m_per_s2, time_s", 100, 1e-3), "a.csv").unwrap();
        assert!((r.sample_rate_hz - 1e3).abs() < 1e-6);
        assert!(
            (r.accel_si[2] - 2f64.sin()).abs() < 1e-12,
            "columns read by the header"
        );
    }

    #[test]
    fn a_bad_header_or_row_names_its_line() {
        let e = read_csv(&csv("t,a", 100, 1e-3), "a.csv").unwrap_err();
        assert!(
            e.to_string().starts_with("a.csv: line 2: header `t,a`"),
            "{e}"
        );
        let mut text = csv("time_s,accel_g", 100, 1e-3);
        text.push_str("0.5, nope\n");
        let e = read_csv(&text, "a.csv").unwrap_err();
        assert!(e.to_string().starts_with("a.csv: line 103:"), "{e}");
        let text = csv("time_s,accel_g", 100, 1e-3).replace("0.050000000,", "0.050000000, NaN,");
        let e = read_csv(&text, "a.csv").unwrap_err();
        assert!(e.to_string().contains("line 53"), "{e}");
    }

    /// A value the record refuses is named by its own line, past comments and blank lines
    /// among the rows (the reader keeps no line numbers and finds the line again).
    #[test]
    fn a_refused_value_names_its_line_past_comments_and_blanks() {
        let mut lines: Vec<String> = csv("time_s,accel_g", 100, 1e-3)
            .lines()
            .map(String::from)
            .collect();
        // Lines 1 and 2 are the comment and the header; row k is on line k + 3 up to row 9,
        // and on line k + 5 after the two lines inserted there: row 56 is on line 61.
        lines.insert(12, "# a note among the rows".into());
        lines.insert(13, "   ".into());
        lines[60] = format!("{:.9}, inf", 56.0 * 1e-3);
        let e = read_csv(&lines.join("\n"), "a.csv").unwrap_err();
        assert_eq!(
            e.to_string(),
            "a.csv: line 61: accel = inf is not a finite number"
        );
        // Row 56 half a step late: the step from row 55 is 1.5 steps.
        lines[60] = format!("{:.9}, 0.5", 56.5 * 1e-3);
        let e = read_csv(&lines.join("\n"), "a.csv").unwrap_err();
        assert!(
            e.to_string().starts_with("a.csv: line 61: time step"),
            "{e}"
        );
    }

    #[test]
    fn a_wav_needs_a_scale_and_one_channel() {
        let dir = std::env::temp_dir().join(format!("endstop-wav-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.wav");
        let spec = hound::WavSpec {
            channels: 1,
            sample_rate: 8000,
            bits_per_sample: 16,
            sample_format: hound::SampleFormat::Int,
        };
        let mut w = hound::WavWriter::create(&path, spec).unwrap();
        for k in 0..800 {
            w.write_sample(if k % 2 == 0 { 16384i16 } else { -16384 })
                .unwrap();
        }
        w.finalize().unwrap();
        assert!(matches!(
            read_record(&path, None),
            Err(RecordFileError::NoScale { .. })
        ));
        let r = read_record(&path, Some(20.0)).unwrap();
        assert_eq!(r.sample_rate_hz, 8000.0);
        assert_eq!(r.accel_si[0], 10.0);
        assert_eq!(r.accel_si[1], -10.0);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Every layout hound decodes reads the same values from the bytes as through hound's
    /// iterator (bit for bit: the same arithmetic on the same integers), with a chunk after
    /// the data ignored; a file cut short inside its data is left to hound, and refused with
    /// its error.
    #[test]
    fn wav_samples_from_the_bytes_are_hounds() {
        use hound::SampleFormat::{Float, Int};
        fn reader(bytes: &[u8]) -> hound::WavReader<std::io::Cursor<&[u8]>> {
            hound::WavReader::new(std::io::Cursor::new(bytes)).unwrap()
        }
        let dir = std::env::temp_dir().join(format!("endstop-wavs-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let layouts = [
            (Float, 32, 4),
            (Int, 8, 1),
            (Int, 16, 2),
            (Int, 24, 3),
            (Int, 24, 4),
            (Int, 32, 4),
        ];
        for (k, &(format, bits, width)) in layouts.iter().enumerate() {
            let path = dir.join(format!("{k}.wav"));
            let spec = hound::WavSpec {
                channels: 1,
                sample_rate: 8000,
                bits_per_sample: bits,
                sample_format: format,
            };
            let spec_ex = hound::WavSpecEx {
                spec,
                bytes_per_sample: width,
            };
            let file = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
            let mut w = hound::WavWriter::new_with_spec_ex(file, spec_ex).unwrap();
            let full = 1i64 << (bits - 1);
            for j in 0..300i64 {
                // Both extremes of the range, zero and values of every sign between.
                let v = (j * 7919 % (2 * full)) - full;
                match format {
                    Float => w.write_sample((v as f64 / full as f64) as f32).unwrap(),
                    Int => w.write_sample(v as i32).unwrap(),
                }
            }
            w.finalize().unwrap();
            let mut bytes = std::fs::read(&path).unwrap();
            bytes.extend_from_slice(b"LIST\x04\0\0\0abcd");
            std::fs::write(&path, &bytes).unwrap();
            let want = hound_samples(&bytes, 3.0).unwrap();
            let got = plain_samples(&bytes, reader(&bytes), 3.0).expect("a plain layout");
            assert_eq!(*read_record(&path, Some(3.0)).unwrap().accel_si, got[..]);
            assert_eq!(got.len(), 300, "{format:?} {bits} bits in {width} bytes");
            let bits_of = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(
                bits_of(&got),
                bits_of(&want),
                "{format:?} {bits} bits in {width} bytes"
            );
            // Cut inside the data (past the header, before the last sample's end).
            let cut = &bytes[..bytes.len() - 12 - 1];
            std::fs::write(&path, cut).unwrap();
            assert_eq!(plain_samples(cut, reader(cut), 3.0), None);
            let want = hound_samples(cut, 3.0).unwrap_err().to_string();
            match read_record(&path, Some(3.0)) {
                Err(RecordFileError::Io { message, .. }) => assert_eq!(message, want),
                other => panic!("{other:?}"),
            }
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A plain row reads the same bits as `str::parse` of its trimmed fields, for numbers of
    /// random bit patterns written as Rust writes them (shortest, exponent, fixed) with signs
    /// and spacing; rows it does not read plainly (words, two commas, a bad number, another
    /// separator) are left to the general path, whose verdict is then the reader's.
    #[test]
    fn plain_rows_read_as_str_parse() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let mut checked = 0;
        for _ in 0..20_000 {
            let (x, y) = (f64::from_bits(next()), f64::from_bits(next() >> 2));
            if !(x.is_finite() && y.is_finite()) {
                continue;
            }
            let forms = [
                format!("{x},{y}"),
                format!(" {x:e} ,\t{y:e}\r"),
                format!("+{:.6},-{:.3e}", x.abs(), y.abs()),
                format!("{:.17e}, .5", x),
            ];
            for row in &forms {
                let (a, b) = row.trim().split_once(',').unwrap();
                let want = (a.trim().parse::<f64>(), b.trim().parse::<f64>());
                let (Ok(wa), Ok(wb)) = want else {
                    panic!("{row:?}: str::parse refuses it")
                };
                let (ga, gb, used) = plain_row(row.as_bytes()).expect(row);
                assert_eq!(
                    (ga.to_bits(), gb.to_bits(), used),
                    (wa.to_bits(), wb.to_bits(), row.len()),
                    "{row:?}"
                );
                checked += 1;
            }
        }
        assert!(checked > 50_000, "{checked} rows checked");
        for row in [
            "inf,1", "1,2,3", "1;2", "1.2.3,4", "1e,2", "# 1,2", "", "1 2,3", "1,2 x",
        ] {
            assert_eq!(plain_row(row.as_bytes()), None, "{row:?}");
        }
        // The row's length stops at its newline.
        assert_eq!(plain_row(b"1,2\n3,4"), Some((1.0, 2.0, 3)));
    }
}
