//! Every byte clothsim hands to the outside world goes through here.
//!
//! - [`Stdout`]: a command's results on standard output. A reader that stops early (`| head`)
//!   ends the command quietly with exit 0; any other failure (a full disk, a standard output
//!   that was closed before clothsim started) is one clear error and a non-zero exit.
//! - [`write_atomic`]: result files, written whole or not at all, keeping the file's mode, links
//!   and owner, with no temporary files left behind by an interruption; [`StreamFile`] the
//!   same for a result written piece by piece (an animation, a table, a recording).

mod atomic;
mod stdout;

pub use atomic::{StreamFile, Written, check_target, write_atomic};
pub use stdout::{Stdout, ended_by_reader};
