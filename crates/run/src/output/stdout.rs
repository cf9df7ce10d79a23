//! Standard output for results, with the errors a user can act on.
//!
//! The Rust runtime ignores SIGPIPE, so a reader that went away shows up as a `BrokenPipe`
//! write error: that is a normal end of the command (exit 0, nothing said), as for `cat` or
//! `ripgrep`. Every other write error is reported once, naming standard output and the cause.
//!
//! A standard output closed before the program started (`clothsim scenes >&-`) needs care: the
//! Rust runtime quietly reopens descriptors 0 to 2 on `/dev/null` before `main`, so writes would
//! succeed and the output vanish. The runtime opens `/dev/null` for reading and writing, which a
//! shell's `>/dev/null` (write only) never does, so the first use of standard output looks at
//! descriptor 1 and [`Stdout`] refuses to write when it is the runtime's stand-in (or still
//! closed, in a program that skipped the runtime's start-up).

use std::io::{self, IsTerminal, Write};
use std::sync::OnceLock;

/// Whether standard output was closed when the process started (see the module doc).
fn closed_at_start() -> bool {
    static CLOSED: OnceLock<bool> = OnceLock::new();
    *CLOSED.get_or_init(stdout_is_a_stand_in)
}

/// Whether descriptor 1 is closed, or the read-write `/dev/null` the runtime puts in place of a
/// closed one.
#[cfg(unix)]
fn stdout_is_a_stand_in() -> bool {
    use std::os::fd::AsFd;
    use std::os::unix::fs::{FileTypeExt, MetadataExt};
    // SAFETY: `fcntl(F_GETFL)` only reads the descriptor's status flags; it touches no memory.
    #[allow(unsafe_code)]
    let flags = unsafe { libc::fcntl(libc::STDOUT_FILENO, libc::F_GETFL) };
    if flags == -1 {
        return true;
    }
    if flags & libc::O_ACCMODE != libc::O_RDWR {
        return false;
    }
    let Ok(fd) = io::stdout().as_fd().try_clone_to_owned() else {
        return false;
    };
    let (Ok(ours), Ok(null)) = (
        std::fs::File::from(fd).metadata(),
        std::fs::metadata("/dev/null"),
    ) else {
        return false;
    };
    ours.file_type().is_char_device() && ours.rdev() == null.rdev()
}

#[cfg(not(unix))]
fn stdout_is_a_stand_in() -> bool {
    false
}

/// A write to standard output failed.
///
/// Its message says what failed and why, once (it has no `source`, so `{:#}` does not repeat
/// the cause).
#[derive(Debug)]
pub struct StdoutError(io::Error);

impl std::fmt::Display for StdoutError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if closed_at_start() {
            write!(
                f,
                "cannot write the results: standard output is closed \
                 (redirect it to a file or a pipe instead of closing it)"
            )
        } else {
            write!(f, "cannot write to standard output: {}", self.0)
        }
    }
}

impl std::error::Error for StdoutError {}

/// The error for a failed write to standard output, ready to return from a command.
pub fn stdout_error(e: io::Error) -> anyhow::Error {
    anyhow::Error::new(StdoutError(e))
}

/// Whether `e` is standard output's reader having gone away: a normal end, not a failure.
pub fn ended_by_reader(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<StdoutError>()
            .is_some_and(|s| s.0.kind() == io::ErrorKind::BrokenPipe)
    })
}

/// Buffered standard output that refuses to write into a closed one (see the module doc).
///
/// Its [`Write`] methods give [`io::Error`]s; [`Stdout::write_all_or_fail`],
/// [`Stdout::flush_or_fail`] and [`Stdout::finish`] give the command's error, one message.
pub struct Stdout {
    out: io::BufWriter<io::StdoutLock<'static>>,
}

impl Stdout {
    /// Standard output, locked for this command.
    pub fn new() -> Self {
        Self {
            out: io::BufWriter::with_capacity(64 * 1024, io::stdout().lock()),
        }
    }

    /// Whether standard output is a terminal.
    pub fn is_terminal() -> bool {
        !closed_at_start() && io::stdout().is_terminal()
    }

    /// Writes `bytes`, as the command's error on failure.
    ///
    /// # Errors
    /// Naming standard output and the cause ([`ended_by_reader`] tells the normal end apart).
    pub fn write_all_or_fail(&mut self, bytes: &[u8]) -> anyhow::Result<()> {
        self.write_all(bytes).map_err(stdout_error)
    }

    /// Sends what is buffered on its way (a frame to a waiting reader), as the command's error
    /// on failure.
    ///
    /// # Errors
    /// As [`Stdout::write_all_or_fail`].
    pub fn flush_or_fail(&mut self) -> anyhow::Result<()> {
        self.flush().map_err(stdout_error)
    }

    /// Flushes what is buffered, as the command's error on failure.
    ///
    /// # Errors
    /// As [`Stdout::write_all_or_fail`].
    pub fn finish(mut self) -> anyhow::Result<()> {
        self.flush().map_err(stdout_error)
    }
}

impl Default for Stdout {
    fn default() -> Self {
        Self::new()
    }
}

impl Write for Stdout {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        if closed_at_start() {
            return Err(io::Error::new(
                io::ErrorKind::NotConnected,
                "standard output is closed",
            ));
        }
        self.out.write(buf)
    }

    fn flush(&mut self) -> io::Result<()> {
        if closed_at_start() {
            return Err(io::Error::new(
                io::ErrorKind::NotConnected,
                "standard output is closed",
            ));
        }
        self.out.flush()
    }
}
