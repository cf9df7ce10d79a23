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
