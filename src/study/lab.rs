//! The one shape of every study: a study plans trials, has them measured
//! in a [`Lab`] (the one runner, with the one reference cache), and turns
//! them into [`Artifact`]s (tables, charts, report sections), recording
//! what a report needs in [`Findings`]. A command runs one study;
//! `reproduce` runs a list of them in one lab, and the files it writes are
//! the artifacts' paths.

use std::path::Path;

use anyhow::Result;
use serde::{Deserialize, Serialize};

use crate::io::charts::Chart;
use crate::io::csv::to_csv;
use crate::io::output::write_atomic;
use crate::mechanics::scene::Scene;
use crate::settings::Settings;
use crate::study::bench::FastestDirect;
use crate::study::bench::goals::BenchOutput;
use crate::study::benchmark::BenchmarkRow;
use crate::study::compare::paper::SeparationRow;
use crate::study::discretization_error::ErrorRow;
use crate::study::reference::{Candidate, Reference, References};
use crate::study::runner::{Keep, Measured, measure_all};
use crate::study::stability::Map;
use crate::study::table1::Table1Row;
use crate::study::trial::TrialSpec;

/// A file a study gives: its path in the output folder and its content.
pub struct Artifact {
    pub path: String,
    pub content: Content,
}

/// What an artifact holds: bytes as written, or a chart drawn when written.
pub enum Content {
    Bytes(Vec<u8>),
    Chart(Chart),
}

impl Artifact {
    /// A CSV table of `rows` (with `header` when there are none).
    pub fn csv<T: Serialize>(path: &str, rows: &[T], header: &[&str]) -> Result<Self> {
        Ok(Self::bytes(path, to_csv(rows, header)?))
    }

    pub fn bytes(path: &str, bytes: Vec<u8>) -> Self {
        Self {
            path: path.to_string(),
            content: Content::Bytes(bytes),
        }
    }

    pub fn text(path: &str, text: &str) -> Self {
        Self::bytes(path, text.as_bytes().to_vec())
    }

    /// A chart, drawn as `charts/NAME.svg`.
    pub fn chart(name: &str, chart: Chart) -> Self {
        Self {
            path: format!("charts/{name}.svg"),
            content: Content::Chart(chart),
        }
    }

    /// Charts given as (name, chart).
    pub fn charts(charts: Vec<(String, Chart)>) -> Vec<Self> {
        charts
            .into_iter()
            .map(|(name, c)| Self::chart(&name, c))
            .collect()
    }

    /// Whether it is a chart (its name without folder and extension then).
    pub fn chart_name(&self) -> Option<&str> {
        match self.content {
            Content::Chart(_) => self
                .path
                .strip_prefix("charts/")
                .and_then(|p| p.strip_suffix(".svg")),
            Content::Bytes(_) => None,
        }
    }
}

/// Writes every artifact into `dir` (each atomically); gives their paths.
pub fn write_artifacts(dir: &Path, artifacts: &[Artifact]) -> Result<Vec<String>> {
    for a in artifacts {
        let path = dir.join(&a.path);
        match &a.content {
            Content::Bytes(b) => write_atomic(&path, b)?,
            Content::Chart(c) => c.write(&path)?,
        }
    }
    Ok(artifacts.iter().map(|a| a.path.clone()).collect())
}

/// What the report of a run needs from its studies, typed.
#[derive(Default)]
pub struct Findings {
    pub table1: Vec<Table1Row>,
    /// Per problem: its comparison trials, then the paper's method at the
    /// paper's settings.
    pub compare: Vec<(u32, Vec<Measured>)>,
    pub separation: Vec<SeparationRow>,
    /// The keys of the comparison's references (see [`Lab::asked`]).
    pub compare_references: Vec<String>,
    /// Separated fraction of problem 1 in plane stress (the reference's).
    pub plane_stress_fraction: Option<f64>,
    pub sweep: Vec<Measured>,
    pub stability: Option<Map>,
    pub bench: Option<BenchOutput>,
    pub benchmark: Vec<BenchmarkRow>,
    pub errors: Vec<ErrorRow>,
    /// What later studies read from earlier ones.
    pub handoff: Handoff,
}

/// What a study reads from the studies before it, kept apart from their
/// trials so that a resumed run (`reproduce --resume`) hands it on from
/// the checkpoint of a study an earlier process ran.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Handoff {
    /// From `bench`: the discretization error's solver unless told.
    pub fastest_direct: FastestDirect,
}

/// Where a lab's progress goes: a study starts a stretch of trials (with
/// the expected relative cost of each, for an estimate of the time left,
/// and the seconds one may take at most), ticks through them, finishes.
pub trait Tracker {
    fn start(&self, what: &str, costs: Vec<f64>, cap: f64);
    fn tick(&self, trial: &TrialSpec);
    fn finish(&self);
}

/// A tracker that tells nobody.
pub struct Quiet;

impl Tracker for Quiet {
    fn start(&self, _: &str, _: Vec<f64>, _: f64) {}
    fn tick(&self, _: &TrialSpec) {}
    fn finish(&self) {}
}

/// Where studies run: the settings, the one reference cache, and where
/// logs and progress go.
pub struct Lab<'a> {
    pub settings: Settings,
    pub references: References,
    /// The keys of the references the current study asked for, in order.
    asked: Vec<String>,
    /// The current study's name (for progress).
    study: &'static str,
    log: &'a dyn Fn(&str),
    tracker: &'a dyn Tracker,
}

impl<'a> Lab<'a> {
    pub fn new(settings: Settings, log: &'a dyn Fn(&str), tracker: &'a dyn Tracker) -> Self {
        Self {
            settings,
            references: References::default(),
            asked: Vec::new(),
            study: "",
            log,
            tracker,
        }
    }

    /// Starts a stretch of `costs.len()` trials (see [`Tracker::start`]).
    pub fn start(&self, what: &str, costs: Vec<f64>, cap: f64) {
        self.tracker.start(what, costs, cap);
    }

    /// Ends the stretch started last.
    pub fn finish(&self) {
        self.tracker.finish();
    }

    /// A line for the log.
    pub fn log(&self, line: &str) {
        (self.log)(line)
    }

    /// The log (to call while the lab is borrowed elsewhere).
    pub fn logger(&self) -> &'a dyn Fn(&str) {
        self.log
    }

    /// Where progress goes (to call while the lab is borrowed elsewhere).
    pub fn tracker(&self) -> &'a dyn Tracker {
        self.tracker
    }

    /// Starts study `name`: the references it asks for are listed anew.
    pub fn begin(&mut self, name: &'static str) {
        self.asked.clear();
        self.study = name;
    }

    /// Runs `study` in this lab (see [`Study::run`]).
    pub fn run(&mut self, study: &dyn Study, findings: &mut Findings) -> Result<Vec<Artifact>> {
        self.begin(study.name());
        study.run(self, findings)
    }

    fn ask(&mut self, scene: &Scene) -> Result<()> {
        let key = References::key(scene)?;
        if !self.asked.contains(&key) {
            self.asked.push(key);
        }
        Ok(())
    }

    /// Measures trials in order, each against the reference of its scene
    /// and mesh (earned on first use, kept for every later study).
    pub fn measure(&mut self, specs: &[TrialSpec], keep: Keep) -> Result<Vec<Measured>> {
        for s in specs.iter().filter(|s| s.wants_reference()) {
            self.ask(&s.scene)?;
        }
        let tracker = self.tracker;
        tracker.start(self.study, vec![1.0; specs.len()], f64::INFINITY);
        let measured = measure_all(specs, &mut self.references, keep, &|t| tracker.tick(t));
        tracker.finish();
        measured
    }

    /// Measures trials that need no reference (counts, not differences).
    pub fn measure_alone(&mut self, specs: &[TrialSpec], keep: Keep) -> Result<Vec<Measured>> {
        let tracker = self.tracker;
        tracker.start(self.study, vec![1.0; specs.len()], f64::INFINITY);
        let measured = measure_all(specs, &mut References::none(), keep, &|t| tracker.tick(t));
        tracker.finish();
        measured
    }

    /// The reference of `scene`, earned on first use.
    pub fn reference(&mut self, scene: &Scene, settings: &Settings) -> Result<Option<&Reference>> {
        self.ask(scene)?;
        self.references.get(scene, settings)
    }

    /// The keys of the references the current study asked for, in order.
    pub fn asked(&self) -> &[String] {
        &self.asked
    }

    /// The candidates of the references the current study asked for, in
    /// the order it asked: its references file.
    pub fn candidates(&self) -> Vec<Candidate> {
        self.references.candidates_for(&self.asked)
    }
}

/// A study: what it is called, and how it runs in a lab.
pub trait Study {
    /// Its name in logs and in the manifest.
    fn name(&self) -> &'static str;

    /// Plans and measures its trials in `lab`, records what the report
    /// needs in `findings`, and gives its artifacts.
    fn run(&self, lab: &mut Lab, findings: &mut Findings) -> Result<Vec<Artifact>>;
}
