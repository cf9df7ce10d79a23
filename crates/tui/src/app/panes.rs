//! The cloth panes: render each visible pane with `cloth-render` into the model (before the
//! pure view draws), and the widget that copies an [`AsciiFrame`] into a ratatui buffer.

use cloth_render::{
    AsciiFrame, Bounds, ColorDepth, Extent, FrameSize, RenderOptions, Rgb, View, ViewSpec,
};
use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::Color;
use ratatui::widgets::Widget;

use super::layout::{self, inner};
use super::model::{App, Level};

/// Renders every visible pane at its current size into `app.frames`.
///
/// Fixed views frame a region that only grows (the union of the scene's bounds over the run),
/// so the picture keeps its scale while the cloth falls; a reset starts it again.
pub fn prepare(app: &mut App, area: Rect) {
    let Some(regions) = layout::regions(app, area) else {
        return;
    };
    let sim = &app.sim;
    // NOTE: a non-finite state never reaches here (the simulation puts back its last good
    // frame); should one, the old extent stays.
    if let Ok(b) = Bounds::of_scene(&sim.state.positions, &sim.settings.colliders) {
        app.extent = Some(app.extent.map_or(b, |e| e.union(&b)));
    }
    let options = RenderOptions {
        mode: app.mode,
        color: app.color,
        ..RenderOptions::default()
    };
    for (slot, rect) in regions.panes {
        let inside = inner(rect);
        let Ok(size) = FrameSize::new(inside.width as usize, inside.height as usize) else {
            app.frames[slot] = None;
            continue;
        };
        let view = app.views[slot];
        let mut spec = ViewSpec::new(view, &app.sim.scene.mesh);
        spec.orbit = app.orbit;
        if view != View::Orbit
            && let Some(e) = app.extent
        {
            spec.extent = Extent::Fixed(e);
        }
        let frame = app.frames[slot].get_or_insert_with(|| AsciiFrame::new(size));
        if frame.size() != size {
            frame.resize(size);
        }
        if let Err(e) = app.renderer.render(
            &app.sim.scene.mesh,
            &app.sim.state,
            &app.sim.settings.colliders,
            &spec,
            &options,
            frame,
        ) {
            app.frames[slot] = None;
            app.say(Level::Error, format!("cannot draw pane {}: {e}", slot + 1));
        }
    }
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

/// The colour a terminal of `depth` is told: 24-bit as is, otherwise the nearest entry of the
/// xterm 6 x 6 x 6 colour cube (which 16-colour terminals also map to their palette).
fn terminal_color(c: Rgb, depth: ColorDepth) -> Color {
    match depth {
        ColorDepth::TrueColor | ColorDepth::None => Color::Rgb(c.0, c.1, c.2),
        ColorDepth::Ansi256 | ColorDepth::Ansi16 => {
            // Cube levels are 0, 95, 135, 175, 215, 255: level i >= 1 sits at 55 + 40 i.
            let level = |v: u8| -> u8 {
                if v < 48 {
                    0
                } else if v < 115 {
                    1
                } else {
                    ((u16::from(v) - 35) / 40).min(5) as u8
                }
            };
            Color::Indexed(16 + 36 * level(c.0) + 6 * level(c.1) + level(c.2))
        }
    }
}

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
