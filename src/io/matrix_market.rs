//! Matrix Market files (NIST's format; what scipy's `mmread`, MATLAB and
//! Julia read and write): `coordinate` (sparse, 1-based triplets) or
//! `array` (dense, column by column), `real`, `double` or `integer`,
//! `general` or `symmetric` (the lower triangle stored).
//!
//! The reader is the guard between a file and an allocation: the sizes a
//! file declares are checked against what the caller expects (an instance's
//! n, a vector of one column) before anything is allocated, the number of
//! entries against the file's length (each needs a few bytes), each index
//! against the declared size and each value for finiteness, and the entries
//! must be exactly as many as declared. A file declaring 1e12 rows is an
//! error that names it, not a failed allocation of 8 TB.

use std::io::BufRead;
use std::path::Path;

use thiserror::Error;

use crate::io::guarded::Lines;

/// A Matrix Market file that cannot be used.
#[derive(Debug, Error, PartialEq)]
#[error("{path}: {reason}")]
pub struct MatrixMarketError {
    pub path: String,
    pub reason: String,
}

/// The fewest bytes a coordinate entry can take (`1 1 0` and a newline).
const MIN_ENTRY_BYTES: u64 = 6;
/// The fewest bytes a dense (array) value can take (`0` and a newline).
const MIN_VALUE_BYTES: u64 = 2;

/// A matrix read from a file: its size and its entries, 0-based, a
/// symmetric file's mirrored entries included, duplicates as they come
/// (to be summed).
#[derive(Clone, Debug, PartialEq)]
pub struct Triplets {
    pub rows: usize,
    pub cols: usize,
    pub entries: Vec<(usize, usize, f64)>,
}

impl Triplets {
    /// Column `j` as a dense vector (duplicates summed).
    pub fn column(&self, j: usize) -> Vec<f64> {
        let mut v = vec![0.0; self.rows];
        for &(i, jj, x) in &self.entries {
            if jj == j {
                v[i] += x;
            }
        }
        v
    }
}

/// The size a caller expects: each dimension exactly, or any.
#[derive(Clone, Copy, Debug)]
pub struct Expect {
    pub rows: Option<usize>,
    pub cols: Option<usize>,
    /// What the file is, for messages: "A (the stiffness)", "--displacements".
    pub what: &'static str,
}

impl Expect {
    fn check(&self, rows: u64, cols: u64) -> Result<(usize, usize), String> {
        let fits = |declared: u64, want: Option<usize>| match want {
            Some(w) => declared == w as u64,
            None => usize::try_from(declared).is_ok(),
        };
        if fits(rows, self.rows) && fits(cols, self.cols) {
            return Ok((rows as usize, cols as usize));
        }
        let shown = |want: Option<usize>| want.map_or("any".to_string(), |w| w.to_string());
        Err(format!(
            "it declares {rows} × {cols}, but {} must be {} × {}",
            self.what,
            shown(self.rows),
            shown(self.cols)
        ))
    }
}

#[derive(Clone, Copy, PartialEq)]
enum Layout {
    Coordinate,
    Array,
}

/// Reads a Matrix Market file at `path`.
pub fn read(path: &Path, expect: Expect) -> Result<Triplets, MatrixMarketError> {
    let error = |reason: String| MatrixMarketError {
        path: path.display().to_string(),
        reason,
    };
    let (lines, len) = Lines::open(path).map_err(error)?;
    parse(lines, len, expect).map_err(error)
}

/// Parses Matrix Market text from `lines` of a file of `len` bytes.
pub fn parse<R: BufRead>(
    mut lines: Lines<R>,
    len: u64,
    expect: Expect,
) -> Result<Triplets, String> {
    let banner = lines
        .next_line()?
        .ok_or("it is empty; give a Matrix Market file")?
        .to_string();
    let (layout, symmetric) = parse_banner(&banner)?;
    // The size line: the first that is neither a comment nor blank.
    let size = loop {
        match lines.next_line()? {
            None => return Err("it ends before its size line".into()),
            Some(l) if l.trim().is_empty() || l.starts_with('%') => continue,
            Some(l) => break l.to_string(),
        }
    };
    let numbers: Vec<u64> = size
        .split_whitespace()
        .map(|t| t.parse::<u64>())
        .collect::<Result<_, _>>()
        .map_err(|_| {
            format!(
                "line {}: the size line '{size}' is not whole numbers",
                lines.number()
            )
        })?;
    let wanted = if layout == Layout::Coordinate { 3 } else { 2 };
    if numbers.len() != wanted {
        return Err(format!(
            "line {}: the size line must hold {} numbers, it holds '{size}'",
            lines.number(),
            if wanted == 3 {
                "rows, columns and entries: three"
            } else {
                "rows and columns: two"
            }
        ));
    }
    let (rows, cols) = expect.check(numbers[0], numbers[1])?;
    if symmetric && rows != cols {
        return Err(format!("it is marked symmetric but is {rows} × {cols}"));
    }
    let (declared, min_bytes) = match layout {
        Layout::Coordinate => (numbers[2], MIN_ENTRY_BYTES),
        Layout::Array => {
            let count = if symmetric {
                (rows as u64).checked_mul(rows as u64 + 1).map(|x| x / 2)
            } else {
                (rows as u64).checked_mul(cols as u64)
            };
            (count.unwrap_or(u64::MAX), MIN_VALUE_BYTES)
        }
    };
    if declared > len / min_bytes {
        return Err(format!(
            "it declares {declared} entries, more than its {len} bytes can hold; the file is truncated or its size line is wrong"
        ));
    }
    let mut entries =
        Vec::with_capacity((declared as usize).saturating_mul(if symmetric { 2 } else { 1 }));
    let mut seen: u64 = 0;
    while let Some((number, line)) = lines.next_numbered()? {
        if line.trim().is_empty() || line.starts_with('%') {
            continue;
        }
        if seen == declared {
            return Err(format!(
                "line {number}: more entries than the {declared} its size line declares"
            ));
        }
        let mut tokens = line.split_whitespace();
        let (i, j) = match layout {
            Layout::Coordinate => {
                let mut index = |name: &str, bound: usize| -> Result<usize, String> {
                    let t = tokens
                        .next()
                        .ok_or_else(|| format!("line {number}: no {name} index"))?;
                    match t.parse::<u64>() {
                        Ok(k) if k >= 1 && k <= bound as u64 => Ok(k as usize - 1),
                        _ => Err(format!(
                            "line {number}: {name} index '{t}' is not in 1..={bound}"
                        )),
                    }
                };
                (index("row", rows)?, index("column", cols)?)
            }
            Layout::Array => array_position(seen, rows, symmetric),
        };
        let t = tokens
            .next()
            .ok_or_else(|| format!("line {number}: no value"))?;
        let x = t
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| format!("line {number}: value '{t}' is not a finite number"))?;
        if tokens.next().is_some() {
            return Err(format!(
                "line {number}: '{line}' holds more than {}",
                if layout == Layout::Coordinate {
                    "row, column and value"
                } else {
                    "one value"
                }
            ));
        }
        if symmetric && j > i {
            return Err(format!(
                "line {number}: entry ({}, {}) lies above the diagonal of a symmetric file, which stores the lower triangle",
                i + 1,
                j + 1
            ));
        }
        entries.push((i, j, x));
        if symmetric && i != j {
            entries.push((j, i, x));
        }
        seen += 1;
    }
    if seen != declared {
        return Err(format!(
            "it holds {seen} entries, but its size line declares {declared}"
        ));
    }
    Ok(Triplets {
        rows,
        cols,
        entries,
    })
}

/// The storage layout and symmetry of a banner such as
/// `%%MatrixMarket matrix coordinate real general` (case-insensitive, as
/// other readers take it).
fn parse_banner(banner: &str) -> Result<(Layout, bool), String> {
    let words: Vec<String> = banner.split_whitespace().map(str::to_lowercase).collect();
    let words: Vec<&str> = words.iter().map(String::as_str).collect();
    let hint =
        "the first line must be a banner such as '%%MatrixMarket matrix coordinate real general'";
    match words.as_slice() {
        ["%%matrixmarket", "matrix", layout, field, symmetry] => {
            let layout = match *layout {
                "coordinate" => Layout::Coordinate,
                "array" => Layout::Array,
                other => return Err(format!("layout '{other}' is not coordinate or array")),
            };
            if !matches!(*field, "real" | "double" | "integer") {
                return Err(format!(
                    "field '{field}' is not real, double or integer: the values must be real numbers"
                ));
            }
            let symmetric = match *symmetry {
                "general" => false,
                "symmetric" => true,
                other => {
                    return Err(format!("symmetry '{other}' is not general or symmetric"));
                }
            };
            Ok((layout, symmetric))
        }
        _ => Err(format!("{hint}, not '{}'", shorten(banner))),
    }
}

/// The (row, column) of the k-th value of a dense file: column by column,
/// the lower triangle only when symmetric.
fn array_position(k: u64, rows: usize, symmetric: bool) -> (usize, usize) {
    if !symmetric {
        return ((k % rows as u64) as usize, (k / rows as u64) as usize);
    }
    let (mut j, mut k) = (0usize, k as usize);
    while k >= rows - j {
        k -= rows - j;
        j += 1;
    }
    (j + k, j)
}

/// At most 60 characters of a line, for a message.
fn shorten(line: &str) -> String {
    let mut s: String = line.chars().take(60).collect();
    if s.len() < line.len() {
        s.push('…');
    }
    s.chars().filter(|c| !c.is_control()).collect()
}

/// Matrix Market text of `entries` (0-based (row, column, value)) in
/// coordinate layout: `symmetric` writes the banner so and only the entries
/// on and below the diagonal (the caller gives a symmetric matrix). Values
/// in shortest round-trip decimal, so a reader gets the same doubles.
pub fn write_coordinate(
    rows: usize,
    cols: usize,
    entries: impl Iterator<Item = (usize, usize, f64)> + Clone,
    symmetric: bool,
) -> String {
    use std::fmt::Write;
    let kept = entries.filter(|&(i, j, _)| !symmetric || j <= i);
    let count = kept.clone().count();
    let mut text = format!(
        "%%MatrixMarket matrix coordinate real {}\n{rows} {cols} {count}\n",
        if symmetric { "symmetric" } else { "general" }
    );
    for (i, j, x) in kept {
        let _ = writeln!(text, "{} {} {x:e}", i + 1, j + 1);
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read_text(text: &str, expect: Expect) -> Result<Triplets, String> {
        parse(Lines::new(text.as_bytes()), text.len() as u64, expect)
    }

    const ANY: Expect = Expect {
        rows: None,
        cols: None,
        what: "the matrix",
    };

    #[test]
    fn general_symmetric_and_array_files_read_as_their_matrix() {
        let g = read_text(
            "%%MatrixMarket matrix coordinate real general\n% c\n2 2 3\n1 1 2.5\n2 1 -1\n1 2 -1\n",
            ANY,
        )
        .unwrap();
        assert_eq!(g.entries, [(0, 0, 2.5), (1, 0, -1.0), (0, 1, -1.0)]);
        let s = read_text(
            "%%matrixmarket matrix coordinate real symmetric\n2 2 2\n1 1 2.5\n2 1 -1\n",
            ANY,
        )
        .unwrap();
        assert_eq!(s.entries, [(0, 0, 2.5), (1, 0, -1.0), (0, 1, -1.0)]);
        let a = read_text(
            "%%MatrixMarket matrix array real general\n2 2\n1\n2\n3\n4\n",
            ANY,
        )
        .unwrap();
        assert_eq!(
            a.entries,
            [(0, 0, 1.0), (1, 0, 2.0), (0, 1, 3.0), (1, 1, 4.0)]
        );
        let a = read_text(
            "%%MatrixMarket matrix array real symmetric\n2 2\n1\n2\n4\n",
            ANY,
        )
        .unwrap();
        assert_eq!(
            a.entries,
            [(0, 0, 1.0), (1, 0, 2.0), (0, 1, 2.0), (1, 1, 4.0)]
        );
        assert_eq!(a.column(1), [2.0, 4.0]);
    }

    #[test]
    fn what_a_file_declares_is_checked_before_it_is_believed() {
        let vector = Expect {
            rows: Some(3),
            cols: Some(1),
            what: "--displacements",
        };
        let bad = |text: &str, expect: Expect, says: &str| {
            let e = read_text(text, expect).unwrap_err();
            assert!(e.contains(says), "{text:?}: {e}");
        };
        let banner = "%%MatrixMarket matrix coordinate real general\n";
        bad(
            &format!("{banner}1000000000000 1 1\n1 1 1\n"),
            vector,
            "must be 3 × 1",
        );
        bad(&format!("{banner}3 2 1\n1 1 1\n"), vector, "must be 3 × 1");
        bad(
            &format!("{banner}3 1 100000000\n1 1 1\n"),
            ANY,
            "more than its",
        );
        bad(&format!("{banner}3 1 2\n1 1 1\n"), ANY, "holds 1 entries");
        bad(
            &format!("{banner}3 1 1\n1 1 1\n2 1 1\n"),
            ANY,
            "more entries",
        );
        bad(&format!("{banner}3 1 1\n4 1 1\n"), ANY, "row index '4'");
        bad(&format!("{banner}3 1 1\n0 1 1\n"), ANY, "row index '0'");
        bad(&format!("{banner}3 1 1\n1 1 nan\n"), ANY, "finite");
        bad(&format!("{banner}3 1 1\n1 1 1e400\n"), ANY, "finite");
        bad(&format!("{banner}3 1 1\n1 1 1 7\n"), ANY, "more than");
        bad(&format!("{banner}3 1\n"), ANY, "three");
        bad(&format!("{banner}-3 1 1\n"), ANY, "whole numbers");
        bad(
            "%%MatrixMarket matrix coordinate complex general\n1 1 1\n1 1 1 0\n",
            ANY,
            "complex",
        );
        bad(
            "%%MatrixMarket matrix coordinate pattern general\n1 1 1\n1 1\n",
            ANY,
            "pattern",
        );
        bad("hello\n", ANY, "banner");
        bad("", ANY, "empty");
        bad(
            "%%MatrixMarket matrix coordinate real symmetric\n2 2 1\n1 2 1\n",
            ANY,
            "above the diagonal",
        );
        bad(
            "%%MatrixMarket matrix array real general\n100000 100000\n1\n",
            ANY,
            "more than its",
        );
    }

    #[test]
    fn what_is_written_reads_back_bit_for_bit() {
        let entries = vec![
            (0, 0, 0.1 + 0.2),
            (1, 0, -1e-300),
            (0, 1, -1e-300),
            (1, 1, 7.0),
        ];
        for symmetric in [false, true] {
            let text = write_coordinate(2, 2, entries.iter().copied(), symmetric);
            assert!(text.starts_with("%%MatrixMarket matrix coordinate real"));
            let back = read_text(&text, ANY).unwrap();
            let mut got = back.entries.clone();
            got.sort_by_key(|e| (e.1, e.0));
            assert_eq!(got, entries);
        }
    }
}
