//! The binary: outputs of `solve`, and help.

mod common;
use std::process::Command;

fn contactlab(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_contactlab"))
        .args(args)
        .output()
        .expect("run contactlab")
}

#[test]
fn solve_writes_the_documented_profile_and_summary() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let o = contactlab(&[
        "solve",
        "--problem",
        "1",
        "--h",
        "1/8",
        "--solver",
        "clarabel",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let profile = std::fs::read_to_string(out.join("profile.csv")).unwrap();
    let mut lines = profile.lines();
    assert_eq!(
        lines.next().unwrap(),
        "x,u1_lower,u2_lower,u1_upper,u2_upper,jump,slip,pressure,friction_traction,g,state,status"
    );
    let mut states = Vec::new();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| {
            let fields: Vec<&str> = l.split(',').collect();
            assert_eq!(
                fields[11], "converged",
                "the run's certified status on every row"
            );
            states.push(fields[10].to_string());
            fields[..10].iter().map(|v| v.parse().unwrap()).collect()
        })
        .collect();
    // The contact state agrees with the law it names, at g = 𝓕p (𝓕 = 0.5),
    // to the certificate's accuracy relative to the largest pressure.
    let scale = 1e-6 * rows.iter().fold(0.0f64, |m, r| m.max(r[7]));
    for (r, state) in rows.iter().zip(&states) {
        assert!((r[9] - 0.5 * r[7]).abs() <= scale, "g = 𝓕p");
        match state.as_str() {
            "open" => assert!(r[7] <= scale && r[5] < 0.0, "open: no pressure, a gap"),
            "slip" => assert!(
                (r[8].abs() - r[9]).abs() <= scale && r[6] != 0.0,
                "slip: |q| = g and the bodies slide"
            ),
            "stick" => assert!(r[8].abs() <= r[9] + scale && r[7] > scale, "stick: |q| ≤ g"),
            other => panic!("unknown contact state {other}"),
        }
    }
    assert_eq!(states.first().map(String::as_str), Some("stick"));
    assert_eq!(states.last().map(String::as_str), Some("open"));
    assert_eq!(rows.len(), 9, "one row per contact node at h = 1/8");
    for w in rows.windows(2) {
        assert!(w[0][0] < w[1][0], "rows in increasing x");
    }
    for r in &rows {
        assert!(
            (r[5] - (r[2] - r[4])).abs() <= 1e-12,
            "jump = u2_lower − u2_upper"
        );
        assert!(
            (r[6] - (r[1] - r[3])).abs() <= 1e-12,
            "slip = u1_lower − u1_upper"
        );
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    for key in [
        "problem",
        "h",
        "solver",
        "friction_coefficient",
        "friction_iterations",
        "status",
        "separated_intervals",
        "separated_fraction",
        "max_pressure",
        "total_contact_force",
        "total_applied_load",
        "objective",
        "certificate",
        "solver_status",
        "outcome",
        "seconds",
    ] {
        assert!(summary.get(key).is_some(), "summary.json lacks {key}");
    }
    assert_eq!(summary["status"], "converged");
    assert_eq!(summary["solver_status"], "converged");
    assert_eq!(summary["certificate"]["law"], "coulomb");
    assert_eq!(summary["h"], "1/8");
    // No temporary files are left behind: the four files and the run's marker.
    let mut names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            ".contactlab-run",
            "displacements.mtx",
            "forces.csv",
            "profile.csv",
            "summary.json"
        ]
    );
    let siblings = common::staging_folders(dir.path());
    assert!(
        siblings.is_empty(),
        "staging folders left behind: {siblings:?}"
    );
}

#[test]
fn every_subcommand_has_help() {
    let o = contactlab(&["--help"]);
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout).to_string();
    let subcommands: Vec<String> = text
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .map(|l| l.split_whitespace().next().unwrap().to_string())
        .filter(|c| c != "help")
        .collect();
    assert!(subcommands.len() >= 2, "{text}");
    for c in subcommands {
        let o = contactlab(&[&c, "--help"]);
        assert!(o.status.success(), "{c} --help failed");
        let help = String::from_utf8_lossy(&o.stdout);
        assert!(
            help.contains("Usage:") && help.lines().count() > 3,
            "{c}: {help}"
        );
    }
}

/// `table1 --problem 1 3` (the form its help's `[default: 1 2 3]` shows)
/// runs those two problems, as `--problem 1,3` does (the older
/// `--problems` is refused with a hint naming `--problem`); and its help states the stopping mode it uses, the paper's (it
/// said `[default: relative]`).
#[test]
fn table1_takes_the_problem_list_its_help_shows() {
    for (flag, list) in [("--problem", &["1", "3"][..]), ("--problem", &["1,3"][..])] {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("t");
        let mut args = vec!["table1", "--h", "1/8", "--schedules", "revisit", flag];
        args.extend_from_slice(list);
        args.extend(["--out", out.to_str().unwrap()]);
        let o = contactlab(&args);
        assert!(
            o.status.success(),
            "{list:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let csv = std::fs::read_to_string(out.join("table1.csv")).unwrap();
        let problems: Vec<&str> = csv
            .lines()
            .skip(1)
            .map(|l| l.split(',').next().unwrap())
            .collect();
        assert_eq!(problems, ["1", "3"], "{list:?}");
    }
    let help = String::from_utf8_lossy(&contactlab(&["table1", "--help"]).stdout).to_string();
    let stopping = help
        .lines()
        .find(|l| l.contains("--stopping <MODE>"))
        .unwrap();
    assert!(stopping.contains("[default: paper]"), "{stopping}");
}

/// A setting given twice, once by its own flag and once by `--set`, in
/// either order: the later one is the one the run used (summary.json says
/// which), for every flag that has a `--set` path beside it. Before, the
/// `--set` always won and the flag was dropped without a word (issue 47).
#[test]
fn the_later_of_a_flag_and_a_set_of_one_setting_wins() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let cases: [(&str, &str, &str, &str, &str); 5] = [
        (
            "--stopping",
            "relative",
            "stopping",
            "paper",
            "/settings/stopping",
        ),
        (
            "--schedule",
            "nested",
            "schedule",
            "finest-only",
            "/settings/schedule",
        ),
        (
            "--certify-tol",
            "1e-4",
            "certificate.tolerance",
            "1e-3",
            "/settings/certificate/tolerance",
        ),
        (
            "--epsilon",
            "1e-6",
            "coulomb.epsilon",
            "1e-5",
            "/settings/coulomb/epsilon",
        ),
        (
            "--max-friction-iterations",
            "40",
            "coulomb.max_iterations",
            "30",
            "/settings/coulomb/max_iterations",
        ),
    ];
    for (flag, flag_value, path, set_value, pointer) in cases {
        for flag_last in [true, false] {
            let set = format!("{path}={set_value}");
            let mut args = vec!["solve", "--problem", "1", "--h", "1/8", "--solver", "tnnmg"];
            let pair = [[flag, flag_value], ["--set", set.as_str()]];
            let order = if flag_last { [1, 0] } else { [0, 1] };
            for k in order {
                args.extend(pair[k]);
            }
            args.extend(["--out", out.to_str().unwrap()]);
            let o = contactlab(&args);
            assert!(
                o.status.success(),
                "{args:?}: {}",
                String::from_utf8_lossy(&o.stderr)
            );
            let summary: serde_json::Value =
                serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
            let used = summary
                .pointer(pointer)
                .unwrap_or_else(|| panic!("{pointer} in {summary}"));
            let expected = if flag_last { flag_value } else { set_value };
            let shown = used
                .as_str()
                .map_or_else(|| used.to_string(), str::to_string);
            let same = match (shown.parse::<f64>(), expected.parse::<f64>()) {
                (Ok(a), Ok(b)) => a == b,
                _ => shown == expected,
            };
            assert!(same, "{args:?}: the run used {shown}, not {expected}");
        }
    }
}

/// One spelling per concept: the timed runs are `--runs RUNS` in every
/// command that times (`--repeats` refused with a hint naming it), and
/// `certify`'s default tolerance is the certificate's own, written as the
/// help of every other command writes it (1e-5, not 0.00001).
#[test]
fn runs_are_spelled_alike_and_certify_states_its_default_as_written() {
    use clap::{CommandFactory, Parser};
    use contactlab::cli::{Cli, Command};
    for cmd in ["bench", "compare", "sweep"] {
        let help = Cli::command()
            .find_subcommand(cmd)
            .unwrap()
            .get_arguments()
            .find(|a| a.get_long() == Some("runs"))
            .map(|a| a.get_value_names().map(|v| v[0].to_string()))
            .unwrap_or_else(|| panic!("{cmd} has --runs"));
        assert_eq!(help.as_deref(), Some("RUNS"), "{cmd}");
    }
    let hint = contactlab::cli::old_spelling(&["--repeats".to_string(), "2".to_string()]);
    assert_eq!(
        hint.as_deref(),
        Some("--repeats is no longer a flag: write --runs")
    );
    let parsed = Cli::try_parse_from([
        "contactlab",
        "certify",
        "--instance",
        "x",
        "--displacements",
        "v",
    ])
    .unwrap();
    match parsed.command {
        Command::Certify(a) => assert_eq!(a.tolerance, contactlab::certificate::DEFAULT_TOLERANCE),
        _ => panic!("certify parses as certify"),
    }
    let help = String::from_utf8(contactlab(&["certify", "--help"]).stdout).unwrap();
    assert!(help.contains("[default: 1e-5]"), "{help}");
}

/// Every file a command writes is named in its help (`table1 --help` and
/// `compare --help` left out the .tex tables they write).
#[test]
fn help_names_every_file_a_command_writes() {
    let dir = tempfile::tempdir().unwrap();
    for (cmd, args) in [
        ("solve", vec!["--problem", "1", "--h", "1/8"]),
        (
            "compare",
            vec!["--problem", "1", "--h", "1/8", "--runs", "0"],
        ),
        ("table1", vec!["--h", "1/8", "--problem", "1"]),
    ] {
        let out = dir.path().join(cmd);
        let mut all = vec![cmd];
        all.extend(&args);
        all.extend(["--out", out.to_str().unwrap()]);
        let o = contactlab(&all);
        assert!(
            o.status.success(),
            "{cmd}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let help = String::from_utf8(contactlab(&[cmd, "--help"]).stdout).unwrap();
        for entry in std::fs::read_dir(&out).unwrap() {
            let name = entry.unwrap().file_name().into_string().unwrap();
            if name.starts_with('.') {
                continue;
            }
            assert!(help.contains(&name), "{cmd} --help does not name {name}");
        }
    }
}

/// `sweep` takes the scene overrides every other command takes: the
/// frictionless sweep is another sweep, and a bad value is refused naming
/// its flag.
#[test]
fn sweep_takes_the_scene_overrides() {
    let dir = tempfile::tempdir().unwrap();
    let run = |extra: &[&str], out: &str| {
        let out = dir.path().join(out);
        let mut args = vec![
            "sweep",
            "--problem",
            "1",
            "--h",
            "1/8",
            "--solvers",
            "tnnmg",
            "--quick",
            "--runs",
            "0",
        ];
        args.extend(extra);
        args.extend(["--out", out.to_str().unwrap()]);
        (contactlab(&args), out)
    };
    let (o, with) = run(&[], "with");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (o, without) = run(&["--friction", "0"], "without");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let read = |p: &std::path::Path| std::fs::read_to_string(p.join("sweep.csv")).unwrap();
    assert_ne!(read(&with), read(&without), "--friction changed nothing");
    let (o, _) = run(&["--friction", "-1"], "bad");
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--friction"));
}

/// `compare --reference SOLVER` measures against that solver's answer:
/// every row names it, and the named solver differs from itself (at its
/// tightest settings) by no more than its own accuracy; without the flag
/// the reference is earned among the exact solvers, never the paper's
/// method under test.
#[test]
fn compare_measures_against_the_reference_the_user_names() {
    let dir = tempfile::tempdir().unwrap();
    let run = |extra: &[&str], out: &str| {
        let out = dir.path().join(out);
        let mut args = vec![
            "compare",
            "--problem",
            "1",
            "--h",
            "1/8",
            "--solvers",
            "relaxation,tnnmg",
            "--runs",
            "0",
            "--out",
        ];
        args.push(out.to_str().unwrap());
        args.extend_from_slice(extra);
        let o = contactlab(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let mut r = csv::Reader::from_path(out.join("compare.csv")).unwrap();
        let header = r.headers().unwrap().clone();
        let col = |n: &str| header.iter().position(|h| h == n).unwrap();
        r.records()
            .map(|x| {
                let x = x.unwrap();
                (
                    x[col("solver")].to_string(),
                    x[col("reference")].to_string(),
                )
            })
            .collect::<Vec<_>>()
    };
    let named = run(&["--reference", "tnnmg"], "named");
    assert!(named.iter().all(|(_, r)| r == "tnnmg"), "{named:?}");
    let earned = run(&[], "earned");
    assert!(
        earned
            .iter()
            .all(|(_, r)| r != "relaxation" && r != "tnnmg" && !r.is_empty()),
        "{earned:?}"
    );
}
