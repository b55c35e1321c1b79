//! Figure 15's ensembles are three of Figure 14's levels: the same device, seed, streams and
//! settings (`endstop::paper::fig15::IN_FIG14`). `fig14` writes them to its results directory
//! with the freshness key of the inputs they were computed from ([`crate::freshness`]);
//! `fig15` takes them when that key is the one it would run under and the ensembles are the
//! ones it would simulate (`endstop::paper::fig15::from_levels`), and simulates them
//! otherwise. So `reproduce` simulates those records once, and `fig15` alone still works.
//!
//! The file is postcard (serde), which keeps every bit of every f64, NaN widths included: the
//! figure built from the file is the figure built from a simulation.

use std::path::PathBuf;

use anyhow::{Context, Result};
use endstop::paper::ensembles::Level;

use crate::jobs;

/// The file, in `fig14`'s results directory.
pub const FILE: &str = "fig15_levels.postcard";

fn path() -> Result<PathBuf> {
    Ok(jobs::job("fig14").context("no fig14 job")?.dir().join(FILE))
}

fn fig15_key() -> Result<String> {
    crate::freshness::key(jobs::job("fig15").context("no fig15 job")?)
}

/// Writes Figure 15's levels (from Figure 14's run) after the current key of the `fig15`
/// job.
pub fn write(levels: &[Level]) -> Result<PathBuf> {
    let bytes = encode(&fig15_key()?, levels)?;
    let p = path()?;
    crate::write_atomic(&p, &bytes)?;
    Ok(p)
}

/// Figure 15's levels as `fig14` last wrote them, if it wrote them under the current key of
/// the `fig15` job; `Ok(None)` when there is no such file or its key is another (the caller
/// simulates), an error when the file cannot be read or its levels cannot be decoded.
pub fn read() -> Result<Option<Vec<Level>>> {
    let p = path()?;
    let bytes = match std::fs::read(&p) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(e).with_context(|| format!("reading {}", p.display())),
    };
    decode(&bytes, &fig15_key()?).with_context(|| format!("decoding {}", p.display()))
}

/// The key, then the levels.
fn encode(key: &str, levels: &[Level]) -> Result<Vec<u8>> {
    let mut bytes = postcard::to_stdvec(key)?;
    bytes.extend(postcard::to_stdvec(levels)?);
    Ok(bytes)
}

/// The levels if the file's key is `key` (they are decoded only then: a file written by
/// other code may hold another layout).
fn decode(bytes: &[u8], key: &str) -> Result<Option<Vec<Level>>> {
    let (file_key, rest) = postcard::take_from_bytes::<String>(bytes)?;
    if file_key != key {
        return Ok(None);
    }
    Ok(Some(postcard::from_bytes(rest)?))
}

#[cfg(test)]
mod tests {
    use super::*;
    use endstop::paper::fig15;

    #[test]
    fn levels_round_trip_bit_for_bit() {
        // Two records per level: every field comes back with the same bits.
        let dev = endstop::device::Device::from_toml_str(
            &std::fs::read_to_string(crate::root().join("data/prototype2.toml")).unwrap(),
            "prototype2.toml",
        )
        .unwrap();
        let run = fig15::run_records(&dev, 2, &|| {}).unwrap();
        let bytes = encode("k", &run.levels).unwrap();
        assert_eq!(decode(&bytes, "another key").unwrap(), None);
        let back = decode(&bytes, "k").unwrap().unwrap();
        // PartialEq on f64 fails on NaN: compare the Debug text, which spells each f64 as
        // its shortest round-trip decimal (so equal text is equal bits) and NaN as NaN.
        assert_eq!(format!("{back:?}"), format!("{:?}", run.levels));
    }
}
