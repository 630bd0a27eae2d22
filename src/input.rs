//! Opening the files a command reads (scenes, meshes, material libraries, checkpoints,
//! EXRs, timelines).
//!
//! Only regular files are opened: a FIFO's `open` blocks until a writer comes, perhaps
//! never, and the process stuck in it does not even reach the signal handling that would
//! let it stop; a folder or a device is no input either. The check reads the path's
//! metadata, which never blocks, so a wrong path fails at once, naming what it is.

use std::fs::File;
use std::io;
use std::path::Path;

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
    check_regular_file(path)?;
    File::open(path)
}

/// [`std::fs::read`] of a regular file only.
pub fn read(path: &Path) -> io::Result<Vec<u8>> {
    check_regular_file(path)?;
    std::fs::read(path)
}

/// [`std::fs::read_to_string`] of a regular file only.
pub fn read_to_string(path: &Path) -> io::Result<String> {
    check_regular_file(path)?;
    std::fs::read_to_string(path)
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
}
