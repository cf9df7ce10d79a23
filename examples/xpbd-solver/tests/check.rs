//! The XPBD solver against clothsim's conformance kit, as any solver crate can hold itself to
//! it, and a snapshot of its frames. (CI runs the kit's whole quick set through the binary:
//! `clothsim-xpbd check --solver xpbd`.)

use cloth_check::{CheckOptions, FramesSpec, check, frames_as_text};
use clothsim_xpbd::Xpbd;
use serde_json::json;

#[test]
fn passes_the_kit_on_the_sphere_it_once_fell_through() {
    let options = CheckOptions {
        scenes: vec!["sphere".to_owned()],
        ..CheckOptions::default()
    };
    let report = check(&Xpbd::ENTRY, &json!({}), &options).unwrap();
    assert!(report.passed(), "{report}");
}

#[test]
fn frames_of_the_sphere() {
    let text = frames_as_text(&Xpbd::ENTRY, &json!({}), "sphere", &FramesSpec::default()).unwrap();
    insta::assert_snapshot!(text);
}
