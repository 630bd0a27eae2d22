//! SIGINT, SIGTERM and SIGHUP (through `signal-hook`): during a render, and during the
//! other commands that write files. SIGHUP (the terminal or the ssh connection went
//! away) is a stop like the others, so that a render whose terminal closed still writes
//! what it has; what it prints then goes nowhere ([`splitray::console`]).
//!
//! The first one asks the render to stop: the pass loop asks before every batch of
//! passes, so the work in flight finishes, and the image (with the samples it reached),
//! its stats and its checkpoint are written; the process then exits with 128 + the
//! signal's number (130 for SIGINT, 143 for SIGTERM, 129 for SIGHUP), as a shell reports
//! a process that a signal ended. A second one exits at once: it removes every temporary
//! output file ([`splitray::film::discard_all_temporaries`], which also keeps the
//! writers from creating or renaming another) and calls `_exit`. That skips the Vulkan
//! teardown on purpose: waiting for a submission in flight, or a driver's exit handlers,
//! is exactly what "at once" rules out; the kernel reclaims the device's memory with the
//! process. Outputs already renamed into place are complete; none is ever left
//! half-written.
//!
//! The other commands that write files (merge, bench, timeline, export-scene) have no
//! partial result worth keeping: [`exit_at_first_signal`] makes the first signal exit at
//! once in the same way.

use std::sync::atomic::{AtomicI32, Ordering};
use std::sync::Arc;

use anyhow::Context;
use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
use signal_hook::iterator::Signals;

/// The signals that stop a command.
const STOP_SIGNALS: [i32; 3] = [SIGINT, SIGTERM, SIGHUP];

/// The first stop signal received, if any.
#[derive(Clone)]
pub struct StopSignals {
    received: Arc<AtomicI32>,
}

impl StopSignals {
    /// Handles the stop signals from here on, on a thread of its own; the first one
    /// tells the user `kept`, what stopping keeps.
    pub fn install(kept: &'static str) -> anyhow::Result<Self> {
        let received = Arc::new(AtomicI32::new(0));
        let mut signals =
            Signals::new(STOP_SIGNALS).context("cannot install the signal handlers")?;
        let first = received.clone();
        std::thread::Builder::new()
            .name("signals".into())
            .spawn(move || {
                for signal in signals.forever() {
                    if first
                        .compare_exchange(0, signal, Ordering::SeqCst, Ordering::SeqCst)
                        .is_ok()
                    {
                        splitray::errln!(
                            "\n{}: stopping after the passes in flight; {kept} (send it \
                             again to exit at once, writing nothing)",
                            name(signal)
                        );
                    } else {
                        exit_at_once(signal, " again");
                    }
                }
            })
            .context("cannot start the signal thread")?;
        Ok(Self { received })
    }

    /// The first signal received (its number), if one was.
    pub fn received(&self) -> Option<i32> {
        match self.received.load(Ordering::SeqCst) {
            0 => None,
            s => Some(s),
        }
    }
}

/// The exit status of a process ended by `signal`, as shells report it.
pub fn exit_status(signal: i32) -> u8 {
    (128 + signal).clamp(0, 255) as u8
}

pub fn name(signal: i32) -> &'static str {
    match signal {
        SIGINT => "SIGINT",
        SIGTERM => "SIGTERM",
        SIGHUP => "SIGHUP",
        _ => "signal",
    }
}

/// Handles the stop signals from here on, on a thread of its own: the first one exits at
/// once, removing every temporary output file, with 128 + its number.
pub fn exit_at_first_signal() -> anyhow::Result<()> {
    let mut signals = Signals::new(STOP_SIGNALS).context("cannot install the signal handlers")?;
    std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            if let Some(signal) = signals.forever().next() {
                exit_at_once(signal, "");
            }
        })
        .context("cannot start the signal thread")?;
    Ok(())
}

/// Removes every temporary output file and exits with 128 + `signal`, saying so (the
/// signal's name, then `again` where it is the second one).
fn exit_at_once(signal: i32, again: &str) -> ! {
    let discarded = splitray::film::discard_all_temporaries();
    splitray::errln!(
        "{}{again}: exiting at once; {} unfinished output file(s) removed",
        name(signal),
        discarded.removed.len()
    );
    // `discarded` stays alive: no writer can create or commit a file until the exit.
    signal_hook::low_level::exit(exit_status(signal) as i32)
}
