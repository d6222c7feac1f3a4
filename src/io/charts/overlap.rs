//! Series that would hide each other. Two series of the same style whose
//! points fall within a pixel of each other are drawn as one, and its
//! legend row names all of them ("problem 1, admm / apgd / newton (same
//! points)"): otherwise the last one drawn covers the others and a reader
//! takes the missing colours for missing results.

use super::Series;

/// How close two points must be to count as the same, as a fraction of
/// each axis' span (about one pixel of a 500-pixel plot).
const SAME: f64 = 2e-3;

/// The legend's mark of a merged row.
pub const SAME_POINTS: &str = "(same points)";

/// `series` with every group of coinciding series merged into its first
/// member (see the module's doc). `points` are the drawable points of each
/// series; `to_unit` maps a drawable point to [0, 1]² on the plot.
pub fn merge_identical(
    series: &[Series],
    points: &[Vec<(f64, f64)>],
    to_unit: &dyn Fn((f64, f64)) -> (f64, f64),
) -> (Vec<Series>, Vec<Vec<(f64, f64)>>) {
    let unit: Vec<Vec<(f64, f64)>> = points
        .iter()
        .map(|p| p.iter().map(|&q| to_unit(q)).collect())
        .collect();
    let same = |i: usize, j: usize| {
        series[i].style == series[j].style
            && !unit[i].is_empty()
            && unit[i].len() == unit[j].len()
            && unit[i]
                .iter()
                .zip(&unit[j])
                .all(|(a, b)| (a.0 - b.0).abs() <= SAME && (a.1 - b.1).abs() <= SAME)
    };
    let mut taken = vec![false; series.len()];
    let (mut out, mut out_points) = (Vec::new(), Vec::new());
    for i in 0..series.len() {
        if taken[i] {
            continue;
        }
        let group: Vec<usize> = (i..series.len())
            .filter(|&j| !taken[j] && (j == i || same(i, j)))
            .collect();
        for &j in &group {
            taken[j] = true;
        }
        let mut merged = series[i].clone();
        // Its colour stays the one it had by position.
        merged.color = Some(series[i].color.unwrap_or(i));
        if group.len() > 1 {
            let names: Vec<&str> = group.iter().map(|&j| series[j].name.as_str()).collect();
            merged.name = joined(&names);
        }
        out.push(merged);
        out_points.push(points[i].clone());
    }
    (out, out_points)
}

/// The names of merged series in one label: their common beginning (up to
/// a ", " or ": ") and common ending (from a ": ", ", " or " (") written
/// once, the parts that differ joined by " / ".
pub fn joined(names: &[&str]) -> String {
    let first = names[0];
    let prefix_len = first
        .match_indices([',', ':'])
        .map(|(k, _)| k + 1)
        .filter(|&k| {
            names
                .iter()
                .all(|n| n.len() >= k && n.as_bytes()[..k] == first.as_bytes()[..k])
        })
        .max()
        .unwrap_or(0);
    let suffix_start = first
        .match_indices([',', ':', '('])
        .map(|(k, c)| if c == "(" { k.saturating_sub(1) } else { k })
        .filter(|&k| k >= prefix_len && first.is_char_boundary(k))
        .filter(|&k| {
            let tail = &first[k..];
            names
                .iter()
                .all(|n| n.ends_with(tail) && n.len() - tail.len() >= prefix_len)
        })
        .min()
        .unwrap_or(first.len());
    let tail = &first[suffix_start..];
    let middles: Vec<&str> = names
        .iter()
        .map(|n| n[prefix_len..n.len() - tail.len()].trim())
        .collect();
    let head = first[..prefix_len].trim_end();
    let space = if head.is_empty() { "" } else { " " };
    format!("{head}{space}{}{tail} {SAME_POINTS}", grouped(&middles))
}

/// Names joined by " / ", those that all read "group, name" written as
/// "group, a / b; other group, c" (each group once, in order).
fn grouped(middles: &[&str]) -> String {
    let split: Option<Vec<(&str, &str)>> = middles.iter().map(|m| m.split_once(", ")).collect();
    let Some(split) = split else {
        return middles.join(" / ");
    };
    let mut groups: Vec<(&str, Vec<&str>)> = Vec::new();
    for (g, name) in split {
        match groups.iter_mut().find(|(h, _)| *h == g) {
            Some((_, names)) => names.push(name),
            None => groups.push((g, vec![name])),
        }
    }
    groups
        .iter()
        .map(|(g, names)| format!("{g}, {}", names.join(" / ")))
        .collect::<Vec<_>>()
        .join("; ")
}

/// The longest legend line a label is wrapped to, in characters.
const LINE: usize = 46;

/// A legend label in lines of at most about [`LINE`] characters, broken
/// after " / " or "; " (where merged names are joined); later lines are
/// indented. A label without such breaks stays whole, however long.
pub fn lines(label: &str) -> Vec<String> {
    if label.chars().count() <= LINE {
        return vec![label.to_string()];
    }
    let mut pieces: Vec<&str> = Vec::new();
    let mut rest = label;
    while let Some(k) = [" / ", "; "]
        .iter()
        .filter_map(|sep| rest.find(sep).map(|k| k + sep.len()))
        .min()
    {
        pieces.push(&rest[..k]);
        rest = &rest[k..];
    }
    pieces.push(rest);
    let mut out: Vec<String> = vec![String::new()];
    for p in pieces {
        let last = out.last_mut().expect("one line at least");
        if !last.trim().is_empty() && last.chars().count() + p.chars().count() > LINE {
            out.push(format!("  {p}"));
        } else {
            last.push_str(p);
        }
    }
    out.into_iter().map(|l| l.trim_end().to_string()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_share_their_common_parts_once() {
        assert_eq!(
            joined(&["problem 1, admm", "problem 1, apgd", "problem 1, newton"]),
            "problem 1, admm / apgd / newton (same points)"
        );
        assert_eq!(
            joined(&["clarabel: not certified", "clarabel-faer: not certified"]),
            "clarabel / clarabel-faer: not certified (same points)"
        );
        assert_eq!(
            joined(&["clarabel (slope 1.20)", "clarabel-qp (slope 1.20)"]),
            "clarabel / clarabel-qp (slope 1.20) (same points)"
        );
        assert_eq!(joined(&["a", "b"]), "a / b (same points)");
        assert_eq!(
            joined(&[
                "problem 1, admm: not certified",
                "problem 1, apgd: not certified",
                "problem 2, admm: not certified",
            ]),
            "problem 1, admm / apgd; problem 2, admm: not certified (same points)"
        );
    }

    #[test]
    fn long_labels_wrap_where_names_are_joined_and_lose_nothing() {
        let label = joined(&[
            "problem 1, admm",
            "problem 1, apgd",
            "problem 1, clarabel",
            "problem 1, clarabel-condensed",
            "problem 1, clarabel-faer",
            "problem 1, newton",
            "problem 1, relaxation",
        ]);
        let wrapped = lines(&label);
        assert!(wrapped.len() > 1);
        assert!(
            wrapped.iter().all(|l| l.chars().count() <= LINE + 2),
            "{wrapped:?}"
        );
        let back: String = wrapped
            .iter()
            .map(|l| l.trim_start())
            .collect::<Vec<_>>()
            .join(" ");
        assert_eq!(back.replace("/  ", "/ "), label);
        assert_eq!(lines("short"), ["short"]);
    }

    #[test]
    fn only_series_that_coincide_on_the_plot_are_merged() {
        let s = |name: &str, y: f64| Series::line(name, vec![(0.0, 0.0), (1.0, y)]);
        let series = vec![
            s("one", 1.0),
            s("two", 1.0005),
            s("three", 0.9),
            s("four", 1.0),
        ];
        let points: Vec<Vec<(f64, f64)>> = series.iter().map(|s| s.points.clone()).collect();
        let (merged, pts) = merge_identical(&series, &points, &|p| p);
        let names: Vec<&str> = merged.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["one / two / four (same points)", "three"]);
        assert_eq!(pts.len(), 2);
        // A different style is not the same series, even on the same points.
        let series = vec![s("line", 1.0), s("crosses", 1.0).failed()];
        let (merged, _) = merge_identical(&series, &points[..2], &|p| p);
        assert_eq!(merged.len(), 2);
    }
}
