//! Everything dibench writes goes through here, so that no exit — an error, Ctrl-C, a full
//! disk, `kill -9` — leaves a half-written file or a set of files that do not belong together:
//! - one file: written under a temporary name in its directory, flushed, renamed over its name
//!   ([`write_atomic`]), so it is whole or absent;
//! - a set of files that must agree (a stored reference, a shard): committed by a manifest
//!   written last ([`store`]);
//! - a compare run: a directory of its own, created exclusively, whose `run.json` says how
//!   complete it is ([`run_dir`]).
//!
//! Temporary files are named `.<name>.<pid>.<random>.tmp`; a process killed mid-write leaves
//! one, which readers ignore and the next write of the same file removes (its process is gone;
//! in a store or a run directory, whoever holds the lock removes them all).

mod exr;
pub mod run_dir;
pub mod store;

pub use exr::{
    Provenance, decode_exr, encode_exr, read_exr, read_provenance, write_exr, write_exr_with,
};

use crate::error::{Error, Result};
use serde::Serialize;
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Ends the name of every temporary file dibench writes.
pub const TEMP_SUFFIX: &str = ".tmp";

/// True for the name of a temporary file (ours: `.<name>.<pid>.<random>.tmp`).
pub fn is_temp_name(name: &str) -> bool {
    name.starts_with('.') && name.ends_with(TEMP_SUFFIX)
}

/// A temporary file in `dir` for a file named `name`, readable as an ordinary output once
/// renamed (mode 0666 less the umask, as `File::create` gives).
pub(crate) fn temp_file_in(dir: &Path, name: &str) -> Result<tempfile::NamedTempFile> {
    let prefix = format!(".{name}.{}.", std::process::id());
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(TEMP_SUFFIX);
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    builder.tempfile_in(dir).map_err(|e| Error::io(dir, e))
}

/// Writes through `write` into a temporary file beside `path` (through its open handle: the
/// file is never reopened by name, so an exit that removed it cannot see it recreated),
/// flushes it to disk (a full disk is reported here, not discovered later) and renames it over
/// `path`. On any error the temporary file is removed; an exit on Ctrl-C waits for the write
/// (`interrupt::critical`). Errors of `write` name `path`.
pub fn write_atomic(path: &Path, write: impl FnOnce(&mut File) -> Result<()>) -> Result<()> {
    let dir = match path.parent().filter(|d| !d.as_os_str().is_empty()) {
        Some(d) => d,
        None => Path::new("."),
    };
    create_dir(dir)?;
    let name = path
        .file_name()
        .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    crate::interrupt::critical(|| {
        remove_dead_temps(dir, &name);
        let (mut tmp, _registered) = crate::interrupt::create_temp(|| temp_file_in(dir, &name))?;
        write(tmp.as_file_mut())?;
        tmp.as_file().sync_all().map_err(|e| Error::io(path, e))?;
        tmp.persist(path).map_err(|e| Error::io(path, e.error))?;
        Ok(())
    })
}

pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic(path, |file| {
        file.write_all(bytes).map_err(|e| Error::io(path, e))
    })
}

pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(value).map_err(|e| Error::Output {
        path: path.into(),
        message: e.to_string(),
    })?;
    write_bytes(path, format!("{text}\n").as_bytes())
}

pub fn write_csv<T: Serialize>(path: &Path, rows: &[T]) -> Result<()> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.serialize(r).map_err(|e| Error::Output {
            path: path.into(),
            message: e.to_string(),
        })?;
    }
    let bytes = w.into_inner().map_err(|e| Error::Output {
        path: path.into(),
        message: e.to_string(),
    })?;
    write_bytes(path, &bytes)
}

/// Creates the directory `dir` and its parents; when that fails, the error says which part of
/// the path is in the way (a file, a dangling symbolic link, no permission).
pub fn create_dir(dir: &Path) -> Result<()> {
    match std::fs::create_dir_all(dir) {
        Ok(()) => Ok(()),
        Err(e) => Err(Error::Output {
            path: dir.into(),
            message: format!("cannot create this directory: {}", obstacle(dir, e)),
        }),
    }
}

/// Why `dir` could not be created: the first part of it that exists and is not a directory.
fn obstacle(dir: &Path, error: std::io::Error) -> String {
    let mut prefix = PathBuf::new();
    for part in dir.components() {
        prefix.push(part);
        let Ok(meta) = std::fs::symlink_metadata(&prefix) else {
            break;
        };
        if meta.file_type().is_symlink() {
            let target = std::fs::read_link(&prefix)
                .map(|t| t.display().to_string())
                .unwrap_or_default();
            match std::fs::metadata(&prefix) {
                Err(_) => {
                    return format!(
                        "{} is a symbolic link to {target}, which does not exist",
                        prefix.display()
                    );
                }
                Ok(m) if !m.is_dir() => {
                    return format!(
                        "{} is a symbolic link to {target}, which is not a directory",
                        prefix.display()
                    );
                }
                Ok(_) => {}
            }
        } else if !meta.is_dir() {
            return format!("{} is a file, not a directory", prefix.display());
        }
    }
    error.to_string()
}

/// Checks, before any work, that output can be written in `dir` (created if missing): an
/// error names `named_by` (the flag or argument that gave the location) and the reason.
pub fn check_output_dir(dir: &Path, named_by: &str) -> Result<()> {
    let named = |e: Error| Error::Output {
        path: dir.into(),
        message: format!("cannot write output here (given by {named_by}): {e}"),
    };
    if dir.as_os_str().is_empty() {
        return Err(Error::Usage(format!("{named_by} must not be empty")));
    }
    create_dir(dir).map_err(named)?;
    // An anonymous file: proves the directory is writable and leaves nothing behind.
    tempfile::tempfile_in(dir)
        .map(drop)
        .map_err(|e| named(Error::io(dir, e)))
}

/// Opens (or with `create`, creates) the lock file `path` without blocking, refusing anything
/// but a regular file: a FIFO put in its place would block an open for writing forever.
pub(crate) fn open_lock(path: &Path, create: bool) -> Result<std::fs::File> {
    let mut options = std::fs::OpenOptions::new();
    options
        .read(true)
        .write(true)
        .create(create)
        .truncate(false);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK);
    }
    let file = options.open(path).map_err(|e| Error::io(path, e))?;
    if !file.metadata().map_err(|e| Error::io(path, e))?.is_file() {
        return Err(Error::Output {
            path: path.into(),
            message: "a lock file that is not a regular file: remove it".into(),
        });
    }
    Ok(file)
}

/// Removes the temporary files directly in `dir` (left by killed processes; call only where no
/// live writer can own one, i.e. holding that directory's lock).
pub(crate) fn remove_temps(dir: &Path, prefix: &str) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if is_temp_name(&name) && name[1..].starts_with(prefix) {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

/// Removes the temporary files for `name` in `dir` whose process is no longer alive.
fn remove_dead_temps(dir: &Path, name: &str) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let prefix = format!(".{name}.");
    for e in entries.flatten() {
        let Ok(file) = e.file_name().into_string() else {
            continue;
        };
        if file.starts_with(&prefix) && is_dead_temp(&file) {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

/// True for a temporary name (`.<name>.<pid>.<random>.tmp`) whose process is gone.
pub(crate) fn is_dead_temp(name: &str) -> bool {
    if !is_temp_name(name) {
        return false;
    }
    let mut parts = name[..name.len() - TEMP_SUFFIX.len()].rsplitn(3, '.');
    let (_random, pid) = (parts.next(), parts.next());
    pid.and_then(|p| p.parse::<u32>().ok())
        .is_some_and(|p| !process_alive(p))
}

/// Whether process `pid` exists (it may have been reused: then its temporary files stay).
#[cfg(unix)]
fn process_alive(pid: u32) -> bool {
    let Ok(pid) = libc::pid_t::try_from(pid) else {
        return true;
    };
    // SAFETY: signal 0 only checks that the process exists and may be signalled.
    unsafe {
        libc::kill(pid, 0) == 0
            || std::io::Error::last_os_error().raw_os_error() != Some(libc::ESRCH)
    }
}

#[cfg(not(unix))]
fn process_alive(_pid: u32) -> bool {
    true
}

/// Flushes a directory's entries (the renames just made in it) to disk, where supported.
pub(crate) fn sync_dir(dir: &Path) {
    if let Ok(d) = std::fs::File::open(dir) {
        let _ = d.sync_all();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atomic_write_leaves_only_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.json");
        write_json(&path, &[1, 2]).unwrap();
        let failed = write_atomic(&dir.path().join("b.json"), |_| {
            Err(Error::Usage("refused".into()))
        });
        assert!(failed.is_err());
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .flatten()
            .map(|e| e.file_name())
            .collect();
        assert_eq!(names, ["a.json"], "temporary files left behind");
    }

    /// A temporary file of a dead process is removed by the next write of its file; one of a
    /// live process (this one) is not.
    #[test]
    fn the_next_write_removes_temporary_files_of_dead_processes() {
        let dir = tempfile::tempdir().unwrap();
        // Above the largest pid_max (2^22), so no such process exists.
        let dead = dir.path().join(".a.csv.2147483000.x1.tmp");
        let live = dir
            .path()
            .join(format!(".a.csv.{}.x2.tmp", std::process::id()));
        std::fs::write(&dead, "half").unwrap();
        std::fs::write(&live, "half").unwrap();
        write_bytes(&dir.path().join("a.csv"), b"x").unwrap();
        assert!(!dead.exists());
        assert!(live.exists());
    }

    #[test]
    fn blocked_output_locations_say_what_is_in_the_way() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("file"), "x").unwrap();
        let msg = check_output_dir(&dir.path().join("file/sub"), "--out")
            .unwrap_err()
            .to_string();
        assert!(msg.contains("--out") && msg.contains("is a file"), "{msg}");
        #[cfg(unix)]
        {
            let link = dir.path().join("dangling");
            std::os::unix::fs::symlink(dir.path().join("nowhere"), &link).unwrap();
            let msg = check_output_dir(&link, "--out").unwrap_err().to_string();
            assert!(
                msg.contains("symbolic link") && msg.contains("does not exist"),
                "{msg}"
            );
        }
    }
}
