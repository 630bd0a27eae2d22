//! Running the `splitray` binary from a test, as a user does.

use std::path::Path;
use std::process::{Command, Output};

/// `splitray ARGS` in `dir`, warnings and errors logged, to run or spawn.
pub fn command(args: &[&str], dir: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_splitray"));
    c.args(args).current_dir(dir).env("RUST_LOG", "warn");
    c
}

/// Runs `splitray ARGS` in `dir` (warnings and errors logged) and waits for it.
pub fn splitray(args: &[&str], dir: &Path) -> Output {
    command(args, dir).output().expect("run splitray")
}

/// Everything the command printed: standard output, then standard error.
pub fn printed(output: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    )
}
