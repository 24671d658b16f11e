//! Bounded allocation from untrusted sizes. Every size or count that comes from a flag or a
//! file is checked before anything is allocated for it: against what the file actually holds
//! (a header cannot claim more than its bytes can carry) and against an estimate of the memory
//! the work needs, compared with the memory this process can still get ([`check_memory`]). The
//! error names the flag or file, the estimate and what is available, instead of an abort in
//! the allocator minutes later.
//!
//! Input files are read through [`read_file`]: regular files only (a FIFO would block forever,
//! `/dev/zero` never ends, a directory is not data), opened without blocking, and their size
//! checked against memory before a byte is read.

use crate::error::{Error, Result};
use std::fs::File;
use std::io::Read;
use std::path::Path;

/// Memory this process can still allocate, in bytes: the least of what the system has
/// available (`MemAvailable`), what the cgroup's limit leaves, and what the address-space and
/// data limits (`ulimit -v`, `ulimit -d`) leave beyond what is mapped already. None where none
/// of these can be read (then nothing is refused).
pub fn available_memory() -> Option<u64> {
    [system_available(), cgroup_available(), rlimit_available()]
        .into_iter()
        .flatten()
        .min()
}

/// An error naming `what` (a flag with its value, or a file and field) when `need` bytes are
/// more than [`available_memory`].
pub fn check_memory(what: impl FnOnce() -> String, need: u64) -> Result<()> {
    match available_memory() {
        Some(available) if need > available => Err(Error::Memory {
            what: what(),
            need,
            available,
        }),
        _ => Ok(()),
    }
}

/// Bytes for `count` items of `each` bytes, saturating (an estimate past u64 is "too much").
pub fn bytes(count: u64, each: u64) -> u64 {
    count.saturating_mul(each)
}

/// `1.5 GiB`, `312 MiB`, `17 B`.
pub fn human_bytes(n: u64) -> String {
    const UNITS: [&str; 7] = ["B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
    let mut value = n as f64;
    let mut unit = 0;
    while value >= 1024.0 && unit < UNITS.len() - 1 {
        value /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{n} B")
    } else {
        format!("{value:.1} {}", UNITS[unit])
    }
}

/// Opens `path` for reading if it is a regular file; anything else is an error naming it and
/// what it is. The open does not block (a FIFO without a writer would).
pub fn open_regular(path: &Path) -> Result<File> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK);
    }
    let file = options.open(path).map_err(|e| Error::io(path, e))?;
    let kind = file.metadata().map_err(|e| Error::io(path, e))?.file_type();
    if !kind.is_file() {
        return Err(Error::Parse {
            path: path.into(),
            message: format!("not a regular file ({})", describe(kind)),
        });
    }
    Ok(file)
}

fn describe(kind: std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_fifo() {
            return "a FIFO";
        }
        if kind.is_char_device() {
            return "a character device";
        }
        if kind.is_block_device() {
            return "a block device";
        }
        if kind.is_socket() {
            return "a socket";
        }
    }
    if kind.is_dir() {
        "a directory"
    } else {
        "not a file"
    }
}

/// The whole content of the regular file `path`, after checking that its size, and
/// `memory_per_byte` more bytes per byte for what the caller builds from it, fit in memory.
pub fn read_file(path: &Path, memory_per_byte: u64) -> Result<Vec<u8>> {
    let file = open_regular(path)?;
    let len = file.metadata().map_err(|e| Error::io(path, e))?.len();
    check_memory(
        || format!("{} ({})", path.display(), human_bytes(len)),
        bytes(len, 1 + memory_per_byte),
    )?;
    let mut content = Vec::new();
    content
        .try_reserve_exact(len as usize)
        .map_err(|e| Error::Parse {
            path: path.into(),
            message: format!("cannot hold {}: {e}", human_bytes(len)),
        })?;
    // Never more than the size checked: a file growing while it is read is cut there.
    file.take(len)
        .read_to_end(&mut content)
        .map_err(|e| Error::io(path, e))?;
    Ok(content)
}

fn system_available() -> Option<u64> {
    kib_field(
        &std::fs::read_to_string("/proc/meminfo").ok()?,
        "MemAvailable:",
    )
}

/// `field` of a `/proc` status text in kB, in bytes.
fn kib_field(text: &str, field: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(field))?;
    let kib: u64 = line[field.len()..]
        .trim()
        .trim_end_matches("kB")
        .trim()
        .parse()
        .ok()?;
    Some(kib.saturating_mul(1024))
}

/// Limit minus usage of this process's memory cgroup (v2 or v1); None when unlimited.
fn cgroup_available() -> Option<u64> {
    let groups = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    let read = |p: String| std::fs::read_to_string(p).ok()?.trim().parse::<u64>().ok();
    let mut found: Option<u64> = None;
    for line in groups.lines() {
        let mut parts = line.splitn(3, ':');
        let (_, controllers, group) = (parts.next(), parts.next()?, parts.next()?);
        let (root, limit, usage) = if controllers.is_empty() {
            ("/sys/fs/cgroup", "memory.max", "memory.current")
        } else if controllers.split(',').any(|c| c == "memory") {
            (
                "/sys/fs/cgroup/memory",
                "memory.limit_in_bytes",
                "memory.usage_in_bytes",
            )
        } else {
            continue;
        };
        // Inside a container the group's own directory is usually the mount's root.
        for base in [format!("{root}{group}"), root.to_string()] {
            // v2 says `max` and v1 a number near 2^63 for "no limit".
            if let (Some(l), Some(u)) = (
                read(format!("{base}/{limit}")),
                read(format!("{base}/{usage}")),
            ) && l < 1 << 60
            {
                let left = l.saturating_sub(u);
                found = Some(found.map_or(left, |f| f.min(left)));
                break;
            }
        }
    }
    found
}

/// What `ulimit -v` (address space) and `ulimit -d` (data) leave beyond what is mapped now.
#[cfg(unix)]
fn rlimit_available() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok();
    let limit = |resource| {
        let mut r = libc::rlimit {
            rlim_cur: 0,
            rlim_max: 0,
        };
        // SAFETY: getrlimit only writes the struct it is given.
        let ok = unsafe { libc::getrlimit(resource, &mut r) } == 0;
        (ok && r.rlim_cur != libc::RLIM_INFINITY).then_some(r.rlim_cur)
    };
    let used = |field| {
        status
            .as_deref()
            .and_then(|s| kib_field(s, field))
            .unwrap_or(0)
    };
    [
        limit(libc::RLIMIT_AS).map(|l| l.saturating_sub(used("VmSize:"))),
        limit(libc::RLIMIT_DATA).map(|l| l.saturating_sub(used("VmData:"))),
    ]
    .into_iter()
    .flatten()
    .min()
}

#[cfg(not(unix))]
fn rlimit_available() -> Option<u64> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn human_bytes_picks_a_unit() {
        assert_eq!(human_bytes(17), "17 B");
        assert_eq!(human_bytes(1536), "1.5 KiB");
        assert_eq!(human_bytes(u64::MAX), "16.0 EiB");
    }

    #[test]
    fn an_impossible_need_is_refused_naming_what() {
        if available_memory().is_none() {
            return;
        }
        let err = check_memory(|| "--runs 4294967295".into(), u64::MAX).unwrap_err();
        let msg = err.to_string();
        assert!(
            msg.starts_with("--runs 4294967295: needs about 16.0 EiB"),
            "{msg}"
        );
        assert!(check_memory(|| unreachable!(), 1).is_ok());
    }

    #[test]
    fn non_regular_files_are_refused_by_kind() {
        let dir = tempfile::tempdir().unwrap();
        let msg = read_file(dir.path(), 0).unwrap_err().to_string();
        assert!(msg.contains("a directory"), "{msg}");
        #[cfg(unix)]
        {
            let msg = read_file(Path::new("/dev/zero"), 0)
                .unwrap_err()
                .to_string();
            assert!(
                msg.contains("/dev/zero") && msg.contains("character device"),
                "{msg}"
            );
        }
    }
}
