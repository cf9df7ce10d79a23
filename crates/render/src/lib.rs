//! Cloth rendering for terminals: cameras, a z-buffered triangle rasteriser and shading that
//! turn a [`ClothState`](cloth_mesh::ClothState) into an [`AsciiFrame`], a grid of glyphs with
//! optional colour.
//!
//! This crate does no terminal I/O. The TUI, the headless `render` command and the snapshot
//! tests all draw through one [`Renderer`]:
//!
//! ```
//! use cloth_mesh::{ClothMesh, ClothState, GridSpec};
//! use cloth_render::{AsciiFrame, RenderOptions, Renderer, View, ViewSpec};
//!
//! let mesh = ClothMesh::new(&GridSpec::default()).unwrap();
//! let state = ClothState::new(&mesh);
//! let mut frame = AsciiFrame::with_size(80, 40).unwrap();
//! let view = ViewSpec::new(View::Top, &mesh);
//! Renderer::new()
//!     .render(&mesh, &state, &[], &view, &RenderOptions::default(), &mut frame)
//!     .unwrap();
//! assert_eq!(frame.to_plain().lines().count(), 40);
//! ```
//!
//! # Pipeline
//!
//! 1. Fit a [`Camera`] to the scene ([`View`], [`Extent`]) for the pixel grid of the
//!    [`Mode`] (1 x 1, 1 x 2 or 2 x 4 pixels per cell), correcting the cell aspect. An
//!    orthographic view fills the frame with the extent; the orbit view keeps its direction
//!    (the course's, along -z) and moves its aim and distance until the extent fills the frame
//!    ([`Orbit::fitted`]), keeping at least [`ViewSpec::ORBIT_MARGIN_CELLS`] cells empty on
//!    each side.
//! 2. Shade each vertex with its area-weighted normal ([`cloth_mesh::vertex_normals`]):
//!    ambient + Lambert key light + headlight, for the front and for the back face.
//! 3. Rasterise the triangles into a depth buffer (integer edge functions, top-left rule) and
//!    ray-cast spheres and floor patches into the same buffer.
//! 4. Map each pixel to a glyph (ramps in [`FRONT_RAMP`] and friends, ordered Bayer dither),
//!    a half block or a braille dot; mark pins.
//!
//! Colour never carries information that the glyphs do not: half-block mode without colour
//! shades covered cells with shade blocks (`░▒▓█`).

mod bounds;
mod camera;
mod color;
mod error;
mod frame;
mod glyphs;
mod options;
mod raster;
mod renderer;

pub use bounds::Bounds;
pub use camera::{Camera, Extent, Orbit, Projected, View, ViewSpec};
pub use color::{ColorChoice, ColorDepth, ColorEnv, TermColor, xterm_rgb};
pub use error::RenderError;
pub use frame::{AsciiFrame, Cell, FrameSize, MAX_HEIGHT, MAX_WIDTH, MIN_HEIGHT, MIN_WIDTH, Rgb};
pub use glyphs::{
    BACK_RAMP, FLOOR_GLYPH, FRONT_RAMP, HAND_GLYPH, PIN_GLYPH, SPHERE_RAMP, bayer_threshold,
    dithered_level, ramp_glyph,
};
pub use options::{Light, Mode, RenderOptions};
pub use renderer::Renderer;
