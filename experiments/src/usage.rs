//! What the process has used so far, read from `getrusage`: processor time (its own threads
//! and its child processes apart) and memory (page faults and the peak resident set), for the
//! time and memory a run reports of itself.

/// Processor time this process has used so far, user and system, its waited-for child
/// processes (ngspice) included (s); None where `getrusage` is not available.
///
/// With the wall time it says how much of the machine an experiment needs: `reproduce` on
/// `n` cores cannot finish before the sum over its experiments divided by `n`.
pub fn cpu_time_s() -> Option<f64> {
    Some(rusage_s(Who::This)? + rusage_s(Who::Children)?)
}

/// Processor time this process's own threads have used so far, user and system, without its
/// child processes (s); None where `getrusage` is not available.
pub fn own_cpu_time_s() -> Option<f64> {
    rusage_s(Who::This)
}

/// Processor time, user and system, of this process's child processes that have ended and
/// been waited for (s); None where `getrusage` is not available.
pub fn children_cpu_time_s() -> Option<f64> {
    rusage_s(Who::Children)
}

enum Who {
    This,
    Children,
}

/// This process's memory so far ([`own_memory`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Memory {
    /// Page faults served without reading a file: each a page the kernel mapped in, most of
    /// them fresh memory it zeroed first (a transparent huge page counts once).
    pub minor_faults: u64,
    /// The largest resident set the process has had (bytes).
    pub peak_rss_bytes: u64,
}

/// This process's page faults and peak resident set so far; None where `getrusage` is not
/// available.
pub fn own_memory() -> Option<Memory> {
    let u = rusage(Who::This)?;
    Some(Memory {
        minor_faults: u.minor_faults,
        peak_rss_bytes: u.peak_rss_bytes,
    })
}

fn rusage_s(who: Who) -> Option<f64> {
    rusage(who).map(|u| u.cpu_s)
}

/// What the run reads of `getrusage`.
struct Usage {
    cpu_s: f64,
    minor_faults: u64,
    peak_rss_bytes: u64,
}

#[cfg(unix)]
fn rusage(who: Who) -> Option<Usage> {
    let who = match who {
        Who::This => libc::RUSAGE_SELF,
        Who::Children => libc::RUSAGE_CHILDREN,
    };
    // SAFETY: `getrusage` only writes the struct it is handed, plain data that is valid
    // zeroed.
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(who, &mut u) } != 0 {
        return None;
    }
    let tv = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    // `ru_maxrss` is in KiB on Linux, in bytes on macOS.
    let rss_unit: u64 = if cfg!(target_os = "macos") { 1 } else { 1024 };
    Some(Usage {
        cpu_s: tv(u.ru_utime) + tv(u.ru_stime),
        minor_faults: u64::try_from(u.ru_minflt).unwrap_or(0),
        peak_rss_bytes: u64::try_from(u.ru_maxrss).unwrap_or(0) * rss_unit,
    })
}

#[cfg(not(unix))]
fn rusage(_who: Who) -> Option<Usage> {
    None
}
