//! The hand in the UI: the mouse grabs, drags, pins and cuts the cloth, keys poke and pin it.

use cloth_mesh::Vec3;
use cloth_render::View;
use ratatui::crossterm::event::KeyCode;

use super::super::hand::Drawn;
use super::super::message::{Button, Message};
use super::super::{App, update};
use super::{app_with, compare_with, compared, left_down, press, screen};

/// Draws the app at 120 x 40 and gives the pane showing `view` of the first cloth.
fn pane(app: &mut App, view: View) -> Drawn {
    screen(app, 120, 40);
    *app.drawn
        .iter()
        .find(|d| d.variant == 0 && d.spec.view == view)
        .unwrap_or_else(|| panic!("no {view} pane drawn"))
}

/// Exactly one frame (the app is paused).
fn step_frame(app: &mut App) {
    press(app, KeyCode::Char('n'));
}

/// A right-button stroke down column `col` of pane `d`, from its top row to its bottom one.
fn cut_down(app: &mut App, d: &Drawn, col: u16) {
    let down = Message::MouseDown {
        col,
        row: d.inner.y,
        button: Button::Right,
        ctrl: false,
    };
    update(app, down);
    let row = d.inner.y + d.inner.height - 1;
    update(app, Message::MouseDrag { col, row });
    update(app, Message::MouseUp);
}

/// The cell at the middle of a pane.
fn middle(d: &Drawn) -> (u16, u16) {
    (
        d.inner.x + d.inner.width / 2,
        d.inner.y + d.inner.height / 2,
    )
}

#[test]
fn a_grabbed_point_follows_the_mouse_within_a_frame_and_swings_when_let_go() {
    let mut app = app_with("pinned4", true);
    let top = pane(&mut app, View::Top);
    let (col, row) = middle(&top);
    update(&mut app, left_down(col, row));
    let held = app.sim.held.expect("the press on the cloth took a point");
    let nw = app.sim.scene.mesh.nw();
    let (x, y) = (held.point % nw, held.point / nw);
    // The middle of the top view is the middle of the flat cloth: a grid step is 1/49 m,
    // more than a cell is wide here, so the point taken is within a step of the centre.
    assert!(
        x.abs_diff(24) <= 2 && y.abs_diff(24) <= 2,
        "took ({x}, {y})"
    );
    let note = &app.note.as_ref().unwrap().text;
    assert!(
        note.starts_with(&format!("holding point ({x}, {y})")),
        "{note}"
    );
    let start = app.sim.state.positions[held.point];
    // Six cells to the right: along +x in the top view, in the plane through the point.
    update(&mut app, Message::MouseDrag { col: col + 6, row });
    let to = app.sim.held.unwrap().to;
    // Held where it was taken, not jumping to the cursor's cell.
    assert!(
        (to.y - start.y).abs() < 1e-12 && (to.z - start.z).abs() < 1e-12,
        "{to}"
    );
    assert!(
        to.x - start.x > 0.05,
        "6 cells of a 1 m wide view move it {}",
        to.x - start.x
    );
    step_frame(&mut app);
    assert_eq!(
        app.sim.state.positions[held.point], to,
        "at the hand after one frame"
    );
    assert!(app.sim.record.last().unwrap().kinetic_energy_j > 0.0);
    update(&mut app, Message::MouseUp);
    assert!(app.sim.held.is_none() && app.grip.is_none());
    assert_eq!(app.note.as_ref().unwrap().text, "let go");
    for _ in 0..5 {
        step_frame(&mut app);
    }
    assert_ne!(app.sim.state.positions[held.point], to, "let go, it swings");
}

#[test]
fn a_press_off_the_cloth_takes_nothing() {
    let mut app = app_with("pinned4", true);
    let top = pane(&mut app, View::Top);
    update(&mut app, left_down(top.inner.x, top.inner.y));
    assert!(app.sim.held.is_none() && app.grip.is_none());
}

#[test]
fn a_right_drag_across_the_cloth_cuts_it_in_two_and_r_makes_it_whole() {
    let mut app = app_with("pinned4", true);
    let top = pane(&mut app, View::Top);
    let (col, _) = middle(&top);
    let down = Message::MouseDown {
        col,
        row: top.inner.y,
        button: Button::Right,
        ctrl: false,
    };
    update(&mut app, down);
    for row in top.inner.y + 1..top.inner.y + top.inner.height {
        update(&mut app, Message::MouseDrag { col, row });
    }
    update(&mut app, Message::MouseUp);
    let mesh = &app.sim.scene.mesh;
    assert!(!mesh.is_whole());
    // A straight stroke across a 50-point cloth crosses at least one spring per row.
    assert!(mesh.springs_cut() >= 50, "{} cut", mesh.springs_cut());
    // Some line between two columns of points (or through one) has no spring across it
    // any more: the cloth is in two pieces.
    let nw = mesh.nw();
    let parted = (1..2 * nw - 2).any(|twice| {
        let s = twice as f64 / 2.0;
        let col = |i: u32| (i as usize % nw) as f64;
        !mesh.springs().iter().any(|sp| {
            let (a, b) = (col(sp.a), col(sp.b));
            a.min(b) < s && a.max(b) > s
        })
    });
    assert!(parted, "the stroke left the cloth in one piece");
    // The drawing shows the gap: a column of the top view's pane with no cloth between
    // columns with cloth, on the stroke's row of the pane's middle.
    for _ in 0..30 {
        step_frame(&mut app);
    }
    let text = screen(&mut app, 120, 40);
    let line: Vec<char> = text
        .lines()
        .nth(usize::from(middle(&top).1))
        .unwrap()
        .chars()
        .collect();
    let inside = &line[usize::from(top.inner.x)..usize::from(top.inner.x + top.inner.width)];
    let cloth: Vec<usize> = (0..inside.len()).filter(|&i| inside[i] != ' ').collect();
    let (first, last) = (cloth[0], *cloth.last().unwrap());
    assert!(
        (first..last).any(|i| inside[i] == ' '),
        "no gap in the top view's middle row: {:?}",
        inside.iter().collect::<String>()
    );
    press(&mut app, KeyCode::Char('r'));
    assert!(app.sim.scene.mesh.is_whole());
}

#[test]
fn control_click_pins_a_point_save_keeps_it_and_r_goes_back_to_the_scenes_pins() {
    let dir = tempfile::tempdir().unwrap();
    let mut app = app_with("pinned4", true);
    app.cwd = dir.path().to_owned();
    let top = pane(&mut app, View::Top);
    let (col, row) = middle(&top);
    update(
        &mut app,
        Message::MouseDown {
            col,
            row,
            button: Button::Left,
            ctrl: true,
        },
    );
    update(&mut app, Message::MouseUp);
    let pins = |app: &App| app.sim.scene.mesh.pinned().iter().filter(|p| **p).count();
    assert_eq!(pins(&app), 5);
    assert!(app.note.as_ref().unwrap().text.starts_with("pinned point"));
    press(&mut app, KeyCode::Char('S'));
    press(&mut app, KeyCode::Enter);
    let saved = cloth_scene::load(
        &dir.path().join("pinned4-edited.json").to_string_lossy(),
        &[],
    )
    .unwrap();
    assert_eq!(saved.mesh.pinned(), app.sim.scene.mesh.pinned());
    // The middle button frees it again.
    update(
        &mut app,
        Message::MouseDown {
            col,
            row,
            button: Button::Middle,
            ctrl: false,
        },
    );
    assert_eq!(pins(&app), 4);
    press(&mut app, KeyCode::Char('P'));
    assert_eq!(pins(&app), 5, "P pins the point under the mouse");
    press(&mut app, KeyCode::Char('r'));
    assert_eq!(pins(&app), 4);
}

#[test]
fn t_pokes_the_cloth_without_a_mouse() {
    let mut app = app_with("pinned4", true);
    pane(&mut app, View::Side);
    press(&mut app, KeyCode::Char('t'));
    assert!(app.note.as_ref().unwrap().text.starts_with("poked point"));
    step_frame(&mut app);
    assert!(app.sim.record.last().unwrap().kinetic_energy_j > 0.0);
}

#[test]
fn a_grab_in_compare_mode_takes_the_same_point_of_every_variant() {
    let mut app = compare_with("pinned4", &["cloth.ks=1000,5000"]);
    screen(&mut app, 160, 48);
    let d = *app.drawn.iter().find(|d| d.variant == 1).unwrap();
    let (col, row) = middle(&d);
    update(&mut app, left_down(col, row));
    let held: Vec<_> = compared(&app)
        .iter()
        .map(|s| s.held.unwrap().point)
        .collect();
    assert_eq!(held[0], held[1]);
    update(&mut app, Message::MouseDrag { col: col + 3, row });
    let to: Vec<Vec3> = compared(&app).iter().map(|s| s.held.unwrap().to).collect();
    assert_eq!(to[0], to[1]);
}

#[test]
fn snapshot_a_held_point_and_a_cut_cloth() {
    let mut app = app_with("pinned4", true);
    screen(&mut app, 100, 30);
    let top = *app.drawn.iter().find(|d| d.spec.view == View::Top).unwrap();
    let (col, row) = middle(&top);
    update(&mut app, left_down(col, row));
    update(
        &mut app,
        Message::MouseDrag {
            col: col + 4,
            row: row - 2,
        },
    );
    for _ in 0..3 {
        step_frame(&mut app);
    }
    let held = screen(&mut app, 100, 30);
    // Marked in the top view; the side view sees the flat cloth edge-on, with the half in
    // front of the point hiding it.
    assert_eq!(
        held.matches('&').count(),
        1,
        "the held point is marked where it shows"
    );
    insta::assert_snapshot!("held_point_100x30", held);
    update(&mut app, Message::MouseUp);
    cut_down(&mut app, &top, col - 3);
    for _ in 0..20 {
        step_frame(&mut app);
    }
    insta::assert_snapshot!("cut_cloth_100x30", screen(&mut app, 100, 30));
}

#[test]
fn a_pin_by_hand_is_an_unsaved_edit_until_saved() {
    let dir = tempfile::tempdir().unwrap();
    let mut app = app_with("pinned4", true);
    app.cwd = dir.path().to_owned();
    pane(&mut app, View::Top);
    assert!(!app.unsaved());
    press(&mut app, KeyCode::Char('P'));
    assert!(app.unsaved(), "a new pin would be lost on quitting");
    press(&mut app, KeyCode::Char('q'));
    assert!(!app.quit, "q asks first");
    press(&mut app, KeyCode::Esc);
    press(&mut app, KeyCode::Char('S'));
    press(&mut app, KeyCode::Enter);
    assert!(!app.unsaved());
}

#[test]
fn the_touches_key_a_writes_replay_headless_to_the_same_bits() {
    let dir = tempfile::tempdir().unwrap();
    let mut app = app_with("pinned4", true);
    app.cwd = dir.path().to_owned();
    let top = pane(&mut app, View::Top);
    let (col, row) = middle(&top);
    step_frame(&mut app);
    update(&mut app, left_down(col, row));
    step_frame(&mut app);
    update(
        &mut app,
        Message::MouseDrag {
            col: col + 3,
            row: row - 4,
        },
    );
    step_frame(&mut app);
    step_frame(&mut app);
    update(&mut app, Message::MouseUp);
    press(&mut app, KeyCode::Char('t'));
    cut_down(&mut app, &top, col - 5);
    for _ in 0..10 {
        step_frame(&mut app);
    }
    press(&mut app, KeyCode::Char('A'));
    let path = dir.path().join("pinned4-actions.jsonl");
    let note = &app.note.as_ref().unwrap().text;
    assert!(note.contains("touches written to"), "{note}");
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.lines().any(|l| l.contains("\"cut\"")), "{text}");
    let scene = cloth_scene::load("pinned4", &[]).unwrap();
    let points = scene.mesh.len();
    let mut script = cloth_run::actions::Actions::parse(&text, "recorded", points).unwrap();
    let mut replay = cloth_run::Run::new(scene, cloth_run::default_registry(), None).unwrap();
    while replay.frames < app.sim.frames {
        script.step_frame(&mut replay, &mut || {}).unwrap().unwrap();
    }
    assert_eq!(replay.state, app.sim.state);
    assert_eq!(replay.scene.mesh, app.sim.scene.mesh);
}

#[test]
fn pinning_the_held_point_takes_it_from_the_hand_and_a_drag_after_moves_nothing() {
    let mut app = app_with("pinned4", true);
    let top = pane(&mut app, View::Top);
    let (col, row) = middle(&top);
    update(&mut app, left_down(col, row));
    let point = app.sim.held.unwrap().point;
    press(&mut app, KeyCode::Char('P'));
    assert!(app.sim.scene.mesh.pinned()[point]);
    assert!(app.sim.held.is_none() && app.grip.is_none());
    update(&mut app, Message::MouseDrag { col: col + 4, row });
    assert_ne!(
        app.note.as_ref().unwrap().level,
        super::super::model::Level::Error
    );
    update(&mut app, Message::MouseUp);
}
