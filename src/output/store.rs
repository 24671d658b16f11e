//! Units of several files that must agree — a reference (image, variance, metadata), a shard
//! (film, metadata) — committed atomically by a manifest written last.
//!
//! A unit `<stem>` in a store directory is
//! ```text
//! <stem>.json             the manifest: the unit's metadata, and under `files` each file's
//!                         name, size and SHA-256
//! <stem>.<sha256[..16]>.<ext>   its files, named by their content
//! .<stem>.lock            locked (flock) by whoever reads or writes the unit
//! ```
//! A commit writes each file under a temporary name, flushes it and renames it to its content
//! name, then replaces the manifest in one rename: that rename is the commit. A kill at any
//! instant leaves the old manifest with its old files, or the new manifest with its new files.
//! Files no manifest names (from a commit killed before its manifest, or replaced by a newer
//! one) and temporary files are removed whenever the unit is locked for writing, since the
//! lock proves that no live process owns them; readers never look at them. A reader checks
//! every file's size and hash against the manifest, so a damaged file is an error naming it,
//! never a wrong image. Locks are released by the kernel when their process dies, so a kill
//! never leaves a unit locked.

use crate::bounded;
use crate::error::{Error, Result};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::fs::{File, TryLockError};
use std::io::{Read, Seek};
use std::path::{Path, PathBuf};
use std::time::Duration;

/// A directory of units.
pub struct Store {
    dir: PathBuf,
}

/// A unit locked for reading (shared) or writing (exclusive); released on drop.
pub struct Locked<'a> {
    store: &'a Store,
    stem: String,
    exclusive: bool,
    _lock: File,
}

/// A unit as read and verified: its metadata and its files' contents by role.
pub struct Unit<M> {
    pub meta: M,
    pub manifest: PathBuf,
    files: BTreeMap<String, (PathBuf, Vec<u8>)>,
}

/// Writes a file's content into the open file it is given; its errors name the path given.
pub type WriteFile<'a> = Box<dyn FnOnce(&mut std::fs::File, &Path) -> Result<()> + 'a>;

/// A file to commit: `write` writes it; `ext` ends its name; `role` names it in the manifest.
pub struct NewFile<'a> {
    pub role: &'static str,
    pub ext: &'static str,
    pub write: WriteFile<'a>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
struct FileRecord {
    name: String,
    bytes: u64,
    sha256: String,
}

#[derive(Serialize)]
struct ManifestOut<'a, M> {
    #[serde(flatten)]
    meta: &'a M,
    files: BTreeMap<&'static str, FileRecord>,
}

#[derive(Deserialize)]
struct ManifestIn<M> {
    #[serde(flatten)]
    meta: M,
    files: BTreeMap<String, FileRecord>,
}

impl<M> Unit<M> {
    /// The verified content of the file with `role`, and its path.
    pub fn file(&self, role: &str) -> Result<(&Path, &[u8])> {
        self.files
            .get(role)
            .map(|(p, b)| (p.as_path(), b.as_slice()))
            .ok_or_else(|| Error::Parse {
                path: self.manifest.clone(),
                message: format!("the manifest names no `{role}` file"),
            })
    }
}

impl Store {
    /// The store in `dir`, created if missing.
    pub fn open(dir: &Path) -> Result<Store> {
        super::create_dir(dir)?;
        Ok(Store { dir: dir.into() })
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    pub fn manifest_path(&self, stem: &str) -> PathBuf {
        self.dir.join(format!("{stem}.json"))
    }

    /// The stems of the units that have a manifest, sorted.
    pub fn stems(&self) -> Result<Vec<String>> {
        let entries = std::fs::read_dir(&self.dir).map_err(|e| Error::io(&self.dir, e))?;
        let mut stems: Vec<String> = entries
            .flatten()
            .filter_map(|e| {
                let name = e.file_name().into_string().ok()?;
                let stem = name.strip_suffix(".json")?;
                (!stem.is_empty() && !stem.starts_with('.')).then(|| stem.to_string())
            })
            .collect();
        stems.sort();
        Ok(stems)
    }

    /// Locks unit `stem` for writing, waiting (and saying so) while another process holds it;
    /// Ctrl-C ends the wait. Then removes what killed writers left of the unit.
    pub fn lock(&self, stem: &str) -> Result<Locked<'_>> {
        let locked = self.acquire(stem, true)?;
        super::remove_temps(&self.dir, &format!("{stem}."));
        let keep = match locked.read_manifest::<serde_json::Value>() {
            Ok(Some((_, files))) => files.into_values().map(|f| f.name).collect(),
            Ok(None) => Vec::new(),
            // A damaged manifest: leave its files for whoever looks into it.
            Err(_) => return Ok(locked),
        };
        locked.remove_unnamed(&keep, true);
        Ok(locked)
    }

    /// Locks unit `stem` for reading (several readers at once).
    pub fn lock_shared(&self, stem: &str) -> Result<Locked<'_>> {
        self.acquire(stem, false)
    }

    fn acquire(&self, stem: &str, exclusive: bool) -> Result<Locked<'_>> {
        let path = self.dir.join(format!(".{stem}.lock"));
        let file = super::open_lock(&path, true)?;
        let _polling = crate::interrupt::polling();
        let mut said = false;
        loop {
            let attempt = if exclusive {
                file.try_lock()
            } else {
                file.try_lock_shared()
            };
            match attempt {
                Ok(()) => break,
                Err(TryLockError::WouldBlock) => {
                    if crate::interrupt::requested() {
                        return Err(Error::Interrupted(format!(
                            "while waiting for {}",
                            path.display()
                        )));
                    }
                    if !said {
                        crate::interrupt::note(&format!(
                            "waiting for another dibench process using {} (lock {})",
                            stem,
                            path.display()
                        ));
                        said = true;
                    }
                    std::thread::sleep(Duration::from_millis(50));
                }
                Err(TryLockError::Error(e)) => return Err(Error::io(&path, e)),
            }
        }
        Ok(Locked {
            store: self,
            stem: stem.into(),
            exclusive,
            _lock: file,
        })
    }
}

impl Locked<'_> {
    pub fn stem(&self) -> &str {
        &self.stem
    }

    /// The manifest's path.
    pub fn manifest_path(&self) -> PathBuf {
        self.store.manifest_path(&self.stem)
    }

    /// The manifest as parsed: None when there is none, or when it predates manifests (no
    /// `files`: such a unit was written without a commit and is not trusted).
    fn read_manifest<M: DeserializeOwned>(
        &self,
    ) -> Result<Option<(M, BTreeMap<String, FileRecord>)>> {
        let path = self.manifest_path();
        if std::fs::symlink_metadata(&path).is_err() {
            return Ok(None);
        }
        let bytes = bounded::read_file(&path, 4)?;
        let damaged = |message: String| Error::Parse {
            path: path.clone(),
            message: format!(
                "{message}; the stored unit is damaged: delete {} to make a new one",
                path.display()
            ),
        };
        let value: serde_json::Value =
            serde_json::from_slice(&bytes).map_err(|e| damaged(e.to_string()))?;
        if value.get("files").is_none() {
            return Ok(None);
        }
        let m: ManifestIn<M> = serde_json::from_value(value).map_err(|e| damaged(e.to_string()))?;
        for r in m.files.values() {
            let plain = Path::new(&r.name).file_name() == Some(r.name.as_ref());
            if !plain || !r.name.starts_with(&format!("{}.", self.stem)) {
                return Err(damaged(format!(
                    "names a file outside the unit: `{}`",
                    r.name
                )));
            }
        }
        Ok(Some((m.meta, m.files)))
    }

    /// The committed metadata alone (files not read nor checked); None when nothing is.
    pub fn meta<M: DeserializeOwned>(&self) -> Result<Option<M>> {
        Ok(self.read_manifest::<M>()?.map(|(m, _)| m))
    }

    /// The unit, every file checked against its manifest; None when nothing is committed.
    pub fn read<M: DeserializeOwned>(&self) -> Result<Option<Unit<M>>> {
        let Some((meta, records)) = self.read_manifest::<M>()? else {
            return Ok(None);
        };
        let manifest = self.manifest_path();
        let mut files = BTreeMap::new();
        for (role, r) in records {
            let path = self.store.dir.join(&r.name);
            let bytes = bounded::read_file(&path, 0)?;
            let sha = hex(&Sha256::digest(&bytes));
            if bytes.len() as u64 != r.bytes || sha != r.sha256 {
                return Err(Error::Parse {
                    path,
                    message: format!(
                        "does not match its manifest {} ({} bytes, expected {}; SHA-256 {}): \
                         the stored unit is damaged: delete the manifest to make a new one",
                        manifest.display(),
                        bytes.len(),
                        r.bytes,
                        if sha == r.sha256 { "equal" } else { "differs" }
                    ),
                });
            }
            files.insert(role, (path, bytes));
        }
        Ok(Some(Unit {
            meta,
            manifest,
            files,
        }))
    }

    /// Commits `meta` with `files` as the unit's new content (see the module comment) and
    /// returns the manifest's path. Needs the write lock.
    pub fn commit<M: Serialize>(&self, meta: &M, files: Vec<NewFile<'_>>) -> Result<PathBuf> {
        if !self.exclusive {
            return Err(Error::Usage(format!(
                "internal: commit of `{}` without the write lock",
                self.stem
            )));
        }
        let dir = &self.store.dir;
        crate::interrupt::critical(|| {
            let mut records = BTreeMap::new();
            for f in files {
                let (mut tmp, _registered) =
                    crate::interrupt::create_temp(|| super::temp_file_in(dir, &self.stem))?;
                let path = tmp.path().to_path_buf();
                (f.write)(tmp.as_file_mut(), &path)?;
                let file = tmp.as_file_mut();
                file.sync_all().map_err(|e| Error::io(&path, e))?;
                // Read back through the handle (never reopened by name: see `write_atomic`).
                let mut bytes = Vec::new();
                file.seek(std::io::SeekFrom::Start(0))
                    .and_then(|_| file.read_to_end(&mut bytes))
                    .map_err(|e| Error::io(&path, e))?;
                let sha256 = hex(&Sha256::digest(&bytes));
                let name = format!("{}.{}.{}", self.stem, &sha256[..16], f.ext);
                tmp.persist(dir.join(&name))
                    .map_err(|e| Error::io(dir.join(&name), e.error))?;
                records.insert(
                    f.role,
                    FileRecord {
                        name,
                        bytes: bytes.len() as u64,
                        sha256,
                    },
                );
            }
            super::sync_dir(dir);
            let keep: Vec<String> = records.values().map(|r| r.name.clone()).collect();
            let manifest = self.manifest_path();
            super::write_json(
                &manifest,
                &ManifestOut {
                    meta,
                    files: records,
                },
            )?;
            super::sync_dir(dir);
            self.remove_unnamed(&keep, false);
            Ok(manifest)
        })
    }

    /// Removes this unit's files that `keep` does not name (never the manifest): with
    /// `content_only`, only content-named files (`<stem>.<16 hex>.<ext>`), so that files of
    /// an older layout stay until a commit replaces them.
    fn remove_unnamed(&self, keep: &[String], content_only: bool) {
        let Ok(entries) = std::fs::read_dir(&self.store.dir) else {
            return;
        };
        let prefix = format!("{}.", self.stem);
        let manifest = format!("{}.json", self.stem);
        for e in entries.flatten() {
            let Ok(name) = e.file_name().into_string() else {
                continue;
            };
            let Some(rest) = name.strip_prefix(&prefix) else {
                continue;
            };
            let content_named = rest.len() > 17
                && rest.as_bytes()[16] == b'.'
                && rest[..16].bytes().all(|b| b.is_ascii_hexdigit());
            if name == manifest || keep.contains(&name) || (content_only && !content_named) {
                continue;
            }
            if e.file_type().is_ok_and(|t| t.is_file()) {
                let _ = std::fs::remove_file(e.path());
            }
        }
    }
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    #[derive(Serialize, Deserialize, PartialEq, Debug)]
    struct Meta {
        spp: u64,
    }

    fn text(s: &'static str) -> NewFile<'static> {
        NewFile {
            role: "data",
            ext: "txt",
            write: Box::new(move |f, p| f.write_all(s.as_bytes()).map_err(|e| Error::io(p, e))),
        }
    }

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .flatten()
            .map(|e| e.file_name().into_string().unwrap())
            .filter(|n| !n.ends_with(".lock"))
            .collect();
        v.sort();
        v
    }

    #[test]
    fn a_commit_replaces_the_unit_and_removes_the_old_files() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(dir.path()).unwrap();
        let lock = store.lock("u").unwrap();
        assert!(lock.read::<Meta>().unwrap().is_none());
        lock.commit(&Meta { spp: 1 }, vec![text("one")]).unwrap();
        lock.commit(&Meta { spp: 2 }, vec![text("two")]).unwrap();
        let unit = lock.read::<Meta>().unwrap().unwrap();
        assert_eq!(unit.meta, Meta { spp: 2 });
        assert_eq!(unit.file("data").unwrap().1, b"two");
        assert_eq!(names(dir.path()).len(), 2, "{:?}", names(dir.path()));
    }

    /// What a writer killed mid-commit leaves (a temporary file, a content file no manifest
    /// names) is ignored by readers and removed by the next writer; a damaged file is an error
    /// naming it.
    #[test]
    fn leftovers_are_ignored_and_cleaned_and_damage_is_reported() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(dir.path()).unwrap();
        {
            let lock = store.lock("u").unwrap();
            lock.commit(&Meta { spp: 1 }, vec![text("one")]).unwrap();
        }
        std::fs::write(dir.path().join(".u.abc123.tmp"), "half").unwrap();
        std::fs::write(dir.path().join("u.0123456789abcdef.txt"), "orphan").unwrap();
        let before = names(dir.path()).len();
        let unit = store
            .lock_shared("u")
            .unwrap()
            .read::<Meta>()
            .unwrap()
            .unwrap();
        assert_eq!(unit.file("data").unwrap().1, b"one");
        assert_eq!(names(dir.path()).len(), before, "a reader removed files");
        let lock = store.lock("u").unwrap();
        assert_eq!(names(dir.path()).len(), 2, "{:?}", names(dir.path()));
        let (path, _) = lock
            .read::<Meta>()
            .unwrap()
            .unwrap()
            .file("data")
            .map(|(p, b)| (p.to_path_buf(), b.to_vec()))
            .unwrap();
        std::fs::write(&path, "tampered").unwrap();
        let msg = lock.read::<Meta>().err().unwrap().to_string();
        assert!(
            msg.contains(&path.display().to_string()) && msg.contains("does not match"),
            "{msg}"
        );
    }
}
