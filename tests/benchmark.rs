//! The benchmark: `benchmark --quick` writes every file with the documented
//! columns; two shards merged give the runs of the whole; and a solver that
//! claims success on a wrong answer is counted as a failure and listed.

mod common;

use std::path::Path;
use std::process::Command;

use contactlab::settings::Settings;
use contactlab::solvers::registry::{self, Accuracy, Entry, Knob, Role, StageInfo};
use contactlab::solvers::settings::{Kind, Validate, from_tree, to_tree};
use contactlab::solvers::{
    ContactProblem, Friction, Law, Observer, Solution, Solver, Start, Status,
};
use contactlab::study::benchmark::merge::{read_csv, read_shards};
use contactlab::study::benchmark::views::{self, summaries};
use contactlab::study::benchmark::{self, BenchmarkRow, BenchmarkSpec};

const COLUMNS: [&str; 17] = [
    "instance",
    "family",
    "h",
    "unknowns",
    "friction_coefficient",
    "solver",
    "target",
    "status",
    "solver_status",
    "success",
    "claimed_but_failed",
    "certificate",
    "failing",
    "seconds",
    "time_limit",
    "work",
    "detail",
];

fn contactlab(args: &[&str]) {
    let o = Command::new(env!("CARGO_BIN_EXE_contactlab"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// Runs a command that must fail with one line naming `expected`.
fn refused(args: &[&str], expected: &str) {
    let o = common::contactlab().args(args).output().unwrap();
    common::one_line_error(&o, &args.join(" "), expected);
}

/// A copy of shard folder `from` as `to`, with `benchmark.csv` edited.
fn edited(from: &Path, to: &Path, edit: impl Fn(String) -> String) {
    std::fs::create_dir(to).unwrap();
    for f in ["manifest.json", "benchmark.csv"] {
        std::fs::copy(from.join(f), to.join(f)).unwrap();
    }
    let csv = std::fs::read_to_string(to.join("benchmark.csv")).unwrap();
    std::fs::write(to.join("benchmark.csv"), edit(csv)).unwrap();
}

fn header(path: &Path) -> Vec<String> {
    csv::Reader::from_path(path)
        .unwrap()
        .headers()
        .unwrap()
        .iter()
        .map(String::from)
        .collect()
}

fn outcomes(rows: &[BenchmarkRow]) -> Vec<(String, String, String, bool)> {
    let mut v: Vec<_> = rows
        .iter()
        .map(|r| {
            (
                r.instance.clone(),
                r.solver.clone(),
                format!("{:e}", r.target),
                r.success,
            )
        })
        .collect();
    v.sort();
    v
}

#[test]
fn quick_benchmark_writes_every_file_and_shards_merge_to_the_whole() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name);
    let s = |name: &str| p(name).to_string_lossy().into_owned();
    contactlab(&["benchmark", "--quick", "--out", &s("whole")]);
    let whole = p("whole");
    assert_eq!(header(&whole.join("benchmark.csv")), COLUMNS);
    for f in [
        "benchmark_trials.csv",
        "benchmark_trials_timing.csv",
        "benchmark_summary.csv",
        "benchmark_1e-4.tex",
        "benchmark_1e-8.tex",
        "benchmark.md",
        "manifest.json",
        "charts/benchmark_profile_1e-4.svg",
        "charts/benchmark_profile_1e-8.svg",
    ] {
        assert!(whole.join(f).is_file(), "missing {f}");
    }
    let tex = std::fs::read_to_string(whole.join("benchmark_1e-8.tex")).unwrap();
    assert!(tex.contains("\\toprule") && tex.contains("\\bottomrule"));
    // Two shards, merged.
    contactlab(&["benchmark", "--quick", "--shard", "1/2", "--out", &s("a")]);
    contactlab(&["benchmark", "--quick", "--shard", "2/2", "--out", &s("b")]);
    contactlab(&["benchmark-merge", &s("a"), &s("b"), "--out", &s("merged")]);
    let rows = |d: &str| read_csv(&p(d)).unwrap();
    let (a, b) = (rows("a"), rows("b"));
    assert!(!a.is_empty() && !b.is_empty());
    assert!(
        a.iter()
            .all(|r| !b.iter().any(|q| q.instance == r.instance)),
        "shards overlap"
    );
    assert_eq!(outcomes(&rows("merged")), outcomes(&rows("whole")));
    assert!(
        p("merged")
            .join("charts/benchmark_profile_1e-4.svg")
            .is_file()
    );
    // A merged folder is one whole run: it merges alone.
    assert_eq!(
        outcomes(&read_shards(&[p("merged")]).unwrap()),
        outcomes(&rows("whole"))
    );
    // What does not make one whole run is refused, with one line.
    let merge = |dirs: &[&str], expected: &str| {
        let mut args = vec!["benchmark-merge".to_string()];
        args.extend(dirs.iter().map(|d| s(d)));
        args.extend(["--out".to_string(), s("never")]);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        refused(&args, expected);
        assert!(!p("never").exists());
    };
    merge(&["a", "a"], "given twice");
    merge(&["a"], "shards 2/2 are missing");
    merge(&["a", "whole"], "different runs");
    contactlab(&[
        "benchmark",
        "--quick",
        "--shard",
        "2/2",
        "--time-limit",
        "4",
        "--out",
        &s("b4"),
    ]);
    merge(&["a", "b4"], "different runs");
    contactlab(&[
        "benchmark",
        "--quick",
        "--shard",
        "2/2",
        "--targets",
        "1e-4",
        "--out",
        &s("b1"),
    ]);
    merge(&["a", "b1"], "different runs");
    // Rows that a run does not write.
    let b = p("b");
    edited(&b, &p("empty"), |csv| {
        csv.lines().next().unwrap().to_string() + "\n"
    });
    merge(&["a", "empty"], "plans");
    edited(&b, &p("short"), |csv| {
        let lines: Vec<&str> = csv.lines().collect();
        lines[..lines.len() - 1].join("\n") + "\n"
    });
    merge(&["a", "short"], "plans");
    let failed_row = |csv: &str| {
        csv.lines()
            .position(|l| l.contains(",inaccurate,") || l.contains(",max_iterations,"))
            .expect("a quick run has a failed row")
    };
    edited(&b, &p("liar"), |csv| {
        let k = failed_row(&csv);
        let mut lines: Vec<String> = csv.lines().map(String::from).collect();
        lines[k] = lines[k].replacen(",false,", ",true,", 1);
        lines.join("\n") + "\n"
    });
    merge(&["a", "liar"], "success = true");
    edited(&b, &p("nan"), |csv| {
        let mut lines: Vec<String> = csv.lines().map(String::from).collect();
        let row = lines[1].clone();
        let fields: Vec<&str> = row.split(',').collect();
        // seconds is the 14th column; an empty field reads as NaN.
        let mut f: Vec<String> = fields.iter().map(|x| x.to_string()).collect();
        f[13] = "-1".into();
        lines[1] = f.join(",");
        lines.join("\n") + "\n"
    });
    merge(&["a", "nan"], "seconds = -1");
    // A shard beyond the collection, and a certificate tolerance that the
    // benchmark would not use.
    refused(
        &[
            "benchmark",
            "--quick",
            "--shard",
            "8/8",
            "--out",
            &s("never"),
        ],
        "has 7 instances",
    );
    refused(
        &[
            "benchmark",
            "--quick",
            "--certify-tol",
            "1e-6",
            "--out",
            &s("never"),
        ],
        "--certify-tol does not apply",
    );
}

/// A solver that claims convergence with no contact force at all: a wrong
/// answer (the load is not balanced).
struct Liar;

impl Solver for Liar {
    fn solve(
        &mut self,
        p: &ContactProblem,
        _friction: Friction<'_>,
        _s: Option<Start<'_>>,
        _o: &mut dyn Observer,
    ) -> Solution {
        let mut s = Solution::failed(p.n(), p.contacts().len(), Status::Converged, "trust me");
        s.status = Status::Converged;
        s
    }
}

static LIAR: Entry = Entry {
    name: "liar",
    about: "claims convergence on a zero answer (a test's)",
    source: "none",
    laws: &[Law::Coulomb],
    warm_starts: false,
    schedule: contactlab_solvers::schedule::Schedule::Revisit,
    schedule_when: None,
    stages: &[StageInfo {
        name: "lie",
        about: "never reported",
        history: false,
    }],
    work_stage: "lie",
    knobs: &[Knob {
        name: "tolerance",
        fields: &["tolerance"],
        help: "ignored",
        kind: Kind::Positive,
    }],
    defaults: |_| to_tree(&LiarSettings { tolerance: 1e-10 }),
    build: contactlab::solvers::registry::Build::Fn(|tree| {
        let _: LiarSettings = from_tree(tree)?;
        Ok(Box::new(Liar))
    }),
    accuracy: Accuracy {
        knob: "tolerance",
        reference: 1e-10,
        exact: false,
    },
    role: Role::Other,
    kernel: None,
    max_unknowns: None,
    uses_mass: false,
    memory: contactlab::solvers::entry::Memory {
        per_unknown: 400.0,
        per_unknown_log2: 0.0,
    },
};

#[derive(serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct LiarSettings {
    tolerance: f64,
}

impl Validate for LiarSettings {
    fn validate(&self) -> Result<(), String> {
        Ok(())
    }
}

#[test]
fn a_solver_claiming_success_on_a_wrong_answer_counts_as_failed() {
    if registry::by_name("liar").is_none() {
        registry::register(&LIAR).unwrap();
    }
    let honest = registry::by_name("newton-coulomb").unwrap();
    let spec = BenchmarkSpec::new(true, vec![&LIAR, honest]);
    let plan = benchmark::plan(&spec, &Settings::default()).unwrap();
    let done = benchmark::run(plan, &|_| Ok(())).unwrap();
    let rows: Vec<BenchmarkRow> = done.into_iter().map(|(r, _)| r).collect();
    let liar: Vec<&BenchmarkRow> = rows.iter().filter(|r| r.solver == "liar").collect();
    assert!(!liar.is_empty());
    for r in &liar {
        assert_eq!(r.solver_status, "converged");
        assert!(!r.success && r.claimed_but_failed, "{r:?}");
        assert!(r.failing.contains("force_balance"), "{r:?}");
    }
    for s in summaries(&rows).iter().filter(|s| s.solver == "liar") {
        assert_eq!((s.successes, s.claimed_but_failed), (0, s.runs));
    }
    assert!(
        views::report(&rows).unwrap().contains("`liar` on"),
        "the refused runs are listed"
    );
    // The honest solver solves every instance.
    assert!(
        rows.iter()
            .filter(|r| r.solver == honest.name)
            .all(|r| r.success)
    );
}
