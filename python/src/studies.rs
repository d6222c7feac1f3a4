//! The studies from Python: the library's own studies (`Compare`,
//! `Benchmark`, `WorkPrecision`), run in a lab like the command line's,
//! with settings resolved by the library's one resolution
//! ([`Changes::resolve`]). They give the files the command line writes
//! (the same bytes for the same inputs) and the study's README section;
//! with `out`, the run folder is written as the command line writes it.

use std::path::PathBuf;

use contactlab::io::run_folder::RunFolder;
use contactlab::settings::Settings;
use contactlab::settings::changes::AS_PATHS;
use contactlab::solve::solver_entry;
use contactlab::solvers::registry::Entry;
use contactlab::study::benchmark::{Benchmark, BenchmarkSpec, Instance};
use contactlab::study::compare::Compare;
use contactlab::study::lab::{Content, Lab, Planned, RunLength, Study, Tracker, write_artifacts};
use contactlab::study::side_by_side::{SideBySide, parse_side, solvers_of};
use contactlab::study::studies as catalog;
use contactlab::study::sweep::{Sweep, SweepSpec};
use contactlab::study::tuning_map::{Axis, TuningMap};
use contactlab::study::work_precision::WorkPrecision;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

use crate::problem::Problem;
use crate::{changes_of, input_error, interruptible};

/// The solvers named (registered ones, Python solvers among them).
fn entries(names: &[String]) -> PyResult<Vec<&'static Entry>> {
    if names.is_empty() {
        return Err(input_error("solvers: give at least one solver"));
    }
    names
        .iter()
        .map(|n| solver_entry(n).map_err(crate::error_of))
        .collect()
}

/// Target accuracies: at least one, each a tolerance the certificate takes
/// (`example`: what to write instead of none).
fn check_targets(targets: &[f64], example: &str) -> PyResult<()> {
    if targets.is_empty() {
        return Err(input_error(format!(
            "targets: give at least one accuracy, such as {example}"
        )));
    }
    for t in targets {
        contactlab::certificate::check_tolerance(*t)
            .map_err(|m| input_error(format!("targets: {m}")))?;
    }
    Ok(())
}

/// `base` with `settings` applied for a run of `running`.
fn resolved(
    base: &Settings,
    settings: Vec<(String, String)>,
    running: &[&'static Entry],
) -> PyResult<Settings> {
    changes_of(&settings)
        .resolve(base.clone(), running, &AS_PATHS)
        .map_err(|r| input_error(r.to_string()))
}

/// Runs `study` at `settings` on a thread of its own (Ctrl-C returns at
/// once), writes its files into `out` as the command line does, and gives
/// `{files: {path: bytes}, tables: {path: JSON records}, report: markdown,
/// charts: {name: svg bytes}}`: each CSV file's rows as typed records
/// (JSON text of the Rust rows, [`contactlab::io::csv::records`]), so
/// that Python reads data, never a file back.
/// A study's progress as Python sees it: nothing shown, and Ctrl-C (the
/// waiting call's [`crate::Cancel`]) read after every trial, so that an
/// interrupted study stops at the next trial instead of computing on in
/// the background and writing its folder.
struct Interruptible(crate::Cancel);

impl Tracker for Interruptible {
    fn start(&self, _: &str, _: Vec<f64>, _: f64) {}
    fn tick(&self, _: &contactlab::study::trial::TrialSpec) {}
    fn finish(&self) {}
    fn interrupted(&self) -> bool {
        (self.0).0.load(std::sync::atomic::Ordering::Relaxed)
    }
}

fn run<S>(
    py: Python<'_>,
    study: S,
    settings: Settings,
    out: Option<PathBuf>,
) -> PyResult<Bound<'_, PyDict>>
where
    S: Study + Send + 'static,
{
    run_planned(py, Box::new(study), settings, out)
}

/// [`run`] for a study whose type is erased (a catalogued one).
fn run_planned(
    py: Python<'_>,
    study: Box<dyn Planned + Send>,
    settings: Settings,
    out: Option<PathBuf>,
) -> PyResult<Bound<'_, PyDict>> {
    let folder = out
        .map(|o| RunFolder::create(&o).map_err(crate::error_of))
        .transpose()?;
    let (files, tables, charts, report) = interruptible(py, move |cancel| {
        let log = |_: &str| {};
        let tracker = Interruptible(cancel);
        let mut lab = Lab::new(settings, &log, &tracker);
        let (artifacts, section) = study.run_for_report(&mut lab)?;
        if tracker.interrupted() {
            anyhow::bail!("interrupted: the study wrote nothing");
        }
        if let Some(folder) = folder {
            write_artifacts(folder.path(), &artifacts)?;
            folder.commit()?;
        }
        let mut files = Vec::new();
        let mut tables = Vec::new();
        let mut charts = Vec::new();
        for a in &artifacts {
            if let Content::Bytes(b) = &a.content {
                files.push((a.path.clone(), b.clone()));
            }
            if let Some(r) = &a.records {
                tables.push((a.path.clone(), r.clone()));
            }
            if let Some(svg) = a.content.svg() {
                let name = a.chart_name().unwrap_or_default().to_string();
                charts.push((name, svg?.into_bytes()));
            }
        }
        Ok((files, tables, charts, section.markdown))
    })?;
    let d = PyDict::new(py);
    let f = PyDict::new(py);
    for (path, bytes) in files {
        f.set_item(path, PyBytes::new(py, &bytes))?;
    }
    let t = PyDict::new(py);
    for (path, json) in tables {
        t.set_item(path, json)?;
    }
    let c = PyDict::new(py);
    for (name, bytes) in charts {
        c.set_item(name, PyBytes::new(py, &bytes))?;
    }
    d.set_item("files", f)?;
    d.set_item("tables", t)?;
    d.set_item("charts", c)?;
    d.set_item("report", report)?;
    Ok(d)
}

/// `contactlab compare`: every solver on the problem's scene against the
/// earned reference.
#[pyfunction]
#[pyo3(signature = (problem, solvers, settings=Vec::new(), repeats=0, out=None, reference=None))]
pub fn _compare<'py>(
    py: Python<'py>,
    problem: &Problem,
    solvers: Vec<String>,
    settings: Vec<(String, String)>,
    repeats: usize,
    out: Option<PathBuf>,
    reference: Option<String>,
) -> PyResult<Bound<'py, PyDict>> {
    let (scene, _) = problem.scene("compare")?;
    let solvers = entries(&solvers)?;
    let settings = resolved(&problem.settings, settings, &solvers)?;
    let reference = reference
        .map(|r| solver_entry(&r).map_err(crate::error_of))
        .transpose()?;
    let study = Compare {
        scene: (**scene).clone(),
        solvers,
        repeats,
        reference,
    };
    run(py, study, settings, out)
}

/// `contactlab compare --side-by-side A,B ...`: each pair of answers node
/// by node; a side is a solver, `reference` (the earned one) or the path of
/// a `profile.csv`.
#[pyfunction]
#[pyo3(signature = (problem, pairs, settings=Vec::new(), out=None))]
pub fn _side_by_side<'py>(
    py: Python<'py>,
    problem: &Problem,
    pairs: Vec<(String, String)>,
    settings: Vec<(String, String)>,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let (scene, _) = problem.scene("side_by_side")?;
    if pairs.is_empty() {
        return Err(input_error(
            "pairs: give at least one pair, such as [(\"relaxation\", \"reference\")]",
        ));
    }
    let pairs = pairs
        .iter()
        .map(|(a, b)| Ok((parse_side(a)?, parse_side(b)?)))
        .collect::<anyhow::Result<Vec<_>>>()
        .map_err(crate::error_of)?;
    let study = SideBySide::new((**scene).clone(), pairs).map_err(crate::error_of)?;
    let settings = resolved(&problem.settings, settings, &solvers_of(&study.pairs))?;
    run(py, study, settings, out)
}

/// `contactlab sweep --grid ... --grid ...`: a tuning map of one solver.
#[pyfunction]
#[pyo3(signature = (problem, solver, axes, law, repeats, settings=Vec::new(), out=None, time_limit=None))]
#[allow(clippy::too_many_arguments)]
pub fn _tuning_map<'py>(
    py: Python<'py>,
    problem: &Problem,
    solver: String,
    axes: Vec<(String, Vec<String>)>,
    law: String,
    repeats: usize,
    settings: Vec<(String, String)>,
    out: Option<PathBuf>,
    time_limit: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    if let Some(t) = time_limit
        && !(t.is_finite() && t > 0.0)
    {
        return Err(input_error(format!(
            "time_limit = {t}: give the seconds each point's solve may take, a number > 0 (or None)"
        )));
    }
    let (scene, _) = problem.scene("tuning_map")?;
    let entry = solver_entry(&solver).map_err(crate::error_of)?;
    if !(2..=3).contains(&axes.len()) {
        return Err(input_error(format!(
            "axes: a tuning map takes two or three settings, got {}",
            axes.len()
        )));
    }
    let axes: Vec<Axis> = axes
        .into_iter()
        .map(|(path, values)| {
            if values.len() < 2 {
                Err(input_error(format!(
                    "axes: {path}: give at least two values"
                )))
            } else {
                Ok(Axis { path, values })
            }
        })
        .collect::<PyResult<_>>()?;
    let law = match law.as_str() {
        "coulomb" => contactlab::solvers::Law::Coulomb,
        "given_friction" | "given-friction" => contactlab::solvers::Law::GivenFriction,
        other => {
            return Err(input_error(format!(
                "law = {other:?}: give \"coulomb\" or \"given_friction\""
            )));
        }
    };
    contactlab::study::tuning_map::check_map(entry, law, &axes).map_err(crate::error_of)?;
    let settings = resolved(&problem.settings, settings, &[entry])?;
    let study = TuningMap {
        scene: (**scene).clone(),
        solver: entry,
        law,
        axes,
        repeats,
        tag: None,
        point_seconds: time_limit,
    };
    run(py, study, settings, out)
}

/// `contactlab benchmark` over the given problems: every solver at every
/// target on every problem, certified at the target, within the time limit.
#[pyfunction]
#[pyo3(signature = (problems, solvers, targets, time_limit, settings=Vec::new(), out=None))]
pub fn _benchmark<'py>(
    py: Python<'py>,
    problems: Vec<PyRef<'py, Problem>>,
    solvers: Vec<String>,
    targets: Vec<f64>,
    time_limit: f64,
    settings: Vec<(String, String)>,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    if problems.is_empty() {
        return Err(input_error("problems: give at least one problem"));
    }
    check_targets(&targets, "[1e-4]")?;
    if !(time_limit.is_finite() && time_limit > 0.0) {
        return Err(input_error(format!(
            "time_limit = {time_limit}: give a positive number of seconds"
        )));
    }
    let solvers = entries(&solvers)?;
    let mut instances = Vec::new();
    for p in &problems {
        let (scene, _) = p.scene("benchmark")?;
        instances.push(Instance::given((**scene).clone()));
    }
    let settings = resolved(&problems[0].settings, settings, &solvers)?;
    let mut spec = BenchmarkSpec::new(false, solvers);
    spec.targets = targets;
    spec.time_limit = time_limit;
    spec.instances = Some(instances);
    run(py, Benchmark { spec }, settings, out)
}

/// Work against precision: each solver at each target on the problem.
#[pyfunction]
#[pyo3(signature = (problem, solvers, targets, settings=Vec::new(), repeats=0, out=None))]
pub fn _work_precision<'py>(
    py: Python<'py>,
    problem: &Problem,
    solvers: Vec<String>,
    targets: Vec<f64>,
    settings: Vec<(String, String)>,
    repeats: usize,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let (scene, _) = problem.scene("work_precision")?;
    check_targets(&targets, "[1e-4, 1e-8]")?;
    let solvers = entries(&solvers)?;
    let settings = resolved(&problem.settings, settings, &solvers)?;
    let study = WorkPrecision {
        scene: (**scene).clone(),
        solvers,
        targets,
        repeats,
    };
    run(py, study, settings, out)
}

/// `contactlab sweep` on the problem's scene and mesh: each solver's
/// registry variations of the Coulomb problem and its accuracy knob on the
/// subproblem (work-precision), against the earned reference.
#[pyfunction]
#[pyo3(signature = (problem, solvers, settings=Vec::new(), quick=false, work_precision=true, repeats=2, out=None))]
#[allow(clippy::too_many_arguments)]
pub fn _sweep<'py>(
    py: Python<'py>,
    problem: &Problem,
    solvers: Vec<String>,
    settings: Vec<(String, String)>,
    quick: bool,
    work_precision: bool,
    repeats: usize,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let (scene, finest) = problem.scene("sweep")?;
    let solvers = entries(&solvers)?;
    let settings = resolved(&problem.settings, settings, &solvers)?;
    let spec = SweepSpec {
        scenes: vec![(**scene).clone()],
        meshes: vec![finest.h()],
        fine_meshes: Vec::new(),
        solvers,
        variations: true,
        work_precision,
        quick,
        repeats,
        work_scale: 1.0,
    };
    let planned = contactlab::study::sweep::plan(&spec, &settings).map_err(crate::error_of)?;
    if planned.is_empty() {
        return Err(input_error(
            "the sweep plans no trials: these solvers have no settings to vary in the registry's sweeps \
             and work_precision=False skips the work-precision diagram",
        ));
    }
    let study = Sweep {
        spec,
        extra: Vec::new(),
        references_file: "references.csv",
    };
    run(py, study, settings, out)
}

/// The catalogued studies: (command, help, its spec at the default run
/// length as JSON), what Python makes a call of each from.
#[pyfunction]
pub fn _studies() -> PyResult<Vec<(String, String, String)>> {
    catalog::catalog()
        .into_iter()
        .map(|e| {
            let spec = e
                .spec_json(RunLength::Standard)
                .map_err(crate::error_of)?
                .to_string();
            Ok((e.command().to_string(), e.about().to_string(), spec))
        })
        .collect()
}

/// The catalogued study `command` at the run length `length` (`quick`,
/// `standard` or `long`), its spec's fields replaced by the JSON object
/// `spec` (Python's keyword arguments), at `settings`.
#[pyfunction]
#[pyo3(signature = (command, length, spec, settings=Vec::new(), out=None))]
pub fn _study<'py>(
    py: Python<'py>,
    command: &str,
    length: &str,
    spec: &str,
    settings: Vec<(String, String)>,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let entry = catalog::by_command(command).ok_or_else(|| {
        let known: Vec<&str> = catalog::catalog().iter().map(|e| e.command()).collect();
        input_error(format!(
            "no study called {command:?}; the studies are {}",
            known.join(", ")
        ))
    })?;
    let length = match length {
        "quick" => RunLength::Quick,
        "standard" => RunLength::Standard,
        "long" => RunLength::Long,
        other => {
            return Err(input_error(format!(
                "length = {other:?}: give \"quick\", \"standard\" or \"long\""
            )));
        }
    };
    let study = entry
        .planned_with_json(length, spec)
        .map_err(|e| input_error(format!("{e:#}")))?;
    let settings = resolved(&entry.settings_base(), settings, &entry.offered_solvers())?;
    run_planned(py, study, settings, out)
}

/// Registers the Python function `f` as the solver `name` (see
/// [`crate::python_solver`]).
#[pyfunction]
pub fn register(name: &str, f: Py<PyAny>) -> PyResult<()> {
    crate::python_solver::register(name, f).map_err(input_error)?;
    Ok(())
}
