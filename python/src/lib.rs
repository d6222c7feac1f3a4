//! `contactlab._contactlab`: the compiled half of the Python package.
//!
//! It exposes the library's own functions, not copies of them: a problem is
//! the scene assembled by `Discretization` (the one the CLI solves) or an
//! algebraic problem checked like an imported instance ([`problem`]); a
//! solve is the library's [`solve_assembled`] (or [`solve_algebraic`]);
//! settings are resolved by the library's one resolution
//! ([`Changes::resolve`]); a certificate is [`certify`] (the CLI's
//! `certify`); the studies are the library's ([`studies`]); a Python
//! function is a registered solver ([`python_solver`]). The Python layer
//! (`contactlab/__init__.py`) holds types, conversions and documentation.
//! Every error is a `contactlab.Error` with the CLI's one-line message: an
//! `InputError` (also a `ValueError`), a `FileError` (also an `OSError`) or
//! an `OutOfMemory` (also a `MemoryError`).

mod problem;
mod python_solver;
mod studies;

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use contactlab::certificate::certify as certify_answer;
use contactlab::settings::Changes;
use contactlab::settings::changes::AS_PATHS;
use contactlab::solve::summary::bound_within_limit;
use contactlab::solve::{Assembled, Caps, solve as solve_assembled, solve_algebraic, solver_entry};
use contactlab::solvers::{Control, Friction, Observer, Progress, Status, registry};
use numpy::{IntoPyArray, PyReadonlyArray1};
use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use problem::{Problem, Source, vector};

create_exception!(
    _contactlab,
    Error,
    PyException,
    "A contactlab error: the same one-line message as the command line's."
);

/// The exception class `name` of this module (made at its start as a
/// subclass of both `Error` and a built-in one), else `Error`.
fn raise(kind: &str, message: String) -> PyErr {
    Python::attach(|py| {
        py.import("contactlab._contactlab")
            .and_then(|m| m.getattr(kind))
            .and_then(|t| Ok(PyErr::from_type(t.cast_into()?, message.clone())))
            .unwrap_or_else(|_| Error::new_err(message))
    })
}

/// Bad input: an `InputError`.
pub fn input_error(e: impl std::fmt::Display) -> PyErr {
    raise("InputError", e.to_string())
}

/// A library error as the exception it is: a file that cannot be read or
/// written (`FileError`), memory that would not suffice (`OutOfMemory`),
/// else bad input (`InputError`).
pub fn error_of(e: anyhow::Error) -> PyErr {
    let message = format!("{e:#}");
    let kind = if e.chain().any(|c| c.is::<std::io::Error>())
        || message.starts_with("cannot read ")
        || message.starts_with("cannot write ")
    {
        "FileError"
    } else if e.chain().any(|c| c.is::<contactlab::memory::MemoryError>())
        || message.starts_with("not enough memory")
    {
        "OutOfMemory"
    } else {
        "InputError"
    };
    raise(kind, message)
}

fn err(e: impl std::fmt::Display) -> PyErr {
    Error::new_err(e.to_string())
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
pub(crate) fn interruptible<T, F>(py: Python<'_>, work: F) -> PyResult<T>
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
            Ok(Ok(result)) => return result.map_err(error_of),
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

/// The registered solvers' names (Python solvers among them).
#[pyfunction]
fn solvers() -> Vec<&'static str> {
    registry::names()
}

/// Refuses, before the matrices are copied, a problem of `n` unknowns and
/// `nnz` stored entries whose copies would not fit in memory: Python's
/// lists of the CSR parts (about 100 B per entry) and the library's
/// problem ([`contactlab::memory::instance`]; the definiteness check's
/// factor checks its own room, and is skipped, saying so, without it).
#[pyfunction]
fn _check_problem_size(what: &str, n: usize, nnz: usize) -> PyResult<()> {
    let need = 100.0 * nnz as f64 + contactlab::memory::instance(n);
    contactlab::memory::check_need(what, need, n, Vec::new()).map_err(|e| error_of(e.into()))
}

/// The address space the library keeps aside beyond its estimates under
/// an address-space limit (the dense products' per-thread buffers, sized
/// by the L3 cache as sysfs reports it: 2.9 GB on a machine whose sysfs
/// says 480 MiB), so that a test can set a limit relative to it.
#[pyfunction]
fn _address_space_reserve() -> f64 {
    contactlab::memory::dense_product_reserve() + contactlab::memory::RESERVED_ADDRESS_SPACE
}

/// Every status a solve can end with, as written in output files.
#[pyfunction]
fn statuses() -> Vec<&'static str> {
    Status::ALL.iter().map(|s| s.as_str()).collect()
}

/// `{path: value}` items as the library's ordered changes (the later
/// change of a setting wins), each named as Python gave it.
pub(crate) fn changes_of(items: &[(String, String)]) -> Changes {
    let mut changes = Changes::default();
    for (path, text) in items {
        changes.push(path, text, &format!("settings[{path:?}]"));
    }
    changes
}

/// The certificate as a dict: passed, tolerance, summary, violations by
/// condition.
fn certificate_dict<'py>(
    py: Python<'py>,
    c: &contactlab::certificate::Certificate,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("passed", c.passed())?;
    d.set_item("law", c.law.as_str())?;
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

/// Progress for a Python callback: each event of a stage that keeps a
/// history (the friction fixed point, a solver's outer loop: not the many
/// inner sweeps) is given to `callback` as a dict; `False` (or an
/// exception, kept to be raised after the solve) stops the solve. Ctrl-C
/// stops it too ([`Cancel`]).
struct Callback {
    callback: Option<Py<PyAny>>,
    cancel: Cancel,
    stages: Vec<&'static str>,
    raised: Arc<Mutex<Option<PyErr>>>,
    stopped: Arc<AtomicBool>,
}

impl Observer for Callback {
    fn observe(&mut self, p: &Progress) -> Control {
        if self.cancel.observe(p) != Control::Continue || self.stopped.load(Ordering::Relaxed) {
            return Control::Stop(Status::NotRun);
        }
        let Some(f) = &self.callback else {
            return Control::Continue;
        };
        if !self.stages.contains(&p.stage) {
            return Control::Continue;
        }
        Python::attach(|py| {
            let d = PyDict::new(py);
            let call = || -> PyResult<bool> {
                d.set_item("stage", p.stage)?;
                d.set_item("iteration", p.iteration)?;
                d.set_item("residual", p.residual)?;
                d.set_item("seconds", p.seconds)?;
                let r = f.call1(py, (d.clone(),))?;
                let r = r.bind(py);
                Ok(r.is_none() || r.is_truthy()?)
            };
            match call() {
                Ok(true) => Control::Continue,
                Ok(false) => {
                    self.stopped.store(true, Ordering::Relaxed);
                    Control::Stop(Status::NotRun)
                }
                Err(e) => {
                    *self.raised.lock().unwrap_or_else(|e| e.into_inner()) = Some(e);
                    self.stopped.store(true, Ordering::Relaxed);
                    Control::Stop(Status::NotRun)
                }
            }
        })
    }
}

/// One solve of the problem's Coulomb law (or the given-friction subproblem
/// at `bound`), certified: the CLI's `solve`.
#[pyfunction]
#[pyo3(signature = (problem, solver=None, settings=Vec::new(), bound=None, target=None, callback=None))]
fn solve<'py>(
    py: Python<'py>,
    problem: &Problem,
    solver: Option<&str>,
    settings: Vec<(String, String)>,
    bound: Option<Vec<f64>>,
    target: Option<f64>,
    callback: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let entry = match solver {
        Some(name) => solver_entry(name).map_err(error_of)?,
        None => registry::with_role(registry::Role::Oracle)
            .ok_or_else(|| err("no oracle is registered"))?,
    };
    let mut settings = changes_of(&settings)
        .resolve(problem.settings.clone(), &[entry], &AS_PATHS)
        .map_err(input_error)?;
    if let Some(t) = target {
        // The benchmark's rule: the solver's accuracy knob and ε at a safety
        // factor below the target, the certificate at the target.
        let t = contactlab::certificate::check_tolerance(t)
            .map_err(|m| input_error(format!("target = {m}")))?;
        settings =
            contactlab::study::benchmark::target_settings(entry, &settings, t).map_err(error_of)?;
    }
    if let Some(g) = &bound {
        problem.bound_checked(g)?;
    }
    let raised = Arc::new(Mutex::new(None));
    let stopped = Arc::new(AtomicBool::new(false));
    let mut stages: Vec<&'static str> = entry
        .stages
        .iter()
        .filter(|s| s.history)
        .map(|s| s.name)
        .collect();
    stages.push(contactlab::coulomb::fixed_point::STAGE);
    let source = problem.source.clone();
    let (theirs, stop) = (raised.clone(), stopped.clone());
    // The answer's error bound, as `solve` prints it: the same gate
    // (certificate.bound_max_unknowns) and the same friction.
    let certificate = settings.certificate;
    let (outcome, profile, error_bound) = interruptible(py, move |cancel| {
        let friction = match &bound {
            Some(g) => Friction::Given(g),
            None => Friction::Coulomb,
        };
        let mut observer = Callback {
            callback,
            cancel,
            stages,
            raised: theirs,
            stopped: stop,
        };
        match source {
            Source::Scene { scene, finest } => {
                // The problem's finest level, lent: a copy took this solve's
                // peak from 1.90 to 3.04 GiB at h = 1/2048. The coarser
                // levels of a continuation are assembled, and so is the
                // finest for a solver that reads the mass matrix M, which
                // the problem does not hold.
                let assembled = if entry.uses_mass && !finest.problem.has_mass() {
                    Assembled::for_solver(&scene, entry)?
                } else {
                    Assembled::lending(&scene, entry, finest)?
                };
                let solved = solve_assembled(
                    assembled,
                    friction,
                    entry,
                    &settings,
                    Caps::default(),
                    &mut observer,
                )?;
                // The bytes `solve --out` writes to profile.csv, by the same code.
                let profile = contactlab::io::csv::to_csv(
                    &solved.profile(),
                    &contactlab::mechanics::contact_zone::PROFILE_COLUMNS,
                )?;
                let error_bound = bound_within_limit(
                    &solved.finest.problem,
                    friction,
                    &solved.outcome.solution,
                    &certificate,
                )
                .with_contraction(solved.outcome.contraction_for_estimate());
                Ok((
                    solved.outcome,
                    Some(String::from_utf8_lossy(&profile).into_owned()),
                    error_bound,
                ))
            }
            Source::Algebraic(p) => {
                let outcome = solve_algebraic(
                    &p,
                    friction,
                    entry,
                    &settings,
                    Caps::default(),
                    &mut observer,
                )?;
                let error_bound = bound_within_limit(&p, friction, &outcome.solution, &certificate)
                    .with_contraction(outcome.contraction_for_estimate());
                Ok((outcome, None, error_bound))
            }
        }
    })?;
    if let Some(e) = raised.lock().unwrap_or_else(|e| e.into_inner()).take() {
        return Err(e);
    }
    let o = &outcome;
    let d = PyDict::new(py);
    d.set_item("solver", entry.name)?;
    d.set_item("status", o.status.to_string())?;
    d.set_item("solver_status", o.claim.to_string())?;
    d.set_item("detail", o.detail.clone())?;
    d.set_item("stopped_by_callback", stopped.load(Ordering::Relaxed))?;
    let c = certificate_dict(py, &o.certificate)?;
    c.set_item("error_bound", bound_dict(py, &error_bound)?)?;
    d.set_item("certificate", c)?;
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
    d.set_item("profile_csv", profile)?;
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
    let cp = problem.algebraic();
    let (n, m) = (cp.n(), cp.contacts().len());
    let slice = |name: &str, a: &Option<PyReadonlyArray1<'py, f64>>, len: usize| {
        a.as_ref()
            .map(|a| -> PyResult<Vec<f64>> {
                let v = vector(a)?;
                if v.len() != len {
                    return Err(input_error(format!(
                        "{name} has {} values, expected {len}",
                        v.len()
                    )));
                }
                if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                    return Err(input_error(format!(
                        "{name}[{i}] is {}: give finite values",
                        v[i]
                    )));
                }
                Ok(v)
            })
            .transpose()
    };
    let v = slice("displacements", &displacements, n)?;
    let p = slice("pressure", &pressure, m)?;
    let q = slice("friction_traction", &friction_traction, m)?;
    let g = slice("bound", &bound, m)?;
    let g_given = g.is_some();
    if let Some(g) = &g {
        problem.bound_checked(g)?;
    }
    let forces = match (p, q) {
        (Some(p), Some(q)) => Some((p, q)),
        (None, None) => None,
        _ => {
            return Err(input_error(
                "give both pressure and friction_traction, or neither",
            ));
        }
    };
    let tolerance = match tolerance {
        Some(t) => contactlab::certificate::check_tolerance(t)
            .map_err(|m| input_error(format!("tolerance = {m}")))?,
        None => contactlab::certificate::DEFAULT_TOLERANCE,
    };
    let cp = Arc::new(cp.clone());
    let (c, v, p, q) = interruptible(py, move |_| {
        let (v, p, q) = contactlab::formats::instance::complete_answer(&cp, v, forces)?;
        let friction = match &g {
            Some(g) => Friction::Given(g),
            None => Friction::Coulomb,
        };
        let bound = contactlab::certificate::BoundReport::of(
            &cp,
            friction,
            &v,
            &p,
            &q,
            contactlab::certificate::bound_room(),
        );
        Ok((
            (certify_answer(&cp, friction, &v, &p, &q, tolerance), bound),
            v,
            p,
            q,
        ))
    })?;
    let (c, bound) = c;
    let friction_law = if g_given {
        contactlab::solvers::Law::GivenFriction
    } else {
        contactlab::solvers::Law::Coulomb
    };
    let d = certificate_dict(py, &c)?;
    d.set_item("law", friction_law.as_str())?;
    d.set_item("error_bound", bound_dict(py, &bound)?)?;
    // The answer the certificate judged, completed (forces from the
    // displacements by stationarity, or displacements from the forces).
    d.set_item("displacements", v.into_pyarray(py))?;
    d.set_item("pressure", p.into_pyarray(py))?;
    d.set_item("friction_traction", q.into_pyarray(py))?;
    Ok(d)
}

/// The bound on an answer's error (issue 51) as a dict: `energy`,
/// `displacement`, `pressure`, `kind` and `summary`, or `not_computed`
/// saying why there is none.
fn bound_dict<'py>(
    py: Python<'py>,
    bound: &contactlab::certificate::BoundReport,
) -> PyResult<Bound<'py, PyDict>> {
    let b = PyDict::new(py);
    match &bound.bound {
        Some(e) => {
            b.set_item("energy", e.energy)?;
            b.set_item("displacement", e.displacement)?;
            b.set_item("pressure", e.pressure)?;
            b.set_item("kind", e.kind.as_str())?;
        }
        None => b.set_item("not_computed", bound.not_computed.as_deref().unwrap_or(""))?,
    }
    b.set_item("summary", bound.line())?;
    Ok(b)
}

/// Writes the problem as `contactlab export` does (A, M, f, the contact
/// nodes, the rigid mode, the condensed form, a README), for another code
/// to read; `bound`: a friction bound g = bound for every node, for the
/// given-friction subproblem.
#[pyfunction]
#[pyo3(signature = (problem, out, bound=None))]
fn export(
    py: Python<'_>,
    problem: &Problem,
    out: std::path::PathBuf,
    bound: Option<f64>,
) -> PyResult<()> {
    let (scene, finest) = problem.scene("export")?;
    let (scene, finest) = (scene.clone(), finest.clone());
    interruptible(py, move |_| {
        let folder = contactlab::io::run_folder::RunFolder::create(&out)?;
        contactlab::formats::instance::export(
            folder.path(),
            &scene,
            &finest,
            bound,
            &contactlab::io::manifest::git_commit(),
        )?;
        folder.commit()?;
        Ok(())
    })
}

/// The exception classes: `Error`, and its subclasses that are also the
/// built-in exception a Python user catches.
fn add_errors(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    let error = py.get_type::<Error>();
    m.add("Error", &error)?;
    let make = |name: &str, builtin: Bound<'_, pyo3::types::PyType>, doc: &str| -> PyResult<()> {
        let namespace = PyDict::new(py);
        namespace.set_item("__doc__", doc)?;
        namespace.set_item("__module__", "contactlab")?;
        let t = py.import("builtins")?.getattr("type")?.call1((
            name,
            (error.clone(), builtin),
            namespace,
        ))?;
        m.add(name, t)
    };
    make(
        "InputError",
        py.get_type::<pyo3::exceptions::PyValueError>(),
        "Bad input: a value, a setting, a shape or a combination that contactlab refuses.",
    )?;
    make(
        "FileError",
        py.get_type::<pyo3::exceptions::PyOSError>(),
        "A file or folder that cannot be read or written.",
    )?;
    make(
        "OutOfMemory",
        py.get_type::<pyo3::exceptions::PyMemoryError>(),
        "A run refused up front: its memory estimate exceeds what the process may use.",
    )?;
    Ok(())
}

#[pymodule]
fn _contactlab(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Problem>()?;
    m.add_function(wrap_pyfunction!(solvers, m)?)?;
    m.add_function(wrap_pyfunction!(statuses, m)?)?;
    m.add_function(wrap_pyfunction!(_check_problem_size, m)?)?;
    m.add_function(wrap_pyfunction!(_address_space_reserve, m)?)?;
    m.add_function(wrap_pyfunction!(solve, m)?)?;
    m.add_function(wrap_pyfunction!(certify, m)?)?;
    m.add_function(wrap_pyfunction!(export, m)?)?;
    m.add_function(wrap_pyfunction!(studies::register, m)?)?;
    m.add_function(wrap_pyfunction!(studies::_compare, m)?)?;
    m.add_function(wrap_pyfunction!(studies::_studies, m)?)?;
    m.add_function(wrap_pyfunction!(studies::_study, m)?)?;
    m.add_function(wrap_pyfunction!(studies::_benchmark, m)?)?;
    m.add_function(wrap_pyfunction!(studies::_work_precision, m)?)?;
    m.add_function(wrap_pyfunction!(studies::_sweep, m)?)?;
    m.add_function(wrap_pyfunction!(studies::_side_by_side, m)?)?;
    m.add_function(wrap_pyfunction!(studies::_tuning_map, m)?)?;
    add_errors(m)
}
