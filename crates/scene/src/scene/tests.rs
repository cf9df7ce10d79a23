use super::*;
use crate::BUNDLED;

fn err(sets: &[&str]) -> String {
    let sets: Vec<String> = sets.iter().map(|s| (*s).to_owned()).collect();
    load("pinned4", &sets).unwrap_err().to_string()
}

#[test]
fn every_bundled_scene_loads() {
    for b in BUNDLED {
        let s = load(b.name, &[]).unwrap_or_else(|e| panic!("{}: {e}", b.name));
        assert_eq!(s.origin, b.name);
        assert!(s.params.validate().is_ok());
    }
}

#[test]
fn course_scenes_read_as_the_spec_states() {
    let p4 = load("pinned4", &[]).unwrap();
    assert_eq!((p4.mesh.nw(), p4.mesh.nh()), (50, 50));
    assert_eq!(p4.mesh.pinned().iter().filter(|&&p| p).count(), 4);
    assert_eq!(p4.params, StepParams::default());
    assert!(p4.colliders.is_empty());
    let sphere = load("sphere", &[]).unwrap();
    assert_eq!(
        sphere.colliders,
        vec![Collider::Sphere(Sphere {
            origin: Vec3::new(0.5, 0.2, 0.5),
            radius: 0.2,
            friction: 0.3
        })]
    );
    let sc = load("selfCollision", &[]).unwrap();
    assert_eq!(sc.mesh.spec().orientation, Orientation::Vertical);
    assert!(
        matches!(sc.colliders[0], Collider::Plane(p) if p.normal == Vec3::y() && p.friction == 0.5)
    );
}

#[test]
fn thickness_is_read_as_the_courses_32_bit_float() {
    // The course's loader stores the thickness in a `float`: the standard scenes' 0.0095 m is
    // 0.00949999969... m there, and self-collision's reach is twice that.
    let p4 = load("pinned4", &[]).unwrap();
    assert_eq!(
        p4.mesh.thickness().to_bits(),
        f64::from(0.0095_f32).to_bits()
    );
    assert_ne!(p4.mesh.thickness(), 0.0095);
}

#[test]
fn set_overrides_reach_the_parameters() {
    let sets = [
        "cloth.ks=100000",
        "cloth.enable_bending=false",
        "simulation.gravity=[0,-1.6,0]",
        "simulation.solver=implicit",
    ]
    .map(String::from);
    let s = load("pinned4", &sets).unwrap();
    assert_eq!(s.params.ks, 100_000.0);
    assert!(!s.params.bending);
    assert_eq!(s.params.gravity, Vec3::new(0.0, -1.6, 0.0));
    assert_eq!(s.solver.as_deref(), Some("implicit"));
}

#[test]
fn missing_unknown_and_mistyped_keys_are_named() {
    let text = cloth_scene_without("ks");
    let e = parse(&text, "x.json", &[]).unwrap_err().to_string();
    assert!(e.starts_with("x.json: cloth: missing field `ks`"), "{e}");
    assert!(err(&["cloth.kss=1"]).contains("cloth.kss: unknown field `kss`"));
    assert!(err(&["colth.ks=1"]).contains("unknown field `colth`"));
    let e = err(&["cloth.ks=\"stiff\""]);
    assert!(
        e.contains("cloth.ks: invalid type: string \"stiff\""),
        "{e}"
    );
    let e = err(&["cloth.orientation=2"]);
    assert_eq!(
        e,
        "pinned4: cloth.orientation is 2, but it must be 0 (horizontal) or 1 (vertical)"
    );
}

fn cloth_scene_without(key: &str) -> String {
    let mut v: Value = serde_json::from_str(bundled("pinned4").unwrap().json).unwrap();
    v["cloth"].as_object_mut().unwrap().remove(key);
    v.to_string()
}

#[test]
fn type_errors_in_files_give_line_and_column() {
    let text = "{\n  \"cloth\": {\n    \"width\": \"wide\"\n  }\n}";
    let e = parse(text, "t.json", &[]).unwrap_err().to_string();
    assert!(
        e.starts_with("t.json: cloth.width: invalid type: string \"wide\""),
        "{e}"
    );
    assert!(e.ends_with("(line 3, column 19)"), "{e}");
}

#[test]
fn invalid_json_gives_line_and_column() {
    let e = parse("{\n \"cloth\": {,\n}", "broken.json", &[]).unwrap_err();
    assert!(
        matches!(
            e,
            SceneError::Syntax {
                line: 2,
                column: 12,
                ..
            }
        ),
        "{e:?}"
    );
    assert!(
        e.to_string()
            .starts_with("broken.json: invalid JSON at line 2, column 12")
    );
}

#[test]
fn grids_too_small_or_absurdly_large_are_rejected() {
    let e = err(&["cloth.num_width_points=1"]);
    assert!(
        e.starts_with("pinned4: cloth.num_width_points is 1, but it must be an integer >= 2"),
        "{e}"
    );
    let e = err(&[
        "cloth.num_width_points=3000",
        "cloth.num_height_points=3000",
    ]);
    assert!(
        e.contains("cloth.num_width_points * cloth.num_height_points is 9000000"),
        "{e}"
    );
    assert!(
        err(&["cloth.num_height_points=-4"])
            .contains("cloth.num_height_points: invalid value: integer `-4`")
    );
}

#[test]
fn pins_outside_the_grid_are_rejected() {
    let e = err(&["cloth.pinned=[[0,0],[49,50]]"]);
    assert_eq!(
        e,
        "pinned4: cloth.pinned[1] is [49, 50], but it must be [column, row] with column in 0..=49 and row in 0..=49"
    );
    assert!(err(&["cloth.pinned=[[-1,0]]"]).contains("cloth.pinned[0] is [-1, 0]"));
}

#[test]
fn physical_values_out_of_range_are_rejected() {
    for (set, key) in [
        ("cloth.ks=-1", "cloth.ks is -1"),
        ("cloth.density=-150", "cloth.density is -150"),
        ("cloth.density=0", "cloth.density is 0"),
        ("cloth.thickness=-0.01", "cloth.thickness is -0.01"),
        ("cloth.thickness=0", "cloth.thickness is 0"),
        (
            "cloth.damping=101",
            "cloth.damping is 101, but it must be between 0 and 100",
        ),
        ("cloth.damping=-0.1", "cloth.damping is -0.1"),
        ("cloth.width=0", "cloth.width is 0"),
        (
            "cloth.width=1e-12",
            "cloth.width is 1e-12, but it must be a finite number from 1e-9 to 1e9 (metres)",
        ),
        ("cloth.height=2e9", "cloth.height is 2e9"),
        (
            "simulation.simulation_steps=0",
            "simulation.simulation_steps is 0",
        ),
        (
            "simulation.frames_per_sec=0",
            "simulation.frames_per_sec is 0",
        ),
    ] {
        let e = err(&[set]);
        assert!(e.contains(key), "{set}: {e}");
    }
}

#[test]
fn non_finite_numbers_are_rejected() {
    // JSON has no NaN or infinity literals; an overflowing literal is the only way to write one.
    let text = bundled("pinned4")
        .unwrap()
        .json
        .replace("\"ks\": 5000.0", "\"ks\": 1e999");
    let e = parse(&text, "inf.json", &[]).unwrap_err().to_string();
    assert!(
        e.starts_with("inf.json: cloth.ks: the number is out of range"),
        "{e}"
    );
    let e = err(&["cloth.ks=1e999"]);
    assert!(e.contains("cloth.ks"), "{e}");
}

#[test]
fn bad_objects_are_rejected() {
    let sphere = |r: &str, f: &str| {
        vec![format!(
            "sphere={{\"origin\":[0.5,0.2,0.5],\"radius\":{r},\"friction\":{f}}}"
        )]
    };
    let e = load("pinned4", &sphere("0", "0.3"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("sphere.radius is 0, but it must be a finite number > 0"),
        "{e}"
    );
    let e = load("pinned4", &sphere("-0.2", "0.3"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("sphere.radius is -0.2"), "{e}");
    let e = load("pinned4", &sphere("0.2", "1.5"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("sphere.friction is 1.5, but it must be between 0 and 1"),
        "{e}"
    );
    let e = load("plane", &["plane.normal=[0,0,0]".into()])
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "plane: plane.normal is [0, 0, 0], but it must be a non-zero vector"
    );
    let e = load("plane", &["plane.friction=-0.5".into()])
        .unwrap_err()
        .to_string();
    assert!(e.contains("plane.friction is -0.5"), "{e}");
    let s = load("plane", &["plane.normal=[0,2,0]".into()]).unwrap();
    assert!(
        matches!(s.colliders[0], Collider::Plane(p) if p.normal == Vec3::y()),
        "normalised on load"
    );
}

#[test]
fn unreadable_files_and_unknown_names_are_explained() {
    let e = load("/nonexistent/dir/scene.json", &[]).unwrap_err();
    assert!(matches!(e, SceneError::Io { .. }));
    assert_eq!(
        e.to_string(),
        "/nonexistent/dir/scene.json: cannot read the scene file"
    );
    let e = load("pinned5", &[]).unwrap_err().to_string();
    assert!(e.starts_with(
        "no bundled scene named \"pinned5\" and no file pinned5; bundled scenes: pinned2, pinned4"
    ));
}

#[test]
fn saving_an_edited_scene_round_trips() {
    let s = load("sphere", &[]).unwrap();
    let mut params = s.params;
    params.ks = 12_345.0;
    params.steps_per_frame = 60;
    let mut colliders = s.colliders.clone();
    colliders[0].set_friction(0.9);
    let file = s.to_file(&params, &colliders, "verlet", &serde_json::json!({}));
    let text = serde_json::to_string_pretty(&file).unwrap();
    let back = parse(&text, "saved.json", &[]).unwrap();
    assert_eq!(back.params, params);
    assert_eq!(back.colliders, colliders);
    assert_eq!(back.mesh, s.mesh);
}

#[test]
fn solver_and_options_are_kept_as_written_for_the_application_to_check() {
    let s = load(
        "pinned4",
        &[
            "simulation.solver=\"anything\"".to_owned(),
            "simulation.solver_options={\"iterations\": 0, \"bogus\": true}".to_owned(),
        ],
    )
    .unwrap();
    assert_eq!(s.solver.as_deref(), Some("anything"));
    assert_eq!(
        Value::Object(s.solver_options.clone()),
        serde_json::json!({"iterations": 0, "bogus": true})
    );
    let e = err(&["simulation.solver_options=3"]);
    assert!(e.contains("simulation.solver_options: invalid type"), "{e}");
}

#[test]
fn scene_options_belong_to_the_scenes_own_solver() {
    let with = |sets: &[&str]| {
        let sets: Vec<String> = sets.iter().map(|s| (*s).to_owned()).collect();
        load("pinned4", &sets).unwrap()
    };
    let s = with(&[
        "simulation.solver=\"fast-implicit\"",
        "simulation.solver_options={\"iterations\": 4}",
    ]);
    assert_eq!(
        s.options_for("fast-implicit", "verlet"),
        serde_json::json!({"iterations": 4})
    );
    assert_eq!(s.options_for("verlet", "verlet"), serde_json::json!({}));
    // A scene naming no solver gives its options to the default one.
    let s = with(&["simulation.solver_options={\"threads\": 2}"]);
    assert_eq!(
        s.options_for("verlet", "verlet"),
        serde_json::json!({"threads": 2})
    );
    assert_eq!(s.options_for("xpbd", "verlet"), serde_json::json!({}));
}

#[test]
fn the_retired_option_keys_are_refused_with_the_spelling_that_replaced_them() {
    for (set, key, option) in [
        (
            "simulation.iterations=7",
            "simulation.iterations",
            "iterations",
        ),
        ("simulation.threads=2", "simulation.threads", "threads"),
        (
            "simulation.constraint_order=\"colored\"",
            "simulation.constraint_order",
            "order",
        ),
    ] {
        let e = err(&[set]);
        assert!(
            e.starts_with(&format!("pinned4: {key}: no longer a scene key")),
            "{set}: {e}"
        );
        assert!(
            e.contains(&format!("write simulation.solver_options.{option}")),
            "{set}: {e}"
        );
    }
}

#[test]
fn a_saved_scene_keeps_its_solver_and_options() {
    let s = load("pinned4", &[]).unwrap();
    let options = serde_json::json!({"iterations": 12});
    let file = s.to_file(&s.params, &s.colliders, "fast-implicit", &options);
    let text = serde_json::to_string(&file).unwrap();
    let back = parse(&text, "saved.json", &[]).unwrap();
    assert_eq!(back.solver.as_deref(), Some("fast-implicit"));
    assert_eq!(Value::Object(back.solver_options.clone()), options);
    // No options: no `solver_options` key at all.
    let file = s.to_file(&s.params, &s.colliders, "verlet", &serde_json::json!({}));
    assert!(file.simulation.unwrap().solver_options.is_none());
}

#[test]
fn the_steps_are_given_by_the_file_or_a_set_only() {
    assert!(!load("pinned4", &[]).unwrap().gives_steps());
    assert!(
        load("pinned4", &["simulation.simulation_steps=5".to_owned()])
            .unwrap()
            .gives_steps()
    );
}

#[test]
fn the_wind_keys_read_into_the_parameters_and_are_checked_by_name() {
    let s = load(
        "curtain",
        &[
            "simulation.wind=[1,0,-3]".to_owned(),
            "simulation.wind_drag=0.8".to_owned(),
            "simulation.wind_gust=0.5".to_owned(),
            "simulation.wind_gust_period=4".to_owned(),
        ],
    )
    .unwrap();
    let w = s.params.wind;
    assert_eq!(w.velocity, Vec3::new(1.0, 0.0, -3.0));
    assert_eq!((w.drag, w.gust, w.gust_period), (0.8, 0.5, 4.0));
    assert!(s.params.validate().is_ok());
    assert!(
        !load("curtain", &[]).unwrap().params.wind.blows(),
        "none by default"
    );

    let e = err(&["simulation.wind=[0,0,2000]"]);
    assert!(
        e.contains("simulation.wind") && e.contains("-1000 to 1000"),
        "{e}"
    );
    let e = err(&["simulation.wind=[0,1]"]);
    assert!(e.contains("simulation.wind"), "{e}");
    let e = err(&["simulation.wind_drag=-1"]);
    assert!(
        e.contains("simulation.wind_drag") && e.contains("from 0 to 100"),
        "{e}"
    );
    let e = err(&["simulation.wind_gust_period=0"]);
    assert!(e.contains("simulation.wind_gust_period"), "{e}");
}

#[test]
fn a_saved_scene_keeps_its_wind_and_a_calm_one_gains_no_wind_keys() {
    let s = load("curtain", &["simulation.wind=[0,0,5]".to_owned()]).unwrap();
    let file = s.to_file(&s.params, &s.colliders, "verlet", &serde_json::json!({}));
    let sim = file.simulation.unwrap();
    assert_eq!(sim.wind, Some([0.0, 0.0, 5.0]));
    assert_eq!(sim.wind_drag, None, "the default drag is not written");
    let calm = load("curtain", &[]).unwrap();
    let file = calm.to_file(
        &calm.params,
        &calm.colliders,
        "verlet",
        &serde_json::json!({}),
    );
    assert_eq!(file.simulation.unwrap().wind, None);
}
