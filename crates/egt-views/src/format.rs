//! Number formats shared by every document and table: short floats,
//! scientific notation, exact fractions, and the `version` every document
//! carries.

use egt_core::numerics::exact::{self, Q};
use serde::Serialize;

/// A float for a table: up to 6 decimals, trailing zeros dropped; scientific
/// notation for very large or very small magnitudes.
pub fn float(x: f64) -> String {
    if !x.is_finite() {
        return x.to_string();
    }
    if x == 0.0 {
        return "0".to_string();
    }
    let a = x.abs();
    if !(1e-4..1e9).contains(&a) {
        return format!("{x:.6e}");
    }
    let s = format!("{x:.6}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".to_string()
    } else {
        s.to_string()
    }
}

/// Six significant digits, scientific when small or large.
pub fn sci(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if (1e-3..1e6).contains(&a) {
        float(v)
    } else {
        format!("{v:.6e}")
    }
}

/// An exact rational as `p/q` (or `p`).
pub fn exact(q: &Q) -> String {
    exact::display(q)
}

/// A document as a JSON value, with the `version` field every report carries
/// (so that stored results can be traced to the egt that wrote them).
///
/// # Errors
/// A value serde cannot represent (none of the documents has one).
pub fn value_of(value: &impl Serialize) -> serde_json::Result<serde_json::Value> {
    let mut value = serde_json::to_value(value)?;
    if let serde_json::Value::Object(map) = &mut value {
        map.insert("version".into(), env!("CARGO_PKG_VERSION").into());
    }
    Ok(value)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floats_are_short_and_signed_zero_is_plain() {
        assert_eq!(float(2.0), "2");
        assert_eq!(float(162.0 / 77.0), "2.103896");
        assert_eq!(float(-0.0), "0");
        assert_eq!(float(-1e-9), "-1.000000e-9");
        assert_eq!(float(1e12), "1.000000e12");
    }

    #[test]
    fn sci_keeps_six_digits() {
        assert_eq!(sci(0.0), "0");
        assert_eq!(sci(12.5), "12.5");
        assert_eq!(sci(1.5e-5), "1.500000e-5");
    }
}
