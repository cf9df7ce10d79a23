//! `--set KEY=VALUE` overrides: a dotted path into the scene JSON and a JSON value.

use serde_json::Value;

use crate::SceneError;

/// Applies one `KEY=VALUE` override to a scene's JSON.
///
/// `KEY` is a dotted path of object keys (`cloth.ks`, `simulation.gravity`); missing objects on
/// the way are created, so `--set simulation.solver=implicit` works on a course file without a
/// `simulation` block. `VALUE` is JSON (`100000`, `false`, `[0,-9.8,0]`); a value that is not
/// valid JSON is taken as a string, so `implicit` need not be quoted. Whether the key exists and
/// the value fits is checked when the scene is parsed, with the same messages as for a file.
///
/// # Errors
/// [`SceneError::BadSet`] when the argument has no `=`, an empty key, or a path through a
/// non-object value.
pub fn apply_set(root: &mut Value, arg: &str) -> Result<(), SceneError> {
    let bad = |reason: &str| SceneError::BadSet {
        arg: arg.to_owned(),
        reason: reason.to_owned(),
    };
    let (key, raw) = arg
        .split_once('=')
        .ok_or_else(|| bad("expected KEY=VALUE, e.g. cloth.ks=100000"))?;
    let key = key.trim();
    if key.is_empty() || key.split('.').any(str::is_empty) {
        return Err(bad(
            "the key must be a dotted path such as cloth.ks or simulation.gravity",
        ));
    }
    let raw = raw.trim();
    let value = match serde_json::from_str(raw) {
        Ok(v) => v,
        // A number JSON cannot hold (1e309) is not a string the user meant: say so.
        Err(_) if looks_like_number(raw) => {
            return Err(bad(&format!(
                "{raw} is out of range: a value's magnitude must be below about 1.8e308 \
                 (the largest 64-bit float)"
            )));
        }
        Err(_) => Value::String(raw.to_owned()),
    };
    let mut node = root;
    let parts: Vec<&str> = key.split('.').collect();
    for (i, part) in parts.iter().enumerate() {
        let Value::Object(map) = node else {
            return Err(bad(&format!(
                "{} is not an object, so it has no key {part:?}",
                parts[..i].join(".")
            )));
        };
        if i + 1 == parts.len() {
            map.insert((*part).to_owned(), value);
            return Ok(());
        }
        node = map
            .entry((*part).to_owned())
            .or_insert_with(|| Value::Object(serde_json::Map::new()));
    }
    Ok(())
}

/// Whether `s` is written as a JSON number (`-12.5e3`), whatever its magnitude.
fn looks_like_number(s: &str) -> bool {
    let s = s.strip_prefix('-').unwrap_or(s);
    let (mantissa, exponent) = match s.find(['e', 'E']) {
        Some(i) => (&s[..i], Some(&s[i + 1..])),
        None => (s, None),
    };
    let (int, frac) = match mantissa.split_once('.') {
        Some((i, f)) => (i, Some(f)),
        None => (mantissa, None),
    };
    let digits = |t: &str| !t.is_empty() && t.bytes().all(|b| b.is_ascii_digit());
    digits(int)
        && frac.is_none_or(digits)
        && exponent.is_none_or(|e| digits(e.strip_prefix(['+', '-']).unwrap_or(e)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sets_numbers_booleans_arrays_and_bare_strings() {
        let mut v: Value = serde_json::json!({"cloth": {"ks": 5000.0}});
        apply_set(&mut v, "cloth.ks=100000").unwrap();
        apply_set(&mut v, "cloth.enable_bending=false").unwrap();
        apply_set(&mut v, "simulation.gravity=[0,-9.8,0]").unwrap();
        apply_set(&mut v, "simulation.solver=implicit").unwrap();
        assert_eq!(v["cloth"]["ks"], 100_000);
        assert_eq!(v["cloth"]["enable_bending"], false);
        assert_eq!(v["simulation"]["gravity"][1], -9.8);
        assert_eq!(v["simulation"]["solver"], "implicit");
    }

    #[test]
    fn malformed_overrides_are_explained() {
        let mut v: Value = serde_json::json!({"cloth": {"ks": 5000.0}});
        assert!(
            apply_set(&mut v, "cloth.ks")
                .unwrap_err()
                .to_string()
                .contains("expected KEY=VALUE")
        );
        assert!(apply_set(&mut v, "cloth..ks=1").is_err());
        let e = apply_set(&mut v, "cloth.ks.x=1").unwrap_err().to_string();
        assert_eq!(
            e,
            "--set cloth.ks.x=1: cloth.ks is not an object, so it has no key \"x\""
        );
    }

    #[test]
    fn a_number_too_large_for_a_float_is_named_as_typed_not_taken_as_a_string() {
        let mut v: Value = serde_json::json!({"cloth": {"ks": 5000.0}});
        let e = apply_set(&mut v, "cloth.ks=1e309").unwrap_err().to_string();
        assert_eq!(
            e,
            "--set cloth.ks=1e309: 1e309 is out of range: a value's magnitude must be below \
             about 1.8e308 (the largest 64-bit float)"
        );
        assert!(apply_set(&mut v, "cloth.ks=-2.5E+400").is_err());
        // Words stay strings, for the checks downstream to name.
        apply_set(&mut v, "simulation.solver=e309").unwrap();
        assert!(looks_like_number("-12.5e-3") && looks_like_number("7"));
        for s in [
            "", "-", "1.", ".5", "1e", "e5", "0x10", "inf", "NaN", "1.2.3",
        ] {
            assert!(!looks_like_number(s), "{s}");
        }
    }
}
