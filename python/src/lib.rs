//! `contactlab._contactlab`: the compiled half of the Python package.
//!
//! It exposes the library's own functions, not copies of them: a problem is
//! the scene assembled by [`Discretization`] (the one the CLI solves), a
//! solve is the library's [`solve_assembled`] on the problem's own finest level (not
//! assembled again) with settings resolved by [`Settings::set_text`]
//! (the CLI's `--set`), a certificate is [`certify`] (the CLI's `certify`).
//! The Python layer (`contactlab/__init__.py`) turns the plain arrays given
//! here into scipy and numpy objects. Every error is one
//! `contactlab.Error` with the CLI's one-line message.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use contactlab::certificate::certify as certify_answer;
use contactlab::mechanics::discretization::Discretization;
use contactlab::mechanics::mesh_size::MeshSize;
use contactlab::mechanics::scene::{Overrides, Scene};
use contactlab::settings::{Changes, Settings};
use contactlab::solve::{Assembled, Caps, solve as solve_assembled, solver_entry};
use contactlab::solvers::numerics::linalg::{ColumnIndex, SparseRows};
use contactlab::solvers::{Control, Friction, Observer, Progress, Status, registry};
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1};
use pyo3::create_exception;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

create_exception!(
    _contactlab,
    Error,
    PyValueError,
    "A contactlab error: the same one-line message as the command line's."
);

fn err(e: impl std::fmt::Display) -> PyErr {
    Error::new_err(e.to_string())
}

fn anyhow_err(e: anyhow::Error) -> PyErr {
    Error::new_err(format!("{e:#}"))
}

/// A flag a long computation reads at each progress event: set when the
/// caller was interrupted (Ctrl-C), so that a computation left running on
/// its thread stops at its next event.
#[derive(Clone, Default)]
struct Cancel(Arc<AtomicBool>);

impl Observer for Cancel {
    fn observe(&mut self, _: &Progress) -> Control {
        if self.0.load(Ordering::Relaxed) {
            Control::Stop(Status::NotRun)
        } else {
            Control::Continue
        }
    }
}

/// How often a waiting call looks for Ctrl-C.
const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// Runs `work` on a thread of its own while this thread waits with the GIL
/// released, looking for signals every [`SIGNAL_POLL`]: Ctrl-C raises
/// `KeyboardInterrupt` within a fraction of a second and leaves the
/// session usable, whatever the work is doing (a factorization cannot be
/// interrupted, so the work is left to end on its thread, told to stop at
/// its next progress event, its answer dropped). A panic in the work is a
/// `contactlab.Error`, never a `PanicException`.
fn interruptible<T, F>(py: Python<'_>, work: F) -> PyResult<T>
where
    T: Send + 'static,
    F: FnOnce(Cancel) -> anyhow::Result<T> + Send + 'static,
{
    let cancel = Cancel::default();
    let theirs = cancel.clone();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::Builder::new()
        .name("contactlab".into())
        .spawn(move || {
            let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| work(theirs)));
            let _ = tx.send(result);
        })
        .map_err(|e| err(format!("cannot start the computation's thread: {e}")))?;
    // The receiver behind a lock, so that the wait can leave the GIL.
    let rx = std::sync::Mutex::new(rx);
    loop {
        let received = py.detach(|| {
            rx.lock()
                .unwrap_or_else(|e| e.into_inner())
                .recv_timeout(SIGNAL_POLL)
        });
        match received {
            Ok(Ok(result)) => return result.map_err(anyhow_err),
            Ok(Err(panic)) => {
                let what = panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                return Err(err(format!("internal error (please report it): {what}")));
            }
            Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
                if let Err(e) = py.check_signals() {
                    cancel.0.store(true, Ordering::Relaxed);
                    return Err(e);
                }
            }
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                return Err(err(
                    "internal error: the computation ended without an answer",
                ));
            }
        }
    }
}

/// The scene of a problem, the settings it brings (a scene file's), and
/// its assembly on the finest mesh (shared with the computations that
/// read it on their own threads).
#[pyclass(frozen, module = "contactlab._contactlab")]
struct Problem {
    scene: Arc<Scene>,
    settings: Settings,
    finest: Arc<Discretization>,
}

/// The scene with the overrides of `solve --problem/--scene`, applied by
/// the library's [`Overrides`] (as the command line does), and assembled
/// (interruptibly, and refused up front if it would not fit in memory).
#[allow(clippy::too_many_arguments)]
fn build(
    py: Python<'_>,
    scene: Scene,
    settings: Settings,
    h: Option<&str>,
    young: Option<f64>,
    poisson: Option<f64>,
    plane: Option<&str>,
    friction: Option<f64>,
) -> PyResult<Problem> {
    let h = h
        .map(|h| h.parse::<MeshSize>().map_err(|m| err(format!("h: {m}"))))
        .transpose()?;
    let plane = plane
        .map(|p| {
            use contactlab::mechanics::material::PlaneModel;
            PlaneModel::ALL
                .into_iter()
                .find(|m| m.name() == p.trim())
                .ok_or_else(|| err(format!("plane = '{p}': give 'strain' or 'stress'")))
        })
        .transpose()?;
    let overrides = Overrides {
        h,
        young,
        poisson,
        plane,
        friction,
    };
    let scene = overrides.apply(scene).map_err(err)?;
    let (scene, finest) = interruptible(py, move |_| {
        let finest = Discretization::new(&scene, scene.finest())?;
        Ok((scene, finest))
    })?;
    Ok(Problem {
        scene: Arc::new(scene),
        settings,
        finest: Arc::new(finest),
    })
}

/// A sparse matrix as numpy arrays: (indptr, indices, data).
type Csr<'py> = (
    Bound<'py, PyArray1<usize>>,
    Bound<'py, PyArray1<usize>>,
    Bound<'py, PyArray1<f64>>,
);

fn csr<'py, A: SparseRows>(py: Python<'py>, a: &A) -> Csr<'py> {
    let cols: Vec<usize> = a.col_indices().iter().map(|&c| c.at()).collect();
    (
        a.row_offsets().to_vec().into_pyarray(py),
        cols.into_pyarray(py),
        a.values().to_vec(a.row_offsets()).into_pyarray(py),
    )
}

#[pymethods]
impl Problem {
    /// The paper's problem `number` (1, 2 or 3).
    #[staticmethod]
    #[pyo3(signature = (number, h=None, young=None, poisson=None, plane=None, friction=None))]
    fn paper(
        py: Python<'_>,
        number: i64,
        h: Option<&str>,
        young: Option<f64>,
        poisson: Option<f64>,
        plane: Option<&str>,
        friction: Option<f64>,
    ) -> PyResult<Self> {
        let number = u32::try_from(number).map_err(|_| {
            err(format!(
                "number = {number}: give the paper's problem 1, 2 or 3"
            ))
        })?;
        let scene = Scene::paper_problem(number).map_err(err)?;
        build(
            py,
            scene,
            Settings::default(),
            h,
            young,
            poisson,
            plane,
            friction,
        )
    }

    /// A scene file (TOML, as `solve --scene` reads it), with the settings
    /// it brings: every solve of the problem starts from them, as the
    /// command line's does.
    #[staticmethod]
    #[pyo3(signature = (path, h=None, young=None, poisson=None, plane=None, friction=None))]
    #[allow(clippy::too_many_arguments)]
    fn from_scene(
        py: Python<'_>,
        path: std::path::PathBuf,
        h: Option<&str>,
        young: Option<f64>,
        poisson: Option<f64>,
        plane: Option<&str>,
        friction: Option<f64>,
    ) -> PyResult<Self> {
        let (scene, settings) = contactlab::formats::scene_file::load(&path).map_err(err)?;
        build(py, scene, settings, h, young, poisson, plane, friction)
    }

    #[getter]
    fn name(&self) -> String {
        self.scene.name.clone()
    }

    #[getter]
    fn h(&self) -> String {
        self.finest.h().to_string()
    }

    #[getter]
    fn n(&self) -> usize {
        self.finest.problem.n()
    }

    /// A in CSR: (indptr, indices, data).
    fn _a<'py>(&self, py: Python<'py>) -> Csr<'py> {
        csr(py, self.finest.problem.a())
    }

    /// M, the mass matrix of the proximal term, in CSR.
    fn _m<'py>(&self, py: Python<'py>) -> PyResult<Csr<'py>> {
        let m = self
            .finest
            .problem
            .mass()
            .ok_or_else(|| err("this problem was assembled without its mass matrix M"))?;
        Ok(csr(py, &*m))
    }

    #[getter]
    fn f<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.finest.problem.f().to_vec().into_pyarray(py)
    }

    /// The contact nodes: t, s (indices of the jump and slip unknowns),
    /// weight, coefficient (𝓕) and x, each an array.
    fn _contact<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let c = self.finest.problem.contacts();
        let d = PyDict::new(py);
        d.set_item(
            "t",
            c.iter().map(|c| c.t).collect::<Vec<_>>().into_pyarray(py),
        )?;
        d.set_item(
            "s",
            c.iter().map(|c| c.s).collect::<Vec<_>>().into_pyarray(py),
        )?;
        d.set_item(
            "weight",
            c.iter()
                .map(|c| c.weight)
                .collect::<Vec<_>>()
                .into_pyarray(py),
        )?;
        d.set_item(
            "coefficient",
            c.iter()
                .map(|c| c.coefficient)
                .collect::<Vec<_>>()
                .into_pyarray(py),
        )?;
        d.set_item("x", self.finest.contact_x().into_pyarray(py))?;
        Ok(d)
    }

    /// The problem's own scales (force, contact load, length of Γ_K,
    /// stiffness, pressure P, displacement U): what the certificate and the
    /// comparisons measure in.
    #[getter]
    fn scales<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = self.finest.problem.scales();
        let d = PyDict::new(py);
        for (name, value) in [
            ("force", s.force),
            ("contact_load", s.contact_load),
            ("length", s.length),
            ("stiffness", s.stiffness),
            ("pressure", s.pressure),
            ("displacement", s.displacement),
        ] {
            d.set_item(name, value)?;
        }
        Ok(d)
    }

    /// The upper body's vertical translation in the unknowns (A's kernel).
    #[getter]
    fn rigid_mode<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        self.finest.kernel_vector().into_pyarray(py)
    }

    fn __repr__(&self) -> String {
        format!(
            "Problem({}, h = {}, {} unknowns, {} contact nodes)",
            self.scene.name,
            self.finest.h(),
            self.finest.problem.n(),
            self.finest.problem.contacts().len()
        )
    }
}

/// The registered solvers' names.
#[pyfunction]
fn solvers() -> Vec<&'static str> {
    registry::names()
}

/// The problem's settings (a scene file's, or the defaults) with
/// `{path: value}` applied in order by the code the command line resolves
/// its flags with ([`Changes`]: the later change of a setting wins), and
/// refused if they set a setting of a solver the solve does not use.
fn settings_from(
    base: &Settings,
    items: Vec<(String, String)>,
    running: &[&'static registry::Entry],
) -> PyResult<Settings> {
    let mut changes = Changes::default();
    for (path, text) in &items {
        changes.push(path, text, &format!("settings[{path:?}]"));
    }
    changes
        .check_used_by(running, &contactlab::settings::changes::AS_PATHS)
        .map_err(err)?;
    changes.apply_to(base.clone()).map_err(err)
}

/// A friction bound given from Python: one finite value ≥ 0 per contact
/// node, checked as a solve checks it.
fn bound_checked(problem: &Problem, g: &[f64]) -> PyResult<()> {
    Friction::Given(g)
        .check(&problem.finest.problem)
        .map_err(|m| err(format!("bound: {m}")))
}

/// The certificate as a dict: passed, tolerance, summary, violations by
/// condition.
fn certificate_dict<'py>(
    py: Python<'py>,
    c: &contactlab::certificate::Certificate,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("passed", c.passed())?;
    d.set_item("tolerance", c.tolerance)?;
    d.set_item("summary", c.summary())?;
    d.set_item("residual", c.residual())?;
    let v = PyDict::new(py);
    for (cond, x) in c.measures() {
        v.set_item(cond.as_str(), x)?;
    }
    d.set_item("violations", v)?;
    Ok(d)
}

/// One solve of the problem's Coulomb law (or the given-friction subproblem
/// at `bound`), certified: the CLI's `solve`.
#[pyfunction]
#[pyo3(signature = (problem, solver=None, settings=Vec::new(), bound=None, target=None))]
fn solve<'py>(
    py: Python<'py>,
    problem: &Problem,
    solver: Option<&str>,
    settings: Vec<(String, String)>,
    bound: Option<Vec<f64>>,
    target: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let entry = match solver {
        Some(name) => solver_entry(name).map_err(anyhow_err)?,
        None => registry::with_role(registry::Role::Oracle)
            .ok_or_else(|| err("no oracle is registered"))?,
    };
    let mut settings = settings_from(&problem.settings, settings, &[entry])?;
    if let Some(t) = target {
        // The benchmark's rule: the solver's accuracy knob and ε at a safety
        // factor below the target, the certificate at the target.
        let t = contactlab::certificate::check_tolerance(t)
            .map_err(|m| err(format!("target = {m}")))?;
        settings = contactlab::study::benchmark::target_settings(entry, &settings, t)
            .map_err(anyhow_err)?;
    }
    if let Some(g) = &bound {
        bound_checked(problem, g)?;
    }
    let (scene, finest) = (problem.scene.clone(), problem.finest.clone());
    let solved = interruptible(py, move |cancel| {
        let friction = match &bound {
            Some(g) => Friction::Given(g),
            None => Friction::Coulomb,
        };
        // The problem's finest level, copied (far cheaper than its
        // assembly); the coarser levels of a continuation are assembled.
        let assembled = Assembled::with_finest(&scene, entry, (*finest).clone())?;
        let mut observer = cancel;
        solve_assembled(
            assembled,
            friction,
            entry,
            &settings,
            Caps::default(),
            &mut observer,
        )
    })?;
    let o = &solved.outcome;
    let d = PyDict::new(py);
    d.set_item("solver", entry.name)?;
    d.set_item("status", o.status.to_string())?;
    d.set_item("solver_status", o.claim.to_string())?;
    d.set_item("detail", o.detail.clone())?;
    d.set_item("certificate", certificate_dict(py, &o.certificate)?)?;
    let s = &o.solution;
    d.set_item("displacements", s.v.clone().into_pyarray(py))?;
    d.set_item("pressure", s.pressure.clone().into_pyarray(py))?;
    d.set_item(
        "friction_traction",
        s.friction_traction.clone().into_pyarray(py),
    )?;
    d.set_item("bound", o.bound.clone().into_pyarray(py))?;
    let it = PyDict::new(py);
    it.set_item("friction", o.friction_iterations())?;
    it.set_item("outer", o.work.outer)?;
    it.set_item("inner", o.work.inner)?;
    d.set_item("iterations", it)?;
    d.set_item("seconds", o.timing.total())?;
    d.set_item("seconds_setup", o.timing.setup)?;
    // The bytes `solve --out` writes to profile.csv, by the same code.
    let profile = contactlab::io::csv::to_csv(
        &solved.profile(),
        &contactlab::mechanics::contact_zone::PROFILE_COLUMNS,
    )
    .map_err(anyhow_err)?;
    d.set_item(
        "profile_csv",
        String::from_utf8_lossy(&profile).into_owned(),
    )?;
    Ok(d)
}

/// The certificate of an answer computed elsewhere: the CLI's `certify`.
/// Give the displacements, or the contact forces (pressure and friction
/// traction), or both; the missing half follows as `certify` derives it.
#[pyfunction]
#[pyo3(signature = (problem, displacements=None, pressure=None, friction_traction=None, bound=None, tolerance=None))]
fn certify<'py>(
    py: Python<'py>,
    problem: &Problem,
    displacements: Option<PyReadonlyArray1<'py, f64>>,
    pressure: Option<PyReadonlyArray1<'py, f64>>,
    friction_traction: Option<PyReadonlyArray1<'py, f64>>,
    bound: Option<PyReadonlyArray1<'py, f64>>,
    tolerance: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let cp = &problem.finest.problem;
    let (n, m) = (cp.n(), cp.contacts().len());
    let slice = |name: &str, a: &Option<PyReadonlyArray1<'py, f64>>, len: usize| {
        a.as_ref()
            .map(|a| -> PyResult<Vec<f64>> {
                let v = a.as_slice().map_err(err)?.to_vec();
                if v.len() != len {
                    return Err(err(format!(
                        "{name} has {} values, expected {len}",
                        v.len()
                    )));
                }
                if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                    return Err(err(format!("{name}[{i}] is {}: give finite values", v[i])));
                }
                Ok(v)
            })
            .transpose()
    };
    let v = slice("displacements", &displacements, n)?;
    let p = slice("pressure", &pressure, m)?;
    let q = slice("friction_traction", &friction_traction, m)?;
    let g = slice("bound", &bound, m)?;
    if let Some(g) = &g {
        bound_checked(problem, g)?;
    }
    let forces = match (p, q) {
        (Some(p), Some(q)) => Some((p, q)),
        (None, None) => None,
        _ => {
            return Err(err("give both pressure and friction_traction, or neither"));
        }
    };
    let tolerance = match tolerance {
        Some(t) => contactlab::certificate::check_tolerance(t)
            .map_err(|m| err(format!("tolerance = {m}")))?,
        None => contactlab::certificate::DEFAULT_TOLERANCE,
    };
    let finest = problem.finest.clone();
    let (c, v, p, q) = interruptible(py, move |_| {
        let cp = &finest.problem;
        let (v, p, q) = contactlab::formats::instance::complete_answer(cp, v, forces)?;
        let friction = match &g {
            Some(g) => Friction::Given(g),
            None => Friction::Coulomb,
        };
        Ok((certify_answer(cp, friction, &v, &p, &q, tolerance), v, p, q))
    })?;
    let friction_law = if bound.is_some() {
        contactlab::solvers::Law::GivenFriction
    } else {
        contactlab::solvers::Law::Coulomb
    };
    let d = certificate_dict(py, &c)?;
    d.set_item("law", friction_law.as_str())?;
    // The answer the certificate judged, completed (forces from the
    // displacements by stationarity, or displacements from the forces).
    d.set_item("displacements", v.into_pyarray(py))?;
    d.set_item("pressure", p.into_pyarray(py))?;
    d.set_item("friction_traction", q.into_pyarray(py))?;
    Ok(d)
}

/// A work-precision chart of a study's trials, drawn by the charts of the
/// command line: per solver, certified points joined, failed ones as
/// crosses. `trials`: (solver, accuracy, seconds, certified).
#[pyfunction]
fn _work_precision_chart(
    title: String,
    x_label: String,
    trials: Vec<(String, f64, f64, bool)>,
    path: std::path::PathBuf,
) -> PyResult<()> {
    use contactlab::io::charts::{Chart, Series};
    let mut names: Vec<&str> = Vec::new();
    for (s, ..) in &trials {
        if !names.contains(&s.as_str()) {
            names.push(s);
        }
    }
    let mut series = Vec::new();
    for name in names {
        let points = |ok: bool| {
            let mut p: Vec<(f64, f64)> = trials
                .iter()
                .filter(|t| t.0 == name && t.3 == ok && t.1 > 0.0 && t.2 > 0.0)
                .map(|t| (t.1, t.2))
                .collect();
            p.sort_by(|a, b| a.0.total_cmp(&b.0));
            p
        };
        series.extend(Series::certified_and_failed(
            name,
            points(true),
            points(false),
        ));
    }
    let chart = Chart::new(&title, &x_label, "seconds", true, true, series);
    chart.write(&path).map_err(anyhow_err)
}

/// The benchmark's views of runs made in Python (registered solvers and
/// Python functions alike), by the code of `contactlab benchmark`: the
/// per-solver summaries (JSON) and the report (markdown). With `out`, the
/// run folder the command line writes (benchmark.csv, benchmark_summary.csv,
/// benchmark.md, a LaTeX table per target, the performance profiles),
/// replaced whole and only if it is empty or a contactlab run. `rows_json`:
/// the rows as `benchmark.csv` has them (`BenchmarkRow`), the certificate
/// as a string.
#[pyfunction]
#[pyo3(signature = (rows_json, out=None))]
fn _benchmark_report(
    rows_json: &str,
    out: Option<std::path::PathBuf>,
) -> PyResult<(String, String)> {
    use contactlab::study::benchmark::{BenchmarkRow, views};
    use contactlab::study::lab::{Artifact, write_artifacts};
    let rows: Vec<BenchmarkRow> =
        serde_json::from_str(rows_json).map_err(|e| err(format!("benchmark rows: {e}")))?;
    if rows.is_empty() {
        return Err(err(
            "benchmark: no runs; give at least one problem, solver and target",
        ));
    }
    if let Some(dir) = out {
        let folder = contactlab::io::run_folder::RunFolder::create(&dir).map_err(anyhow_err)?;
        let mut artifacts = vec![Artifact::csv("benchmark.csv", &rows, &[]).map_err(anyhow_err)?];
        artifacts.extend(views::artifacts(&rows).map_err(anyhow_err)?);
        write_artifacts(folder.path(), &artifacts).map_err(anyhow_err)?;
        folder.commit().map_err(anyhow_err)?;
    }
    let summaries = serde_json::to_string(&views::summaries(&rows)).map_err(err)?;
    Ok((summaries, views::report(&rows)))
}

#[pymodule]
fn _contactlab(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Problem>()?;
    m.add_function(wrap_pyfunction!(solvers, m)?)?;
    m.add_function(wrap_pyfunction!(solve, m)?)?;
    m.add_function(wrap_pyfunction!(certify, m)?)?;
    m.add_function(wrap_pyfunction!(_work_precision_chart, m)?)?;
    m.add_function(wrap_pyfunction!(_benchmark_report, m)?)?;
    m.add("Error", m.py().get_type::<Error>())?;
    Ok(())
}
