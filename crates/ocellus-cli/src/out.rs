//! Standard output and error that report failed writes instead of panicking.
//!
//! `println!` panics when stdout cannot be written (`> /dev/full`), and with the default
//! SIGPIPE action a closed reader (`| head -1`, or an ffmpeg that died) kills the process
//! without a word. Rust ignores SIGPIPE, so a write to a closed pipe returns `BrokenPipe`:
//! [`outln!`] turns every failed write into a [`StdoutError`] that `main` reports with a
//! non-zero exit, or ends on quietly when the reader went away.

use std::fmt;
use std::io::Write;

/// A write to standard output failed.
#[derive(Debug)]
pub struct StdoutError(pub std::io::Error);

impl fmt::Display for StdoutError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "cannot write to standard output: {}", self.0)
    }
}

// No `source`: the message already carries the OS error, and `{:#}` would print it twice.
impl std::error::Error for StdoutError {}

impl StdoutError {
    /// Whether the reader closed the pipe (`ocellus ... | head -1`): not worth a message.
    pub fn is_broken_pipe(&self) -> bool {
        self.0.kind() == std::io::ErrorKind::BrokenPipe
    }
}

thread_local! {
    /// Where [`write_stdout`] writes while [`captured`] runs on this thread.
    static CAPTURE: std::cell::RefCell<Option<String>> = const { std::cell::RefCell::new(None) };
}

/// Writes formatted text to standard output (used by [`outln!`] and [`out!`]), or into the
/// buffer of a [`captured`] call on this thread.
pub fn write_stdout(args: fmt::Arguments<'_>) -> Result<(), StdoutError> {
    let taken = CAPTURE.with(|c| match c.borrow_mut().as_mut() {
        Some(buf) => {
            // Writing to a String cannot fail.
            let _ = fmt::Write::write_fmt(buf, args);
            true
        }
        None => false,
    });
    if taken {
        return Ok(());
    }
    std::io::stdout().lock().write_fmt(args).map_err(StdoutError)
}

/// Runs `f` with what it writes through [`outln!`] and [`out!`] on this thread collected
/// instead of printed (the demo keeps each command's report for its page); returns `f`'s
/// result and the text. Nested calls collect into the innermost.
pub fn captured<T>(f: impl FnOnce() -> T) -> (T, String) {
    let outer = CAPTURE.with(|c| c.borrow_mut().replace(String::new()));
    let r = f();
    let text = CAPTURE.with(|c| std::mem::replace(&mut *c.borrow_mut(), outer)).unwrap_or_default();
    (r, text)
}

/// Flushes standard output: the last bytes of a block-buffered stdout fail only here.
pub fn flush_stdout() -> Result<(), StdoutError> {
    std::io::stdout().lock().flush().map_err(StdoutError)
}

/// Writes a line to standard error, ignoring failure: a message about a failure must not
/// itself become a panic when stderr is gone.
pub fn write_stderr(args: fmt::Arguments<'_>) {
    let _ = std::io::stderr().lock().write_fmt(args);
}

/// `println!` that returns a [`StdoutError`] from the enclosing function with `?`.
macro_rules! outln {
    () => {
        $crate::out::write_stdout(format_args!("\n"))?
    };
    ($($arg:tt)*) => {
        $crate::out::write_stdout(format_args!("{}\n", format_args!($($arg)*)))?
    };
}

/// `print!` that returns a [`StdoutError`] from the enclosing function with `?`.
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::out::write_stdout(format_args!($($arg)*))?
    };
}

/// `eprintln!` that never panics.
macro_rules! errln {
    ($($arg:tt)*) => {
        $crate::out::write_stderr(format_args!("{}\n", format_args!($($arg)*)))
    };
}
