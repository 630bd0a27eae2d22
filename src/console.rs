//! What splitray prints for people: text on standard output and notes on standard
//! error, written so that a stream that cannot take them never ends the program.
//!
//! `println!` panics when standard output is a closed pipe (`splitray render … | head`,
//! a log reader that died) or a full disk. A render that had finished would then lose
//! every file it had yet to write. Here a failed write is dropped instead: the first
//! failure of standard output is noted once on standard error, and later text for it is
//! not tried again; a failed note on standard error is dropped silently (there is
//! nowhere left to say it).

use std::fmt;
use std::io::Write;
use std::sync::atomic::{AtomicBool, Ordering};

/// Standard output failed once: its text is dropped from then on.
static STDOUT_LOST: AtomicBool = AtomicBool::new(false);

/// Writes `text` to standard output (and flushes it, so that a failure shows now).
pub fn write_out(text: fmt::Arguments<'_>) {
    if STDOUT_LOST.load(Ordering::Relaxed) {
        return;
    }
    let mut out = std::io::stdout().lock();
    if let Err(e) = out.write_fmt(text).and_then(|()| out.flush()) {
        if !STDOUT_LOST.swap(true, Ordering::Relaxed) {
            write_err(format_args!(
                "note: standard output failed ({e}); what splitray prints there is \
                 dropped, its files are still written\n"
            ));
        }
    }
}

/// Writes `text` to standard error, dropping it if that fails.
pub fn write_err(text: fmt::Arguments<'_>) {
    let mut err = std::io::stderr().lock();
    let _ = err.write_fmt(text).and_then(|()| err.flush());
}

/// `print!` that never panics ([`write_out`](crate::console::write_out)).
#[macro_export]
macro_rules! out {
    ($($arg:tt)*) => { $crate::console::write_out(format_args!($($arg)*)) };
}

/// `println!` that never panics ([`write_out`](crate::console::write_out)).
#[macro_export]
macro_rules! outln {
    () => {
        $crate::console::write_out(format_args!("\n"))
    };
    ($($arg:tt)*) => {
        $crate::console::write_out(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// `eprint!` that never panics ([`write_err`](crate::console::write_err)).
#[macro_export]
macro_rules! err {
    ($($arg:tt)*) => { $crate::console::write_err(format_args!($($arg)*)) };
}

/// `eprintln!` that never panics ([`write_err`](crate::console::write_err)).
#[macro_export]
macro_rules! errln {
    () => {
        $crate::console::write_err(format_args!("\n"))
    };
    ($($arg:tt)*) => {
        $crate::console::write_err(format_args!("{}\n", format_args!($($arg)*)))
    };
}
