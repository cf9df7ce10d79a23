//! The one function that changes the model: `update(&mut App, Message)`.

use std::path::PathBuf;

use cloth_render::{Mode, Orbit, View};
use ratatui::layout::{Position, Rect};

use super::layout;
use super::message::Message;
use super::model::{App, Layout, Level, Overlay, Picker, Prompt, Purpose, RATES};
use super::params::{Kind, is_option_row, row, row_count};
use super::sim::Simulation;
use crate::output;

/// Radians of orbit per cell of mouse drag.
const DRAG_TURN: f64 = 0.05;

/// Applies one message.
pub fn update(app: &mut App, msg: Message) {
    match msg {
        Message::Quit => app.quit = true,
        Message::Escape => escape(app),
        Message::ToggleHelp => {
            app.overlay = if app.overlay == Overlay::Help {
                Overlay::None
            } else {
                app.help_scroll = 0;
                Overlay::Help
            };
        }
        Message::TogglePause => toggle_pause(app),
        Message::StepFrame => step_frame(app),
        Message::Reset => reset(app),
        Message::Faster | Message::Slower => {
            app.rate = if msg == Message::Faster {
                (app.rate + 1).min(RATES.len() - 1)
            } else {
                app.rate.saturating_sub(1)
            };
            let r = app.rate();
            let text = if r >= 1.0 {
                format!("simulated time runs at {r}x real time")
            } else {
                format!("simulated time runs at 1/{}x real time", (1.0 / r).round())
            };
            app.say(Level::Info, text);
        }
        Message::SelectPrev => {
            app.selected = app
                .selected
                .checked_sub(1)
                .unwrap_or(row_count(&app.sim) - 1);
        }
        Message::SelectNext => app.selected = (app.selected + 1) % row_count(&app.sim),
        Message::Nudge { dir, coarse } => nudge(app, dir, coarse),
        Message::EditValue => edit_value(app),
        Message::RestoreParam => restore(app, false),
        Message::RestoreAll => restore(app, true),
        Message::CycleLayout => {
            app.layout = app.layout.next();
            app.maximised = false;
            if app.layout != Layout::Single && app.focus >= app.layout.panes() {
                app.focus = 0;
            }
            app.say(Level::Info, format!("layout: {}", app.layout.name()));
        }
        Message::ToggleMaximise => app.maximised = !app.maximised,
        Message::FocusNext | Message::FocusPrev => {
            let n = if app.layout == Layout::Single || app.maximised {
                app.views.len()
            } else {
                app.layout.panes()
            };
            app.focus = if msg == Message::FocusNext {
                (app.focus + 1) % n
            } else {
                (app.focus + n - 1) % n
            };
        }
        Message::CycleView => {
            let v = app.views[app.focus];
            let i = View::ALL.iter().position(|&x| x == v).unwrap_or(0);
            app.views[app.focus] = View::ALL[(i + 1) % View::ALL.len()];
            app.say(
                Level::Info,
                format!(
                    "pane {}: {}",
                    app.focus + 1,
                    app.views[app.focus].describe()
                ),
            );
        }
        Message::CycleMode => {
            let i = Mode::ALL.iter().position(|&m| m == app.mode).unwrap_or(0);
            app.mode = Mode::ALL[(i + 1) % Mode::ALL.len()];
            let extra = if app.mode == Mode::Half && !app.color {
                " (without colour, half blocks show coverage only; C turns colour on)"
            } else {
                ""
            };
            app.say(Level::Info, format!("glyph mode: {}{extra}", app.mode));
        }
        Message::ToggleColor => {
            app.color = !app.color;
            let text = match (app.color, app.color_allowed) {
                (true, false) => {
                    "colour on (NO_COLOR or --color never asked for none; C turns it off)"
                }
                (true, true) => "colour on",
                (false, _) => "colour off",
            };
            app.say(Level::Info, text);
        }
        Message::Orbit { yaw, pitch } => turn(app, yaw, pitch),
        Message::Zoom(f) => zoom(app, f),
        Message::ResetCamera => {
            app.orbit = Orbit::course_default(&app.sim.scene.mesh);
            app.say(Level::Info, "orbit camera reset");
        }
        Message::OpenPicker => {
            app.overlay = Overlay::Picker(Picker {
                selected: 0,
                files: json_files(&app.cwd),
            });
        }
        Message::Save => {
            let stem = std::path::Path::new(&app.sim.scene.origin)
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("scene")
                .to_owned();
            app.overlay = Overlay::Prompt(Prompt::new(
                Purpose::SavePath,
                format!("{stem}-edited.json"),
            ));
        }
        Message::Input(c) => prompt_edit(app, |p| {
            let at = byte_index(&p.text, p.cursor);
            p.text.insert(at, c);
            p.cursor += 1;
        }),
        Message::Backspace => prompt_edit(app, |p| {
            if p.cursor > 0 {
                p.cursor -= 1;
                let at = byte_index(&p.text, p.cursor);
                p.text.remove(at);
            }
        }),
        Message::Delete => prompt_edit(app, |p| {
            if p.cursor < p.text.chars().count() {
                let at = byte_index(&p.text, p.cursor);
                p.text.remove(at);
            }
        }),
        Message::Move(d) => match &mut app.overlay {
            Overlay::Help => {
                app.help_scroll = (i64::from(app.help_scroll) + i64::from(d)).clamp(0, 200) as u16;
            }
            Overlay::Picker(p) => {
                let n = p.len() as i64;
                p.selected = (p.selected as i64 + i64::from(d)).rem_euclid(n) as usize;
            }
            Overlay::Prompt(p) => {
                let len = p.text.chars().count();
                p.cursor = (p.cursor as i64 + i64::from(d)).clamp(0, len as i64) as usize;
            }
            _ => {}
        },
        Message::Home => prompt_edit(app, |p| p.cursor = 0),
        Message::End => prompt_edit(app, |p| p.cursor = p.text.chars().count()),
        Message::Submit => submit(app),
        Message::Answer(yes) => answer(app, yes),
        Message::MouseDown { col, row } => {
            app.drag = orbit_pane_at(app, col, row).map(|_| (col, row));
        }
        Message::MouseDrag { col, row } => {
            if let Some((c0, r0)) = app.drag {
                let dx = f64::from(col) - f64::from(c0);
                let dy = f64::from(row) - f64::from(r0);
                turn(app, dx * DRAG_TURN, dy * DRAG_TURN);
                app.drag = Some((col, row));
            }
        }
        Message::MouseUp => app.drag = None,
        Message::Wheel { col, row, dir } => {
            if orbit_pane_at(app, col, row).is_some() {
                zoom(
                    app,
                    if dir < 0 {
                        super::keymap::ZOOM
                    } else {
                        1.0 / super::keymap::ZOOM
                    },
                );
            }
        }
        Message::Resize { width, height } => app.screen = (width, height),
        Message::Tick(wall) => {
            if app.running && app.sim.fault.is_none() {
                app.debt += wall.as_secs_f64() * app.rate();
            }
        }
        Message::Measured(stats) => app.stats = stats,
    }
}

/// Takes owed steps while `more()` allows; returns how many steps ran. The loop passes a
/// wall-clock budget as `more`; tests pass a counter.
pub fn run_owed(app: &mut App, more: &mut dyn FnMut() -> bool) -> u64 {
    let mut n = 0;
    while app.running && app.debt >= app.sim.dt() && more() {
        app.debt -= app.sim.dt();
        n += 1;
        if app.sim.step().is_err() {
            stopped(app);
            break;
        }
    }
    n
}

/// The simulation failed: pause and explain.
fn stopped(app: &mut App) {
    app.running = false;
    app.debt = 0.0;
    app.overlay = Overlay::Fault;
}

fn escape(app: &mut App) {
    match app.overlay {
        Overlay::None => app.quit = true,
        Overlay::Fault => {
            app.overlay = Overlay::None;
            app.say(
                Level::Warn,
                "stopped: press r to reset (parameters are kept), u to restore a parameter",
            );
        }
        _ => app.overlay = Overlay::None,
    }
}

fn toggle_pause(app: &mut App) {
    if app.sim.fault.is_some() {
        app.overlay = Overlay::Fault;
        return;
    }
    app.running = !app.running;
    app.debt = 0.0;
    app.say(
        Level::Info,
        if app.running {
            "running"
        } else {
            "paused: n steps one frame, space resumes"
        },
    );
}

fn step_frame(app: &mut App) {
    app.running = false;
    app.debt = 0.0;
    if app.sim.step_frame().is_err() {
        stopped(app);
    } else {
        app.say(
            Level::Info,
            format!(
                "one frame: t = {:.4} s (frame {})",
                app.sim.time, app.sim.frames
            ),
        );
    }
}

fn reset(app: &mut App) {
    app.sim.reset();
    app.debt = 0.0;
    app.extent = None;
    if app.overlay == Overlay::Fault {
        app.overlay = Overlay::None;
    }
    app.say(
        Level::Info,
        "reset to the start positions (parameters kept)",
    );
}

fn nudge(app: &mut App, dir: i32, coarse: bool) {
    let p = row(&app.sim, app.selected);
    if p.kind == Kind::Solver {
        cycle_solver(app, dir);
        return;
    }
    let Some(v) = (p.get)(&app.sim.settings) else {
        app.say(Level::Warn, absent(p.label));
        return;
    };
    let nv = p.nudged(v, dir, coarse);
    (p.set)(&mut app.sim.settings, nv);
    changed(app, app.selected);
}

fn absent(label: &str) -> String {
    let object = label.split_whitespace().next().unwrap_or(label);
    format!("this scene has no {object}, so {label} does not apply")
}

/// After a parameter changed: say its new value, or warn.
fn changed(app: &mut App, at: usize) {
    let p = row(&app.sim, at);
    if is_option_row(at)
        && let Err(e) = app.sim.apply_options()
    {
        app.say(Level::Warn, format!("{e:#}"));
        return;
    }
    let shown = p.format((p.get)(&app.sim.settings));
    if let Some(w) = app.sim.stability_warning() {
        app.say(Level::Warn, w);
    } else {
        let unit = if p.unit.is_empty() {
            String::new()
        } else {
            format!(" {}", p.unit)
        };
        app.say(Level::Info, format!("{} = {shown}{unit}", p.label));
    }
}

fn cycle_solver(app: &mut App, dir: i32) {
    let all: Vec<&'static str> = app.sim.registry().names().collect();
    let n = all.len() as i64;
    let current = app.sim.entry().name();
    let at = all.iter().position(|&k| k == current).unwrap_or(0) as i64;
    let mut refused = Vec::new();
    for i in 1..n {
        let name = all[(at + i * i64::from(dir.signum())).rem_euclid(n) as usize];
        match app.sim.set_solver(name) {
            Ok(()) => {
                app.selected = app.selected.min(row_count(&app.sim) - 1);
                let entry = app.sim.entry();
                let steps = entry.steps_per_frame();
                let mut text = format!(
                    "solver: {name} ({}; meant for {steps} step{} per frame)",
                    entry.description(),
                    if steps == 1 { "" } else { "s" }
                );
                if let Some(first) = refused.first() {
                    text = format!("{text}; skipped: {first}");
                }
                app.say(Level::Info, text);
                if let Some(w) = app.sim.stability_warning() {
                    app.say(Level::Warn, w);
                }
                return;
            }
            Err(e) => refused.push(format!("{e:#}")),
        }
    }
    app.say(
        Level::Warn,
        format!(
            "staying with {}: {}",
            app.sim.entry().name(),
            refused.join("; ")
        ),
    );
}

fn edit_value(app: &mut App) {
    let p = row(&app.sim, app.selected);
    match p.kind {
        Kind::Solver => cycle_solver(app, 1),
        Kind::Toggle => nudge(app, 1, false),
        Kind::Number { .. } => match (p.get)(&app.sim.settings) {
            Some(v) => {
                // Full precision, so accepting the prompt unchanged changes nothing.
                app.overlay =
                    Overlay::Prompt(Prompt::new(Purpose::Value(app.selected), format!("{v}")));
            }
            None => app.say(Level::Warn, absent(p.label)),
        },
    }
}

fn restore(app: &mut App, all: bool) {
    let scene = app.sim.scene_settings();
    if all {
        app.sim.settings = scene;
        let wanted = app.sim.scene_solver().to_owned();
        let result = if app.sim.entry().name() == wanted {
            app.sim.apply_options()
        } else {
            app.sim.set_solver(&wanted)
        };
        app.selected = app.selected.min(row_count(&app.sim) - 1);
        if let Err(e) = result {
            app.say(Level::Warn, format!("{e:#}"));
            return;
        }
        app.say(
            Level::Info,
            "every parameter restored to the scene's values",
        );
        return;
    }
    let p = row(&app.sim, app.selected);
    match p.kind {
        Kind::Solver => {
            let wanted = app.sim.scene_solver().to_owned();
            match app.sim.set_solver(&wanted) {
                Ok(()) => {
                    app.selected = app.selected.min(row_count(&app.sim) - 1);
                    app.say(Level::Info, format!("solver restored: {wanted}"));
                }
                Err(e) => app.say(Level::Warn, format!("{e:#}")),
            }
        }
        _ => match (p.get)(&scene) {
            Some(v) => {
                (p.set)(&mut app.sim.settings, v);
                changed(app, app.selected);
            }
            None => app.say(Level::Warn, absent(p.label)),
        },
    }
}

fn turn(app: &mut App, yaw: f64, pitch: f64) {
    app.orbit.yaw = (app.orbit.yaw + yaw).rem_euclid(std::f64::consts::TAU);
    app.orbit.pitch = (app.orbit.pitch + pitch).clamp(-Orbit::MAX_PITCH, Orbit::MAX_PITCH);
    orbit_hint(app);
}

fn zoom(app: &mut App, factor: f64) {
    let size = {
        let s = app.sim.scene.mesh.spec();
        s.width.max(s.height)
    };
    // NOTE: keep the eye outside the cloth's neighbourhood and the cloth on screen.
    app.orbit.distance = (app.orbit.distance * factor).clamp(0.3 * size, 30.0 * size);
    orbit_hint(app);
}

fn orbit_hint(app: &mut App) {
    if !app.views.contains(&View::Orbit) || !visible_orbit(app) {
        app.say(
            Level::Info,
            "no orbit view on screen: press c to make the focused pane an orbit view",
        );
    }
}

fn visible_orbit(app: &App) -> bool {
    app.visible_slots()
        .iter()
        .any(|&s| app.views[s] == View::Orbit)
}

/// The slot of the orbit pane under a cell, if any.
fn orbit_pane_at(app: &App, col: u16, row: u16) -> Option<usize> {
    let (w, h) = app.screen;
    let r = layout::regions(app, Rect::new(0, 0, w, h))?;
    r.panes
        .iter()
        .find(|(slot, rect)| {
            app.views[*slot] == View::Orbit && rect.contains(Position::new(col, row))
        })
        .map(|(slot, _)| *slot)
}

fn prompt_edit(app: &mut App, f: impl FnOnce(&mut Prompt)) {
    if let Overlay::Prompt(p) = &mut app.overlay {
        f(p);
        p.error = None;
    }
}

/// The `*.json` files directly in `dir`, sorted; none if it cannot be read.
fn json_files(dir: &std::path::Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .map(|rd| {
            rd.filter_map(Result::ok)
                .filter(|e| e.file_type().is_ok_and(|t| t.is_file()))
                .filter_map(|e| e.file_name().into_string().ok())
                .filter(|n| {
                    std::path::Path::new(n)
                        .extension()
                        .is_some_and(|x| x.eq_ignore_ascii_case("json"))
                })
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

fn byte_index(s: &str, chars: usize) -> usize {
    s.char_indices().nth(chars).map_or(s.len(), |(i, _)| i)
}

fn submit(app: &mut App) {
    match std::mem::take(&mut app.overlay) {
        Overlay::Picker(p) => {
            let bundled = cloth_scene::BUNDLED.len();
            if let Some(b) = cloth_scene::BUNDLED.get(p.selected) {
                open_scene(app, b.name);
            } else if let Some(name) = p.files.get(p.selected - bundled) {
                if let Err(e) = submit_open(app, name) {
                    app.say(Level::Error, e);
                }
            } else {
                app.overlay = Overlay::Prompt(Prompt::new(Purpose::OpenPath, String::new()));
            }
        }
        Overlay::Prompt(mut p) => {
            let result = match p.purpose {
                Purpose::Value(row) => submit_value(app, row, &p.text),
                Purpose::SavePath => submit_save(app, &p.text),
                Purpose::OpenPath => submit_open(app, &p.text),
            };
            if let Err(e) = result {
                p.error = Some(e);
                app.overlay = Overlay::Prompt(p);
            }
        }
        other => app.overlay = other,
    }
}

fn submit_value(app: &mut App, at: usize, text: &str) -> Result<(), String> {
    let p = row(&app.sim, at);
    let v = p.parse(text)?;
    (p.set)(&mut app.sim.settings, v);
    changed(app, at);
    Ok(())
}

fn submit_save(app: &mut App, text: &str) -> Result<(), String> {
    let name = text.trim();
    if name.is_empty() {
        return Err("type a file name, e.g. my-scene.json".to_owned());
    }
    let path = app.cwd.join(name);
    if path.is_dir() {
        return Err(format!("{} is a folder; type a file name", path.display()));
    }
    if path.exists() {
        app.overlay = Overlay::ConfirmOverwrite(PathBuf::from(name));
        return Ok(());
    }
    save(app, &path).map_err(|e| format!("{e:#}"))
}

fn answer(app: &mut App, yes: bool) {
    let Overlay::ConfirmOverwrite(name) = std::mem::take(&mut app.overlay) else {
        return;
    };
    if !yes {
        // Back to the file name, so another can be typed.
        app.overlay = Overlay::Prompt(Prompt::new(
            Purpose::SavePath,
            name.to_string_lossy().into_owned(),
        ));
        return;
    }
    let path = app.cwd.join(&name);
    if let Err(e) = save(app, &path) {
        let mut p = Prompt::new(Purpose::SavePath, name.to_string_lossy().into_owned());
        p.error = Some(format!("{e:#}"));
        app.overlay = Overlay::Prompt(p);
    }
}

fn save(app: &mut App, path: &std::path::Path) -> anyhow::Result<()> {
    let sim = &app.sim;
    let file = sim.scene.to_file(
        &sim.settings.params,
        &sim.settings.colliders,
        sim.entry().name(),
        sim.options(),
    );
    let mut text = serde_json::to_string_pretty(&file)?;
    text.push('\n');
    let written = output::write_atomic(path, text.as_bytes())?;
    let saved = format!(
        "saved to {} (load it with: clothsim tui {})",
        path.display(),
        path.display()
    );
    match written.note() {
        Some(note) => app.say(Level::Warn, format!("{saved}; {note}")),
        None => app.say(Level::Info, saved),
    }
    Ok(())
}

fn submit_open(app: &mut App, text: &str) -> Result<(), String> {
    let name = text.trim();
    if name.is_empty() {
        return Err("type the path of a scene JSON file".to_owned());
    }
    let path = app.cwd.join(name);
    let scene = cloth_scene::load(&path.to_string_lossy(), &[]).map_err(|e| e.to_string())?;
    replace_scene(app, scene);
    Ok(())
}

fn open_scene(app: &mut App, name: &str) {
    match cloth_scene::load(name, &[]) {
        Ok(scene) => replace_scene(app, scene),
        Err(e) => app.say(Level::Error, e.to_string()),
    }
}

fn replace_scene(app: &mut App, scene: cloth_scene::Scene) {
    let registry = app.sim.registry().clone();
    let mut fallback = false;
    let result = Simulation::new(scene.clone(), registry.clone(), None).or_else(|e| {
        // The scene asks for a solver this binary lacks, or gives it options it refuses: run
        // it with the default solver at its defaults and say so.
        let default = registry
            .default_entry()
            .map_or("", cloth_solver::SolverEntry::name);
        app.say(Level::Warn, format!("{e:#}; using {default}"));
        fallback = true;
        let mut plain = scene;
        plain.solver = None;
        plain.solver_options.clear();
        plain.iterations = None;
        Simulation::new(plain, registry, None)
    });
    match result {
        Ok(sim) => {
            app.orbit = Orbit::course_default(&sim.scene.mesh);
            app.sim = sim;
            app.selected = app.selected.min(row_count(&app.sim) - 1);
            app.extent = None;
            app.debt = 0.0;
            app.frames = [None, None, None, None];
            if !fallback {
                app.say(Level::Info, format!("opened {}", app.sim.scene.origin));
            }
        }
        Err(e) => app.say(Level::Error, format!("{e:#}")),
    }
}
