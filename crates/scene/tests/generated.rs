//! Generated scene files and `--set` values, as a careless or hostile user would write them:
//! loading never panics and never hangs, and every error names where it came from (the file or
//! the `--set` argument) and, for a value, the key.

use cloth_scene::{BUNDLED, SceneError, load, parse};
use proptest::prelude::*;
use serde_json::{Map, Value, json};

/// Every key a scene may hold, by dotted path, plus some it may not.
const KEYS: &[&str] = &[
    "cloth.width",
    "cloth.height",
    "cloth.num_width_points",
    "cloth.num_height_points",
    "cloth.thickness",
    "cloth.orientation",
    "cloth.pinned",
    "cloth.enable_structural",
    "cloth.enable_shearing",
    "cloth.enable_bending",
    "cloth.damping",
    "cloth.density",
    "cloth.ks",
    "sphere",
    "sphere.origin",
    "sphere.radius",
    "sphere.friction",
    "plane",
    "plane.point",
    "plane.normal",
    "plane.friction",
    "simulation",
    "simulation.frames_per_sec",
    "simulation.simulation_steps",
    "simulation.gravity",
    "simulation.self_collision",
    "simulation.stretch_limit",
    "simulation.solver",
    "simulation.iterations",
    "simulation.seed",
    "description",
    "cloth.kss",
    "colth",
];

/// Numbers at and past every edge the scene checks, and ordinary ones.
fn number() -> impl Strategy<Value = Value> {
    prop_oneof![
        Just(json!(0)),
        Just(json!(1)),
        Just(json!(2)),
        Just(json!(-1)),
        Just(json!(1e-300)),
        Just(json!(1e308)),
        Just(json!(-1e308)),
        Just(json!(u64::MAX)),
        Just(json!(i64::MIN)),
        Just(json!(4_194_305)),
        Just(json!(0.5)),
        Just(json!(100.000_001)),
        (-1e6f64..1e6).prop_map(|v| json!(v)),
        (0u64..60).prop_map(|v| json!(v)),
    ]
}

/// Any JSON value a user might put where another was expected.
fn value() -> impl Strategy<Value = Value> {
    let leaf = prop_oneof![
        number(),
        Just(Value::Null),
        any::<bool>().prop_map(Value::Bool),
        "[a-z0-9 .\\-]{0,8}".prop_map(Value::String),
    ];
    leaf.prop_recursive(3, 24, 5, |inner| {
        prop_oneof![
            prop::collection::vec(inner.clone(), 0..5).prop_map(Value::Array),
            prop::collection::vec(("[a-z_]{1,6}", inner), 0..3)
                .prop_map(|kv| Value::Object(kv.into_iter().collect::<Map<_, _>>())),
        ]
    })
}

/// One edit of a scene: set a key to a value, or remove it.
fn edit() -> impl Strategy<Value = (usize, Option<Value>)> {
    (0..KEYS.len(), prop::option::weighted(0.85, value()))
}

fn apply(root: &mut Value, key: &str, v: Option<Value>) {
    let mut node = root;
    let parts: Vec<&str> = key.split('.').collect();
    for (i, part) in parts.iter().enumerate() {
        let Value::Object(map) = node else { return };
        if i + 1 == parts.len() {
            match v {
                Some(v) => {
                    map.insert((*part).to_owned(), v);
                }
                None => {
                    map.remove(*part);
                }
            }
            return;
        }
        node = map
            .entry((*part).to_owned())
            .or_insert_with(|| Value::Object(Map::new()));
    }
}

/// The error message names `origin`, and a value error names a key that is in the message.
fn assert_names_origin_and_key(e: &SceneError, origin: &str) {
    let text = e.to_string();
    match e {
        SceneError::Field { key, .. } | SceneError::Invalid { key, .. } => {
            assert!(text.starts_with(&format!("{origin}: ")), "{text}");
            assert!(!key.is_empty(), "{text}");
            if key != "." {
                assert!(text.contains(key.as_str()), "{text}");
            }
        }
        SceneError::Syntax { .. } => {
            assert!(
                text.starts_with(&format!("{origin}: invalid JSON")),
                "{text}"
            );
        }
        SceneError::BadSet { arg, .. } => {
            assert!(text.starts_with(&format!("--set {arg}: ")), "{text}");
        }
        other => panic!("unexpected error for generated text: {other}"),
    }
}

/// A scene small enough to build at once: a generated grid that is valid but huge would only
/// measure memory, which is not what these tests are about.
fn small_enough(v: &Value) -> bool {
    let n = |k: &str| v["cloth"][k].as_u64().unwrap_or(0);
    n("num_width_points").saturating_mul(n("num_height_points")) <= 10_000
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn an_edited_scene_file_loads_or_says_which_file_and_key_is_wrong(
        base in 0..BUNDLED.len(),
        edits in prop::collection::vec(edit(), 1..6),
        bom in any::<bool>(),
        pretty in any::<bool>(),
    ) {
        let mut v: Value = serde_json::from_str(BUNDLED[base].json).unwrap();
        for (k, val) in edits {
            apply(&mut v, KEYS[k], val);
        }
        prop_assume!(small_enough(&v));
        let mut text = if pretty {
            serde_json::to_string_pretty(&v).unwrap()
        } else {
            v.to_string()
        };
        if bom {
            text.insert(0, '\u{feff}');
        }
        match parse(&text, "gen.json", &[]) {
            Ok(scene) => {
                prop_assert!(scene.params.validate().is_ok());
                prop_assert!(scene.mesh.len() >= 4);
            }
            Err(e) => assert_names_origin_and_key(&e, "gen.json"),
        }
    }

    #[test]
    fn set_values_as_typed_load_or_say_which_argument_and_key_is_wrong(
        sets in prop::collection::vec(
            (0..KEYS.len(), prop_oneof![
                value().prop_map(|v| v.to_string()),
                "[ -~]{0,12}",
                Just("1e309".to_owned()),
                Just("-1e400".to_owned()),
                Just("[1,2,3]".to_owned()),
                Just("[0.5,0.2,0.5,1]".to_owned()),
            ]),
            1..4,
        ),
    ) {
        let sets: Vec<String> = sets.into_iter().map(|(k, v)| format!("{}={v}", KEYS[k])).collect();
        let mut v: Value = serde_json::from_str(BUNDLED[1].json).unwrap();
        for s in &sets {
            if let Some((k, raw)) = s.split_once('=') {
                let val = serde_json::from_str(raw.trim()).unwrap_or(Value::Null);
                apply(&mut v, k, Some(val));
            }
        }
        prop_assume!(small_enough(&v));
        match load("pinned4", &sets) {
            Ok(scene) => prop_assert!(scene.params.validate().is_ok()),
            Err(e) => assert_names_origin_and_key(&e, "pinned4"),
        }
    }

    #[test]
    fn any_bytes_in_a_scene_file_give_a_result_or_an_error_naming_the_file(
        bytes in prop::collection::vec(any::<u8>(), 0..200),
        prefix in prop_oneof![
            Just(Vec::new()),
            Just(b"\xEF\xBB\xBF".to_vec()),
            Just(b"\xFF\xFE".to_vec()),
            Just(b"{\"cloth\": ".to_vec()),
        ],
    ) {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bytes.json");
        let mut all = prefix;
        all.extend(bytes);
        std::fs::write(&path, &all).unwrap();
        let name = path.to_string_lossy().into_owned();
        if let Err(e) = load(&name, &[]) {
            prop_assert!(e.to_string().starts_with(&name), "{e}");
        }
    }
}

#[test]
fn wrong_length_arrays_name_their_key_and_show_the_array() {
    let pinned4 = BUNDLED[1].json;
    let text = pinned4.replace("[49, 0]", "[49, 0, 7]");
    let e = parse(&text, "pins.json", &[]).unwrap_err().to_string();
    assert!(
        e.starts_with(
            "pins.json: cloth.pinned[2]: [49, 0, 7] has 3 integers, but it must be \
             [column, row] (2 integers)"
        ),
        "{e}"
    );
    assert!(e.contains("(line "), "{e}");
    let e = load("sphere", &["sphere.origin=[0.5,0.2,0.5,1]".to_owned()])
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "sphere: sphere.origin: [0.5, 0.2, 0.5, 1] has 4 numbers, but it must be [x, y, z] \
         (3 numbers)"
    );
}

#[test]
fn a_number_too_large_for_a_float_in_a_file_names_its_key() {
    let text = BUNDLED[1].json.replace("\"ks\": 5000.0", "\"ks\": 1e309");
    let e = parse(&text, "big.json", &[]).unwrap_err().to_string();
    assert!(
        e.starts_with("big.json: cloth.ks: the number is out of range"),
        "{e}"
    );
    // Also when --set edits follow, which read the file another way.
    let e = parse(&text, "big.json", &["cloth.damping=1".to_owned()])
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("big.json: cloth.ks: the number is out of range"),
        "{e}"
    );
}

#[test]
fn a_tiny_thickness_is_printed_as_typed_not_as_300_digits() {
    let e = load("pinned4", &["cloth.thickness=1e-300".to_owned()])
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "pinned4: cloth.thickness is 1e-300, but it must be a finite number from 1e-9 to 1e9 \
         (metres)"
    );
}

#[test]
fn a_byte_order_mark_is_accepted_in_a_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bom.json");
    std::fs::write(&path, format!("\u{feff}{}", BUNDLED[1].json)).unwrap();
    let s = load(&path.to_string_lossy(), &[]).unwrap();
    assert_eq!(s.mesh.len(), 2500);
}

#[test]
fn a_bare_name_is_the_bundled_scene_and_a_path_is_the_file() {
    // The current folder is the crate's; a file named like a bundled scene would shadow it
    // under the old rule. The explicit form reads the file, the bare name the bundled scene.
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("plane");
    std::fs::write(&file, BUNDLED[1].json).unwrap();
    let as_path = load(&file.to_string_lossy(), &[]).unwrap();
    assert_eq!(as_path.mesh.pinned().iter().filter(|&&p| p).count(), 4);
    let bundled = load("plane", &[]).unwrap();
    assert_eq!(bundled.origin, "plane");
    assert!(
        bundled.mesh.pinned().iter().all(|&p| !p),
        "the bundled plane has no pins"
    );
    let e = load("no-such-scene", &[]).unwrap_err().to_string();
    assert!(
        e.contains("a path with a folder, such as ./no-such-scene, or ending in .json"),
        "{e}"
    );
}

/// Words of Rust, not of scenes: a message holding one shows a type name or Debug output.
const RUST: [&str; 4] = ["struct", "enum", "{ ", "::"];

/// Any value, from strings and object keys that hold no word of [`RUST`] themselves (a
/// message may echo what was typed).
fn tame_value() -> impl Strategy<Value = Value> {
    let leaf = prop_oneof![
        number(),
        Just(Value::Null),
        any::<bool>().prop_map(Value::Bool),
        prop::sample::select(vec!["", "a", "1.5", "yes", "x y", "-"])
            .prop_map(|s| Value::String(s.to_owned())),
    ];
    leaf.prop_recursive(3, 24, 5, |inner| {
        prop_oneof![
            prop::collection::vec(inner.clone(), 0..5).prop_map(Value::Array),
            prop::collection::vec(
                (
                    prop::sample::select(vec!["a", "cloth", "ks", "origin", "radius", "x"]),
                    inner
                ),
                0..3
            )
            .prop_map(|kv| Value::Object(
                kv.into_iter()
                    .map(|(k, v)| (k.to_owned(), v))
                    .collect::<Map<_, _>>()
            )),
        ]
    })
}

/// Whether `text` holds `word` as a word of its own (`struct`, not `enable_structural`).
fn has_word(text: &str, word: &str) -> bool {
    let part = |c: Option<char>| c.is_some_and(|c| c.is_alphanumeric() || c == '_');
    text.match_indices(word).any(|(i, _)| {
        let before = text[..i].chars().next_back();
        let after = text[i + word.len()..].chars().next();
        // `{ ` and `::` are marks, not words: any occurrence counts.
        !word.starts_with(char::is_alphabetic) || !(part(before) || part(after))
    })
}

fn assert_no_rust(e: &SceneError) {
    let text = e.to_string();
    for word in RUST {
        assert!(!has_word(&text, word), "{word:?} in: {text}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 600, ..ProptestConfig::default() })]

    #[test]
    fn hostile_scene_text_never_shows_a_rust_type_name_or_debug_output(
        base in 0..BUNDLED.len(),
        edits in prop::collection::vec(
            (0..KEYS.len(), prop::option::weighted(0.85, tame_value())),
            1..6,
        ),
        whole in prop::option::weighted(0.1, tame_value()),
        as_sets in any::<bool>(),
    ) {
        let mut v: Value = serde_json::from_str(BUNDLED[base].json).unwrap();
        let mut sets = Vec::new();
        for (k, val) in edits {
            if as_sets {
                let raw = val.as_ref().map_or_else(|| "null".to_owned(), Value::to_string);
                sets.push(format!("{}={raw}", KEYS[k]));
            } else {
                apply(&mut v, KEYS[k], val);
            }
        }
        // Now and then the whole scene is something else: a list, a number, a string.
        if let Some(w) = whole {
            v = w;
        }
        prop_assume!(small_enough(&v));
        let text = serde_json::to_string_pretty(&v).unwrap();
        if let Err(e) = parse(&text, "gen.json", &sets) {
            assert_no_rust(&e);
        }
    }
}

#[test]
fn rust_type_names_are_told_in_a_scene_authors_words() {
    for (text, expected) in [
        (
            "[]",
            "gen.json: .: invalid type: a list, expected an object with the keys cloth",
        ),
        (
            "7",
            "gen.json: .: invalid type: a number, expected an object",
        ),
        (
            "{\"cloth\": 5}",
            "gen.json: cloth: invalid type: a number, expected an object",
        ),
        (
            "{\"cloth\": [1, 2]}",
            "gen.json: cloth: invalid type: a list, expected an object",
        ),
    ] {
        let e = parse(text, "gen.json", &[]).unwrap_err();
        assert!(e.to_string().starts_with(expected), "{e}");
        assert_no_rust(&e);
    }
    let e = load("sphere", &["sphere=[1,2]".to_owned()]).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("pinned4: sphere: invalid type: a list, expected an object")
            || e.to_string()
                .starts_with("sphere: sphere: invalid type: a list, expected an object"),
        "{e}"
    );
}

#[test]
fn a_number_past_its_type_is_shown_as_typed() {
    let e = load(
        "pinned4",
        &["simulation.seed=18446744073709551616".to_owned()],
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("`18446744073709551616`") && !e.contains("1.8446744073709552e+19"),
        "{e}"
    );
    let text = BUNDLED[1].json.replace(
        "\"cloth\": {",
        "\"simulation\": {\"seed\": 18446744073709551616},\n  \"cloth\": {",
    );
    let e = parse(&text, "seed.json", &[]).unwrap_err().to_string();
    assert!(
        e.contains("`18446744073709551616`")
            && e.contains("expected a whole number from 0 to 18446744073709551615"),
        "{e}"
    );
}

#[test]
fn thickness_bounds_hold_for_the_value_as_typed() {
    // The course reads thickness into a 32-bit float, in which 1e-9 is 9.9999997e-10: the
    // documented minimum must still load, and a value just past it must not.
    for at_bound in ["1e-9", "1e9"] {
        let s = load("pinned4", &[format!("cloth.thickness={at_bound}")]).unwrap();
        assert!(cloth_mesh::EXTENT_RANGE.contains(&s.mesh.spec().thickness));
    }
    for past in ["0.9998e-9", "1.0002e9"] {
        let e = load("pinned4", &[format!("cloth.thickness={past}")])
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with(&format!(
                "pinned4: cloth.thickness is {}",
                past.replace("0.9998e-9", "9.998e-10")
                    .replace("1.0002e9", "1000200000")
            )),
            "{e}"
        );
    }
}
