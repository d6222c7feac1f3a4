//! What the command-line tests share: the binary, a run with a deadline
//! (a hang is a failure, not a stuck test), and the shape every refusal
//! must have (one line on stderr, a non-zero exit, no panic).
#![allow(dead_code)]

use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// The contactlab binary under test.
pub fn contactlab() -> Command {
    Command::new(env!("CARGO_BIN_EXE_contactlab"))
}

/// `solve` of the paper's problem 1 at mesh `h` by `solver`, its files
/// into `out` (the run the output-folder tests repeat).
pub fn solve_into(h: &str, solver: &str, out: &std::path::Path) -> Command {
    let mut cmd = contactlab();
    cmd.args([
        "solve",
        "--problem",
        "1",
        "--h",
        h,
        "--solver",
        solver,
        "--out",
    ])
    .arg(out);
    cmd
}

/// Runs `cmd`, failing the test if it takes more than `seconds`.
pub fn run_with_deadline(mut cmd: Command, seconds: u64) -> Output {
    let mut child = cmd
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            return child.wait_with_output().unwrap();
        }
        if start.elapsed() > Duration::from_secs(seconds) {
            let _ = child.kill();
            panic!("{cmd:?} did not finish within {seconds} s");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// A refusal: a non-zero exit and one line on stderr that names `expected`,
/// with no panic and no failed allocation.
pub fn one_line_error(o: &Output, what: &str, expected: &str) {
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{what}: exit code 0");
    assert!(!stderr.contains("panicked"), "{what}: {stderr}");
    assert!(!stderr.contains("memory allocation"), "{what}: {stderr}");
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "{what}: not one line: {stderr}");
    assert!(
        stderr.contains(expected),
        "{what}: '{expected}' not in {stderr}"
    );
}

/// Checks that the README of the run in `out` lists every file the run
/// wrote at its top level (charts and profiles are listed by pattern), and
/// names no file that is not there; gives the files.
pub fn readme_lists_every_file(out: &std::path::Path) -> std::collections::BTreeSet<String> {
    let readme = std::fs::read_to_string(out.join("README.md")).unwrap();
    let listed: std::collections::BTreeSet<String> = readme
        .lines()
        .filter_map(|l| l.strip_prefix("- `"))
        .filter_map(|l| l.split('`').next())
        .filter(|f| out.join(f).is_file())
        .map(String::from)
        .collect();
    let written: std::collections::BTreeSet<String> = std::fs::read_dir(out)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|f| !f.starts_with('.') && out.join(f).is_file())
        .collect();
    assert_eq!(listed, written);
    written
}

/// The staging folders of runs left in `dir` (a run's output folder's
/// parent): the names that contain `staging`.
pub fn staging_folders(dir: &std::path::Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains("staging"))
        .collect()
}

/// The Coulomb problem of `scene` solved by newton-coulomb at its default
/// settings, which the tests hold to be converged: a true answer.
pub fn true_answer(scene: &contactlab::mechanics::scene::Scene) -> contactlab::solve::Solved {
    let run = contactlab::solve::solve_scene(
        scene,
        contactlab::solvers::Friction::Coulomb,
        contactlab::solve::solver_entry("newton-coulomb").unwrap(),
        &contactlab::settings::Settings::default(),
        &mut contactlab::solvers::Silent,
    )
    .unwrap();
    assert!(run.outcome.status.is_converged(), "{}", run.outcome.detail);
    run
}

/// Every `.tex` table in `dir`: plain ASCII, a `table` float with its
/// caption and the label of its file, booktabs rules, at most
/// [`contactlab::io::latex::MAX_COLUMNS`] columns, and compiled together by
/// pdfLaTeX into a default one-column article
/// ([`contactlab::io::latex::document`]) without an overfull box or a
/// label defined twice. Without
/// pdfLaTeX the compile is skipped with a line saying so, unless
/// `CONTACTLAB_REQUIRE_LATEX` is set (CI sets it when it could install TeX).
pub fn latex_tables_compile(dir: &std::path::Path) {
    use contactlab::io::latex::{MAX_COLUMNS, document};
    let mut tables: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tex"))
        .collect();
    tables.sort();
    assert!(!tables.is_empty(), "no .tex in {}", dir.display());
    for t in &tables {
        let tex = std::fs::read_to_string(dir.join(t)).unwrap();
        assert!(tex.is_ascii(), "{t} is not plain ASCII:\n{tex}");
        for rule in ["\\toprule", "\\midrule", "\\bottomrule"] {
            assert!(tex.contains(rule), "{t} has no {rule}");
        }
        for env in ["\\begin{table}", "\\caption{", "\\end{table}"] {
            assert!(tex.contains(env), "{t} has no {env}");
        }
        let label = format!(
            "\\label{{tab:{}}}",
            t.trim_end_matches(".tex").replace('_', "-")
        );
        assert!(tex.contains(&label), "{t} has no {label}");
        let specs: Vec<&str> = tex
            .split("\\begin{tabular}{")
            .skip(1)
            .filter_map(|s| s.split('}').next())
            .collect();
        assert!(!specs.is_empty(), "{t} has no tabular");
        for spec in specs {
            assert!(
                spec.len() <= MAX_COLUMNS,
                "{t} has {} columns: {spec}",
                spec.len()
            );
        }
        assert!(
            !tex.lines().any(|l| !l.starts_with('%')
                && l.contains("e-")
                && l.split(|c: char| !c.is_ascii_alphanumeric() && c != '.' && c != '-')
                    .any(|w| w.contains("e-") && w.starts_with(|c: char| c.is_ascii_digit()))),
            "{t} has a number not in math mode:\n{tex}"
        );
    }
    if std::process::Command::new("pdflatex")
        .arg("--version")
        .output()
        .is_err()
    {
        assert!(
            std::env::var_os("CONTACTLAB_REQUIRE_LATEX").is_none(),
            "pdflatex is required (CONTACTLAB_REQUIRE_LATEX) but not found"
        );
        eprintln!("skipped: compiling the LaTeX tables (no pdflatex here)");
        return;
    }
    let names: Vec<&str> = tables.iter().map(|t| t.trim_end_matches(".tex")).collect();
    std::fs::write(dir.join("tables_document.tex"), document(&names)).unwrap();
    let o = std::process::Command::new("pdflatex")
        .args([
            "-interaction=nonstopmode",
            "-halt-on-error",
            "tables_document.tex",
        ])
        .current_dir(dir)
        .output()
        .unwrap();
    let log = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "pdflatex failed:\n{log}");
    assert!(!log.contains("Missing character"), "{log}");
    // A default one-column article: a table wider than \linewidth is an
    // overfull box (the committed tables once ran 151-202 pt past it).
    assert!(
        !log.contains("Overfull \\hbox"),
        "a table does not fit the page:\n{log}"
    );
    assert!(
        !log.contains("multiply defined"),
        "two tables share a label:\n{log}"
    );
    for extra in [
        "tables_document.tex",
        "tables_document.aux",
        "tables_document.log",
        "tables_document.pdf",
    ] {
        let _ = std::fs::remove_file(dir.join(extra));
    }
}
