//! When `reproduce` may skip a job: its outputs exist and every file it reads is byte for byte
//! what it was at its last successful run. The key of a job is a SHA-256 over the paths and
//! contents of those files: the code (`src/`, `experiments/`, the manifests and the lock file),
//! the bundled font, the claims file (compiled into the library), the data files the job names
//! in its [`Job::reads`], and, for a job that reads the calibrated prototype 1, the calibration
//! artefact.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use sha2::{Digest, Sha256};

use crate::pipeline::jobs::Job;

/// Directories and files whose content every job depends on, relative to the project root.
pub const CODE_INPUTS: &[&str] = &[
    "Cargo.toml",
    "Cargo.lock",
    "src",
    "experiments",
    "assets",
    "data/claims.toml",
];

fn walk(dir: &Path, out: &mut Vec<PathBuf>) -> Result<()> {
    for entry in std::fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))? {
        let p = entry?.path();
        if p.is_dir() {
            walk(&p, out)?;
        } else {
            out.push(p);
        }
    }
    Ok(())
}

/// Every file a job reads (sorted, absolute), under the project root `root`.
pub fn input_files(root: &Path, job: &Job) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for rel in CODE_INPUTS.iter().chain(job.reads) {
        let p = root.join(rel);
        if p.is_dir() {
            walk(&p, &mut files)?;
        } else {
            files.push(p);
        }
    }
    if job.reads_calibration {
        files.push(
            crate::reports::calibration_io::calibration_dir()
                .join(crate::reports::calibration_io::DEVICE_FILE),
        );
    }
    files.sort();
    files.dedup();
    Ok(files)
}

/// The content hash of `files`, with their paths relative to `root`. A missing file is hashed
/// as missing (so its appearance changes the key).
pub fn key_of(root: &Path, files: &[PathBuf]) -> String {
    let mut h = Sha256::new();
    for f in files {
        h.update(
            f.strip_prefix(root)
                .unwrap_or(f)
                .to_string_lossy()
                .as_bytes(),
        );
        h.update([0u8]);
        match std::fs::read(f) {
            Ok(bytes) => {
                h.update([1u8]);
                h.update(bytes);
            }
            Err(_) => h.update([2u8]),
        }
        h.update([0u8]);
    }
    format!("{:x}", h.finalize())
}

/// The freshness key of a job from its input files as they are on disk.
pub fn key(job: &Job) -> Result<String> {
    let root = crate::root();
    Ok(key_of(&root, &input_files(&root, job)?))
}

fn key_path(job: &Job) -> PathBuf {
    job.dir().join("inputs.sha256")
}

/// True when the job's last successful run had this key and its outputs (those of every
/// experiment it writes) are still there.
pub fn is_fresh(job: &Job, key: &str) -> bool {
    std::fs::read_to_string(key_path(job)).is_ok_and(|k| k.trim() == key)
        && job.dir().join("summary.json").exists()
        && job.also.iter().all(|e| {
            crate::pipeline::jobs::experiment_dir(e)
                .join("summary.json")
                .exists()
        })
        && job.completion_marker().exists()
}

/// Records a successful run's key.
pub fn mark_done(job: &Job, key: &str) -> Result<()> {
    crate::write_atomic(&key_path(job), key.as_bytes())
}

/// Forgets a job's key (after a failed run).
pub fn forget(job: &Job) {
    let _ = std::fs::remove_file(key_path(job));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::jobs::{job, JOBS};

    #[test]
    fn every_job_key_holds_the_claims_file_and_the_files_it_reads() {
        let root = crate::root();
        for j in JOBS {
            let files = input_files(&root, j).unwrap();
            assert!(
                files.contains(&root.join("data/claims.toml")),
                "{}: claims file not in its key",
                j.name
            );
            for r in j.reads {
                assert!(
                    files.contains(&root.join(r)),
                    "{}: {r} not in its key",
                    j.name
                );
            }
        }
        let own = job("own_device_sweep").unwrap();
        let files = input_files(&root, own).unwrap();
        assert!(files.contains(&root.join("data/examples/my_harvester.toml")));
        let fig08 = job("fig08").unwrap();
        assert!(input_files(&root, fig08)
            .unwrap()
            .iter()
            .any(|f| f.ends_with(crate::reports::calibration_io::DEVICE_FILE)));
    }

    #[test]
    fn the_key_changes_with_any_input_and_only_then() {
        let dir = std::env::temp_dir().join(format!("endstop-fresh-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (a, b) = (dir.join("a.toml"), dir.join("b.toml"));
        std::fs::write(&a, "x = 1").unwrap();
        std::fs::write(&b, "y = 2").unwrap();
        let files = vec![a.clone(), b.clone()];
        let k0 = key_of(&dir, &files);
        assert_eq!(k0, key_of(&dir, &files));
        std::fs::write(&b, "y = 3").unwrap();
        let k1 = key_of(&dir, &files);
        assert_ne!(k0, k1);
        std::fs::remove_file(&a).unwrap();
        assert_ne!(k1, key_of(&dir, &files));
        std::fs::remove_dir_all(&dir).ok();
    }
}
