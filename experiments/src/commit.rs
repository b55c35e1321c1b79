//! The commit every output names: the commit of the working tree, `-dirty` when a
//! tracked file changed, read once per process and, where a run asks, on a thread beside its
//! work (the files it writes wait for the answer, so the answer describes the tree before the
//! run wrote into it).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::OnceLock;

/// The git commit of the working tree (with `-dirty` if a tracked file has uncommitted
/// changes), or `unknown` outside a repository or before its first commit.
///
/// One `git status` gives both: with `--porcelain=v2 --branch` its `# branch.oid` line names
/// the commit `HEAD` points to, and every line that does not start with `#` is a changed
/// tracked file (`--untracked-files=no`; `--no-ahead-behind` spares the count against an
/// upstream, which the answer does not need; `--no-optional-locks` keeps it from writing the
/// index it refreshes, which a look-up beside other work must not lock). A process started
/// costs about 1.5 ms of processor time, the dirty check itself about 2.5 ms more, the state
/// of every tracked file read from the index and the disk. It runs in this crate's folder,
/// inside the repository: `git status` answers for the whole working tree from any folder.
pub fn git_commit() -> String {
    static COMMIT: OnceLock<String> = OnceLock::new();
    COMMIT
        .get_or_init(|| {
            std::process::Command::new("git")
                .args([
                    "--no-optional-locks",
                    "status",
                    "--porcelain=v2",
                    "--branch",
                    "--no-ahead-behind",
                    "--untracked-files=no",
                ])
                .current_dir(env!("CARGO_MANIFEST_DIR"))
                .output()
                .ok()
                .filter(|o| o.status.success())
                .and_then(|o| commit_of_status(&String::from_utf8_lossy(&o.stdout)))
                .unwrap_or_else(|| "unknown".to_string())
        })
        .clone()
}

/// Whether [`git_commit_in_background`] started the look-up: then [`write_atomic`](crate::write_atomic) waits for
/// its answer before it writes anything.
static GIT_IN_BACKGROUND: AtomicBool = AtomicBool::new(false);

/// Starts [`git_commit`] on a thread, so that its `git status` (a process of some 4 ms of
/// processor time) runs beside the caller's reading and integrating instead of before them.
///
/// The answer stays what it would be at the start of the run: [`write_atomic`](crate::write_atomic) waits for it
/// before it writes any file, so the dirty check never sees the run's own outputs. Where no
/// thread can be started, [`git_commit`] runs `git` itself when it is first asked.
pub fn git_commit_in_background() {
    if !GIT_IN_BACKGROUND.swap(true, Ordering::SeqCst) {
        let started = std::thread::Builder::new()
            .name("git-commit".into())
            .spawn(|| {
                git_commit();
            });
        drop(started);
    }
}

/// The commit, `-dirty` when a tracked file changed, from the text of `git status
/// --porcelain=v2 --branch`; None without a commit (`# branch.oid (initial)`).
fn commit_of_status(status: &str) -> Option<String> {
    let oid = status
        .lines()
        .find_map(|l| l.strip_prefix("# branch.oid "))?
        .trim();
    if !oid.bytes().all(|b| b.is_ascii_hexdigit()) || oid.is_empty() {
        return None;
    }
    let dirty = status.lines().any(|l| !l.is_empty() && !l.starts_with('#'));
    Some(if dirty {
        format!("{oid}-dirty")
    } else {
        oid.to_string()
    })
}

/// Whether the look-up runs on its thread ([`git_commit_in_background`] was called).
pub(crate) fn in_background() -> bool {
    GIT_IN_BACKGROUND.load(Ordering::SeqCst)
}

/// Waits for the look-up started by [`git_commit_in_background`], if one was started.
pub(crate) fn await_background() {
    if in_background() {
        git_commit();
    }
}

#[cfg(test)]
mod commit_tests {
    use super::commit_of_status;

    #[test]
    fn commit_of_status_reads_the_oid_and_the_changed_files() {
        let oid = "a6d7e3904cf3721f8e87eba4a158f962f400ca9e";
        let clean = format!("# branch.oid {oid}\n# branch.head main\n");
        assert_eq!(commit_of_status(&clean).as_deref(), Some(oid));
        let changed =
            format!("{clean}1 .M N... 100644 100644 100644 f5218f58 f5218f58 src/drive/noise.rs\n");
        assert_eq!(commit_of_status(&changed), Some(format!("{oid}-dirty")));
        // A detached head has the same oid line; a repository without a commit has none.
        let detached = format!("# branch.oid {oid}\n# branch.head (detached)\n");
        assert_eq!(commit_of_status(&detached).as_deref(), Some(oid));
        let initial = "# branch.oid (initial)\n# branch.head main\n";
        assert_eq!(commit_of_status(initial), None);
        assert_eq!(commit_of_status(""), None);
    }
}
