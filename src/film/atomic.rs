//! Atomic file output: write to a temporary file beside the target, rename on success.
//!
//! A reader of the target path sees either the previous file (or nothing) or the complete
//! new file, never a partially written one. On any error — and on a panic during the
//! write — the temporary file is removed.
//!
//! Every live temporary file is also listed in one process-wide registry, so that a
//! process told to exit at once (a second Ctrl-C) can remove them all first
//! ([`discard_all_temporaries`]) without waiting for the writers to unwind.

use std::collections::BTreeSet;
use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, MutexGuard};

use super::FilmError;

/// Distinguishes temporary files of concurrent writes within one process.
static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// The temporary files of every live [`AtomicFile`]. Creating, committing and discarding
/// a temporary file happen under this lock, so a temporary file is either listed here or
/// gone (renamed over its target or removed).
static LIVE_TEMPORARIES: Mutex<BTreeSet<PathBuf>> = Mutex::new(BTreeSet::new());

fn live_temporaries() -> MutexGuard<'static, BTreeSet<PathBuf>> {
    // A writer that panicked while holding the lock left the set consistent: every
    // change to it is a single insert or remove.
    LIVE_TEMPORARIES
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Holds every [`AtomicFile`] of the process still: while it lives, none can be created
/// or committed. Returned by [`discard_all_temporaries`] for a caller about to exit.
pub struct TemporariesDiscarded {
    _lock: MutexGuard<'static, BTreeSet<PathBuf>>,
    /// The temporary files removed.
    pub removed: Vec<PathBuf>,
}

/// Removes the temporary file of every live [`AtomicFile`] and blocks all of them (other
/// threads that try to create or commit one wait forever) until the returned guard is
/// dropped: for a process that exits at once and must leave no partial output behind.
/// A file being renamed over its target meanwhile is complete, so it is left in place.
pub fn discard_all_temporaries() -> TemporariesDiscarded {
    let mut live = live_temporaries();
    let removed: Vec<PathBuf> = std::mem::take(&mut *live).into_iter().collect();
    for temp in &removed {
        // Best effort: the process is about to exit and has nobody to tell.
        let _ = std::fs::remove_file(temp);
    }
    TemporariesDiscarded {
        _lock: live,
        removed,
    }
}

/// A temporary file that becomes `target` on [`AtomicFile::commit`] and is deleted if
/// dropped uncommitted.
///
/// The temporary file lives in the target's directory (so the rename cannot cross file
/// systems) and is named `.<file name>.tmp-<pid>-<n>` (`.splitray.tmp-<pid>-<n>` for a
/// target whose name is too long for that).
#[derive(Debug)]
pub struct AtomicFile {
    target: PathBuf,
    temp: PathBuf,
    writer: Option<BufWriter<File>>,
}

/// The longest file name most file systems take, in bytes (Linux's `NAME_MAX`).
const MAX_NAME_BYTES: usize = 255;

/// Whether `path` ends in a path separator (`out.exr/`).
pub fn ends_in_a_separator(path: &Path) -> bool {
    path.as_os_str()
        .as_encoded_bytes()
        .last()
        .is_some_and(|&b| std::path::is_separator(b as char))
}

/// The name of a new temporary file for the target named `file_name`:
/// `.<file name>.tmp-<pid>-<n>`, or `.splitray.tmp-<pid>-<n>` where that would be too
/// long a name (a target whose name is near the limit is still a legal output).
fn temp_name(file_name: &std::ffi::OsStr) -> std::ffi::OsString {
    let suffix = format!(
        ".tmp-{}-{}",
        std::process::id(),
        TEMP_COUNTER.fetch_add(1, Ordering::Relaxed)
    );
    let mut name = std::ffi::OsString::from(".");
    if 1 + file_name.len() + suffix.len() <= MAX_NAME_BYTES {
        name.push(file_name);
    } else {
        name.push("splitray");
    }
    name.push(suffix);
    name
}

impl AtomicFile {
    /// Creates the temporary file for `target`.
    ///
    /// Fails with [`FilmError::MissingDirectory`] when the target's folder does not exist
    /// or is not a folder, and with [`FilmError::Io`] naming the target when the temporary
    /// file cannot be created (e.g. the folder is not writable).
    pub fn create(target: impl AsRef<Path>) -> Result<Self, FilmError> {
        let target = target.as_ref().to_path_buf();
        let file_name = target
            .file_name()
            .ok_or_else(|| FilmError::invalid(&target, "output path has no file name"))?;
        let dir = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        if !dir.is_dir() {
            return Err(FilmError::MissingDirectory {
                path: target,
                folder: dir,
            });
        }
        // Renaming over a folder, or to a path that ends in a separator (`out.exr/`,
        // whose file name `Path` reads as `out.exr`), fails only at the end, after the
        // work.
        if target.is_dir() {
            return Err(FilmError::invalid(&target, "is a folder, not a file"));
        }
        if ends_in_a_separator(&target) {
            return Err(FilmError::invalid(
                &target,
                "ends in a separator, so it names a folder, not a file",
            ));
        }
        let temp = dir.join(temp_name(file_name));
        let mut live = live_temporaries();
        let file = OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&temp)
            .map_err(|e| FilmError::io(&target, "create a temporary file for it", e))?;
        live.insert(temp.clone());
        drop(live);
        Ok(Self {
            target,
            temp,
            writer: Some(BufWriter::new(file)),
        })
    }

    /// The final path.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// The temporary path being written.
    pub fn temp_path(&self) -> &Path {
        &self.temp
    }

    /// The buffered writer of the temporary file (seekable, as the EXR encoder needs).
    pub fn writer(&mut self) -> &mut BufWriter<File> {
        self.writer
            .as_mut()
            .expect("AtomicFile writer is present until commit")
    }

    /// Flushes and syncs the temporary file, then renames it over the target.
    /// On error the temporary file is removed and the target is untouched.
    pub fn commit(mut self) -> Result<PathBuf, FilmError> {
        let writer = self.writer.take().expect("AtomicFile committed twice");
        let file = writer
            .into_inner()
            .map_err(|e| FilmError::io(&self.target, "flush its temporary file", e.into_error()))?;
        file.sync_all()
            .map_err(|e| FilmError::io(&self.target, "sync its temporary file", e))?;
        drop(file);
        let mut live = live_temporaries();
        if !live.remove(&self.temp) {
            // Discarded by `discard_all_temporaries` between the sync and the lock.
            self.temp = PathBuf::new();
            return Err(FilmError::invalid(
                &self.target,
                "discarded before the rename",
            ));
        }
        if let Err(e) = std::fs::rename(&self.temp, &self.target) {
            live.insert(self.temp.clone());
            return Err(FilmError::io(
                &self.target,
                "rename its temporary file over it",
                e,
            ));
        }
        drop(live);
        // Renamed: nothing left to clean up.
        self.temp = PathBuf::new();
        #[cfg(unix)]
        if let Some(dir) = self.target.parent().filter(|p| !p.as_os_str().is_empty()) {
            // Best effort: make the rename itself durable.
            let _ = File::open(dir).and_then(|d| d.sync_all());
        }
        Ok(self.target.clone())
    }
}

impl Drop for AtomicFile {
    fn drop(&mut self) {
        if !self.temp.as_os_str().is_empty() {
            drop(self.writer.take());
            let mut live = live_temporaries();
            if !live.remove(&self.temp) {
                // Already removed by `discard_all_temporaries`.
                return;
            }
            if let Err(e) = std::fs::remove_file(&self.temp) {
                log::warn!(
                    "could not remove temporary file {}: {e}",
                    self.temp.display()
                );
            }
        }
    }
}

/// Writes `target` atomically: `write` fills a temporary file which is renamed over
/// `target` only if `write` succeeds; otherwise the temporary file is removed.
pub fn write_atomically<F>(target: impl AsRef<Path>, write: F) -> Result<PathBuf, FilmError>
where
    F: FnOnce(&mut BufWriter<File>) -> Result<(), FilmError>,
{
    let mut file = AtomicFile::create(target)?;
    write(file.writer())?;
    file.commit()
}

/// Convenience: [`write_atomically`] of a byte slice.
pub fn write_bytes_atomically(
    target: impl AsRef<Path>,
    bytes: &[u8],
) -> Result<PathBuf, FilmError> {
    let target = target.as_ref();
    write_atomically(target, |w| {
        w.write_all(bytes)
            .map_err(|e| FilmError::io(target, "write", e))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entries(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn success_replaces_target_and_leaves_no_temp() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out.bin");
        std::fs::write(&target, b"old").unwrap();
        write_bytes_atomically(&target, b"new").unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
        assert_eq!(entries(dir.path()), ["out.bin"]);
    }

    #[test]
    fn failing_writer_keeps_old_target_and_removes_temp() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out.bin");
        std::fs::write(&target, b"old").unwrap();
        let err = write_atomically(&target, |w| {
            w.write_all(b"partial").unwrap();
            Err(FilmError::invalid(&target, "boom"))
        })
        .unwrap_err();
        assert!(err.to_string().contains("boom"));
        assert_eq!(std::fs::read(&target).unwrap(), b"old");
        assert_eq!(entries(dir.path()), ["out.bin"]);
    }

    #[test]
    fn panicking_writer_removes_temp() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out.bin");
        let r = std::panic::catch_unwind(|| {
            let _ = write_atomically(&target, |_| panic!("writer panicked"));
        });
        assert!(r.is_err());
        assert!(entries(dir.path()).is_empty());
    }

    #[test]
    fn missing_directory_names_the_path() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("no-such-dir");
        let err = write_bytes_atomically(missing.join("x.bin"), b"x").unwrap_err();
        assert!(matches!(&err, FilmError::MissingDirectory { folder, .. } if *folder == missing));
        assert!(err.to_string().contains("no-such-dir"), "{err}");
    }

    #[test]
    fn a_file_name_near_the_limit_gets_a_short_temporary_name() {
        let dir = tempfile::tempdir().unwrap();
        let name = format!("{}.exr", "n".repeat(MAX_NAME_BYTES - 4));
        let target = dir.path().join(&name);
        let f = AtomicFile::create(&target).unwrap();
        let temp = f.temp_path().file_name().unwrap().to_str().unwrap();
        assert!(temp.starts_with(".splitray.tmp-"), "{temp}");
        f.commit().unwrap();
        assert_eq!(entries(dir.path()), [name]);
    }

    #[test]
    fn a_file_in_place_of_the_folder_is_named_as_such() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("plain"), "").unwrap();
        let err = AtomicFile::create(dir.path().join("plain/x.exr")).unwrap_err();
        assert!(err.to_string().ends_with("plain is not a folder"), "{err}");
    }

    #[test]
    fn a_path_that_names_a_folder_is_refused_before_any_write() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("sub")).unwrap();
        for target in [dir.path().join("sub"), dir.path().join("x.exr/")] {
            let err = AtomicFile::create(&target).unwrap_err().to_string();
            assert!(err.contains("not a file"), "{err}");
        }
        assert_eq!(entries(dir.path()), ["sub"]);
    }

    #[test]
    fn uncommitted_file_is_removed_on_drop() {
        let dir = tempfile::tempdir().unwrap();
        let mut f = AtomicFile::create(dir.path().join("a.exr")).unwrap();
        f.writer().write_all(b"abc").unwrap();
        let temp = f.temp_path().to_path_buf();
        assert!(temp
            .file_name()
            .unwrap()
            .to_str()
            .unwrap()
            .starts_with(".a.exr.tmp-"));
        assert!(temp.exists());
        drop(f);
        assert!(entries(dir.path()).is_empty());
    }
}
