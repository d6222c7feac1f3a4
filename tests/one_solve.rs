//! One solve, one outcome: `solve`'s summary and a study's trial are views
//! of the same record, so they report the same iterations, times and
//! separation, for a fixed point (the paper's method, by continuation) and
//! for a direct solver of the Coulomb problem. `solve --out` once wrote
//! `"iterations_outer": 0, "seconds_setup": -0.0` after 13 Newton steps,
//! because its summary read a fixed point's history that a direct solve
//! leaves empty.

mod common;

use contactlab::mechanics::mesh_size::MeshSize;
use contactlab::mechanics::scene::Scene;
use contactlab::settings::Settings;
use contactlab::solve::summary::{Summary, answer_bound};
use contactlab::solve::{Assembled, Caps, level_for, solve, solve_scene, solver_entry};
use contactlab::solvers::{Friction, Law, Silent};
use contactlab::study::runner::trial_row;
use contactlab::study::trial::TrialSpec;

use std::sync::Arc;

fn scene(k: u32) -> Scene {
    Scene::paper_problem_to(1, MeshSize::from_level(k).unwrap()).unwrap()
}

#[test]
fn the_summary_and_the_trial_of_one_solve_agree() {
    let settings = Settings::default();
    for (name, fixed_point) in [("relaxation", true), ("newton-coulomb", false)] {
        let entry = solver_entry(name).unwrap();
        let scene = scene(4);
        let solved = solve_scene(&scene, Friction::Coulomb, entry, &settings, &mut Silent).unwrap();
        let o = &solved.outcome;
        assert!(o.status.is_converged(), "{name}: {}", o.detail);
        let bound = answer_bound(&solved, &settings.certificate);
        let summary = Summary::of(&solved, &scene, &settings, bound, "test".into());
        let spec = TrialSpec::new("test", "test", &scene, entry, Law::Coulomb, &settings);
        let trial = trial_row(&spec, None, &solved.finest, o);
        assert_eq!(summary.iterations_outer, trial.outer_iterations, "{name}");
        assert_eq!(summary.iterations_inner, trial.inner_iterations, "{name}");
        assert_eq!(
            summary.friction_iterations, trial.friction_iterations,
            "{name}"
        );
        assert_eq!(summary.status, trial.status, "{name}");
        assert_eq!(summary.solver_status, trial.solver_status, "{name}");
        assert_eq!(summary.certificate.residual(), trial.residual(), "{name}");
        assert_eq!(
            summary.separated_fraction, trial.separated_fraction,
            "{name}"
        );
        assert_eq!(summary.separated_intervals, trial.separated, "{name}");
        // The error bound: one computation, the same in both views.
        assert!(summary.error_bound.bound.is_some(), "{name}");
        assert_eq!(Some(&summary.error_bound), trial.bound.as_ref(), "{name}");
        // Times: one record, the set-up apart and inside the whole.
        assert_eq!(summary.seconds, o.timing.total(), "{name}");
        assert_eq!(summary.seconds_setup, o.timing.setup, "{name}");
        assert!(
            summary.seconds_setup > 0.0 && summary.seconds_setup <= summary.seconds,
            "{name}: set-up {} of {}",
            summary.seconds_setup,
            summary.seconds
        );
        // The work is counted, whoever counts it.
        assert!(summary.iterations_outer > 0, "{name}");
        assert_eq!(summary.friction_iterations > 0, fixed_point, "{name}");
        assert_eq!(trial.work, o.work.events, "{name}");
        assert!(o.work.events > 0, "{name}: no work events counted");
    }
}

/// Through the command line: `solve --out` and `compare --out` of the same
/// problem give the same counts and zone for each solver (times differ
/// between runs; their definitions are tested above).
#[test]
fn solve_and_compare_report_the_same_counts_and_zone() {
    let dir = tempfile::tempdir().unwrap();
    let out = |name: &str| dir.path().join(name);
    let run = |args: &[&str]| {
        let o = common::contactlab().args(args).output().unwrap();
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    };
    let compare = out("compare");
    run(&[
        "compare",
        "--problem",
        "1",
        "--h",
        "1/16",
        "--solvers",
        "relaxation,newton-coulomb",
        "--runs",
        "0",
        "--out",
        compare.to_str().unwrap(),
    ]);
    let rows: Vec<csv::StringRecord> = csv::Reader::from_path(compare.join("compare.csv"))
        .unwrap()
        .records()
        .map(|r| r.unwrap())
        .collect();
    let header: Vec<String> = csv::Reader::from_path(compare.join("compare.csv"))
        .unwrap()
        .headers()
        .unwrap()
        .iter()
        .map(String::from)
        .collect();
    let col = |row: &csv::StringRecord, name: &str| -> String {
        row[header.iter().position(|h| h == name).unwrap()].to_string()
    };
    for name in ["relaxation", "newton-coulomb"] {
        let target = out(name);
        run(&[
            "solve",
            "--problem",
            "1",
            "--h",
            "1/16",
            "--solver",
            name,
            "--out",
            target.to_str().unwrap(),
        ]);
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(target.join("summary.json")).unwrap())
                .unwrap();
        let row = rows
            .iter()
            .find(|r| col(r, "solver") == name && col(r, "law") == "coulomb")
            .unwrap();
        for (key, column) in [
            ("iterations_outer", "outer_iterations"),
            ("iterations_inner", "inner_iterations"),
            ("friction_iterations", "friction_iterations"),
        ] {
            assert_eq!(
                summary[key].as_u64().unwrap().to_string(),
                col(row, column),
                "{name}: {key}"
            );
        }
        assert_eq!(
            summary["status"].as_str().unwrap(),
            col(row, "status"),
            "{name}"
        );
        let fraction: f64 = col(row, "separated_fraction").parse().unwrap();
        assert!(
            (summary["separated_fraction"].as_f64().unwrap() - fraction).abs() < 1e-9,
            "{name}"
        );
    }
}

/// A finest level lent to the solve (the Python package's problem keeps
/// it) is the one solved and certified, not a copy: the solve gives the
/// same level back, and once its answer is dropped the lender holds the
/// only reference again. The answer is, to the bit, that of a solve that
/// assembles its own levels. A copy (the package's solve cloned the level,
/// 6.7 GB at h = 1/8192) fails the first assertion; a level kept by the
/// solve, the last.
#[test]
fn a_lent_finest_level_is_solved_where_it_is() {
    let scene = scene(5);
    let entry = solver_entry("tnnmg").unwrap();
    let settings = Settings::default();
    let finest = Arc::new(level_for(&scene, scene.finest(), entry).unwrap());
    let problem = Assembled::lending(&scene, entry, finest.clone()).unwrap();
    let lent = solve(
        problem,
        Friction::Coulomb,
        entry,
        &settings,
        Caps::default(),
        &mut Silent,
    )
    .unwrap();
    assert!(
        Arc::ptr_eq(&lent.finest, &finest),
        "the lent level, not a copy"
    );
    assert!(
        lent.outcome.status.is_converged(),
        "{}",
        lent.outcome.detail
    );
    let own = solve_scene(&scene, Friction::Coulomb, entry, &settings, &mut Silent).unwrap();
    assert_eq!(lent.outcome.solution.v, own.outcome.solution.v);
    assert_eq!(
        lent.outcome.solution.pressure,
        own.outcome.solution.pressure
    );
    drop(lent);
    assert_eq!(Arc::strong_count(&finest), 1, "the solve kept no reference");
}

/// `solve --time-limit`: the paper's method (about 11 s at 1/64 on one
/// core) stopped at 0.5 s ends with the status `time_limit`, its answer
/// certified and written whole, and a
/// non-zero exit whose one line names the limit.
#[test]
fn a_solve_past_its_time_limit_stops_with_a_status_and_its_files() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("limited");
    let mut cmd = common::solve_into("1/64", "relaxation", &out);
    cmd.args(["--time-limit", "0.5"]);
    let o = common::run_with_deadline(cmd, 120);
    assert!(!o.status.success(), "a stopped solve is not a success");
    let stderr = String::from_utf8_lossy(&o.stderr);
    let last = stderr.lines().last().unwrap_or_default();
    assert!(
        last.contains("--time-limit 0.5 s") && last.contains("time_limit"),
        "{stderr}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"].as_str(), Some("time_limit"), "{summary}");
    for file in ["profile.csv", "displacements.mtx", "forces.csv"] {
        assert!(out.join(file).is_file(), "{file} not written");
    }
}
