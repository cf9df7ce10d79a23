//! The hand: the mouse grabs, drags, pins and cuts the cloth in any pane, and keys poke and pin
//! it without a mouse. Every gesture becomes a [`Touch`] that the run applies between two steps,
//! so every solver of the registry feels it without knowing of it.
//!
//! A gesture picks the point it acts on from the pane's own drawing: the pane is drawn again
//! with the camera it was shown with, the renderer's depth says which point of the cloth the
//! cell shows (the front layer where the cloth folds over itself), and the cloth's nearest
//! point to it is the one taken. A drag keeps the camera of its start and moves the point in the
//! plane through it parallel to the screen; a cut's stroke is seen from that camera, so it cuts
//! the springs it crosses on screen. In compare mode every variant gets the same touch, at the
//! same place of its grid.

use cloth_mesh::{ClothMesh, Knife, Sight, Vec3};
use cloth_render::{AsciiFrame, Camera, FrameSize, RenderOptions, Renderer, ViewSpec};
use cloth_run::{Command, Run, Touch};
use ratatui::layout::{Position, Rect};

use super::model::{App, Level};
use super::panes::Display;

/// How fast a poke pushes the point under the focused pane's centre into the screen, m/s; its
/// neighbours within [`POKE_REACH`] grid steps get less, falling off linearly.
pub const POKE_SPEED: f64 = 3.0;
/// How many grid steps a poke reaches around its point.
pub const POKE_REACH: usize = 3;

/// A pane as it was last drawn: where its frame is on screen, which variant it shows (0 the
/// first or only cloth) and the view it was drawn with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Drawn {
    /// The frame's cells on screen (the pane inside its border).
    pub inner: Rect,
    /// Which variant it shows (compare mode; 0 otherwise).
    pub variant: usize,
    /// The view it was drawn with.
    pub spec: ViewSpec,
}

/// A pane's camera as a gesture found it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Seen {
    inner: Rect,
    camera: Camera,
    pixels: (usize, usize),
}

impl Seen {
    /// The pixel position at the centre of screen cell `(col, row)`.
    fn pixel(&self, col: u16, row: u16) -> (f64, f64) {
        let x = (f64::from(col) - f64::from(self.inner.x) + 0.5) * self.pixels.0 as f64;
        let y = (f64::from(row) - f64::from(self.inner.y) + 0.5) * self.pixels.1 as f64;
        (x, y)
    }

    /// The world point at cell `(col, row)` with depth key `depth`.
    fn at(&self, col: u16, row: u16, depth: f64) -> Vec3 {
        let (x, y) = self.pixel(col, row);
        self.camera.unproject(x, y, depth)
    }

    /// Any depth key in front of the camera: where a stroke is drawn (a cut does not depend on
    /// it, see [`Knife`]).
    fn stroke_depth(&self) -> f64 {
        if self.camera.is_perspective() {
            -1.0
        } else {
            0.0
        }
    }

    /// How the camera sees.
    fn sight(&self) -> Sight {
        match self.camera.eye() {
            Some(eye) => Sight::From(eye),
            None => Sight::Along(self.camera.forward()),
        }
    }
}

/// What a mouse button holds while it is down.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Grip {
    /// A point of the cloth, carried in the plane through it parallel to the screen.
    Hold {
        /// The camera of the pane it was taken in.
        seen: Seen,
        /// The depth key of that plane.
        depth: f64,
        /// From the point under the mouse in that plane to the point held, m: kept, so the
        /// point does not jump to the cursor when the drag begins.
        offset: Vec3,
    },
    /// A knife, cutting from the last cell the mouse was at.
    Cut {
        /// The camera of the pane the stroke began in.
        seen: Seen,
        /// The last cell of the stroke.
        last: (u16, u16),
        /// Strokes sent.
        strokes: usize,
    },
}

/// The variant `k`'s run (0 the first or only cloth).
fn variant(app: &App, k: usize) -> Option<&Run> {
    if k == 0 {
        return Some(&app.sim);
    }
    app.compare.as_ref()?.members.get(k - 1).map(|m| &m.sim)
}

/// The pane drawn at cell `(col, row)`.
fn pane_at(app: &App, col: u16, row: u16) -> Option<Drawn> {
    app.drawn
        .iter()
        .find(|d| d.inner.contains(Position::new(col, row)))
        .copied()
}

/// Draws pane `d` again as it was shown, into the picker's buffers: its camera, and the point
/// of the cloth at cell `(col, row)` if the cell shows cloth.
fn look(app: &mut App, d: &Drawn, col: u16, row: u16) -> Option<(Seen, Option<Vec3>)> {
    let sim = variant(app, d.variant)?;
    let size = FrameSize::new(d.inner.width as usize, d.inner.height as usize).ok()?;
    let options = RenderOptions {
        mode: app.mode,
        color: false,
        ..RenderOptions::default()
    };
    let mut frame = AsciiFrame::new(size);
    let mut picker = Renderer::new();
    // NOTE: a big cloth is shown through a coarser grid; the depth it leaves is the depth
    // that was shown.
    let display = Display::for_mesh(&sim.scene.mesh).map(|mut d| {
        d.update(&sim.state.positions);
        d
    });
    let (mesh, state) = match &display {
        Some(d) => (&d.mesh, &d.state),
        None => (&*sim.scene.mesh, &sim.state),
    };
    picker
        .render(
            mesh,
            state,
            &sim.settings.colliders,
            &d.spec,
            &options,
            &mut frame,
        )
        .ok()?;
    let seen = Seen {
        inner: d.inner,
        camera: *picker.camera()?,
        pixels: app.mode.pixels_per_cell(),
    };
    let cell = (
        usize::from(col.checked_sub(d.inner.x)?),
        usize::from(row.checked_sub(d.inner.y)?),
    );
    Some((seen, picker.surface_at(cell.0, cell.1)))
}

/// The point of `positions` nearest to `at`.
fn nearest(positions: &[Vec3], at: Vec3) -> Option<usize> {
    (0..positions.len()).min_by(|&a, &b| {
        (positions[a] - at)
            .norm_squared()
            .total_cmp(&(positions[b] - at).norm_squared())
    })
}

/// The point of `to` at the place of `from`'s point `point` on the grid (the same point when
/// the grids are equal).
fn same_place(from: &ClothMesh, to: &ClothMesh, point: usize) -> usize {
    let scale = |i: usize, n: usize, m: usize| {
        if n <= 1 {
            0
        } else {
            (i * (m - 1) + (n - 1) / 2) / (n - 1)
        }
    };
    let (x, y) = (point % from.nw(), point / from.nw());
    to.index(scale(x, from.nw(), to.nw()), scale(y, from.nh(), to.nh()))
}

/// Sends each variant the touch `of` gives it (none: nothing), and says any refusal.
fn send_each(app: &mut App, of: impl Fn(&Run) -> Option<Touch>) {
    let count = app.compare.as_ref().map_or(1, super::compare::Compare::len);
    let touches: Vec<Option<Touch>> = (0..count).map(|k| variant(app, k).and_then(&of)).collect();
    let mut errors = Vec::new();
    if let Some(g) = app.group() {
        for (k, t) in touches.iter().enumerate() {
            if let Some(t) = t {
                g.send_to(k, Command::Touch(*t));
            }
        }
    } else {
        if let Some(c) = &mut app.compare {
            for (m, t) in c.members.iter_mut().zip(&touches[1..]) {
                if let Some(t) = t
                    && let Err(e) = m.sim.apply(Command::Touch(*t))
                {
                    errors.push(e);
                }
            }
        }
        if let Some(t) = touches[0] {
            match &app.worker {
                Some(w) => w.send(Command::Touch(t)),
                None => {
                    if let Err(e) = app.sim.apply(Command::Touch(t)) {
                        errors.push(e);
                    }
                }
            }
        }
    }
    for e in errors {
        app.say(Level::Error, e);
    }
}

/// The grid place of point `point` of `mesh`, as the status line names it.
fn place(mesh: &ClothMesh, point: usize) -> String {
    format!("({}, {})", point % mesh.nw(), point / mesh.nw())
}

/// The point of the cloth seen at a cell of pane `d`, with the pane's camera: the cloth
/// under the cell, or (`fallback`) the point drawn nearest to the cell when none is there.
fn point_at(app: &mut App, d: &Drawn, col: u16, row: u16, fallback: bool) -> Option<(Seen, usize)> {
    let (seen, surface) = look(app, d, col, row)?;
    let sim = variant(app, d.variant)?;
    let positions = &sim.state.positions;
    let point = match surface {
        Some(at) => nearest(positions, at)?,
        None if fallback => {
            let (x, y) = seen.pixel(col, row);
            (0..positions.len())
                .filter_map(|i| {
                    let p = seen.camera.project(positions[i])?;
                    Some((i, (p.x - x).powi(2) + (p.y - y).powi(2)))
                })
                .min_by(|a, b| a.1.total_cmp(&b.1))?
                .0
        }
        None => return None,
    };
    Some((seen, point))
}

/// A mouse button went down at `(col, row)`; true when the hand took it (the cell shows cloth,
/// or the right button began a cut), false to leave it to the orbit.
pub fn press(
    app: &mut App,
    col: u16,
    row: u16,
    button: super::message::Button,
    ctrl: bool,
) -> bool {
    use super::message::Button;
    let Some(d) = pane_at(app, col, row) else {
        return false;
    };
    match (button, ctrl) {
        (Button::Left, false) => {
            let Some((seen, point)) = point_at(app, &d, col, row, false) else {
                return false;
            };
            let Some(sim) = variant(app, d.variant) else {
                return false;
            };
            let at = sim.state.positions[point];
            let mesh = std::sync::Arc::clone(&sim.scene.mesh);
            let depth = seen.camera.depth_of(at);
            app.grip = Some(Grip::Hold {
                seen,
                depth,
                offset: at - seen.at(col, row, depth),
            });
            send_each(app, |run| {
                let p = same_place(&mesh, &run.scene.mesh, point);
                Some(Touch::Grab {
                    point: p,
                    to: run.state.positions[p],
                })
            });
            app.say(
                Level::Info,
                format!(
                    "holding point {} of the cloth: drag to carry it, let go to release it",
                    place(&mesh, point)
                ),
            );
            true
        }
        (Button::Left, true) | (Button::Middle, _) => {
            let Some((_, point)) = point_at(app, &d, col, row, false) else {
                return false;
            };
            toggle_pin(app, d.variant, point);
            true
        }
        (Button::Right, _) => {
            let Some((seen, _)) = look(app, &d, col, row) else {
                return false;
            };
            app.grip = Some(Grip::Cut {
                seen,
                last: (col, row),
                strokes: 0,
            });
            app.say(
                Level::Info,
                "cutting: the springs the stroke crosses part; r restores the cloth",
            );
            true
        }
    }
}

/// Pins variant `k`'s point `point` if it is free, frees it if pinned, in every variant.
fn toggle_pin(app: &mut App, k: usize, point: usize) {
    let Some(sim) = variant(app, k) else {
        return;
    };
    let mesh = std::sync::Arc::clone(&sim.scene.mesh);
    let pinned = !mesh.pinned()[point];
    if matches!(app.grip, Some(Grip::Hold { .. })) {
        // A pin takes the point from the hand (the run lets go of a point it pins); the
        // hand lets go of any other, so the drag that follows moves nothing.
        app.grip = None;
        send_each(app, |_| Some(Touch::Release));
    }
    send_each(app, |run| {
        Some(Touch::Pin {
            point: same_place(&mesh, &run.scene.mesh, point),
            pinned,
        })
    });
    let what = if pinned { "pinned" } else { "unpinned" };
    app.say(
        Level::Info,
        format!(
            "{what} point {}: S saves the scene with its pins, r goes back to the scene's",
            place(&mesh, point)
        ),
    );
}

/// The mouse moved to `(col, row)` with a button down; true when the hand has it.
pub fn drag(app: &mut App, col: u16, row: u16) -> bool {
    match app.grip {
        Some(Grip::Hold {
            seen,
            depth,
            offset,
        }) => {
            let to = seen.at(col, row, depth) + offset;
            send_each(app, |_| Some(Touch::Drag { to }));
            true
        }
        Some(Grip::Cut {
            seen,
            last,
            strokes,
        }) => {
            if last == (col, row) {
                return true;
            }
            let depth = seen.stroke_depth();
            let knife = Knife {
                from: seen.at(last.0, last.1, depth),
                to: seen.at(col, row, depth),
                sight: seen.sight(),
            };
            send_each(app, |_| Some(Touch::Cut(knife)));
            app.grip = Some(Grip::Cut {
                seen,
                last: (col, row),
                strokes: strokes + 1,
            });
            true
        }
        None => false,
    }
}

/// The button went up: a held point is let go with the hand's velocity.
pub fn release(app: &mut App) {
    match app.grip.take() {
        Some(Grip::Hold { .. }) => {
            send_each(app, |_| Some(Touch::Release));
            app.say(Level::Info, "let go");
        }
        Some(Grip::Cut { strokes: 0, .. }) => {
            app.say(
                Level::Info,
                "no cut: drag with the right button across the cloth",
            );
        }
        Some(Grip::Cut { .. }) => app.say(Level::Info, "cut: r restores the cloth"),
        None => {}
    }
}

/// The drawn pane that has the focus (compare mode: the first variant's).
fn focused(app: &App) -> Option<Drawn> {
    if app.compare.is_some() {
        return app.drawn.iter().find(|d| d.variant == 0).copied();
    }
    let slots = app.visible_slots();
    let k = slots.iter().position(|&s| s == app.focus)?;
    app.drawn.get(k).copied()
}

/// The centre cell of a pane.
fn centre(d: &Drawn) -> (u16, u16) {
    (
        d.inner.x + d.inner.width / 2,
        d.inner.y + d.inner.height / 2,
    )
}

/// Pokes the cloth at the focused pane's centre: the point shown there (or drawn nearest to
/// it) and its neighbours are pushed into the screen.
pub fn poke(app: &mut App) {
    let Some(d) = focused(app) else {
        app.say(Level::Warn, "no pane on screen to poke the cloth in");
        return;
    };
    let (col, row) = centre(&d);
    let Some((seen, point)) = point_at(app, &d, col, row, true) else {
        app.say(Level::Warn, "no cloth in the focused pane to poke");
        return;
    };
    let Some(sim) = variant(app, d.variant) else {
        return;
    };
    let mesh = std::sync::Arc::clone(&sim.scene.mesh);
    let push = seen.camera.forward() * POKE_SPEED;
    let (x0, y0) = (point % mesh.nw(), point / mesh.nw());
    let reach = POKE_REACH as isize;
    let mut around = Vec::new();
    for dy in -reach..=reach {
        for dx in -reach..=reach {
            let (Some(x), Some(y)) = (x0.checked_add_signed(dx), y0.checked_add_signed(dy)) else {
                continue;
            };
            let r = dx.unsigned_abs().max(dy.unsigned_abs()) as f64;
            if x < mesh.nw() && y < mesh.nh() {
                around.push((mesh.index(x, y), 1.0 - r / (POKE_REACH as f64 + 1.0)));
            }
        }
    }
    for (p, weight) in around {
        send_each(app, |run| {
            Some(Touch::Poke {
                point: same_place(&mesh, &run.scene.mesh, p),
                velocity: push * weight,
            })
        });
    }
    app.say(
        Level::Info,
        format!(
            "poked point {} at {POKE_SPEED} m/s into the screen",
            place(&mesh, point)
        ),
    );
}

/// Pins or unpins the point under the mouse, or at the focused pane's centre when the mouse
/// is not over the cloth.
pub fn pin_here(app: &mut App) {
    let under = app.pointer.and_then(|(col, row)| {
        let d = pane_at(app, col, row)?;
        let (_, point) = point_at(app, &d, col, row, false)?;
        Some((d.variant, point))
    });
    let target = under.or_else(|| {
        let d = focused(app)?;
        let (col, row) = centre(&d);
        let (_, point) = point_at(app, &d, col, row, true)?;
        Some((d.variant, point))
    });
    match target {
        Some((k, point)) => toggle_pin(app, k, point),
        None => app.say(Level::Warn, "no cloth on screen to pin"),
    }
}

/// Writes the touches since the start or the last reset as an actions file that
/// `clothsim simulate --actions` replays.
pub fn write_actions(app: &mut App) {
    let touched = &app.sim.touched;
    if touched.is_empty() {
        app.say(
            Level::Warn,
            "no touches since the start or the last reset: grab, pin, cut or poke the cloth first",
        );
        return;
    }
    let stem = std::path::Path::new(&app.sim.scene.origin)
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("scene")
        .to_owned();
    let path = app.cwd.join(format!("{stem}-actions.jsonl"));
    let text: String = touched
        .iter()
        .map(|t| cloth_run::actions::line(t) + "\n")
        .collect();
    let count = touched.len();
    let frames = app.sim.frames;
    match cloth_run::output::write_atomic(&path, text.as_bytes()) {
        Ok(_) => app.say(
            Level::Info,
            format!(
                "{count} touches written to {}: replay with clothsim simulate {} --actions {} \
                 --frames {frames} (with the settings the run had)",
                path.display(),
                app.sim.scene.origin,
                path.display()
            ),
        ),
        Err(e) => app.say(Level::Error, format!("{e:#}")),
    }
}
