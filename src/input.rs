//! Opening the files a command reads (scenes, meshes, material libraries, checkpoints,
//! EXRs, timelines).
//!
//! Only regular files are opened: a FIFO's `open` blocks until a writer comes, perhaps
//! never, and the process stuck in it does not even reach the signal handling that would
//! let it stop; a folder or a device is no input either. The check reads the path's
//! metadata, which never blocks, so a wrong path fails at once, naming what it is. The
//! path is then opened without blocking (`O_NONBLOCK`, which reads of a regular file
//! ignore) and the opened file's own metadata checked again: a file replaced by a FIFO
//! between the two is refused as well, not waited on.
//!
//! Every file opened here is remembered ([`files_read`]), so that a command can refuse
//! an output path that would overwrite one of its inputs — a scene's meshes and material
//! libraries as much as the files named on its command line.

use std::collections::BTreeSet;
use std::fs::File;
use std::io::{self, Read};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The paths of the files this process opened through [`open`].
static FILES_READ: Mutex<BTreeSet<PathBuf>> = Mutex::new(BTreeSet::new());

/// Every file this process has read through this module so far, as the paths it was
/// opened by.
pub fn files_read() -> Vec<PathBuf> {
    // The set is never left half-changed (one insert at a time), so a panic elsewhere
    // while it was held does not spoil it.
    let read = FILES_READ.lock().unwrap_or_else(|p| p.into_inner());
    read.iter().cloned().collect()
}

/// Fails unless `path` (followed through symbolic links) is a regular file; the error
/// says what it is instead.
pub fn check_regular_file(path: &Path) -> io::Result<()> {
    let kind = std::fs::metadata(path)?.file_type();
    if kind.is_file() {
        return Ok(());
    }
    Err(io::Error::new(
        io::ErrorKind::InvalidInput,
        format!("it is {}, not a regular file", describe(&kind)),
    ))
}

/// What a file that is not a regular file is, for an error message.
fn describe(kind: &std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_fifo() {
            return "a FIFO";
        }
        if kind.is_socket() {
            return "a socket";
        }
        if kind.is_char_device() || kind.is_block_device() {
            return "a device";
        }
    }
    if kind.is_dir() {
        "a folder"
    } else {
        "not a file"
    }
}

/// [`File::open`] of a regular file only.
pub fn open(path: &Path) -> io::Result<File> {
    // The path's metadata first: opening a device can itself have effects.
    check_regular_file(path)?;
    let file = open_without_blocking(path)?;
    FILES_READ
        .lock()
        .unwrap_or_else(|p| p.into_inner())
        .insert(path.to_path_buf());
    Ok(file)
}

/// Opens `path` for reading without waiting for a FIFO's writer, and fails unless what
/// was opened is a regular file (the check of the open file, so no race with a rename).
fn open_without_blocking(path: &Path) -> io::Result<File> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK);
    }
    let file = options.open(path)?;
    let kind = file.metadata()?.file_type();
    if kind.is_file() {
        return Ok(file);
    }
    Err(io::Error::new(
        io::ErrorKind::InvalidInput,
        format!("it is {}, not a regular file", describe(&kind)),
    ))
}

/// [`std::fs::read`] of a regular file only.
pub fn read(path: &Path) -> io::Result<Vec<u8>> {
    let mut bytes = Vec::new();
    open(path)?.read_to_end(&mut bytes)?;
    Ok(bytes)
}

/// [`std::fs::read_to_string`] of a regular file only.
pub fn read_to_string(path: &Path) -> io::Result<String> {
    let mut text = String::new();
    open(path)?.read_to_string(&mut text)?;
    Ok(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_regular_files_are_read() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("a.txt");
        std::fs::write(&file, "text").unwrap();
        assert_eq!(read_to_string(&file).unwrap(), "text");
        assert!(files_read().contains(&file));
        let error = read(dir.path()).unwrap_err();
        assert_eq!(error.to_string(), "it is a folder, not a regular file");
        #[cfg(unix)]
        assert_eq!(
            open(Path::new("/dev/null")).unwrap_err().to_string(),
            "it is a device, not a regular file"
        );
        let missing = read(&dir.path().join("missing")).unwrap_err();
        assert_eq!(missing.kind(), io::ErrorKind::NotFound);
    }

    /// A FIFO that takes the place of a checked file before it is opened: the open
    /// neither waits for a writer nor returns the FIFO.
    #[cfg(unix)]
    #[test]
    fn a_fifo_behind_the_check_is_refused_without_waiting() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("scene.toml");
        let made = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .expect("run mkfifo");
        assert!(made.success());
        let error = open_without_blocking(&fifo).unwrap_err();
        assert_eq!(error.to_string(), "it is a FIFO, not a regular file");
        assert_eq!(error.kind(), io::ErrorKind::InvalidInput);
    }
}
