//! A study is one file plus one line: this file is the file, and the list
//! handed to `run_studies` below is the line (for the library's studies it
//! is one line of `study::catalog::catalog`; a program adds one with
//! `catalog::register`, as the second test does, and finds it as a
//! command, as Python's call and in `reproduce`). The toy study plans its trials,
//! has them measured and certified by the one runner against the earned
//! reference, writes a table and a chart, hands a value on to a later
//! study, and writes its own README section; a run of studies states its
//! estimate, records it in the checkpoint and, resumed, takes it from
//! there without running it again. Nothing else in the code knows it.

use std::cell::Cell;

use anyhow::Result;
use contactlab::io::charts::{Chart, Series};
use contactlab::mechanics::mesh_size::MeshSize;
use contactlab::mechanics::scene::Scene;
use contactlab::settings::Settings;
use contactlab::solvers::{Law, registry};
use contactlab::study::catalog::{self, Catalogued, Of};
use contactlab::study::lab::{
    Artifact, Lab, Planned, Quiet, Ran, RunLength, Section, Study, chart_markdown,
};
use contactlab::study::reproduce::checkpoint::{Checkpoint, RunKey};
use contactlab::study::reproduce::{ReproduceSpec, estimate_of, run_studies};
use contactlab::study::runner::{Keep, Measured};
use contactlab::study::studies;
use contactlab::study::trial::TrialSpec;
use serde::{Deserialize, Serialize};

/// The toys' trials: the solvers named on problem 1 at `h`, the Coulomb
/// law, measured by the lab against its reference.
fn measure_toy(lab: &mut Lab, h: MeshSize, solvers: &[impl AsRef<str>]) -> Result<Vec<Measured>> {
    let scene = Scene::paper_problem_to(1, h)?;
    let specs: Vec<TrialSpec> = solvers
        .iter()
        .map(|n| {
            let entry = registry::by_name(n.as_ref()).unwrap();
            TrialSpec::new("toy", "toy", &scene, entry, Law::Coulomb, &lab.settings)
        })
        .collect();
    lab.measure(&specs, Keep::default())
}

/// What the toy hands on to the studies after it.
#[derive(Debug, PartialEq, Serialize, Deserialize)]
struct Fastest(String);

/// Two solvers on problem 1 at h = 1/8, the fastest named.
struct Toy<'a> {
    runs: &'a Cell<usize>,
}

impl Study for Toy<'_> {
    type Findings = Vec<Measured>;

    fn name(&self) -> &'static str {
        "toy"
    }

    fn estimated_seconds(&self, length: RunLength) -> f64 {
        if length == RunLength::Quick { 0.5 } else { 7.0 }
    }

    fn run(&self, lab: &mut Lab) -> Result<Ran<Vec<Measured>>> {
        self.runs.set(self.runs.get() + 1);
        let measured = measure_toy(lab, MeshSize::from_level(3)?, &["newton-coulomb", "tnnmg"])?;
        let fastest = measured
            .iter()
            .min_by(|a, b| a.timing.seconds_min.total_cmp(&b.timing.seconds_min))
            .map(|m| m.trial.solver.name.to_string())
            .unwrap_or_default();
        lab.handoff.put(&Fastest(fastest))?;
        let seconds = Series::line(
            "seconds",
            measured
                .iter()
                .enumerate()
                .map(|(k, m)| (k as f64, m.timing.seconds_min))
                .collect(),
        );
        let chart = Chart::new(
            "toy: seconds per solver",
            "solver",
            "seconds",
            false,
            false,
            vec![seconds],
        );
        let mut artifacts = Artifact::trials("toy", &measured)?;
        artifacts.push(Artifact::chart("toy_seconds", chart));
        Ok(Ran {
            findings: measured,
            artifacts,
        })
    }

    fn section(&self, measured: &Vec<Measured>, _: &Lab, charts: &[String]) -> Result<Section> {
        let certified = measured.iter().filter(|m| m.trial.certified()).count();
        let mut markdown = format!(
            "## The toy study\n\n{certified} of {} trials certified.\n\n",
            measured.len()
        );
        for c in charts {
            markdown += &chart_markdown(c, "How long each solver took.");
        }
        Ok(Section { markdown })
    }
}

/// A later study that reads what the toy handed on.
struct Reader<'a> {
    read: &'a Cell<bool>,
}

impl Study for Reader<'_> {
    type Findings = ();

    fn name(&self) -> &'static str {
        "reader"
    }

    fn estimated_seconds(&self, _: RunLength) -> f64 {
        1.0
    }

    fn run(&self, lab: &mut Lab) -> Result<Ran<()>> {
        let fastest = lab.handoff.get::<Fastest>();
        self.read.set(fastest.is_some_and(|f| !f.0.is_empty()));
        Ok(Ran {
            findings: (),
            artifacts: vec![Artifact::text("reader.txt", "read")],
        })
    }

    fn section(&self, _: &(), _: &Lab, _: &[String]) -> Result<Section> {
        Ok(Section {
            markdown: "## Reader\n".into(),
        })
    }
}

#[test]
fn a_study_added_in_one_file_runs_writes_reports_and_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let settings = Settings::default();
    let key = RunKey::of(&ReproduceSpec::quick(), &settings).unwrap();
    let (runs, read) = (Cell::new(0), Cell::new(false));
    // The one line: the list of studies.
    let studies: Vec<Box<dyn Planned + '_>> = vec![
        Box::new(Toy { runs: &runs }),
        Box::new(Reader { read: &read }),
    ];
    let (seconds, said) = estimate_of(&studies, RunLength::Standard, 0);
    assert_eq!(seconds, 8.0);
    assert!(said.contains("toy 7 s"), "{said}");

    let mut checkpoint = Checkpoint::start(dir.path(), &key).unwrap();
    let mut lab = Lab::new(settings.clone(), &|_| {}, &Quiet);
    let done = run_studies(
        &studies,
        RunLength::Standard,
        &mut lab,
        dir.path(),
        &mut checkpoint,
    )
    .unwrap();
    assert_eq!(runs.get(), 1);
    assert!(read.get(), "the reader got the toy's handoff");
    for f in [
        "toy.csv",
        "toy_timing.csv",
        "charts/toy_seconds.svg",
        "reader.txt",
    ] {
        assert!(done.files.contains(&f.to_string()), "{f}: {:?}", done.files);
        assert!(dir.path().join(f).is_file(), "{f} written");
    }
    let toy_csv = std::fs::read_to_string(dir.path().join("toy.csv")).unwrap();
    assert_eq!(toy_csv.lines().count(), 3, "a header and two trials");
    let section = &done.sections[0].markdown;
    assert!(section.starts_with("## The toy study"), "{section}");
    assert!(section.contains("2 of 2 trials certified"), "{section}");
    assert!(section.contains("![toy_seconds](charts/toy_seconds.svg)"));

    // Resumed: both studies come from the checkpoint, with the toy's
    // section and handoff, and nothing runs again.
    read.set(false);
    let plan: Vec<&str> = studies.iter().map(|s| s.name()).collect();
    let mut checkpoint = Checkpoint::resume(dir.path(), &key, &plan).unwrap();
    assert_eq!(checkpoint.done.len(), 2, "{:?}", checkpoint.notes);
    let mut lab = Lab::new(settings, &|_| {}, &Quiet);
    let again = run_studies(
        &studies,
        RunLength::Standard,
        &mut lab,
        dir.path(),
        &mut checkpoint,
    )
    .unwrap();
    assert_eq!(runs.get(), 1, "the toy did not run again");
    assert!(!read.get(), "nor did the reader");
    assert_eq!(again.sections[0], done.sections[0]);
    assert_eq!(again.resumed.len(), 2);
    assert!(
        lab.handoff.get::<Fastest>().is_some(),
        "the handoff came back"
    );
}

/// The catalogued toy's parameters, declared once: its flags and its JSON
/// form (Python's keywords).
#[derive(Clone, Debug, Serialize, Deserialize, clap::Args)]
struct ToySpec {
    /// The mesh of problem 1 the toy solves on.
    #[arg(long, value_name = "H", required = false)]
    h: MeshSize,
    /// The solvers it runs, such as tnnmg,newton-coulomb.
    #[arg(long, value_delimiter = ',', value_parser = catalog::registered_solver)]
    solvers: Vec<String>,
}

/// A toy study in the catalog: the solvers of its spec on problem 1.
struct Listed {
    spec: ToySpec,
}

impl Catalogued for Listed {
    const COMMAND: &'static str = "toy";
    const ABOUT: &'static str = "The toy study: a few solvers on problem 1.";
    type Spec = ToySpec;

    fn spec(length: RunLength) -> ToySpec {
        ToySpec {
            h: MeshSize::from_level(if length == RunLength::Quick { 3 } else { 4 }).unwrap(),
            solvers: vec!["newton-coulomb".into(), "tnnmg".into()],
        }
    }

    fn of(spec: ToySpec) -> Result<Self> {
        anyhow::ensure!(!spec.solvers.is_empty(), "solvers: give at least one");
        Ok(Self { spec })
    }
}

impl Study for Listed {
    type Findings = Vec<Measured>;

    fn name(&self) -> &'static str {
        "toy"
    }

    fn estimated_seconds(&self, _: RunLength) -> f64 {
        1.0
    }

    fn run(&self, lab: &mut Lab) -> Result<Ran<Vec<Measured>>> {
        let measured = measure_toy(lab, self.spec.h, &self.spec.solvers)?;
        let artifacts = Artifact::trials("toy", &measured)?;
        Ok(Ran {
            findings: measured,
            artifacts,
        })
    }

    fn section(&self, measured: &Vec<Measured>, _: &Lab, _: &[String]) -> Result<Section> {
        Ok(Section {
            markdown: format!("## The toy study\n\n{} trials.\n", measured.len()),
        })
    }
}

static LISTED: Of<Listed> = Of::ENTRY;

/// One line (`catalog::register` here, a line of `catalog::catalog` for
/// the library's studies) makes the toy a command with its spec's flags
/// and help, the study Python's `contactlab.study("toy", ...)` runs (the
/// same entry, from JSON), and a section of `reproduce`. A study the
/// command line or `reproduce` wired by hand, flags that do not reach the
/// spec, or a JSON field the spec ignores, fails here.
#[test]
fn a_catalogued_study_is_a_command_a_python_call_and_a_reproduce_section() {
    use clap::{CommandFactory, Parser};
    studies::register(&LISTED).unwrap();
    assert!(studies::register(&LISTED).is_err(), "registered twice");

    // The command line: its help from the spec's doc comments, its run.
    let mut cli = contactlab::cli::Cli::command();
    let help = cli
        .find_subcommand_mut("toy")
        .expect("a toy command")
        .render_long_help()
        .to_string();
    assert!(help.contains("The toy study: a few solvers"), "{help}");
    assert!(
        help.contains("--solvers") && help.contains("The solvers it runs"),
        "{help}"
    );
    assert!(
        help.contains("--quick") && help.contains("--certify-tol"),
        "{help}"
    );
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("toy");
    let parsed = contactlab::cli::Cli::try_parse_from([
        "contactlab",
        "toy",
        "--quick",
        "--solvers",
        "tnnmg",
        "--out",
        out.to_str().unwrap(),
    ])
    .unwrap();
    contactlab::cli::run(parsed).unwrap();
    let csv = std::fs::read_to_string(out.join("toy.csv")).unwrap();
    assert_eq!(
        csv.lines().count(),
        2,
        "a header and the one solver asked: {csv}"
    );
    assert!(csv.contains(",tnnmg,") && csv.contains(",1/8,"), "{csv}");
    let wrong = contactlab::cli::Cli::try_parse_from([
        "contactlab",
        "toy",
        "--solvers",
        "no-such-solver",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(wrong.unwrap_err().to_string().contains("unknown solver"));

    // Python's path: the entry by name, its spec changed from JSON.
    let entry = studies::by_command("toy").unwrap();
    let study = entry
        .planned_with_json(
            RunLength::Quick,
            r#"{"solvers": ["newton-coulomb"], "h": "1/16"}"#,
        )
        .unwrap();
    let mut lab = Lab::new(Settings::default(), &|_| {}, &Quiet);
    let (artifacts, section) = study.run_for_report(&mut lab).unwrap();
    assert!(
        section.markdown.contains("1 trials"),
        "{}",
        section.markdown
    );
    let records: serde_json::Value =
        serde_json::from_str(artifacts[0].records.as_ref().expect("typed rows")).unwrap();
    assert_eq!(records[0]["solver"], "newton-coulomb");
    assert_eq!(records[0]["h"], "1/16");
    let unknown = entry.planned_with_json(RunLength::Quick, r#"{"mesh": "1/16"}"#);
    let message = format!("{:#}", unknown.err().unwrap());
    assert!(
        message.contains("\"mesh\"") && message.contains("h, solvers"),
        "{message}"
    );

    // reproduce: in its list of studies.
    let names: Vec<&str> =
        contactlab::study::reproduce::studies(&ReproduceSpec::quick(), &Settings::default())
            .iter()
            .map(|s| s.name())
            .collect();
    assert!(names.contains(&"toy"), "{names:?}");
}
