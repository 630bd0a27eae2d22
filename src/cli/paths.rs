//! Checks of the paths a command writes, made before any work: an output of the right
//! kind in an existing folder, and no two files of one command on one path (a later
//! write would replace an earlier output, or an input the command read).

use std::path::{Path, PathBuf};

use anyhow::bail;

/// The folder of `path` (the current one for a bare file name).
pub fn folder_of(path: &Path) -> &Path {
    path.parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
}

/// Checks an output path before any work: its extension is one of `extensions` (in any
/// case: `x.EXR` is an EXR) and its folder exists. `wanted` names the kinds in the
/// error ("an .exr file"). Returns the extension, lower case.
pub fn check_output(path: &Path, extensions: &[&str], wanted: &str) -> anyhow::Result<String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    if !extensions.contains(&ext.as_str()) {
        bail!("{}: the output must be {wanted}", path.display());
    }
    if splitray::film::atomic::ends_in_a_separator(path) {
        bail!(
            "{}: the output must be {wanted}, not a folder (the path ends in a separator)",
            path.display()
        );
    }
    let folder = folder_of(path);
    if folder.exists() && !folder.is_dir() {
        bail!("{}: {} is not a folder", path.display(), folder.display());
    }
    if !folder.is_dir() {
        bail!(
            "{}: the folder {} does not exist",
            path.display(),
            folder.display()
        );
    }
    Ok(ext)
}

/// One file a command reads or writes, named as the command line names it.
pub struct Role<'a> {
    pub what: &'a str,
    pub path: &'a Path,
    /// A render's checkpoint: the one it saves, or the one it resumes. The two may be
    /// one file (that is how a resumed render keeps going); no other pair may.
    pub checkpoint: bool,
}

impl<'a> Role<'a> {
    pub fn file(what: &'a str, path: &'a Path) -> Self {
        Self {
            what,
            path,
            checkpoint: false,
        }
    }

    pub fn checkpoint(what: &'a str, path: &'a Path) -> Self {
        Self {
            what,
            path,
            checkpoint: true,
        }
    }
}

/// Refuses a command whose outputs would overwrite one another, or overwrite one of its
/// inputs (a reference image, the checkpoint a render resumes, a part merged): the later
/// write would replace the earlier one, losing it. Saving a checkpoint over the one the
/// render resumes is allowed.
pub fn refuse_clashing_paths(outputs: &[Role], inputs: &[Role]) -> anyhow::Result<()> {
    for (i, a) in outputs.iter().enumerate() {
        let later_outputs = outputs[i + 1..].iter().map(|b| (b, false));
        for (b, input) in later_outputs.chain(inputs.iter().map(|b| (b, true))) {
            let saves_over_its_resumed_checkpoint = input && a.checkpoint && b.checkpoint;
            if !saves_over_its_resumed_checkpoint && same_file(a.path, b.path) {
                let lost = match input {
                    true => "writing it would destroy the input",
                    false => "one would be written over the other",
                };
                bail!(
                    "{}: {} and {} name the same file: {lost}",
                    a.path.display(),
                    a.what,
                    b.what
                );
            }
        }
    }
    Ok(())
}

/// Whether two paths name one file: their folders resolved (where they exist), then
/// their file names compared.
pub fn same_file(a: &Path, b: &Path) -> bool {
    fn resolved(path: &Path) -> PathBuf {
        match (folder_of(path).canonicalize(), path.file_name()) {
            (Ok(folder), Some(name)) => folder.join(name),
            _ => path.to_path_buf(),
        }
    }
    resolved(a) == resolved(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn clash(outputs: &[Role], inputs: &[Role]) -> Option<String> {
        refuse_clashing_paths(outputs, inputs)
            .err()
            .map(|e| e.to_string())
    }

    #[test]
    fn only_a_checkpoint_saved_over_the_one_resumed_may_share_its_path() {
        let dir = tempfile::tempdir().unwrap();
        let same = dir.path().join("run.ckpt");
        let other = dir.path().join("other.ckpt");
        let saved = Role::checkpoint("--checkpoint", &same);
        let resumed = Role::checkpoint("--resume", &same);
        assert_eq!(clash(&[saved], &[resumed]), None);
        let saved = Role::checkpoint("--checkpoint", &same);
        let resumed_elsewhere = Role::checkpoint("--resume", &other);
        assert_eq!(clash(&[saved], &[resumed_elsewhere]), None);

        // Any other pair on one path is refused, naming both roles.
        let pairs = [
            (
                Role::file("the image", &same),
                Role::checkpoint("--resume", &same),
            ),
            (
                Role::checkpoint("--checkpoint", &same),
                Role::file("--reference", &same),
            ),
            (
                Role::file("--stats", &same),
                Role::file("--reference", &same),
            ),
        ];
        for (output, input) in pairs {
            let (a, b) = (output.what, input.what);
            let message = clash(&[output], &[input]).expect("refused");
            assert!(
                message.contains(&format!("{a} and {b} name the same file")),
                "{message}"
            );
        }
        let outputs = [
            Role::checkpoint("--checkpoint", &same),
            Role::file("--timeline", &same),
        ];
        let message = clash(&outputs, &[]).expect("two outputs on one path");
        assert!(message.contains("--checkpoint and --timeline"), "{message}");
    }

    #[test]
    fn one_file_is_recognised_however_its_path_is_written() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::create_dir(d.join("sub")).unwrap();
        let plain = d.join("p.exr");
        assert!(same_file(&plain, &d.join("sub/../p.exr")));
        assert!(same_file(&plain, &d.join("./p.exr")));
        assert!(!same_file(&plain, &d.join("sub/p.exr")));
        // Relative to the current folder, and absolute.
        let here = std::env::current_dir().unwrap();
        assert!(same_file(Path::new("x.exr"), &here.join("x.exr")));
        assert!(same_file(Path::new("./x.exr"), Path::new("x.exr")));
    }

    #[test]
    fn an_output_must_have_its_kind_and_a_folder() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let exr = |p: &Path| check_output(p, &["exr"], "an .exr file").map_err(|e| e.to_string());
        assert_eq!(exr(&d.join("a.EXR")).unwrap(), "exr");
        assert!(exr(&d.join("a.png"))
            .unwrap_err()
            .contains("must be an .exr file"));
        let missing = exr(&d.join("nowhere/a.exr")).unwrap_err();
        assert!(missing.contains("the folder") && missing.contains("does not exist"));
        std::fs::write(d.join("plain"), "").unwrap();
        let file = exr(&d.join("plain/a.exr")).unwrap_err();
        assert!(file.ends_with("plain is not a folder"), "{file}");
        let folder = exr(Path::new("a.exr/")).unwrap_err();
        assert!(
            folder.contains("not a folder (the path ends in a separator)"),
            "{folder}"
        );
    }
}
