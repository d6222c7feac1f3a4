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

thread_local! {
    /// Whether rows are being serialized as typed records ([`records`])
    /// rather than as CSV text: [`fixed`] then gives the number itself.
    static TYPED: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// serde `serialize_with` for an f64 field: the fixed format in a CSV
/// file; the number itself (none if not finite) in [`records`].
pub fn fixed<S: Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
    if TYPED.get() {
        return match x.is_finite() {
            true => s.serialize_f64(*x),
            false => s.serialize_none(),
        };
    }
    s.serialize_str(&format_fixed(*x))
}

/// serde `serialize_with` for an `Option<f64>` field (empty when none).
pub fn fixed_opt<S: Serializer>(x: &Option<f64>, s: S) -> Result<S::Ok, S::Error> {
    match x {
        Some(x) => fixed(x, s),
        None if TYPED.get() => s.serialize_none(),
        None => s.serialize_str(""),
    }
}

/// serde `serialize_with` for a setting's value (`1e-4`, `multigrid`):
/// its text in a CSV file; in [`records`] the number when it is one (a
/// finite f64, as the settings read it), none when empty, else the text.
pub fn setting_value<S: Serializer>(v: &str, s: S) -> Result<S::Ok, S::Error> {
    if TYPED.get() {
        if v.is_empty() {
            return s.serialize_none();
        }
        if let Ok(x) = v.trim().parse::<f64>()
            && x.is_finite()
        {
            return s.serialize_f64(x);
        }
    }
    s.serialize_str(v)
}

/// Rows as typed records, the values a CSV file of them holds as text:
/// a JSON array of one object per row, its keys in the file's column
/// order, numbers as numbers (a non-finite one, an empty field in the
/// file, as null), so that Python gets the data without parsing the file
/// back.
pub fn records<T: Serialize + ?Sized>(rows: &T) -> Result<String> {
    Ok(typed(|| serde_json::to_string(rows))?)
}

/// `f()` with rows serialized as typed values: [`fixed`] and its kin give
/// the number itself (none if not finite), not the CSV text. For
/// [`records`] and for the facts a README template reads.
pub fn typed<R>(f: impl FnOnce() -> R) -> R {
    struct Reset(bool);
    impl Drop for Reset {
        fn drop(&mut self) {
            TYPED.set(self.0);
        }
    }
    let _reset = Reset(TYPED.replace(true));
    f()
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
