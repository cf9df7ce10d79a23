//! Numbers in messages, as a person would write them.

/// `v` as a person would type it: the shortest decimal that reads back as `v` (`5000`, `-1`,
/// `0.01`), or its exponent form when that is much shorter (`1e9`, `1e-300`), so a message
/// never prints hundreds of digits. Every form reads back as the same `f64`.
#[must_use]
pub fn show(v: f64) -> String {
    let plain = v.to_string();
    if !v.is_finite() {
        return plain;
    }
    let exponent = format!("{v:e}");
    if exponent.len() + 4 <= plain.len() {
        exponent
    } else {
        plain
    }
}

/// A computed `v` to four significant digits (`0.06`, `5.222e-6`), for figures a message
/// derives rather than repeats.
#[must_use]
pub fn approx(v: f64) -> String {
    format!("{v:.3e}")
        .parse::<f64>()
        .map_or_else(|_| show(v), show)
}

#[cfg(test)]
mod tests {
    use super::{approx, show};

    #[test]
    fn numbers_read_as_typed_and_never_run_to_hundreds_of_digits() {
        assert_eq!(show(5000.0), "5000");
        assert_eq!(show(100_000.0), "100000");
        assert_eq!(show(-1.0), "-1");
        assert_eq!(show(0.0), "0");
        assert_eq!(show(0.01), "0.01");
        assert_eq!(show(0.0095), "0.0095");
        assert_eq!(show(2e9), "2e9");
        assert_eq!(show(1e-300), "1e-300");
        assert_eq!(show(1e-12), "1e-12");
        assert_eq!(show(1.5e300), "1.5e300");
        assert_eq!(show(f64::MAX), "1.7976931348623157e308");
        assert_eq!(approx(0.060_000_000_000_000_005), "0.06");
        assert_eq!(approx(8.8e9), "8.8e9");
        assert_eq!(approx(5.222_329_678_670_935e-6), "0.000005222");
        for v in [1e-300, 0.1, 123.456, 1e20, -7e-9, f64::MIN_POSITIVE] {
            assert_eq!(show(v).parse::<f64>().unwrap(), v, "{v}");
        }
    }
}
