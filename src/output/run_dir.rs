//! A compare run's own directory, `<scene dir>/<stamp>-seed<N>`: created exclusively (a run
//! that finds the name taken, e.g. another run of the same seed started in the same second,
//! takes `<stamp>-seed<N>-2`, `-3`, …), locked for the run's life, and with a `run.json` that
//! always tells how complete the run is: `status` is `running` from the directory's creation
//! while the run works, then `complete`, `interrupted` or `failed` (with the error). A run that
//! ends before any result was recorded removes its directory. A run killed outright (or whose
//! last `run.json` could not be written: a full disk) stays `running` until the next run in the
//! same scene directory finds its lock free: that one removes its temporary files, and marks it
//! `unfinished`, or removes it if it holds no results.

use crate::error::{Error, Result};
use serde::Serialize;
use serde_json::Value;
use std::fs::File;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    Running,
    Complete,
    Interrupted,
    Failed,
    /// Found dead by a later run: the process ended without recording how.
    Unfinished,
}

impl Status {
    fn name(self) -> &'static str {
        match self {
            Status::Running => "running",
            Status::Complete => "complete",
            Status::Interrupted => "interrupted",
            Status::Failed => "failed",
            Status::Unfinished => "unfinished",
        }
    }
}

/// The run directory, held (locked) while this value lives.
pub struct RunDir {
    path: PathBuf,
    shared: Arc<Shared>,
    _lock: File,
    _hook: crate::interrupt::ExitHook,
}

struct Shared {
    path: PathBuf,
    /// The last `run.json` written.
    record: Mutex<Option<Value>>,
    /// Something worth keeping is in the directory (set by [`RunDir::keep`]).
    keep: AtomicBool,
}

const LOCK: &str = ".lock";
const RUN_JSON: &str = "run.json";

impl RunDir {
    /// Creates `<scene_dir>/<base>` (or `<base>-2`, … if taken) and locks it; first marks the
    /// dead runs in `scene_dir` (see the module comment).
    pub fn create(scene_dir: &Path, base: &str) -> Result<RunDir> {
        super::create_dir(scene_dir)?;
        mark_dead_runs(scene_dir);
        // Built under a temporary name (with this process's pid, see `is_dead_temp`), locked and
        // with its run.json, then renamed into place: a run directory never exists without
        // both, so a free lock on one always means a dead run.
        // The whole build is one critical section: an exit on Ctrl-C waits for it (within
        // its grace), and if it cannot, the hook registered right after the directory's
        // creation removes it, so no interrupt leaves a directory under its temporary name.
        crate::interrupt::critical(|| -> Result<RunDir> {
            let mut builder = tempfile::Builder::new();
            let prefix = format!(".{base}.{}.", std::process::id());
            builder.prefix(&prefix).suffix(super::TEMP_SUFFIX);
            #[cfg(unix)]
            {
                use std::os::unix::fs::PermissionsExt;
                builder.permissions(std::fs::Permissions::from_mode(0o777));
            }
            let tmp = builder
                .tempdir_in(scene_dir)
                .map_err(|e| Error::io(scene_dir, e))?;
            let tmp_path = tmp.path().to_path_buf();
            let _building = crate::interrupt::on_exit(move || {
                let _ = std::fs::remove_dir_all(&tmp_path);
            });
            let lock_path = tmp.path().join(LOCK);
            let lock = super::open_lock(&lock_path, true)?;
            lock.lock().map_err(|e| Error::io(&lock_path, e))?;
            let building = Shared {
                path: tmp.path().to_path_buf(),
                record: Mutex::new(None),
                keep: AtomicBool::new(false),
            };
            building.write(Value::Object(Default::default()), Status::Running, None)?;
            let mut k = 1u32;
            let path = loop {
                let name = if k == 1 {
                    base.to_string()
                } else {
                    format!("{base}-{k}")
                };
                let path = scene_dir.join(name);
                // rename(2) replaces only an empty directory; a run directory never is one.
                match std::fs::rename(tmp.path(), &path) {
                    Ok(()) => break path,
                    Err(e)
                        if matches!(
                            e.kind(),
                            std::io::ErrorKind::AlreadyExists
                                | std::io::ErrorKind::DirectoryNotEmpty
                        ) && k < 10_000 =>
                    {
                        k += 1
                    }
                    Err(e) => {
                        return Err(Error::Output {
                            path,
                            message: format!("cannot create the run directory: {e}"),
                        });
                    }
                }
            };
            // Renamed: nothing left for the temporary directory to remove.
            let _ = tmp.keep();
            let shared = Arc::new(Shared {
                path: path.clone(),
                record: Mutex::new(
                    building
                        .record
                        .into_inner()
                        .unwrap_or_else(|p| p.into_inner()),
                ),
                keep: AtomicBool::new(false),
            });
            let on_exit = shared.clone();
            let hook =
                crate::interrupt::on_exit(move || on_exit.abandon(Status::Interrupted, None));
            Ok(RunDir {
                path,
                shared,
                _lock: lock,
                _hook: hook,
            })
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Writes `run.json`: `meta` (an object) with `status`, `interrupted` and `error` set.
    pub fn record(&self, meta: &impl Serialize, status: Status) -> Result<()> {
        let value = serde_json::to_value(meta).map_err(|e| Error::Output {
            path: self.path.join(RUN_JSON),
            message: e.to_string(),
        })?;
        self.shared.write(value, status, None)
    }

    /// From now on the directory holds results: an early end records it instead of removing it.
    pub fn keep(&self) {
        self.shared.keep.store(true, Ordering::SeqCst);
    }

    /// Ends the run with `error`: records `failed` (or `interrupted`) with the error in
    /// `run.json` when the directory holds results, else removes the directory.
    pub fn abandon(&self, error: &Error) {
        let status = match error {
            Error::Interrupted(_) => Status::Interrupted,
            _ => Status::Failed,
        };
        self.shared.abandon(status, Some(error.to_string()));
    }
}

impl Shared {
    fn write(&self, mut value: Value, status: Status, error: Option<String>) -> Result<()> {
        if let Value::Object(map) = &mut value {
            map.insert("status".into(), status.name().into());
            map.insert("interrupted".into(), (status == Status::Interrupted).into());
            map.insert("error".into(), error.map_or(Value::Null, Value::String));
        }
        // Not under the lock: an exit on Ctrl-C may stop this thread inside the write, and
        // its hook then needs the record.
        super::write_json(&self.path.join(RUN_JSON), &value)?;
        *self.record.lock().unwrap_or_else(|p| p.into_inner()) = Some(value);
        Ok(())
    }

    fn abandon(&self, status: Status, error: Option<String>) {
        if !self.keep.load(Ordering::SeqCst) {
            remove_run_dir(&self.path);
            return;
        }
        let last = self
            .record
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .clone();
        if let Some(value) = last {
            // Best effort: on a full disk run.json keeps saying `running`, which is true too
            // (the run did not complete).
            let _ = self.write(value, status, error);
        }
    }
}

/// Removes a run directory so that no kill leaves it half-removed under its own name (its
/// run.json gone, its lock free: a directory no later run could account for). It is first
/// renamed, atomically, to a temporary name of this process; if this process dies while
/// removing it, a later run removes what is left (`is_dead_temp`, in [`mark_dead_runs`]).
fn remove_run_dir(dir: &Path) {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let (Some(parent), Some(name)) = (dir.parent(), dir.file_name()) else {
        let _ = std::fs::remove_dir_all(dir);
        return;
    };
    let tmp = parent.join(format!(
        ".{}.{}.rm{}{}",
        name.to_string_lossy(),
        std::process::id(),
        NEXT.fetch_add(1, Ordering::SeqCst),
        super::TEMP_SUFFIX
    ));
    match std::fs::rename(dir, &tmp) {
        Ok(()) => {
            let _ = std::fs::remove_dir_all(&tmp);
        }
        Err(_) => {
            let _ = std::fs::remove_dir_all(dir);
        }
    }
}

/// Finds the runs in `scene_dir` whose process ended while running (`run.json` says `running`
/// but nobody holds the lock): removes their temporary files, and marks them `unfinished`, or
/// removes them when they hold no results.
fn mark_dead_runs(scene_dir: &Path) {
    let Ok(entries) = std::fs::read_dir(scene_dir) else {
        return;
    };
    for e in entries.flatten() {
        let dir = e.path();
        // A run directory being built, or being removed: by a process that died, it goes; by a
        // live one, it is that process's.
        let name = e.file_name().to_string_lossy().into_owned();
        if super::is_temp_name(&name) {
            if super::is_dead_temp(&name) {
                let _ = std::fs::remove_dir_all(&dir);
            }
            continue;
        }
        let Ok(lock) = super::open_lock(&dir.join(LOCK), false) else {
            continue;
        };
        if lock.try_lock().is_err() {
            continue;
        }
        super::remove_temps(&dir, "");
        let json = dir.join(RUN_JSON);
        let Ok(bytes) = crate::bounded::read_file(&json, 4) else {
            continue;
        };
        let Ok(mut value) = serde_json::from_slice::<Value>(&bytes) else {
            continue;
        };
        if value.get("status").and_then(Value::as_str) == Some(Status::Running.name()) {
            if !dir.join("results.csv").exists() {
                drop(lock);
                remove_run_dir(&dir);
                continue;
            }
            value["status"] = Status::Unfinished.name().into();
            let _ = super::write_json(&json, &value);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run directory removed by `remove_run_dir` leaves nothing, and one a process was
    /// killed while removing (renamed to its temporary name, partly emptied) is removed by the
    /// next run's sweep. Control: a live process's temporary directory stays.
    #[test]
    fn a_half_removed_run_directory_is_swept() {
        let dir = tempfile::tempdir().unwrap();
        let run = dir.path().join("r-seed1");
        std::fs::create_dir(&run).unwrap();
        std::fs::write(run.join(RUN_JSON), "{}").unwrap();
        std::fs::write(run.join(LOCK), "").unwrap();
        remove_run_dir(&run);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        // pid_max is at most 2^22: this pid is dead.
        let dead = dir.path().join(format!(
            ".r-seed1.2147483000.rm0{}",
            super::super::TEMP_SUFFIX
        ));
        let live = dir.path().join(format!(
            ".q-seed1.{}.rm0{}",
            std::process::id(),
            super::super::TEMP_SUFFIX
        ));
        for d in [&dead, &live] {
            std::fs::create_dir(d).unwrap();
            std::fs::write(d.join(LOCK), "").unwrap();
        }
        mark_dead_runs(dir.path());
        assert!(!dead.exists());
        assert!(live.exists());
    }

    #[test]
    fn the_same_name_twice_gives_two_directories() {
        let dir = tempfile::tempdir().unwrap();
        let a = RunDir::create(dir.path(), "t-seed1").unwrap();
        let b = RunDir::create(dir.path(), "t-seed1").unwrap();
        assert_ne!(a.path(), b.path());
        assert!(b.path().ends_with("t-seed1-2"));
    }

    #[test]
    fn a_run_without_results_leaves_nothing_and_one_with_results_says_why_it_ended() {
        let dir = tempfile::tempdir().unwrap();
        let empty = RunDir::create(dir.path(), "a").unwrap();
        empty
            .record(&serde_json::json!({"x": 1}), Status::Running)
            .unwrap();
        empty.abandon(&Error::Usage("boom".into()));
        assert!(!empty.path().exists());
        let kept = RunDir::create(dir.path(), "b").unwrap();
        kept.record(&serde_json::json!({"x": 1}), Status::Running)
            .unwrap();
        kept.keep();
        kept.abandon(&Error::Interrupted("stop".into()));
        let v: Value =
            serde_json::from_slice(&std::fs::read(kept.path().join(RUN_JSON)).unwrap()).unwrap();
        assert_eq!(v["status"], "interrupted");
        assert_eq!(v["interrupted"], true);
        assert_eq!(v["x"], 1);
    }

    /// A run whose process is gone (its lock free) but whose run.json says `running` is marked
    /// `unfinished` by the next run, or removed if it has no results; a live one is left alone.
    #[test]
    fn dead_runs_are_marked_unfinished_and_live_ones_are_not() {
        let dir = tempfile::tempdir().unwrap();
        let live = RunDir::create(dir.path(), "live").unwrap();
        live.record(&serde_json::json!({}), Status::Running)
            .unwrap();
        let dead = dir.path().join("dead");
        std::fs::create_dir(&dead).unwrap();
        File::create(dead.join(LOCK)).unwrap();
        std::fs::write(dead.join(RUN_JSON), r#"{"status": "running"}"#).unwrap();
        std::fs::write(dead.join(".results.csv.x1.tmp"), "half").unwrap();
        std::fs::write(dead.join("results.csv"), "rows").unwrap();
        let empty = dir.path().join("empty");
        std::fs::create_dir(&empty).unwrap();
        File::create(empty.join(LOCK)).unwrap();
        std::fs::write(empty.join(RUN_JSON), r#"{"status": "running"}"#).unwrap();
        let _next = RunDir::create(dir.path(), "next").unwrap();
        let status = |d: &Path| {
            let v: Value =
                serde_json::from_slice(&std::fs::read(d.join(RUN_JSON)).unwrap()).unwrap();
            v["status"].as_str().unwrap().to_string()
        };
        assert_eq!(status(&dead), "unfinished");
        assert_eq!(status(live.path()), "running");
        assert!(!dead.join(".results.csv.x1.tmp").exists());
        assert!(!empty.exists());
    }
}
