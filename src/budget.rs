//! The one memory budget (the CLI's `--max-memory SIZE`, a global flag; the Python package's
//! `max_memory`): every grid, sample set and archive member a command allocates is estimated
//! first and refused when the estimate exceeds it, with one message naming the flags
//! ([`check`]).
//!
//! The default is half the machine's memory (`MemTotal` of `/proc/meminfo`), and at most half the
//! process's address-space limit (`ulimit -v`, from `/proc/self/limits`) so that an estimate
//! accepted under such a limit leaves room for what it does not count (the mesh, its BVH, thread
//! stacks); 8 GiB where neither can be read.

use crate::grid::spec::{format_bytes, parse_memory_size, DEFAULT_MAX_MEMORY_BYTES};
use crate::{Error, Result};

/// The budget in bytes: `--max-memory` when given, else the default of the module doc.
pub fn max_memory(flag: Option<&str>) -> Result<u64> {
    match flag {
        Some(text) => parse_memory_size(text),
        None => Ok(default_max_memory()),
    }
}

/// Half the machine's memory, within half the address-space limit (see the module doc).
pub fn default_max_memory() -> u64 {
    let total = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|t| meminfo_total(&t));
    let limit = std::fs::read_to_string("/proc/self/limits")
        .ok()
        .and_then(|t| address_space_limit(&t));
    let half = |b: u64| b / 2;
    match (total, limit) {
        (Some(t), Some(l)) => half(t).min(half(l)),
        (Some(t), None) => half(t),
        (None, Some(l)) => half(l).min(DEFAULT_MAX_MEMORY_BYTES),
        (None, None) => DEFAULT_MAX_MEMORY_BYTES,
    }
}

/// `MemTotal` of a `/proc/meminfo` text, bytes.
fn meminfo_total(text: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// The soft "Max address space" of a `/proc/self/limits` text, bytes (None when unlimited).
fn address_space_limit(text: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with("Max address space"))?;
    line["Max address space".len()..]
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

/// Most area samples per surface `--samples` takes (a billion would take hours).
pub const MAX_SAMPLES: usize = 100_000_000;

/// Bytes held per area sample of a surface distance: the point and its distance.
const BYTES_PER_SAMPLE: u64 = 32;

/// Refuses a sample count (of `flag`) above [`MAX_SAMPLES`] or whose two sample sets exceed the
/// budget `max`.
pub fn check_samples(flag: &str, samples: usize, max: u64) -> Result<()> {
    if samples > MAX_SAMPLES {
        return Err(Error::Refused(format!(
            "{flag} {samples} is more than the {MAX_SAMPLES} samples per surface allowed"
        )));
    }
    let bytes = (samples as u64).saturating_mul(2 * BYTES_PER_SAMPLE);
    check(
        &format!("{flag} {samples}"),
        bytes,
        max,
        "use fewer samples or ",
    )
}

/// Refuses `what` when its estimate `bytes` exceeds `max`: "{what} needs about X, more than the Y
/// memory limit: {advice}raise --max-memory".
pub fn check(what: &str, bytes: u64, max: u64, advice: &str) -> Result<()> {
    if bytes > max {
        return Err(Error::Refused(format!(
            "{what} needs about {}, more than the {} memory limit: {advice}raise --max-memory",
            format_bytes(bytes),
            format_bytes(max)
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_proc_files() {
        let meminfo = "MemTotal:       24500000 kB\nMemFree:        15000000 kB\n";
        assert_eq!(meminfo_total(meminfo), Some(24_500_000 * 1024));
        let limits = "Limit                     Soft Limit           Hard Limit           Units     \n\
                      Max address space         2147483648           unlimited            bytes     \n";
        assert_eq!(address_space_limit(limits), Some(2_147_483_648));
        let unlimited =
            "Max address space         unlimited            unlimited            bytes     \n";
        assert_eq!(address_space_limit(unlimited), None);
    }

    #[test]
    fn refusal_names_the_flag() {
        assert!(check("x", 10, 10, "").is_ok());
        let e = check("a grid", 3 << 30, 1 << 30, "use a coarser --voxel or ")
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "a grid needs about 3.0 GiB, more than the 1.0 GiB memory limit: use a coarser \
             --voxel or raise --max-memory"
        );
    }
}
