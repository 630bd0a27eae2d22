//! Tests that change what is process-wide run in a process of their own.
//!
//! nextest gives every test a process, but `cargo test` runs all of this binary's tests
//! in one, on parallel threads. A test that installs a global `tracing` subscriber (one
//! per process, for good) would take it from every later test that needs one, the
//! timeline's capture among them; such a test calls [`in_own_process`] first.

use std::process::Command;

/// Set in the environment of the child process a test runs alone in.
const OWN_PROCESS: &str = "SPLITRAY_TEST_OWN_PROCESS";

/// True where the calling test is the only test of its process and may go on. Otherwise
/// it runs `test` (its full name, `module::name`) alone in a child process of this test
/// binary, fails unless that one test ran and passed, and returns false: the caller
/// returns. The binary cannot tell nextest's one-test processes from `cargo test`'s
/// shared one, so under nextest the test runs in a child too.
pub fn in_own_process(test: &str) -> bool {
    if std::env::var_os(OWN_PROCESS).is_some_and(|name| name == test) {
        return true;
    }
    let binary = std::env::current_exe().expect("the test binary's path");
    let output = Command::new(&binary)
        .args(["--exact", test, "--nocapture", "--test-threads", "1"])
        .env(OWN_PROCESS, test)
        .output()
        .expect("run the test binary");
    let stdout = String::from_utf8_lossy(&output.stdout);
    eprint!("{stdout}{}", String::from_utf8_lossy(&output.stderr));
    assert!(
        output.status.success() && stdout.contains("test result: ok. 1 passed"),
        "{test}, alone in a process of {}: {}",
        binary.display(),
        output.status
    );
    false
}
