//! Generated key sequences fed to `update` through the real input mapping, the screen drawn
//! after every key: never a panic, and the model's invariants hold after each key.

use proptest::prelude::*;
use ratatui::crossterm::event::{Event, KeyCode, KeyEvent, KeyModifiers};

use super::super::model::{Level, Overlay, RATES, Then};
use super::super::params::{Kind, row, row_count};
use super::{App, Args, build_in, input, screen, update};

/// Every key the app answers somewhere (the keymap, the boxes, the prompt's editing keys) and a
/// few it does not, so sequences wander through every overlay.
fn keys() -> Vec<KeyEvent> {
    let plain = |code| KeyEvent::new(code, KeyModifiers::NONE);
    let ctrl = |c| KeyEvent::new(KeyCode::Char(c), KeyModifiers::CONTROL);
    let shift = |code| KeyEvent::new(code, KeyModifiers::SHIFT);
    let mut keys: Vec<KeyEvent> = "?qpnr+=-kjhlHLuUvfcmCMadwszx0oSy. e123456789"
        .chars()
        .map(|c| plain(KeyCode::Char(c)))
        .collect();
    keys.extend(
        [
            KeyCode::Esc,
            KeyCode::Enter,
            KeyCode::Up,
            KeyCode::Down,
            KeyCode::Left,
            KeyCode::Right,
            KeyCode::Home,
            KeyCode::End,
            KeyCode::PageUp,
            KeyCode::PageDown,
            KeyCode::Tab,
            KeyCode::BackTab,
            KeyCode::Backspace,
            KeyCode::Delete,
            KeyCode::F(1),
        ]
        .map(plain),
    );
    keys.extend([shift(KeyCode::Left), shift(KeyCode::Right)]);
    keys.extend(['c', 'z', 'u', 'w', 'a', 'e', 'q'].map(ctrl));
    keys
}

/// The app on pinned4 shrunk to 8 x 8 points, so a step costs next to nothing; it saves and
/// opens files only under a folder that does not exist.
fn small_app() -> App {
    let args = Args {
        paused: true,
        sets: vec![
            "cloth.num_width_points=8".to_owned(),
            "cloth.num_height_points=8".to_owned(),
            "cloth.pinned=[[0,0],[7,0],[0,7],[7,7]]".to_owned(),
        ],
        ..Args::default()
    };
    let mut app = build_in(
        &args,
        &cloth_run::default_registry(),
        false,
        &cloth_render::ColorEnv::default(),
    )
    .unwrap();
    app.cwd = std::path::PathBuf::from("/nonexistent");
    app
}

/// What identifies the scene running: a replacement changes it (or says "opened").
fn scene_id(app: &App) -> (String, usize) {
    (app.sim.scene.origin.clone(), app.sim.scene.mesh.len())
}

fn opened_note(app: &App) -> Option<String> {
    app.note
        .as_ref()
        .filter(|n| n.level == Level::Info && n.text.starts_with("opened "))
        .map(|n| n.text.clone())
}

/// The model's invariants that hold after any key.
fn check_invariants(app: &App, start: &App) -> Result<(), TestCaseError> {
    let rows = row_count(&app.sim);
    prop_assert!(
        app.selected < rows,
        "selected row {} of {rows}",
        app.selected
    );
    prop_assert!(app.rate < RATES.len());
    prop_assert!(app.focus < app.views.len());
    for i in 0..rows {
        let param = row(&app.sim, i);
        let Kind::Number {
            min, max, integer, ..
        } = param.kind
        else {
            continue;
        };
        let Some(v) = (param.get)(&app.sim.settings) else {
            continue;
        };
        // A scene may start a value outside the panel's range; edits keep it inside.
        let untouched = i < row_count(&start.sim)
            && scene_id(app) == scene_id(start)
            && (row(&start.sim, i).get)(&start.sim.settings) == Some(v);
        prop_assert!(
            untouched || ((min..=max).contains(&v) && (!integer || v.fract() == 0.0)),
            "{} = {v}, outside {min}..={max}{}",
            param.label,
            if integer { " (whole)" } else { "" }
        );
    }
    match &app.overlay {
        Overlay::Prompt(p) => {
            prop_assert!(p.cursor <= p.text.chars().count(), "cursor past the text");
            prop_assert!(!p.selected || !p.text.is_empty(), "an empty selection");
            if let super::super::model::Purpose::Value(i) = p.purpose {
                prop_assert!(i < rows, "a prompt for row {i} of {rows}");
            }
        }
        Overlay::Picker(p) => prop_assert!(p.selected < p.len()),
        Overlay::ConfirmBig(_) => prop_assert!(app.big.is_some(), "no scene waits"),
        _ => {}
    }
    Ok(())
}

/// Feeds `sequence` to a fresh app, drawing after each key, checking the invariants and that
/// unsaved edits are dropped only after the user said so.
fn run(sequence: &[KeyEvent]) -> Result<(), TestCaseError> {
    let start = small_app();
    let mut app = small_app();
    // Set once the user answers yes to "discard the unsaved edits?" before opening a scene;
    // forgotten when the main screen is back.
    let mut discard_confirmed = false;
    for (k, key) in sequence.iter().enumerate() {
        let before_overlay = app.overlay.clone();
        let before_unsaved = app.unsaved();
        let before_scene = scene_id(&app);
        let before_opened = opened_note(&app);
        if let Some(m) = input::message(&app, &Event::Key(*key)) {
            update(&mut app, m);
        }
        // The loop suspends and resumes; here the flag is simply taken.
        app.suspend = false;
        let at = format!("key {k} ({key:?}) of {sequence:?}");
        if matches!(before_overlay, Overlay::ConfirmDiscard(Then::Open))
            && matches!(app.overlay, Overlay::Picker(_))
        {
            discard_confirmed = true;
        }
        if app.quit {
            prop_assert!(
                !before_unsaved || before_overlay == Overlay::ConfirmDiscard(Then::Quit),
                "quit with unsaved edits without asking, at {at}"
            );
            return Ok(());
        }
        let replaced = scene_id(&app) != before_scene
            || opened_note(&app).is_some_and(|n| Some(n) != before_opened);
        prop_assert!(
            !replaced || !before_unsaved || discard_confirmed,
            "a scene replaced unsaved edits without asking, at {at}"
        );
        if app.overlay == Overlay::None {
            discard_confirmed = false;
        }
        check_invariants(&app, &start).map_err(|e| TestCaseError::fail(format!("{e} at {at}")))?;
        let _ = screen(&mut app, 100, 30);
    }
    Ok(())
}

proptest! {
    // NOTE: 64 sequences of up to 60 keys on an 8 x 8 cloth: a few seconds, and enough to pass
    // through every overlay (a sequence opens one within a few keys) many times over.
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn any_key_sequence_keeps_the_model_whole(
        sequence in proptest::collection::vec(proptest::sample::select(keys()), 1..=60)
    ) {
        run(&sequence)?;
    }
}
