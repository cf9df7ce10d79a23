//! The one function that changes the model: `update(&mut App, Message)`.

use std::path::PathBuf;

use cloth_render::{Mode, Orbit, View};
use ratatui::layout::{Position, Rect};

use super::hand;
use super::layout;
use super::message::{Button, Message};
use super::model::{App, Layout, Level, Overlay, Picker, Prompt, Purpose, RATES, Then};
use super::params::{Kind, is_option_row, row, row_count};
use cloth_run::output;
use cloth_run::{Command, Run};

/// Radians of orbit per cell of mouse drag.
const DRAG_TURN: f64 = 0.05;

/// Points above which opening a scene asks first (a 500 x 500 cloth).
pub const BIG_CLOTH: usize = 250_000;

/// Applies one message.
pub fn update(app: &mut App, msg: Message) {
    match msg {
        Message::Quit => {
            if app.unsaved() && app.overlay != Overlay::ConfirmDiscard(Then::Quit) {
                app.overlay = Overlay::ConfirmDiscard(Then::Quit);
            } else {
                app.quit = true;
            }
        }
        Message::Escape => {
            app.after_save = None;
            escape(app);
        }
        Message::Suspend => app.suspend = true,
        Message::ToggleMouse => {
            app.mouse = !app.mouse;
            app.drag = None;
            app.say(
                Level::Info,
                if app.mouse {
                    "mouse captured: drag turns the orbit view, the wheel zooms (M frees it)"
                } else {
                    "mouse free: the terminal selects text again (M captures it)"
                },
            );
        }
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
            send_run(app);
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
        Message::Undo => undo(app),
        Message::RestoreAll => restore_all(app),
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
            app.say(Level::Info, format!("glyph mode: {}", app.mode));
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
            app.orbit_fitted = true;
            app.say(Level::Info, "orbit camera fitted to the scene");
        }
        Message::OpenPicker => {
            if app.unsaved()
                && app.compare.is_none()
                && app.overlay != Overlay::ConfirmDiscard(Then::Open)
            {
                app.overlay = Overlay::ConfirmDiscard(Then::Open);
            } else {
                open_picker(app);
            }
        }
        Message::Save => {
            // S in the quit (or open) dialog saves, then quits (or opens), as it says.
            app.after_save = match app.overlay {
                Overlay::ConfirmDiscard(then) => Some(then),
                _ => None,
            };
            let stem = scene_stem(app);
            app.overlay = Overlay::Prompt(Prompt::prefilled(
                Purpose::SavePath,
                format!("{stem}-edited.json"),
            ));
        }
        Message::WriteStats => write_stats(app),
        Message::ToggleRecording => toggle_recording(app),
        Message::Input(c) => prompt_edit(app, |p| {
            if p.selected {
                p.text.clear();
                p.cursor = 0;
            }
            let at = byte_index(&p.text, p.cursor);
            p.text.insert(at, c);
            p.cursor += 1;
        }),
        Message::Backspace => prompt_edit(app, |p| {
            if p.selected {
                p.text.clear();
                p.cursor = 0;
            } else if p.cursor > 0 {
                p.cursor -= 1;
                let at = byte_index(&p.text, p.cursor);
                p.text.remove(at);
            }
        }),
        Message::Delete => prompt_edit(app, |p| {
            if p.selected {
                p.text.clear();
                p.cursor = 0;
            } else if p.cursor < p.text.chars().count() {
                let at = byte_index(&p.text, p.cursor);
                p.text.remove(at);
            }
        }),
        Message::KillToStart => prompt_edit(app, |p| {
            let at = if p.selected {
                p.text.len()
            } else {
                byte_index(&p.text, p.cursor)
            };
            p.text.replace_range(..at, "");
            p.cursor = 0;
        }),
        Message::KillToEnd => prompt_edit(app, |p| {
            let at = if p.selected {
                0
            } else {
                byte_index(&p.text, p.cursor)
            };
            p.text.truncate(at);
            p.cursor = p.text.chars().count();
        }),
        Message::KillWord => prompt_edit(app, |p| {
            if p.selected {
                p.text.clear();
                p.cursor = 0;
                return;
            }
            // Like readline's Ctrl-W: the blanks before the cursor, then the word before them.
            let chars: Vec<char> = p.text.chars().collect();
            let mut start = p.cursor.min(chars.len());
            while start > 0 && chars[start - 1].is_whitespace() {
                start -= 1;
            }
            while start > 0 && !chars[start - 1].is_whitespace() {
                start -= 1;
            }
            let (a, b) = (byte_index(&p.text, start), byte_index(&p.text, p.cursor));
            p.text.replace_range(a..b, "");
            p.cursor = start;
        }),
        Message::Move(d) => match &mut app.overlay {
            Overlay::Help => {
                // The scroll stops where the last row shows, so the way back is as short.
                let most = i64::from(super::view::help_scroll_max(app));
                app.help_scroll = (i64::from(app.help_scroll) + i64::from(d)).clamp(0, most) as u16;
            }
            Overlay::Picker(p) => {
                // NOTE: the list stops at its ends rather than wrapping, so a held key does
                // not land on "type a path" from the top.
                let last = p.len().saturating_sub(1) as i64;
                p.selected = (p.selected as i64 + i64::from(d)).clamp(0, last) as usize;
            }
            Overlay::Prompt(p) => {
                let len = p.text.chars().count();
                if p.selected {
                    // A cursor key keeps the pre-filled text for editing, at that end.
                    p.selected = false;
                    p.cursor = if d < 0 { 0 } else { len };
                } else {
                    p.cursor = (p.cursor as i64 + i64::from(d)).clamp(0, len as i64) as usize;
                }
            }
            _ => {}
        },
        Message::Home => prompt_edit(app, |p| {
            p.selected = false;
            p.cursor = 0;
        }),
        Message::End => prompt_edit(app, |p| p.cursor = p.text.chars().count()),
        Message::Submit => submit(app),
        Message::Answer(yes) => answer(app, yes),
        Message::MouseDown { .. } | Message::MouseDrag { .. } | Message::Wheel { .. }
            if !app.mouse => {}
        Message::MouseDown {
            col,
            row,
            button,
            ctrl,
        } => {
            app.pointer = Some((col, row));
            app.drag = None;
            // NOTE: the left button on the cloth takes a point; off it, in an orbit pane, it
            // turns the camera as before.
            if !hand::press(app, col, row, button, ctrl) && button == Button::Left && !ctrl {
                app.drag = orbit_pane_at(app, col, row).map(|_| (col, row));
            }
        }
        Message::MouseDrag { col, row } => {
            app.pointer = Some((col, row));
            if hand::drag(app, col, row) {
                return;
            }
            if let Some((c0, r0)) = app.drag {
                let dx = f64::from(col) - f64::from(c0);
                let dy = f64::from(row) - f64::from(r0);
                turn(app, dx * DRAG_TURN, dy * DRAG_TURN);
                app.drag = Some((col, row));
            }
        }
        Message::MouseUp => {
            app.drag = None;
            hand::release(app);
        }
        Message::Poke => hand::poke(app),
        Message::Pin => hand::pin_here(app),
        Message::WriteActions => hand::write_actions(app),
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
        #[cfg(test)]
        Message::Tick(wall) => {
            if !app.threaded() && app.running && (app.sim.fault.is_none() || app.compare.is_some())
            {
                app.debt += wall.as_secs_f64() * app.rate();
            }
        }
        Message::Measured(stats) => app.stats = stats,
    }
}

/// Takes owed steps inline while `more()` allows; returns how many steps ran. The live app
/// steps on a worker thread; tests step inline with this, deterministically.
#[cfg(test)]
pub fn run_owed(app: &mut App, more: &mut dyn FnMut() -> bool) -> u64 {
    let mut n = 0;
    if app.compare.is_some() {
        // Compare mode pays the group's time a frame at a time, every variant in lockstep.
        let span = 1.0 / app.sim.settings.params.frames_per_sec;
        let before = faults(app);
        while app.running && app.debt >= span && more() {
            app.debt -= span;
            n += 1;
            if !app.step_group_inline() {
                break;
            }
        }
        stopped_variants(app, &before);
        return n;
    }
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

/// The simulation failed: pause and explain. (In compare mode a variant stops alone, greyed
/// with its reason: see [`stopped_variants`].)
fn stopped(app: &mut App) {
    if app.compare.is_some() {
        return;
    }
    app.running = false;
    app.debt = 0.0;
    app.overlay = Overlay::Fault;
}

fn escape(app: &mut App) {
    match app.overlay {
        Overlay::None => app.say(Level::Info, "Esc closes boxes; q quits"),
        Overlay::Fault => {
            app.overlay = Overlay::None;
            app.say(
                Level::Warn,
                "stopped: r resets (parameters are kept), space goes on anyway, u undoes an edit",
            );
        }
        Overlay::ConfirmBig(_) => {
            app.big = None;
            app.overlay = Overlay::None;
        }
        _ => app.overlay = Overlay::None,
    }
}

/// Tells the worker whether to run and how fast.
fn send_run(app: &mut App) {
    let rate = app.rate();
    let running = app.running;
    let _ = app.send(Command::Run { running, rate });
}

fn toggle_pause(app: &mut App) {
    // NOTE: in compare mode a stopped variant waits for a reset (the others stay at one
    // frame), so space only pauses and resumes the group.
    if app.sim.fault.is_some() && app.compare.is_none() {
        resume_anyway(app);
        return;
    }
    app.running = !app.running;
    app.debt = 0.0;
    app.stats.rates = cloth_run::lockstep::Rates::default();
    send_run(app);
    app.say(
        Level::Info,
        if app.running {
            "running"
        } else {
            "paused: n steps one frame, space resumes"
        },
    );
}

/// Goes on after a stop, from the last good frame, with the runaway test off until a reset.
fn resume_anyway(app: &mut App) {
    match app.sim.resume_anyway() {
        Ok(()) => {
            let _ = app.send(Command::ResumeAnyway);
            app.overlay = Overlay::None;
            app.running = true;
            app.debt = 0.0;
            send_run(app);
            app.say(
                Level::Warn,
                "going on anyway: the runaway test is off until r resets the cloth",
            );
        }
        Err(e) => {
            app.overlay = Overlay::Fault;
            app.say(Level::Error, e);
        }
    }
}

fn step_frame(app: &mut App) {
    app.running = false;
    app.debt = 0.0;
    if app.threaded() {
        let _ = app.send(Command::StepFrame);
        app.step_note = true;
        return;
    }
    if app.compare.is_some() {
        let before = faults(app);
        app.step_group_inline();
        if !stopped_variants(app, &before) {
            say_frame(app);
        }
        return;
    }
    if app.sim.step_frame().is_err() {
        stopped(app);
    } else {
        say_frame(app);
    }
}

/// "one frame: t = ..." after a single frame (the group's time in compare mode).
pub fn say_frame(app: &mut App) {
    let (frames, time) = match &app.compare {
        Some(c) => c.clock(&app.sim),
        None => (app.sim.frames, app.sim.time),
    };
    app.say(
        Level::Info,
        format!("one frame: t = {time:.4} s (frame {frames})"),
    );
}

/// Which variants have stopped (compare mode), in the study's order.
fn faults(app: &App) -> Vec<bool> {
    let Some(c) = &app.compare else {
        return Vec::new();
    };
    std::iter::once(&app.sim)
        .chain(c.members.iter().map(|m| &m.sim))
        .map(|s| s.fault.is_some())
        .collect()
}

/// Compare mode: says which variant stopped since `before` (which variants had), and that the
/// others go on; when none is left, the group pauses. True when one stopped.
fn stopped_variants(app: &mut App, before: &[bool]) -> bool {
    let Some(c) = &app.compare else {
        return false;
    };
    let sims = std::iter::once((c.title.as_str(), &app.sim))
        .chain(c.members.iter().map(|m| (m.title.as_str(), &m.sim)));
    let mut newly = None;
    let mut live = 0;
    for (k, (title, sim)) in sims.enumerate() {
        match &sim.fault {
            Some(f) if !before.get(k).copied().unwrap_or(false) => {
                newly = Some(format!(
                    "{title} stopped at t = {:.2} s: {}",
                    f.time, f.what
                ));
            }
            Some(_) => {}
            None => live += 1,
        }
    }
    let Some(text) = newly else {
        return false;
    };
    if live == 0 {
        app.running = false;
        app.say(
            Level::Warn,
            format!("{text}; every variant has stopped: r resets all"),
        );
    } else {
        app.say(
            Level::Warn,
            format!("{text}; the others go on (r resets all)"),
        );
    }
    true
}

/// Takes in what the coordinator published (compare mode): every variant, the group's rates
/// and any stop.
fn adopt_group(app: &mut App) -> bool {
    let before = faults(app);
    let Some(got) = app.adopt_group() else {
        return false;
    };
    app.stats.rates = got.rates;
    for e in got.errors {
        app.say(Level::Error, e);
    }
    let stopped = stopped_variants(app, &before);
    if !got.running && app.running {
        // The group paused by itself: to step a frame, or every variant stopped.
        app.running = false;
    }
    if app.step_note {
        app.step_note = false;
        if !stopped {
            say_frame(app);
        }
    }
    true
}

/// Takes in what the worker published: the cloth, its clock and any stop.
pub fn adopt(app: &mut App) -> bool {
    if app.compare.is_some() {
        return adopt_group(app);
    }
    let Some(w) = &app.worker else {
        return false;
    };
    let Some(got) = w.adopt_into(&mut [&mut app.sim]) else {
        return false;
    };
    app.stats.rates = got.rates;
    for e in got.errors {
        app.say(Level::Error, e);
    }
    if app.sim.fault.is_some() && app.running {
        stopped(app);
    } else if !got.running && app.running && app.sim.fault.is_none() {
        // The worker paused by itself only to step a frame; follow it.
        app.running = false;
    }
    if app.step_note {
        app.step_note = false;
        if app.sim.fault.is_some() {
            stopped(app);
        } else {
            say_frame(app);
        }
    }
    true
}

fn reset(app: &mut App) {
    if app.threaded() {
        let _ = app.send(Command::Reset);
    }
    // The UI's copies too, so no pane shows the old run until the next snapshot.
    if let Some(c) = &mut app.compare {
        for m in &mut c.members {
            m.sim.reset();
        }
    }
    app.sim.reset();
    app.grip = None;
    app.debt = 0.0;
    app.extent = None;
    if app.overlay == Overlay::Fault {
        app.overlay = Overlay::None;
    }
    app.say(
        Level::Info,
        "reset to the start positions and the scene's pins (parameters kept)",
    );
}

/// In compare mode, whether `label`'s row is a varied key (each variant keeps its own value,
/// so it is not edited), saying so.
fn varied(app: &mut App, label: &str) -> bool {
    let Some(c) = &app.compare else {
        return false;
    };
    let Some((key, values)) = c
        .axes
        .iter()
        .find(|(k, _)| k.rsplit('.').next() == Some(label))
        .cloned()
    else {
        return false;
    };
    app.say(
        Level::Warn,
        format!("{key} is what the variants compare ({values}): each keeps its own"),
    );
    true
}

fn nudge(app: &mut App, dir: i32, coarse: bool) {
    let p = row(&app.sim, app.selected);
    if varied(app, p.label) {
        return;
    }
    if p.kind == Kind::Solver {
        cycle_solver(app, dir);
        return;
    }
    let Some(v) = (p.get)(&app.sim.settings) else {
        app.say(Level::Warn, absent(p.label));
        return;
    };
    let nv = p.nudged(v, dir, coarse);
    remember(app);
    (p.set)(&mut app.sim.settings, nv);
    changed(app, app.selected);
}

/// Keeps the settings before an edit, for undo.
fn remember(app: &mut App) {
    /// Edits kept for undo.
    const DEPTH: usize = 100;
    let now = (app.sim.settings.clone(), app.sim.entry().name());
    if app.undo.last() != Some(&now) {
        if app.undo.len() == DEPTH {
            app.undo.remove(0);
        }
        app.undo.push(now);
    }
}

fn undo(app: &mut App) {
    let Some((settings, name)) = app.undo.pop() else {
        app.say(Level::Info, "nothing to undo");
        return;
    };
    // The solver first: its options are rows only while it is the active one.
    let solver_changed = name != app.sim.entry().name();
    if solver_changed && let Err(e) = app.sim.set_solver(name) {
        app.say(Level::Warn, format!("{e:#}"));
        return;
    }
    // Say which row the undo changed, and select it.
    let row_at = (0..row_count(&app.sim)).find(|&i| {
        let p = row(&app.sim, i);
        match p.kind {
            Kind::Solver => solver_changed,
            _ => !solver_changed && (p.get)(&settings) != (p.get)(&app.sim.settings),
        }
    });
    let options_changed = settings.options != app.sim.settings.options;
    app.sim.settings = settings;
    if options_changed && let Err(e) = app.sim.apply_options() {
        app.say(Level::Warn, format!("{e:#}"));
        return;
    }
    let Some(r) = row_at else {
        app.selected = app.selected.min(row_count(&app.sim) - 1);
        app.say(Level::Info, "undone");
        return;
    };
    app.selected = r;
    if row(&app.sim, r).kind == Kind::Solver {
        app.say(Level::Info, format!("undone: solver {name}"));
        if let Some(w) = app.sim.stability_warning() {
            app.say(Level::Warn, w);
        }
    } else {
        changed(app, r);
        if let Some(n) = &mut app.note {
            n.text = format!("undone: {}", n.text);
        }
    }
}

fn absent(label: &str) -> String {
    let object = label.split_whitespace().next().unwrap_or(label);
    format!("this scene has no {object}, so {label} does not apply")
}

/// After a parameter changed: say its new value, or warn.
fn changed(app: &mut App, at: usize) {
    let p = row(&app.sim, at);
    if is_option_row(&app.sim, at)
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
    let before = (app.sim.settings.clone(), current);
    for i in 1..n {
        let name = all[(at + i * i64::from(dir.signum())).rem_euclid(n) as usize];
        match app.sim.set_solver(name) {
            Ok(()) => {
                let was = before.0.params.steps_per_frame;
                app.undo.push(before);
                app.selected = app.selected.min(row_count(&app.sim) - 1);
                let entry = app.sim.entry();
                let meant = entry.steps_per_frame();
                let now = app.sim.settings.params.steps_per_frame;
                let plural = |n: u32| if n == 1 { "" } else { "s" };
                let steps = if now != was {
                    format!("steps/frame follow it: {was} -> {now}")
                } else if now == meant {
                    format!("meant for {meant} step{} per frame", plural(meant))
                } else {
                    format!(
                        "meant for {meant} step{} per frame; steps/frame stay {now}, as {}",
                        plural(meant),
                        if app.sim.scene.gives_steps() && app.sim.steps_follow_solver() {
                            "the scene gives them"
                        } else {
                            "edited"
                        }
                    )
                };
                let mut text = format!("solver: {name} ({}; {steps})", entry.description());
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
    if varied(app, p.label) {
        return;
    }
    match p.kind {
        Kind::Solver => cycle_solver(app, 1),
        Kind::Toggle | Kind::Choice { .. } => nudge(app, 1, false),
        Kind::Number { .. } => match (p.get)(&app.sim.settings) {
            Some(v) => {
                // Full precision, so accepting the prompt unchanged changes nothing.
                app.overlay =
                    Overlay::Prompt(Prompt::prefilled(Purpose::Value(app.selected), exact(v)));
            }
            None => app.say(Level::Warn, absent(p.label)),
        },
    }
}

/// `v` written exactly (it reads back to the same bits) and short: plain decimals in the
/// usual range, scientific notation for tiny or huge values (`1e-300`, not 300 digits).
pub fn exact(v: f64) -> String {
    if v == 0.0 || (1.0e-4..1.0e15).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

fn restore_all(app: &mut App) {
    let scene = app.sim.scene_settings();
    let wanted = app.sim.scene_solver().to_owned();
    if app.sim.settings == scene && app.sim.entry().name() == wanted {
        app.say(Level::Info, "every parameter already has the scene's value");
        return;
    }
    remember(app);
    // The scene's solver first (its options as the scene gives them), then the scene's values.
    if app.sim.entry().name() != wanted
        && let Err(e) = app.sim.set_solver(&wanted)
    {
        app.say(Level::Warn, format!("{e:#}"));
        return;
    }
    app.sim.settings = app.sim.scene_settings();
    app.selected = app.selected.min(row_count(&app.sim) - 1);
    if let Err(e) = app.sim.apply_options() {
        app.say(Level::Warn, format!("{e:#}"));
        return;
    }
    app.say(
        Level::Info,
        "every parameter restored to the scene's values (u undoes it)",
    );
}

fn turn(app: &mut App, yaw: f64, pitch: f64) {
    app.orbit_fitted = false;
    app.orbit.yaw = (app.orbit.yaw + yaw).rem_euclid(std::f64::consts::TAU);
    app.orbit.pitch = (app.orbit.pitch + pitch).clamp(-Orbit::MAX_PITCH, Orbit::MAX_PITCH);
    orbit_hint(app);
}

fn zoom(app: &mut App, factor: f64) {
    let size = {
        let s = app.sim.scene.mesh.spec();
        s.width.max(s.height)
    };
    app.orbit_fitted = false;
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
        // Any edit ends the selection of the pre-filled text (it was replaced or kept).
        p.selected = false;
    }
}

/// Whether `path` holds a cloth's state (what `simulate` writes) rather than a scene: its
/// first key is the state's, where a scene's never is.
fn is_state_file(path: &std::path::Path) -> bool {
    use std::io::Read as _;
    let mut head = [0u8; 64];
    let n = std::fs::File::open(path)
        .and_then(|mut f| f.read(&mut head))
        .unwrap_or(0);
    let text = String::from_utf8_lossy(&head[..n]);
    text.trim_start()
        .trim_start_matches('{')
        .trim_start()
        .starts_with("\"num_width_points\"")
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
        Overlay::ConfirmDiscard(then) => {
            app.overlay = Overlay::ConfirmDiscard(then);
            answer(app, true);
        }
        Overlay::ConfirmBig(n) => {
            app.overlay = Overlay::ConfirmBig(n);
            answer(app, true);
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
    if (p.get)(&app.sim.settings) != Some(v) {
        remember(app);
    }
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
    let name = match std::mem::take(&mut app.overlay) {
        Overlay::ConfirmOverwrite(name) => name,
        Overlay::ConfirmDiscard(then) => {
            match (yes, then) {
                (true, Then::Quit) => app.quit = true,
                (true, Then::Open) => open_picker(app),
                (false, _) => {}
            }
            return;
        }
        Overlay::ConfirmBig(_) => {
            if let Some(scene) = app.big.take()
                && yes
            {
                start_scene(app, *scene);
            }
            return;
        }
        other => {
            app.overlay = other;
            return;
        }
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
    let mut file = sim.scene.to_file(
        &sim.settings.params,
        &sim.settings.colliders,
        sim.entry().name(),
        sim.options(),
    );
    // A key the scene did not give stays out unless its value was edited, so the saved scene
    // loads as the original did: above all, steps per frame that follow the solver's
    // recommendation must not be pinned to the number the current solver happens to use.
    let given = sim.scene.file.simulation.clone().unwrap_or_default();
    let (now, loaded) = (&sim.settings.params, &sim.scene.params);
    if let Some(s) = file.simulation.as_mut() {
        if given.simulation_steps.is_none() && sim.steps_follow_solver() {
            s.simulation_steps = None;
        }
        if given.frames_per_sec.is_none() && now.frames_per_sec == loaded.frames_per_sec {
            s.frames_per_sec = None;
        }
        if given.gravity.is_none() && now.gravity == loaded.gravity {
            s.gravity = None;
        }
        if given.self_collision.is_none() && now.self_collision == loaded.self_collision {
            s.self_collision = None;
        }
    }
    let mut text = serde_json::to_string_pretty(&file)?;
    text.push('\n');
    let written = output::write_atomic(path, text.as_bytes())?;
    app.mark_saved();
    let saved = format!(
        "saved to {} (load it with: clothsim tui {})",
        path.display(),
        path.display()
    );
    match written.note() {
        Some(note) => app.say(Level::Warn, format!("{saved}; {note}")),
        None => app.say(Level::Info, saved),
    }
    match app.after_save.take() {
        Some(Then::Quit) => app.quit = true,
        Some(Then::Open) => open_picker(app),
        None => {}
    }
    Ok(())
}

/// The scene's name as the start of a file name (`pinned4`, `my-scene`).
fn scene_stem(app: &App) -> String {
    std::path::Path::new(&app.sim.scene.origin)
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("scene")
        .to_owned()
}

/// Writes the run's table of numbers (every frame since the start or the last reset) to the
/// first free `SCENE-stats.csv` of the folder.
fn write_stats(app: &mut App) {
    let path = super::recording::free_name(&app.cwd, &format!("{}-stats", scene_stem(app)), "csv");
    match cloth_run::export::StatsTable::write(&path, &app.sim.record) {
        Ok(()) => {
            let rows = app.sim.record.len();
            app.say(
                Level::Info,
                format!("wrote {rows} frames of numbers to {}", path.display()),
            );
        }
        Err(e) => app.say(Level::Error, format!("{e:#}")),
    }
}

/// Starts recording the screen to the first free `SCENE.cast` of the folder, or stops the
/// recording and keeps it.
fn toggle_recording(app: &mut App) {
    if let Some(result) = app.stop_recording() {
        match result {
            Ok(path) => app.say(
                Level::Info,
                format!(
                    "recording saved to {} (play it with: asciinema play {})",
                    path.display(),
                    path.display()
                ),
            ),
            Err(e) => app.say(Level::Error, format!("{e:#}")),
        }
        return;
    }
    let path = super::recording::free_name(&app.cwd, &scene_stem(app), "cast");
    let (width, height) = app.screen;
    match super::recording::Recording::start(&path, width, height, &app.sim.scene.origin) {
        Ok(r) => {
            app.recording = Some(r);
            app.say(
                Level::Info,
                format!("recording the screen to {}; R stops", path.display()),
            );
        }
        Err(e) => app.say(Level::Error, format!("{e:#}")),
    }
}

/// Opens the scene picker on the scene that is open now.
fn open_picker(app: &mut App) {
    if app.compare.is_some() {
        // The variants are one scene's: another scene is another study.
        app.say(
            Level::Warn,
            "compare shows one scene's variants: quit and run clothsim compare on another scene",
        );
        return;
    }
    let files = json_files(&app.cwd);
    let origin = &app.sim.scene.origin;
    let selected = cloth_scene::BUNDLED
        .iter()
        .position(|b| b.name == origin)
        .or_else(|| {
            let name = std::path::Path::new(origin).file_name()?.to_str()?;
            let in_cwd = app.cwd.join(name) == std::path::Path::new(origin)
                || std::path::Path::new(origin).parent() == Some(std::path::Path::new(""));
            files
                .iter()
                .position(|f| in_cwd && f == name)
                .map(|i| cloth_scene::BUNDLED.len() + i)
        })
        .unwrap_or(0);
    let states = files
        .iter()
        .map(|f| is_state_file(&app.cwd.join(f)))
        .collect();
    app.overlay = Overlay::Picker(Picker {
        selected,
        files,
        states,
    });
}

/// A typed path with a leading `~` meaning the home folder, as a shell would read it.
fn expand_home(text: &str) -> PathBuf {
    let home = || std::env::var_os("HOME").filter(|h| !h.is_empty());
    if text == "~" {
        if let Some(h) = home() {
            return PathBuf::from(h);
        }
    } else if let Some(rest) = text.strip_prefix("~/")
        && let Some(h) = home()
    {
        return PathBuf::from(h).join(rest);
    }
    PathBuf::from(text)
}

/// An error with its causes (the OS's reason included), as one line.
fn chain(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        let more = s.to_string();
        if !text.contains(&more) {
            text = format!("{text}: {more}");
        }
        source = s.source();
    }
    text
}

fn submit_open(app: &mut App, text: &str) -> Result<(), String> {
    let name = text.trim();
    if name.is_empty() {
        return Err("type the path of a scene JSON file".to_owned());
    }
    let path = app.cwd.join(expand_home(name));
    let scene = cloth_scene::load(&path.to_string_lossy(), &[]).map_err(|e| chain(&e))?;
    replace_scene(app, scene);
    Ok(())
}

fn open_scene(app: &mut App, name: &str) {
    match cloth_scene::load(name, &[]) {
        Ok(scene) => replace_scene(app, scene),
        Err(e) => app.say(Level::Error, chain(&e)),
    }
}

/// Opens `scene`, asking first when its cloth is big; refuses it when it would need more
/// memory than the app may take.
fn replace_scene(app: &mut App, scene: cloth_scene::Scene) {
    if let Err(e) = check_memory(app, &scene) {
        app.say(Level::Error, format!("{e:#}"));
        return;
    }
    let n = scene.mesh.len();
    if n > BIG_CLOTH {
        app.big = Some(Box::new(scene));
        app.overlay = Overlay::ConfirmBig(n);
        return;
    }
    start_scene(app, scene);
}

/// Refuses `scene` when its cloth would need more memory than the app may take (see
/// [`cloth_run::memory::check`]), with the solver it asks for or else the default one.
/// What the UI would need to run `scene` (with the solver it would get) and that solver;
/// `None` with no solver registered. The one estimate behind the memory check and the big
/// cloth's question.
pub fn scene_need(
    app: &App,
    scene: &cloth_scene::Scene,
) -> Option<(cloth_solver::SolverEntry, cloth_run::memory::Need)> {
    let registry = app.sim.registry();
    let (entry, options) = match cloth_run::solvers::choose(registry, scene, None) {
        Ok(choice) => (choice.entry, choice.options),
        Err(_) => (*registry.default_entry()?, serde_json::Value::Null),
    };
    let need = cloth_run::memory::ui_need(&entry, &options, &scene.mesh);
    Some((entry, need))
}

fn check_memory(app: &App, scene: &cloth_scene::Scene) -> anyhow::Result<()> {
    let Some((entry, need)) = scene_need(app, scene) else {
        return Ok(());
    };
    let who = cloth_run::memory::solver(&entry);
    let limit = (app.max_memory, cloth_run::memory::SMALLER_SCENE);
    cloth_run::memory::check(&scene.origin, &who, &scene.mesh, need, limit)
}

fn start_scene(app: &mut App, scene: cloth_scene::Scene) {
    let registry = app.sim.registry().clone();
    let mut fallback = false;
    let result = Run::new(scene.clone(), registry.clone(), None).or_else(|e| {
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
        Run::new(plain, registry, None)
    });
    match result {
        Ok(sim) => {
            app.orbit = Orbit::course_default(&sim.scene.mesh);
            app.orbit_fitted = true;
            app.undo.clear();
            app.display = super::panes::Display::for_mesh(&sim.scene.mesh);
            app.sim = sim;
            app.mark_saved();
            app.selected = app.selected.min(row_count(&app.sim) - 1);
            app.extent = None;
            app.debt = 0.0;
            app.frames = [None, None, None, None];
            app.stats.rates = cloth_run::lockstep::Rates::default();
            if let Some(notify) = app.notify.clone()
                && let Err(e) = app.start_worker(notify)
            {
                app.say(Level::Error, format!("{e:#}"));
                return;
            }
            if !fallback {
                app.say(Level::Info, format!("opened {}", app.sim.scene.origin));
            }
        }
        Err(e) => app.say(Level::Error, format!("{e:#}")),
    }
}
