//! `compare --side-by-side`: two answers node by node, in the problem's
//! scales, against a solver, the reference or an imported profile.

mod common;

use std::path::Path;

use common::{contactlab, one_line_error, run_with_deadline, solve_into};

fn rows(path: &Path) -> Vec<csv::StringRecord> {
    let mut r = csv::Reader::from_path(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    r.records().map(|x| x.unwrap()).collect()
}

fn header(path: &Path) -> Vec<String> {
    let mut r = csv::Reader::from_path(path).unwrap();
    r.headers().unwrap().iter().map(String::from).collect()
}

fn column(path: &Path, name: &str) -> Vec<String> {
    let j = header(path)
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name} in {}", path.display()));
    rows(path).iter().map(|r| r[j].to_string()).collect()
}

fn floats(path: &Path, name: &str) -> Vec<f64> {
    column(path, name)
        .iter()
        .map(|v| v.parse().unwrap())
        .collect()
}

/// The same deterministic solver read back from its own profile differs
/// from itself only by the profile's ten significant digits (a mispaired
/// column or node would show at the size of the answer); the
/// paper's method against the reference differs by its own accuracy, and
/// each difference is the two columns' difference over the scale: U for
/// displacements, P = N/L = 20 for the pressures of problem 1 (load 20 on
/// Γ_K of length 1).
#[test]
fn pairs_are_compared_node_by_node_in_the_problems_scales() {
    let dir = tempfile::tempdir().unwrap();
    let own = dir.path().join("own");
    let o = run_with_deadline(solve_into("1/16", "newton-coulomb", &own), 60);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = dir.path().join("sbs");
    let mut cmd = contactlab();
    cmd.args(["compare", "--problem", "1", "--h", "1/16", "--side-by-side"])
        .arg(format!(
            "newton-coulomb,{}",
            own.join("profile.csv").display()
        ))
        .args(["--side-by-side", "relaxation,reference", "--out"])
        .arg(&out);
    let o = run_with_deadline(cmd, 120);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let same = out.join("side_by_side_newton-coulomb_own_profile_csv.csv");
    for c in [
        "du_over_u",
        "djump_over_u",
        "dslip_over_u",
        "dp_over_p",
        "dq_over_p",
    ] {
        let d = floats(&same, c);
        assert!(d.iter().all(|&d| d < 1e-8), "{c}: {d:?}");
    }
    assert!(column(&same, "states_match").iter().all(|s| s == "true"));
    assert_eq!(rows(&same).len(), 17, "17 contact nodes at h = 1/16");

    let summary = out.join("side_by_side.csv");
    let p = floats(&summary, "scale_p");
    assert!(p.iter().all(|&p| (p - 20.0).abs() < 1e-9), "{p:?}");
    assert_eq!(column(&summary, "b")[1], "reference (newton-coulomb)");

    let versus = out.join("side_by_side_relaxation_reference.csv");
    let (pa, pb, dp) = (
        floats(&versus, "pressure_a"),
        floats(&versus, "pressure_b"),
        floats(&versus, "dp_over_p"),
    );
    // The columns carry ten significant digits.
    for k in 0..pa.len() {
        let digits = 1e-9 * (pa[k].abs() + pb[k].abs()) / 20.0;
        assert!(((pa[k] - pb[k]).abs() / 20.0 - dp[k]).abs() <= digits + 1e-300);
    }
    let largest = dp.iter().fold(0.0f64, |m, &d| m.max(d));
    // Certified at 1e-5, the paper's method is close, but not equal.
    assert!(largest > 0.0 && largest < 1e-4, "{largest}");
    assert_eq!(floats(&summary, "max_dp_over_p")[1], largest);
    for chart in ["overlay", "difference"] {
        assert!(
            out.join(format!(
                "charts/side_by_side_relaxation_reference_{chart}.svg"
            ))
            .is_file()
        );
    }
}

/// A pair that is not two answers, a file that is not there and a profile
/// of another mesh are refused in one line each.
#[test]
fn a_bad_pair_is_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let coarse = dir.path().join("coarse");
    let o = run_with_deadline(solve_into("1/8", "newton-coulomb", &coarse), 60);
    assert!(o.status.success());
    let run = |pair: String| {
        let mut cmd = contactlab();
        cmd.args([
            "compare",
            "--problem",
            "1",
            "--h",
            "1/16",
            "--side-by-side",
            &pair,
        ]);
        run_with_deadline(cmd, 60)
    };
    one_line_error(&run("relaxation".into()), "one side", "two answers, `A,B`");
    one_line_error(
        &run("relaxation,missing.csv".into()),
        "missing file",
        "`missing.csv` is neither `reference`, a solver",
    );
    one_line_error(
        &run(format!(
            "newton-coulomb,{}",
            coarse.join("profile.csv").display()
        )),
        "another mesh",
        "not the same mesh",
    );
}
