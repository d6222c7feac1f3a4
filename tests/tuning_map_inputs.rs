//! `sweep --grid`: every input of a tuning map is checked before any work
//! (issue 73): one setting twice, one value in two spellings, an axis the
//! solver does not read, a grid too large to read, a law the solver cannot
//! be run at; the README's own map (the relaxation at the default Coulomb
//! law, by the friction fixed point) runs; two problems in one run write
//! two maps.

mod common;

use common::{contactlab, one_line_error, run_with_deadline};

fn sweep(args: &[&str], out: &std::path::Path) -> std::process::Output {
    let mut cmd = contactlab();
    cmd.arg("sweep").args(args).arg("--out").arg(out);
    run_with_deadline(cmd, 120)
}

#[test]
fn a_map_that_compares_a_setting_with_itself_is_refused_up_front() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("map");
    let cases: &[(&str, &[&str], &str)] = &[
        (
            "one path twice",
            &[
                "--grid",
                "newton.tolerance=1e-6,1e-8",
                "--grid",
                "newton.tolerance=1e-4,1e-5",
            ],
            "given twice",
        ),
        (
            "one value in three spellings",
            &[
                "--grid",
                "relaxation.epsilon=1e-6,0.000001,1.0e-6",
                "--grid",
                "relaxation.r=1e3,1e5",
            ],
            "are one value",
        ),
        (
            "an axis the solver does not read",
            &[
                "--grid",
                "newton-coulomb.tolerance=1e-6,1e-8",
                "--grid",
                "coulomb.epsilon=1e-4,1e-6",
            ],
            "never reads coulomb.*",
        ),
        (
            "a grid of two million points",
            &[
                "--grid",
                &(format!(
                    "relaxation.r={}",
                    (1..=1000)
                        .map(|k| format!("{k}e3"))
                        .collect::<Vec<_>>()
                        .join(",")
                )),
                "--grid",
                &(format!(
                    "relaxation.epsilon={}",
                    (1..=1000)
                        .map(|k| format!("{k}e-9"))
                        .collect::<Vec<_>>()
                        .join(",")
                )),
                "--grid",
                "relaxation.omega=1.0,1.5",
            ],
            "is more than a map of 400",
        ),
        (
            "a law the solver cannot be run at",
            &[
                "--grid",
                "newton-coulomb.tolerance=1e-6,1e-8",
                "--grid",
                "newton-coulomb.max_iter=50,100",
                "--law",
                "given-friction",
            ],
            "solves the Coulomb law only",
        ),
    ];
    for (what, args, expected) in cases {
        let start = std::time::Instant::now();
        let o = sweep(args, &out);
        one_line_error(&o, what, expected);
        // Refused before any solve (a 1/64 point takes about a second).
        assert!(start.elapsed().as_secs_f64() < 5.0, "{what}: not up front");
        assert!(!out.exists(), "{what}: wrote {}", out.display());
    }
}

#[test]
fn the_readmes_map_runs_at_the_default_law_and_two_problems_write_two_maps() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("map");
    let o = sweep(
        &[
            "--problem",
            "1,3",
            "--h",
            "1/8",
            "--grid",
            "relaxation.r=1e3,1e5",
            "--grid",
            "relaxation.epsilon=1e-4,1e-6",
            "--runs",
            "0",
        ],
        &out,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let maps: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| {
            n.starts_with("tuning_map_relaxation_coulomb_h8")
                && !n.contains("trials")
                && n.ends_with(".csv")
        })
        .collect();
    assert_eq!(maps.len(), 2, "{maps:?}");
}

/// `--time-limit` caps each point's solve: a map of points that cannot
/// finish in it still ends, states its budget and its form before it starts,
/// and writes each point with the status time_limit (not certified).
#[test]
fn a_time_limited_map_states_its_budget_and_ends_with_every_point() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("map");
    let o = sweep(
        &[
            "--h",
            "1/32",
            "--grid",
            "relaxation.r=1e3,1e5",
            "--grid",
            "relaxation.epsilon=1e-8,1e-9",
            "--runs",
            "0",
            "--time-limit",
            "0.02",
        ],
        &out,
    );
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stderr.contains("mapping relaxation (inner = sweeps)")
            && stderr.contains("4 solves")
            && stderr.contains("at most 0 s with --time-limit 0.02 s a solve"),
        "{stderr}"
    );
    let map = std::fs::read_to_string(out.join("tuning_map_relaxation_coulomb_h32.csv")).unwrap();
    let rows: Vec<&str> = map.lines().skip(1).collect();
    assert_eq!(rows.len(), 4, "{map}");
    assert!(
        rows.iter().all(|r| r.contains(",time_limit,false,")),
        "{map}"
    );
}
