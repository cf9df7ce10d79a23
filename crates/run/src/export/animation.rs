//! Animations of the cloth: every K-th frame's positions, for a 3D package.
//!
//! - **Point Cache 2** (`.pc2`, little-endian, as Blender's Mesh Cache modifier reads it): a
//!   32-byte header (`char[12]` `"POINTCACHE2\0"`, `i32` version 1, `i32` points, `f32` start
//!   frame, `f32` frames between samples, `i32` samples), then per sample and per point three
//!   `f32`s.
//! - **MDD** (`.mdd`, big-endian): `i32` samples, `i32` points, one `f32` time (seconds) per
//!   sample, then per sample and per point three `f32`s.
//! - **OBJ sequence** (a name with `%d` or `%04d`, ending in `.obj`): one OBJ per sample, the
//!   frame number in its name, each with texture coordinates and normals.
//!
//! Points are in the scene's row-major order, the order of the `v` lines of the OBJ that goes
//! with a cache (the first sample's mesh, written next to it as `NAME.obj`), so a user loads
//! that mesh and attaches the cache to it.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::bail;
use cloth_mesh::{ClothMesh, Vec3};

use super::mesh_file::obj;
use super::write_error;
use crate::output::{self, StreamFile};

/// Which animation format a `--out` names.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum AnimationKind {
    /// Blender's Point Cache 2.
    Pc2,
    /// The MDD point cache.
    Mdd,
    /// One OBJ per sample: the pattern's text before and after the number, and the number's
    /// zero-padded width.
    ObjSequence {
        /// The name up to the `%`.
        before: String,
        /// The smallest number of digits (`%04d`: 4).
        width: usize,
        /// The name after the `d`.
        after: String,
    },
}

impl AnimationKind {
    /// The animation `path` names, `None` for a path with no `%` that names no animation
    /// format (a final-state file, left to the caller).
    ///
    /// # Errors
    /// A pattern that is not one `%d` / `%0Nd` in a name ending in `.obj`, naming it and what
    /// is allowed.
    pub fn of(path: &Path) -> anyhow::Result<Option<Self>> {
        let text = path.to_string_lossy();
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        if !text.contains('%') {
            return Ok(match ext.as_deref() {
                Some("pc2") => Some(Self::Pc2),
                Some("mdd") => Some(Self::Mdd),
                _ => None,
            });
        }
        let bad = |why: &str| -> anyhow::Result<Option<Self>> {
            bail!(
                "--out {text}: {why}; a frame sequence is an .obj name with one %d or %0Nd for \
                 the frame number, such as frames/f_%04d.obj"
            )
        };
        if ext.as_deref() != Some("obj") {
            return bad("a numbered sequence is written as OBJ files");
        }
        let Some((before, rest)) = text.split_once('%') else {
            return bad("no %d");
        };
        let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
        let Some(after) = rest[digits.len()..].strip_prefix('d') else {
            return bad("the % is not followed by d or 0Nd");
        };
        if after.contains('%') || before.contains('%') {
            return bad("more than one %");
        }
        if path
            .file_name()
            .is_none_or(|n| !n.to_string_lossy().contains('%'))
        {
            return bad("the %d must be in the file's name, not in a folder's");
        }
        let width = if digits.is_empty() {
            0
        } else if digits.starts_with('0') && digits.len() <= 3 {
            digits.parse().unwrap_or(0)
        } else {
            return bad("the width must be written 0N, as in %04d, and be at most 99");
        };
        Ok(Some(Self::ObjSequence {
            before: before.to_owned(),
            width,
            after: after.to_owned(),
        }))
    }

    /// The file of frame `frame` of an OBJ sequence.
    fn frame_path(before: &str, width: usize, after: &str, frame: u64) -> PathBuf {
        PathBuf::from(format!("{before}{frame:0width$}{after}"))
    }
}

/// An animation being written, one sample at a time.
#[derive(Debug)]
pub struct Animation {
    kind: AnimationKind,
    /// The cache file (not for an OBJ sequence).
    file: Option<StreamFile>,
    /// The mesh written next to a cache.
    mesh_path: Option<PathBuf>,
    /// That mesh's OBJ, written when the cache is put in place.
    mesh_obj: String,
    samples: u64,
    planned: u64,
    origin: String,
}

/// When an animation's samples are taken.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sampling {
    /// The frame number of the first sample.
    pub first_frame: u64,
    /// Frames between samples (at least 1).
    pub every: u64,
    /// How many samples the run writes.
    pub samples: u64,
    /// Frames per simulated second.
    pub frames_per_sec: f64,
}

impl Animation {
    /// Starts the animation `kind` at `path` of a cloth of `points` points sampled as
    /// `sampling` says; `origin` names the scene in the OBJ comments. Checks the folder (and
    /// creates a cache's file) before any work is done.
    ///
    /// # Errors
    /// A folder that does not exist or a file that cannot be created, naming it; more points
    /// or samples than the format's 32-bit counts hold.
    pub fn create(
        kind: AnimationKind,
        path: &Path,
        points: usize,
        sampling: Sampling,
        origin: &str,
    ) -> anyhow::Result<Self> {
        let count = |n: u64, what: &str| {
            i32::try_from(n).map_err(|_| {
                anyhow::anyhow!(
                    "--out {}: {n} {what} do not fit the format's 32-bit count",
                    path.display()
                )
            })
        };
        let mut head = Vec::new();
        match &kind {
            AnimationKind::Pc2 => {
                head.extend_from_slice(b"POINTCACHE2\0");
                head.extend_from_slice(&1i32.to_le_bytes());
                head.extend_from_slice(&count(points as u64, "points")?.to_le_bytes());
                head.extend_from_slice(&(sampling.first_frame as f32).to_le_bytes());
                head.extend_from_slice(&(sampling.every as f32).to_le_bytes());
                head.extend_from_slice(&count(sampling.samples, "samples")?.to_le_bytes());
            }
            AnimationKind::Mdd => {
                head.extend_from_slice(&count(sampling.samples, "samples")?.to_be_bytes());
                head.extend_from_slice(&count(points as u64, "points")?.to_be_bytes());
                for i in 0..sampling.samples {
                    let frame = sampling.first_frame + i * sampling.every;
                    let time = (frame as f64 / sampling.frames_per_sec) as f32;
                    head.extend_from_slice(&time.to_be_bytes());
                }
            }
            AnimationKind::ObjSequence { .. } => {}
        }
        let (file, mesh_path) = match &kind {
            AnimationKind::ObjSequence {
                before,
                width,
                after,
            } => {
                // The last frame's name is the longest; the first's is checked for its folder.
                let last = sampling.first_frame
                    + sampling
                        .samples
                        .saturating_sub(1)
                        .saturating_mul(sampling.every);
                output::check_target(&AnimationKind::frame_path(
                    before,
                    *width,
                    after,
                    sampling.first_frame,
                ))?;
                output::check_target(&AnimationKind::frame_path(before, *width, after, last))?;
                (None, None)
            }
            AnimationKind::Pc2 | AnimationKind::Mdd => {
                let mesh_path = path.with_extension("obj");
                output::check_target(&mesh_path)?;
                let mut file = StreamFile::create(path)?;
                file.write_all(&head).map_err(|e| write_error(path, e))?;
                (Some(file), Some(mesh_path))
            }
        };
        Ok(Self {
            kind,
            file,
            mesh_path,
            mesh_obj: String::new(),
            samples: 0,
            planned: sampling.samples,
            origin: origin.to_owned(),
        })
    }

    /// Adds frame `frame`'s `positions` of `mesh` as the next sample; the first sample's mesh
    /// is kept for the OBJ next to a cache.
    ///
    /// # Errors
    /// A failed write, naming the file.
    pub fn push(&mut self, mesh: &ClothMesh, frame: u64, positions: &[Vec3]) -> anyhow::Result<()> {
        if self.samples == 0
            && let Some(file) = &self.file
        {
            let what = format!(
                "{}, frame {frame}: the mesh for the point cache {}",
                self.origin,
                file.path().display()
            );
            self.mesh_obj = obj(mesh, positions, &what);
        }
        self.samples += 1;
        match &self.kind {
            AnimationKind::ObjSequence {
                before,
                width,
                after,
            } => {
                let path = AnimationKind::frame_path(before, *width, after, frame);
                let what = format!("{}, frame {frame}", self.origin);
                output::write_atomic(&path, obj(mesh, positions, &what).as_bytes())?;
                Ok(())
            }
            AnimationKind::Pc2 | AnimationKind::Mdd => {
                let big = self.kind == AnimationKind::Mdd;
                let Some(file) = self.file.as_mut() else {
                    return Ok(());
                };
                let mut bytes = Vec::with_capacity(positions.len() * 12);
                for p in positions {
                    for c in [p.x, p.y, p.z] {
                        let c = c as f32;
                        bytes.extend_from_slice(&if big {
                            c.to_be_bytes()
                        } else {
                            c.to_le_bytes()
                        });
                    }
                }
                file.write_all(&bytes)
                    .map_err(|e| write_error(file.path(), e))
            }
        }
    }

    /// Puts the cache, and the first sample's mesh next to it, in place once every planned
    /// sample is written.
    ///
    /// # Errors
    /// Fewer samples than planned (the header would lie), or a failed write or rename.
    pub fn finish(mut self) -> anyhow::Result<()> {
        let Some(file) = self.file.take() else {
            return Ok(());
        };
        if self.samples != self.planned {
            bail!(
                "{}: {} of {} samples were written; the cache is not kept",
                file.path().display(),
                self.samples,
                self.planned
            );
        }
        file.finish()?;
        if let Some(mesh_path) = &self.mesh_path {
            output::write_atomic(mesh_path, self.mesh_obj.as_bytes())?;
        }
        Ok(())
    }
}
