//! `reproduce --quick`: every file, the documented headers, accuracy figures
//! against a committed reference, valid charts; sweeps keep failed runs.

use std::path::Path;
use std::process::Command;

use contactlab::mechanics::contact_zone::PROFILE_COLUMNS;
use contactlab::mechanics::mesh_size::MeshSize;
use contactlab::settings::Settings;
use contactlab::study::compare::COMPARE_COLUMNS;
use contactlab::study::reproduce::FILES;
use contactlab::study::sweep::{Factor, SWEEP_COLUMNS, SWEEP_TIMING_COLUMNS, SweepSpec, sweep};

/// The committed reference: `compare.csv` of `reproduce --quick`.
const REFERENCE: &str = include_str!("reference/quick_compare.csv");

/// Figures are deterministic on one machine; across machines floating-point
/// library functions may differ in the last bits, and a stopping test may
/// then flip by one iteration. So: statuses exactly, iteration counts within
/// 2%, floats within 1e-3 relative (or 1e-10 absolute).
fn float_close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-3 * a.abs().max(b.abs()) || (a - b).abs() <= 1e-10
}

fn header(path: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    text.lines()
        .next()
        .unwrap_or_default()
        .split(',')
        .map(String::from)
        .collect()
}

fn svg_texts(path: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap();
    let doc = roxmltree::Document::parse(&text)
        .unwrap_or_else(|e| panic!("{} is not valid XML: {e}", path.display()));
    assert_eq!(doc.root_element().tag_name().name(), "svg");
    doc.descendants()
        .filter(|n| n.tag_name().name() == "text")
        .filter_map(|n| n.text().map(|t| t.to_string()))
        .collect()
}

#[test]
fn reproduce_quick_writes_every_file_and_matches_the_reference() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("results");
    let o = Command::new(env!("CARGO_BIN_EXE_contactlab"))
        .args(["reproduce", "--quick", "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in FILES {
        assert!(out.join(f).is_file(), "missing {f}");
    }
    for p in [1, 2, 3] {
        for solver in contactlab::solvers::registry::names() {
            for kind in ["friction", "frictionless"] {
                let path = out.join(format!("profiles/p{p}_{solver}_{kind}.csv"));
                assert_eq!(header(&path), PROFILE_COLUMNS, "{}", path.display());
            }
        }
    }
    assert_eq!(header(&out.join("compare.csv")), COMPARE_COLUMNS);
    assert_eq!(header(&out.join("sweep.csv")), SWEEP_COLUMNS);
    assert_eq!(header(&out.join("sweep_timing.csv")), SWEEP_TIMING_COLUMNS);
    assert_eq!(
        header(&out.join("table1.csv"))[..5],
        ["problem", "schedule", "status", "mpp", "mu"]
    );
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("manifest.json")).unwrap()).unwrap();
    for key in [
        "git_commit",
        "git_dirty",
        "rustc",
        "cpu",
        "cores",
        "date",
        "settings",
    ] {
        assert!(manifest.get(key).is_some(), "manifest lacks {key}");
    }
    // Accuracy figures against the committed reference, row by row.
    let got = std::fs::read_to_string(out.join("compare.csv")).unwrap();
    let rows = |text: &str| -> Vec<Vec<String>> {
        text.lines()
            .skip(1)
            .map(|l| l.split(',').map(String::from).collect())
            .collect()
    };
    let (reference, got) = (rows(REFERENCE), rows(&got));
    assert!(!reference.is_empty());
    for want in &reference {
        let key = &want[..4];
        let have = got
            .iter()
            .find(|g| &g[..4] == key)
            .unwrap_or_else(|| panic!("no row for {key:?}"));
        for (i, column) in COMPARE_COLUMNS.iter().enumerate() {
            let (a, b) = (&have[i], &want[i]);
            match (a.parse::<f64>(), b.parse::<f64>()) {
                _ if column.ends_with("iterations") => {
                    let (a, b): (f64, f64) = (a.parse().unwrap(), b.parse().unwrap());
                    assert!(
                        (a - b).abs() <= 0.02 * b.max(1.0),
                        "{key:?} {column}: {a} vs reference {b}"
                    );
                }
                (Ok(x), Ok(y)) => {
                    assert!(float_close(x, y), "{key:?} {column}: {x} vs reference {y}")
                }
                _ if *column == "separated" => {
                    // Interval ends within 1e-3.
                    let nums = |s: &str| -> Vec<f64> {
                        s.split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-' || c == 'e'))
                            .filter_map(|t| t.parse().ok())
                            .collect()
                    };
                    let (x, y) = (nums(a), nums(b));
                    assert_eq!(x.len(), y.len(), "{key:?} separated: {a} vs {b}");
                    assert!(
                        x.iter().zip(&y).all(|(p, q)| (p - q).abs() < 1e-3),
                        "{key:?} separated: {a} vs {b}"
                    );
                }
                _ => assert_eq!(a, b, "{key:?} {column}"),
            }
        }
    }
    // Charts: valid SVG, title, axis labels, one series per solver.
    let charts = out.join("charts");
    let solvers = contactlab::solvers::registry::names();
    let mut seen = 0;
    for entry in std::fs::read_dir(&charts).unwrap() {
        let path = entry.unwrap().path();
        let texts = svg_texts(&path);
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        let has = |t: &str| texts.iter().any(|x| x.contains(t));
        assert!(texts.len() >= 4, "{name}: too little text");
        let (title, x, y, per_solver) = if name.starts_with("work_precision") {
            (
                "Work-precision",
                "max pressure error",
                "solver time [s]",
                true,
            )
        } else if name.starts_with("profile_") {
            ("problem", "x along Γ_K", "[", true)
        } else if name.starts_with("convergence") {
            ("Convergence histories", "iteration", "residual", true)
        } else if name.starts_with("sweep_") {
            ("problem 1", "", "", false)
        } else if name.starts_with("performance_") {
            ("time against unknowns", "unknowns", "median time [s]", true)
        } else if name == "stability_friction" {
            (
                "Coulomb fixed point",
                "friction coefficient",
                "contraction",
                false,
            )
        } else if name.starts_with("stability_") {
            ("Stability", "", "", false)
        } else {
            panic!("unexpected chart {name}");
        };
        assert!(
            has(title) && has(x) && has(y),
            "{name}: title or axis label missing in {texts:?}"
        );
        if per_solver {
            for s in &solvers {
                assert!(has(s), "{name}: no series for {s}");
            }
        }
        seen += 1;
    }
    assert!(seen >= 12 + 3 + 1 + 4 + 6 + 2, "only {seen} charts");
    assert_eq!(
        header(&out.join("performance.csv")),
        contactlab::study::bench::PERFORMANCE_COLUMNS
    );
}

#[test]
fn sweep_rows_that_do_not_converge_are_marked_not_dropped() {
    let spec = SweepSpec {
        meshes: vec![MeshSize::from_level(3).unwrap()],
        factors: vec![Factor::R, Factor::Epsilon],
        // Relative values: r in units of K/L, ε of P.
        r_values: vec![1e-8, 1e7],
        epsilon_values: vec![1e-6, 1e-15],
        time_limit: 0.5,
        repeats: 0,
        ..SweepSpec::default()
    };
    let (rows, references) = sweep(&spec, &Settings::default(), &|_| {}).unwrap();
    // The reference is the exact solver, and the oracle agrees with it to its own accuracy.
    assert_eq!(references[0].solver, "newton");
    assert!(references[0].oracle_pressure_error < 1e-6, "{references:?}");
    assert_eq!(rows.len(), 4, "one row per planned run");
    let row = |factor: &str, value: &str| {
        rows.iter()
            .find(|r| r.factor == factor && r.value == value)
            .unwrap()
    };
    for (factor, value) in [("r", "1e-8"), ("epsilon", "1e-15")] {
        let r = row(factor, value);
        assert!(
            !r.converged && r.status != "converged",
            "{factor} = {value}: {}",
            r.status
        );
    }
    for (factor, value) in [("r", "1e7"), ("epsilon", "1e-6")] {
        assert!(row(factor, value).converged);
    }
}
