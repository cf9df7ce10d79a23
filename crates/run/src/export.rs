//! What a run leaves behind besides its final state: the mesh with texture coordinates,
//! animations (Point Cache 2, MDD, a sequence of OBJ files), the per-frame table of numbers and
//! asciinema recordings.
//!
//! Nothing here steps a cloth or reads a clock: callers hand each frame's state (and, for the
//! table, the wall time they measured), so the same run writes the same bytes.

mod animation;
mod cast;
mod mesh_file;
mod stats;

pub use animation::{Animation, AnimationKind, Sampling};
pub use cast::{Cast, cast_frame, header as cast_header};
pub use mesh_file::obj;
pub use stats::{StatsFormat, StatsRow, StatsTable};

/// A failed write to `path`, naming it.
fn write_error(path: &std::path::Path, e: std::io::Error) -> anyhow::Error {
    anyhow::Error::new(e).context(format!("{}: cannot write", path.display()))
}
