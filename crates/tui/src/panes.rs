//! The cloth panes: render each visible pane with `cloth-render` into the model (before the
//! pure view draws), and the widget that copies an [`AsciiFrame`] into a ratatui buffer.
//!
//! A big cloth is drawn through a [`Display`]: a coarser grid whose points are a subset of the
//! cloth's, so drawing costs the same at 2048 x 2048 as at 128 x 128 (a pane has far fewer
//! pixels than that grid has points) and the keyboard is never kept waiting by a draw.

use cloth_render::{
    AsciiFrame, Bounds, ColorDepth, Extent, FrameSize, RenderOptions, Rgb, TermColor, View,
    ViewSpec,
};
use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::Color;
use ratatui::widgets::Widget;

use cloth_mesh::{ClothMesh, ClothState, GridSpec};

use super::hand::Drawn;
use super::layout::{self, inner};
use super::model::{App, Level};

/// Most points per side drawn; a bigger cloth is drawn through a [`Display`].
///
/// NOTE: a braille pane of 100 x 40 cells has 200 x 160 pixels, about what a grid of 128 points
/// a side covers with a triangle each, and drawing two panes of it leaves a key waiting at most
/// a few milliseconds.
pub const DISPLAY_SIDE: usize = 128;

/// A coarser copy of a big cloth for drawing: every k-th point (the edges and corners
/// included), with the pins moved to their nearest drawn point. Compare mode draws every
/// variant of one grid through one display, its positions gathered pane by pane.
pub struct Display {
    /// The grid of the cloth it draws.
    source: GridSpec,
    /// The coarse grid.
    pub mesh: ClothMesh,
    /// The cloth's index of each coarse point.
    pick: Vec<usize>,
    /// The coarse grid's positions, gathered from the cloth's.
    pub state: ClothState,
}

impl Display {
    /// The display grid for `full`, or `None` when it is small enough to draw as it is.
    pub fn for_mesh(full: &ClothMesh) -> Option<Self> {
        let (nw, nh) = (full.nw(), full.nh());
        if nw <= DISPLAY_SIDE && nh <= DISPLAY_SIDE {
            return None;
        }
        let (mw, mh) = (nw.min(DISPLAY_SIDE), nh.min(DISPLAY_SIDE));
        // Coarse index i to the cloth's, and back to the nearest coarse index.
        let to_full = |i: usize, m: usize, n: usize| i * (n - 1) / (m - 1);
        let to_coarse = |k: usize, m: usize, n: usize| (k * (m - 1) + (n - 1) / 2) / (n - 1);
        let spec = full.spec();
        let pinned = spec
            .pinned
            .iter()
            .map(|&(x, y)| (to_coarse(x, mw, nw), to_coarse(y, mh, nh)))
            .collect();
        let coarse = GridSpec {
            num_width_points: mw,
            num_height_points: mh,
            pinned,
            ..spec.clone()
        };
        let mesh = ClothMesh::new(&coarse).ok()?;
        let pick = (0..mh)
            .flat_map(|y| (0..mw).map(move |x| (x, y)))
            .map(|(x, y)| full.index(to_full(x, mw, nw), to_full(y, mh, nh)))
            .collect();
        let state = ClothState::new(&mesh);
        Some(Self {
            source: spec.clone(),
            mesh,
            pick,
            state,
        })
    }

    /// Whether it draws cloths of `full`'s grid.
    pub fn draws(&self, full: &ClothMesh) -> bool {
        self.source == *full.spec()
    }

    /// Gathers the drawn points' positions from the cloth's.
    pub fn update(&mut self, positions: &[cloth_solver::Vec3]) {
        for (p, &k) in self.state.positions.iter_mut().zip(&self.pick) {
            if let Some(q) = positions.get(k) {
                *p = *q;
            }
        }
    }
}

/// Renders every visible pane at its current size into `app.frames`.
///
/// Every view frames a region that only grows (the union of the scene's bounds over the run),
/// so the picture keeps its scale while the cloth falls; a reset starts it again. The fitted
/// orbit camera is refitted to it for the pane it is drawn in, so it moves only when the
/// region grows.
pub fn prepare(app: &mut App, area: Rect) {
    app.drawn.clear();
    let Some(regions) = layout::regions(app, area) else {
        return;
    };
    if app.compare.is_some() {
        prepare_compare(app, &regions.variants);
        return;
    }
    if app
        .display
        .as_ref()
        .is_some_and(|d| !d.draws(&app.sim.scene.mesh))
    {
        // A pin by hand changed the grid's pins.
        app.display = Display::for_mesh(&app.sim.scene.mesh);
    }
    if let Some(d) = &mut app.display {
        d.update(&app.sim.state.positions);
    }
    let sim = &app.sim;
    let (mesh, state) = match &app.display {
        Some(d) => (&d.mesh, &d.state),
        None => (&*sim.scene.mesh, &sim.state),
    };
    // NOTE: a non-finite state never reaches here (the simulation puts back its last good
    // frame); should one, the old extent stays.
    if let Ok(b) = Bounds::of_scene(&state.positions, &sim.settings.colliders) {
        app.extent = Some(app.extent.map_or(b, |e| e.union(&b)));
    }
    let options = RenderOptions {
        mode: app.mode,
        color: app.color,
        hand: held_at(sim),
        ..RenderOptions::default()
    };
    let mut errors = Vec::new();
    for (slot, rect) in regions.panes {
        let inside = inner(rect);
        let Ok(size) = FrameSize::new(inside.width as usize, inside.height as usize) else {
            app.frames[slot] = None;
            continue;
        };
        let view = app.views[slot];
        let mut spec = ViewSpec::new(view, mesh);
        if let Some(e) = app.extent {
            spec.extent = Extent::Fixed(e);
            if view == View::Orbit && app.orbit_fitted {
                app.orbit = spec.orbit_in(&e, size.width, size.height, options.cell_aspect);
            }
        }
        spec.orbit = app.orbit;
        spec.fit_orbit = false;
        let frame = app.frames[slot].get_or_insert_with(|| AsciiFrame::new(size));
        if frame.size() != size {
            frame.resize(size);
        }
        if let Err(e) =
            app.renderer
                .render(mesh, state, &sim.settings.colliders, &spec, &options, frame)
        {
            app.frames[slot] = None;
            errors.push(format!("cannot draw pane {}: {e}", slot + 1));
        }
        app.drawn.push(Drawn {
            inner: inside,
            variant: 0,
            spec,
        });
    }
    for e in errors {
        app.say(Level::Error, e);
    }
}

/// Compare mode: renders every variant into its pane with the focused pane's view, all fitted
/// to one extent (the union over the variants and the run), so their shapes compare honestly.
/// The panes share the renderer's scratch buffers and, for a big cloth, one [`Display`] (the
/// variants of a study mostly share their grid).
fn prepare_compare(app: &mut App, rects: &[Rect]) {
    let App {
        sim: first,
        compare,
        display,
        renderer,
        extent,
        drawn,
        ..
    } = app;
    let Some(c) = compare else {
        return;
    };
    let sims = std::iter::once(&*first).chain(c.members.iter().map(|m| &m.sim));
    for sim in sims {
        if let Ok(b) = Bounds::of_scene(&sim.state.positions, &sim.settings.colliders) {
            *extent = Some(extent.map_or(b, |e| e.union(&b)));
        }
    }
    let options = RenderOptions {
        mode: app.mode,
        color: app.color,
        ..RenderOptions::default()
    };
    let view = app.views[app.focus];
    let mut errors = Vec::new();
    let frames = std::iter::once((&*first, &mut c.frame))
        .chain(c.members.iter_mut().map(|m| (&m.sim, &mut m.frame)));
    for (i, ((sim, slot), rect)) in frames.zip(rects).enumerate() {
        let inside = inner(*rect);
        let Ok(size) = FrameSize::new(inside.width as usize, inside.height as usize) else {
            *slot = None;
            continue;
        };
        let full: &ClothMesh = &sim.scene.mesh;
        if display.as_ref().is_none_or(|d| !d.draws(full)) {
            *display = Display::for_mesh(full);
        }
        let (mesh, state) = match display {
            Some(d) => {
                d.update(&sim.state.positions);
                (&d.mesh, &d.state)
            }
            None => (full, &sim.state),
        };
        let mut spec = ViewSpec::new(view, mesh);
        if let Some(e) = *extent {
            spec.extent = Extent::Fixed(e);
            if view == View::Orbit && app.orbit_fitted {
                app.orbit = spec.orbit_in(&e, size.width, size.height, options.cell_aspect);
            }
        }
        spec.orbit = app.orbit;
        spec.fit_orbit = false;
        let frame = slot.get_or_insert_with(|| AsciiFrame::new(size));
        if frame.size() != size {
            frame.resize(size);
        }
        let options = RenderOptions {
            hand: held_at(sim),
            ..options
        };
        if let Err(e) =
            renderer.render(mesh, state, &sim.settings.colliders, &spec, &options, frame)
        {
            *slot = None;
            errors.push(format!("cannot draw variant {}: {e}", i + 1));
        }
        drawn.push(Drawn {
            inner: inside,
            variant: i,
            spec,
        });
    }
    for e in errors {
        app.say(Level::Error, e);
    }
}

/// Where the point a hand holds is, to mark it.
fn held_at(sim: &cloth_run::Run) -> Option<cloth_solver::Vec3> {
    sim.held
        .and_then(|h| sim.state.positions.get(h.point).copied())
}

/// Draws an [`AsciiFrame`] into a ratatui buffer, cell for cell, with its colours at `depth`
/// ([`ColorDepth::None`]: glyphs only).
pub struct AsciiView<'a> {
    frame: &'a AsciiFrame,
    depth: ColorDepth,
}

impl<'a> AsciiView<'a> {
    /// The widget for `frame`.
    pub fn new(frame: &'a AsciiFrame, depth: ColorDepth) -> Self {
        Self { frame, depth }
    }
}

/// The colour a terminal of `depth` is told, by the renderer's one conversion: 24-bit as
/// is, else the nearest palette entry (the 16 basic colours are named, so a 16-colour
/// terminal gets basic codes).
fn terminal_color(c: Rgb, depth: ColorDepth) -> Color {
    match depth.quantise(c) {
        TermColor::Basic(i) => BASIC[usize::from(i).min(15)],
        TermColor::Indexed(i) => Color::Indexed(i),
        TermColor::Rgb(Rgb(r, g, b)) => Color::Rgb(r, g, b),
    }
}

/// ratatui's names of the 16 basic colours, in SGR order.
const BASIC: [Color; 16] = [
    Color::Black,
    Color::Red,
    Color::Green,
    Color::Yellow,
    Color::Blue,
    Color::Magenta,
    Color::Cyan,
    Color::Gray,
    Color::DarkGray,
    Color::LightRed,
    Color::LightGreen,
    Color::LightYellow,
    Color::LightBlue,
    Color::LightMagenta,
    Color::LightCyan,
    Color::White,
];

impl Widget for AsciiView<'_> {
    fn render(self, area: Rect, buf: &mut Buffer) {
        let w = (area.width as usize).min(self.frame.width());
        let h = (area.height as usize).min(self.frame.height());
        for y in 0..h {
            for (x, c) in self.frame.row(y).iter().take(w).enumerate() {
                let Some(cell) = buf.cell_mut((area.x + x as u16, area.y + y as u16)) else {
                    continue;
                };
                cell.set_char(c.glyph);
                if self.depth != ColorDepth::None {
                    if let Some(fg) = c.fg {
                        cell.set_fg(terminal_color(fg, self.depth));
                    }
                    if let Some(bg) = c.bg {
                        cell.set_bg(terminal_color(bg, self.depth));
                    }
                }
            }
        }
    }
}
