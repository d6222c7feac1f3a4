//! CSV from serde rows: a header from the row type's fields, floats in the
//! fixed format of accuracy files (10 significant digits, so that reruns
//! compare byte for byte and a last-bit difference between machines does
//! not show), non-finite values as empty fields, never as NaN.

use anyhow::Result;
use serde::{Serialize, Serializer};

/// A float in the fixed format (empty if not finite).
pub fn format_fixed(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.9e}")
    } else {
        String::new()
    }
}

/// serde `serialize_with` for an f64 field.
pub fn fixed<S: Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(&format_fixed(*x))
}

/// serde `serialize_with` for an `Option<f64>` field (empty when none).
pub fn fixed_opt<S: Serializer>(x: &Option<f64>, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(&x.map(format_fixed).unwrap_or_default())
}

/// Rows as CSV bytes (header from the first row's fields; a header alone
/// from `header` when there are no rows).
/// Reads what [`fixed`] writes: a number, or an empty field (not finite)
/// as NaN.
pub fn fixed_or_nan<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    let text = <String as serde::Deserialize>::deserialize(d)?;
    if text.trim().is_empty() {
        return Ok(f64::NAN);
    }
    text.trim().parse().map_err(serde::de::Error::custom)
}

pub fn to_csv<T: Serialize>(rows: &[T], header: &[&str]) -> Result<Vec<u8>> {
    let mut w = csv::Writer::from_writer(Vec::new());
    if rows.is_empty() {
        w.write_record(header)?;
    }
    for r in rows {
        w.serialize(r)?;
    }
    w.into_inner().map_err(|e| anyhow::anyhow!("csv: {e}"))
}

/// The field names of a row type, in order (for documentation and tests).
pub fn header_of<T: Serialize>(row: &T) -> Result<Vec<String>> {
    let bytes = to_csv(std::slice::from_ref(row), &[])?;
    let text = String::from_utf8(bytes)?;
    Ok(text
        .lines()
        .next()
        .unwrap_or_default()
        .split(',')
        .map(String::from)
        .collect())
}
