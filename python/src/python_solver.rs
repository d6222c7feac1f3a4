//! A Python function as a registered solver: it implements the library's
//! [`Solver`] trait, so that it stands wherever a registered solver stands
//! (every study, `solve`, the registry's list), and its answer is
//! certified by the same code as every other.
//!
//! The function is called as `fn(problem, target)` with the problem it is
//! given (a `contactlab.Problem`) and its `target` setting (the benchmark
//! sets it at a safety factor below the target accuracy, like every
//! solver's accuracy knob), and returns the displacements, or a mapping
//! with `displacements` and/or `forces` = (pressure, friction_traction). It
//! solves the whole Coulomb problem. A function that raises, or whose
//! answer cannot be judged, is one failed run: it never stops a study.

use std::sync::{Arc, Mutex};
use std::time::Instant;

use contactlab::formats::instance::complete_answer;
use contactlab::solvers::Stopping;
use contactlab::solvers::registry::{self, Accuracy, Build, Entry, Knob, Role, StageInfo};
use contactlab::solvers::settings::Kind;
use contactlab::solvers::{
    ContactProblem, Friction, Law, Observer, Solution, Solver, Start, Status, Timing,
};
use pyo3::prelude::*;
use pyo3::types::PyMapping;
use serde_json::Value;

use crate::problem::Problem;

/// The setting a Python solver reads: the accuracy it is asked for.
const TARGET: &str = "target";

/// Its default, where no study sets it.
const DEFAULT_TARGET: f64 = 1e-8;

/// The function of each Python solver, by name: a solver registered again
/// under its name takes the new function (an entry, once registered, stays).
type Functions = Mutex<Vec<(&'static str, Arc<Py<PyAny>>)>>;

static FUNCTIONS: Functions = Mutex::new(Vec::new());

/// The longest solver name: the built-in names are at most 16 characters,
/// and a name is part of file names, CSV columns and settings paths.
const MAX_NAME_CHARS: usize = 48;

/// Names that already mean something where a solver's name is read: the
/// settings sections (`coulomb.*`, `stopping`, `schedule`, `certificate.*`)
/// and the side of a comparison that is the earned reference, and the
/// solver lists' `all`.
const RESERVED: &[&str] = &[
    contactlab::settings::COULOMB,
    "reference",
    "stopping",
    "schedule",
    "certificate",
    "all",
    "oracle",
];

/// The function registered under `name`.
fn function(name: &str) -> Option<Arc<Py<PyAny>>> {
    FUNCTIONS
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, f)| f.clone())
}

/// Registers the Python function `f` as the solver `name`, or gives the
/// solver `name` the new function if a Python solver has it already. A
/// name of a built-in solver is refused.
pub fn register(name: &str, f: Py<PyAny>) -> Result<&'static Entry, String> {
    let name = name.trim();
    if name.len() > MAX_NAME_CHARS {
        return Err(format!(
            "solver name of {} characters: give at most {MAX_NAME_CHARS} (it names files, columns and settings)",
            name.chars().count()
        ));
    }
    if let Some(word) = RESERVED.iter().find(|w| w.eq_ignore_ascii_case(name)) {
        return Err(format!(
            "solver name '{name}': '{word}' is a word contactlab gives its own meaning (a settings section or the earned reference); give your function another name"
        ));
    }
    if name.is_empty()
        || !name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
    {
        return Err(format!(
            "solver name '{name}': use letters, digits, '-' and '_' (it names files and settings)"
        ));
    }
    let mut functions = FUNCTIONS.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(slot) = functions.iter_mut().find(|(n, _)| *n == name) {
        slot.1 = Arc::new(f);
        return registry::by_name(name)
            .ok_or_else(|| format!("solver '{name}' was not registered"));
    }
    if registry::by_name(name).is_some() {
        return Err(format!(
            "'{name}' is a registered solver's name; give your function another"
        ));
    }
    let name: &'static str = Box::leak(name.to_string().into_boxed_str());
    let build: &'static registry::BuildFn = Box::leak(Box::new(move |tree: &Value| {
        let target = tree
            .get(TARGET)
            .and_then(Value::as_f64)
            .unwrap_or(DEFAULT_TARGET);
        let f = function(name).ok_or_else(|| format!("no Python function for '{name}'"))?;
        Ok(Box::new(PythonSolver { f, target }) as Box<dyn Solver>)
    }));
    let entry: &'static Entry = Box::leak(Box::new(Entry {
        name,
        about: "a Python function (contactlab.register or a study's solvers)",
        source: "the user's Python code",
        laws: &[Law::Coulomb],
        warm_starts: false,
        schedule: contactlab::solvers::schedule::Schedule::Revisit,
        schedule_when: None,
        stages: &[StageInfo {
            name: "python",
            about: "the Python function's one call",
            history: false,
        }],
        work_stage: "python",
        knobs: &[Knob {
            name: TARGET,
            fields: &[TARGET],
            help: "the accuracy the function is asked for (its second argument)",
            kind: Kind::Positive,
        }],
        defaults: |_: Stopping| serde_json::json!({ TARGET: DEFAULT_TARGET }),
        build: Build::Closure(build),
        accuracy: Accuracy {
            knob: TARGET,
            reference: 1e-12,
            exact: false,
        },
        role: Role::Other,
        kernel: None,
        max_unknowns: None,
        uses_mass: false,
        // What the harness holds around it; the function's own memory is
        // its business.
        memory: registry::Memory {
            per_unknown: 400.0,
            per_unknown_log2: 0.0,
        },
    }));
    registry::register(entry)?;
    functions.push((name, Arc::new(f)));
    Ok(entry)
}

/// A Python function at one `target`.
struct PythonSolver {
    f: Arc<Py<PyAny>>,
    target: f64,
}

impl Solver for PythonSolver {
    fn solve(
        &mut self,
        problem: &ContactProblem,
        friction: Friction<'_>,
        _start: Option<Start<'_>>,
        _observer: &mut dyn Observer,
    ) -> Solution {
        let (n, m) = (problem.n(), problem.contacts().len());
        if friction != Friction::Coulomb {
            return Solution::failed(
                n,
                m,
                Status::NotRun,
                "a Python solver solves the Coulomb law only",
            );
        }
        let started = Instant::now();
        let answer = Python::attach(|py| -> Result<Answer, (Status, String)> {
            let given = Problem::of_algebraic(problem.clone())
                .wrapped(py)
                .map_err(|e| {
                    (
                        Status::NotRun,
                        format!("cannot hand the problem to Python: {e}"),
                    )
                })?;
            let out = self.f.call1(py, (given, self.target)).map_err(|e| {
                let kind = e
                    .get_type(py)
                    .name()
                    .map(|n| n.to_string())
                    .unwrap_or_else(|_| "an exception".into());
                (
                    Status::NumericalError,
                    format!("the Python solver raised {kind}: {}", e.value(py)),
                )
            })?;
            read_answer(py, out.bind(py), n, m).map_err(|e| {
                (
                    Status::NonFinite,
                    format!("its answer cannot be judged: {e}"),
                )
            })
        });
        let seconds = started.elapsed().as_secs_f64();
        let (v, forces) = match answer {
            Ok(a) => a,
            Err((status, detail)) => {
                let mut s = Solution::failed(n, m, status, detail);
                s.timing = Timing {
                    setup: 0.0,
                    solve: seconds,
                };
                return s;
            }
        };
        match complete_answer(problem, v, forces) {
            Ok((v, pressure, friction_traction)) => Solution {
                v,
                pressure,
                friction_traction,
                status: Status::Converged,
                detail: "the Python function answered".into(),
                iterations: Default::default(),
                timing: Timing {
                    setup: 0.0,
                    solve: seconds,
                },
                diagnostics: Vec::new(),
            },
            Err(e) => Solution::failed(
                n,
                m,
                Status::NonFinite,
                format!("its answer cannot be judged: {e:#}"),
            ),
        }
    }
}

/// Displacements, and forces (pressure, friction traction).
type Answer = (Option<Vec<f64>>, Option<(Vec<f64>, Vec<f64>)>);

/// What the function returned: displacements, or a mapping with
/// `displacements` and/or `forces`; real finite arrays of the right sizes.
fn read_answer(py: Python<'_>, out: &Bound<'_, PyAny>, n: usize, m: usize) -> PyResult<Answer> {
    let array = |x: &Bound<'_, PyAny>, name: &str, len: usize| -> PyResult<Vec<f64>> {
        let checked = py
            .import("contactlab")?
            .getattr("_array")?
            .call1((x, name))?;
        let v: Vec<f64> = checked.extract()?;
        if v.len() != len {
            return Err(crate::input_error(format!(
                "{name} has {} values, expected {len}",
                v.len()
            )));
        }
        if let Some(i) = v.iter().position(|x| !x.is_finite()) {
            return Err(crate::input_error(format!("{name}[{i}] is {}", v[i])));
        }
        Ok(v)
    };
    if let Ok(map) = out.cast::<PyMapping>() {
        let v = match map.get_item("displacements") {
            Ok(x) if !x.is_none() => Some(array(&x, "displacements", n)?),
            _ => None,
        };
        let forces = match map.get_item("forces") {
            Ok(x) if !x.is_none() => {
                let (p, q): (Bound<'_, PyAny>, Bound<'_, PyAny>) = x.extract()?;
                Some((
                    array(&p, "pressure", m)?,
                    array(&q, "friction_traction", m)?,
                ))
            }
            _ => None,
        };
        if v.is_none() && forces.is_none() {
            return Err(crate::input_error(
                "the mapping has neither displacements nor forces",
            ));
        }
        return Ok((v, forces));
    }
    Ok((Some(array(out, "displacements", n)?), None))
}
