"""contactlab from Python: the paper's contact problem, its certified solvers
and its studies (Zhiltsov & Namm 2019, two plane elastic bodies in unilateral
contact with Coulomb friction).

Everything numerical is contactlab's own Rust code, the code the command
line runs: a ``Problem`` is the assembled scene, ``solve`` is ``contactlab
solve``, ``certify`` is ``contactlab certify``. This module only turns its
arrays into numpy and scipy objects.

    import contactlab as cl
    p = cl.Problem.paper(1, h="1/64")
    r = cl.solve(p, solver="newton-coulomb")
    r.status, r.certificate.passed, r.pressure.max()
"""

from __future__ import annotations

import json
import math
import numbers
import os
import time
from dataclasses import dataclass, field
from typing import Callable, Dict, Iterable, List, Mapping, Optional, Sequence, Union

import numpy as np
import scipy.sparse

from . import _contactlab
from ._contactlab import Error

__all__ = [
    "Error",
    "Problem",
    "Contact",
    "Certificate",
    "Result",
    "Trial",
    "solvers",
    "solve",
    "certify",
    "work_precision",
    "compare",
    "Comparison",
    "benchmark",
    "BenchmarkResult",
    "BenchmarkSummary",
]


def solvers() -> List[str]:
    """The registered solvers' names, as ``contactlab solve --solver`` takes them."""
    return list(_contactlab.solvers())


@dataclass(frozen=True)
class Contact:
    """The contact nodes of a problem on Γ_K, one entry per node.

    ``t`` and ``s`` index the jump t = v'_2 − v''_2 and the slip
    s = v'_1 − v''_1 in the unknowns; ``weight`` is the trapezoid weight
    w_i, ``coefficient`` the friction coefficient 𝓕_i and ``x`` the node's
    abscissa.
    """

    t: np.ndarray
    s: np.ndarray
    weight: np.ndarray
    coefficient: np.ndarray
    x: np.ndarray

    def __len__(self) -> int:
        return len(self.t)


def _h(h) -> Optional[str]:
    """A mesh size as the command line writes it: "1/64", or a number."""
    if h is None:
        return None
    if isinstance(h, str):
        return h
    if isinstance(h, numbers.Real) and not isinstance(h, bool):
        return repr(float(h))
    raise Error(f"h = {h!r}: give a mesh size such as \"1/64\" or 1/64")


def _number(x, name: str) -> Optional[float]:
    if x is None:
        return None
    if isinstance(x, bool) or not isinstance(x, numbers.Real):
        raise Error(f"{name} = {x!r}: give a number")
    return float(x)


def _text(x, name: str) -> Optional[str]:
    if x is None:
        return None
    if not isinstance(x, str):
        raise Error(f"{name} = {x!r}: give a word")
    return x


def _path(p, name: str) -> str:
    """A path as str, bytes or os.PathLike."""
    try:
        return os.fsdecode(os.fspath(p))
    except TypeError:
        raise Error(f"{name} = {p!r}: give a path (str, bytes or os.PathLike)") from None


def _csr(parts, n: int) -> scipy.sparse.csr_array:
    indptr, indices, data = parts
    return scipy.sparse.csr_array((data, indices, indptr), shape=(n, n))


class Problem:
    """One scene assembled on its finest mesh, in the problem's own unknowns
    (boundary conditions and the (t, s) change of variables on Γ_K applied).

    ``A`` (stiffness) and ``M`` (the mass matrix of the proximal term) are
    ``scipy.sparse.csr_array``; ``f`` is the load vector; ``contact`` the
    contact nodes; ``rigid_mode`` the kernel of A (the upper body's vertical
    translation).
    """

    def __init__(self, inner: "_contactlab.Problem"):
        self._p = inner

    @classmethod
    def paper(
        cls,
        number: int,
        h: Optional[Union[str, float]] = None,
        young: Optional[float] = None,
        poisson: Optional[float] = None,
        friction: Optional[float] = None,
        plane: Optional[str] = None,
    ) -> "Problem":
        """The paper's problem 1, 2 or 3 (``h`` such as "1/64" or 1/64: the
        finest mesh; ``plane`` "strain" or "stress")."""
        if isinstance(number, bool) or not isinstance(number, numbers.Integral):
            raise Error(f"number = {number!r}: give the paper's problem 1, 2 or 3")
        return cls(
            _contactlab.Problem.paper(
                int(number),
                _h(h),
                _number(young, "young"),
                _number(poisson, "poisson"),
                _text(plane, "plane"),
                _number(friction, "friction"),
            )
        )

    @classmethod
    def from_scene(
        cls,
        path: Union[str, bytes, "os.PathLike"],
        h: Optional[Union[str, float]] = None,
        young: Optional[float] = None,
        poisson: Optional[float] = None,
        friction: Optional[float] = None,
        plane: Optional[str] = None,
    ) -> "Problem":
        """A scene file, as ``contactlab solve --scene`` reads it, with the
        settings it brings (every solve of the problem starts from them)."""
        return cls(
            _contactlab.Problem.from_scene(
                _path(path, "path"),
                _h(h),
                _number(young, "young"),
                _number(poisson, "poisson"),
                _text(plane, "plane"),
                _number(friction, "friction"),
            )
        )

    @property
    def name(self) -> str:
        return self._p.name

    @property
    def h(self) -> str:
        return self._p.h

    @property
    def n(self) -> int:
        return self._p.n

    @property
    def A(self) -> scipy.sparse.csr_array:
        return _csr(self._p._a(), self.n)

    @property
    def M(self) -> scipy.sparse.csr_array:
        return _csr(self._p._m(), self.n)

    @property
    def f(self) -> np.ndarray:
        return self._p.f

    @property
    def contact(self) -> Contact:
        return Contact(**self._p._contact())

    @property
    def scales(self) -> Dict[str, float]:
        """The problem's own scales: ``force``, ``contact_load``, ``length``
        (of Γ_K), ``stiffness``, ``pressure`` (P) and ``displacement`` (U),
        in which the certificate and ``compare`` measure."""
        return dict(self._p.scales)

    @property
    def rigid_mode(self) -> np.ndarray:
        return self._p.rigid_mode

    def __repr__(self) -> str:
        return repr(self._p)


@dataclass(frozen=True)
class Certificate:
    """The verdict of contactlab's certificate on an answer: each condition's
    violation in the problem's own scales (nonpenetration, complementarity,
    the friction law, stationarity, force balance, ...), and whether the
    largest is within the tolerance."""

    passed: bool
    tolerance: float
    residual: float
    summary: str
    violations: Dict[str, float]
    law: str = "coulomb"

    @classmethod
    def _of(cls, d: Mapping) -> "Certificate":
        return cls(
            passed=bool(d["passed"]),
            tolerance=float(d["tolerance"]),
            residual=float(d["residual"]),
            summary=str(d["summary"]),
            violations=dict(d["violations"]),
            law=str(d.get("law", "coulomb")),
        )


@dataclass(frozen=True)
class Result:
    """One certified solve. ``status`` is the certified verdict,
    ``solver_status`` the solver's own claim."""

    solver: str
    status: str
    solver_status: str
    detail: str
    certificate: Certificate
    displacements: np.ndarray
    pressure: np.ndarray
    friction_traction: np.ndarray
    bound: np.ndarray
    iterations: Dict[str, int]
    seconds: float
    seconds_setup: float
    #: The contact zone, node by node: the bytes ``solve --out`` writes to
    #: ``profile.csv``.
    profile_csv: str = ""


def _problem(problem) -> None:
    if not isinstance(problem, Problem):
        raise Error(f"problem: give a contactlab.Problem (got {type(problem).__name__})")


def _settings(settings) -> List[tuple]:
    """``{path: value}`` (or pairs) as text, in the order given, as
    ``--set path=value`` writes them: the engine resolves them with the
    command line's own code (the later change of a setting wins)."""
    if settings is None:
        return []
    if isinstance(settings, Mapping):
        pairs = list(settings.items())
    else:
        try:
            pairs = [tuple(item) for item in settings]
        except TypeError:
            raise Error(
                f"settings = {settings!r}: give a mapping {{path: value}}, e.g. {{\"tnnmg.tolerance\": 1e-10}}"
            ) from None
        if any(len(pair) != 2 for pair in pairs):
            raise Error("settings: give a mapping {path: value} or (path, value) pairs")
    out = []
    for path, value in pairs:
        if isinstance(value, bool):
            value = "true" if value else "false"
        out.append((str(path), str(value)))
    return out


def solve(
    problem: Problem,
    solver: Optional[str] = None,
    settings: Optional[Mapping[str, object]] = None,
    bound: Optional[Sequence[float]] = None,
    target: Optional[float] = None,
) -> Result:
    """Solves the problem's Coulomb law (or, given ``bound``, the
    given-friction subproblem at that bound) with a registered solver (the
    oracle if none) and certifies the answer: ``contactlab solve``.

    ``settings`` maps ``OWNER.NAME`` paths to values, as ``--set`` does
    (``{"newton-coulomb.tolerance": 1e-12}``). ``target`` sets the solver's
    accuracy knob and ε below it and certifies at it, as the benchmark does.
    """
    _problem(problem)
    if solver is not None and not isinstance(solver, str):
        raise Error(f"solver = {solver!r}: give a registered solver's name ({', '.join(solvers())})")
    g = _array(bound, "bound")
    d = _contactlab.solve(
        problem._p,
        solver,
        _settings(settings),
        None if g is None else g.tolist(),
        _number(target, "target"),
    )
    return Result(
        solver=d["solver"],
        status=d["status"],
        solver_status=d["solver_status"],
        detail=d["detail"],
        certificate=Certificate._of(d["certificate"]),
        displacements=d["displacements"],
        pressure=d["pressure"],
        friction_traction=d["friction_traction"],
        bound=d["bound"],
        iterations=dict(d["iterations"]),
        seconds=float(d["seconds"]),
        seconds_setup=float(d["seconds_setup"]),
        profile_csv=d["profile_csv"],
    )


def _array(x, name: str) -> Optional[np.ndarray]:
    """A one-dimensional array of real numbers (integers or floats), as
    float64; complex values, booleans, objects and strings are refused
    rather than cast (a complex answer's imaginary part was dropped with a
    warning and the rest certified)."""
    if x is None:
        return None
    a = np.asarray(x)
    if a.dtype.kind not in "iuf":
        raise Error(
            f"{name}: give real numbers (an array of dtype {a.dtype} was given"
            + (": its imaginary part would be lost)" if a.dtype.kind == "c" else ")")
        )
    a = np.ascontiguousarray(a, dtype=np.float64)
    if a.ndim != 1:
        raise Error(f"{name}: give a one-dimensional array (it has shape {a.shape})")
    return a


def _forces(forces):
    """``(pressure, friction_traction)``, or a mapping with those keys."""
    if forces is None:
        return None, None
    if isinstance(forces, Mapping):
        keys = set(forces)
        if keys != {"pressure", "friction_traction"}:
            raise Error(
                f"forces: give the keys 'pressure' and 'friction_traction' (got {sorted(map(str, keys))})"
            )
        return forces["pressure"], forces["friction_traction"]
    try:
        p, q = forces
    except (TypeError, ValueError):
        raise Error("forces: give a pair (pressure, friction_traction) or a mapping with those keys") from None
    return p, q


def certify(
    problem: Problem,
    displacements=None,
    forces: Optional[tuple] = None,
    bound=None,
    tolerance: Optional[float] = None,
) -> Certificate:
    """The certificate of an answer computed anywhere: ``contactlab certify``.

    Give ``displacements`` (the contact forces then follow from stationarity
    at the contact rows), ``forces=(pressure, friction_traction)`` per
    contact node (the displacements then follow from the elastic response),
    or both. With ``bound`` the given-friction law at that bound is checked,
    else the Coulomb law.
    """
    return Certificate._of(_certified(problem, displacements, forces, bound, tolerance))


def _certified(problem: Problem, displacements, forces, bound, tolerance) -> Mapping:
    """The certify binding's answer: the certificate's fields, and the
    answer it judged, completed (displacements, pressure, friction
    traction)."""
    _problem(problem)
    p, q = _forces(forces)
    if tolerance is not None:
        tolerance = _number(tolerance, "tolerance")
    return _contactlab.certify(
        problem._p,
        _array(displacements, "displacements"),
        _array(p, "pressure"),
        _array(q, "friction_traction"),
        _array(bound, "bound"),
        tolerance,
    )


#: A solver written in Python: called as ``fn(problem, target)``, it gives
#: the displacements (an array of ``problem.n``), or a dict with
#: ``displacements`` and/or ``forces`` = (pressure, friction_traction).
PythonSolver = Callable[[Problem, float], object]


@dataclass(frozen=True)
class Trial:
    """One run of a study: a solver at a target accuracy, certified."""

    solver: str
    target: float
    certified: bool
    certificate: Certificate
    seconds: float
    status: str
    python: bool = False
    #: The problem's name and mesh (``benchmark`` runs several).
    problem: str = ""
    #: The solver's own claim (a registered solver's status before the
    #: certificate; "answered" for a Python function).
    solver_status: str = ""

    @property
    def claimed(self) -> bool:
        """Whether the solver claimed an answer: a registered solver that
        says converged, or a Python function that returned one (not one
        that raised)."""
        return self.solver_status in ("converged", "answered")


def _failed_certificate(target: float, summary: str) -> "Certificate":
    """The certificate of a run that gave no answer to judge."""
    return Certificate(
        passed=False,
        tolerance=target,
        residual=math.inf,
        summary=summary,
        violations={},
    )


def _python_answer(fn: PythonSolver, problem: Problem, target: float):
    """A Python function's answer, timed and certified at ``target``:
    (certificate, seconds, the completed answer as the certificate judged
    it: displacements, pressure, friction traction, or None when there is
    none, and the solver's claim). A function that raises, or whose answer
    cannot be judged (NaN, a wrong shape, complex values), is one failed
    run, said in its certificate's summary: it never stops the study."""
    start = time.perf_counter()
    try:
        answer = fn(problem, target)
    except Exception as e:  # noqa: BLE001 - the run failed; the study goes on
        seconds = time.perf_counter() - start
        return _failed_certificate(target, f"the solver raised {type(e).__name__}: {e}"), seconds, None, "raised"
    seconds = time.perf_counter() - start
    try:
        if isinstance(answer, Mapping):
            v, forces = answer.get("displacements"), answer.get("forces")
        else:
            v, forces = answer, None
        d = _certified(problem, v, forces, None, target)
    except Error as e:
        return _failed_certificate(target, f"its answer cannot be judged: {e}"), seconds, None, "answered"
    completed = (d["displacements"], d["pressure"], d["friction_traction"])
    return Certificate._of(d), seconds, completed, "answered"


def _python_trial(name: str, fn: PythonSolver, problem: Problem, target: float) -> Trial:
    c, seconds, _, claim = _python_answer(fn, problem, target)
    return Trial(
        solver=name,
        target=target,
        certified=c.passed,
        certificate=c,
        seconds=seconds,
        status=_python_status(c, claim),
        python=True,
        problem=_instance(problem),
        solver_status=claim,
    )


def _python_status(c: "Certificate", claim: str) -> str:
    """A Python function's certified status: converged if its answer
    passes, inaccurate if it answered and fails, failed if it raised."""
    if claim == "raised":
        return "failed"
    return "converged" if c.passed else "inaccurate"


def _solvers(solvers) -> Mapping:
    """Registered names, or a mapping of display names to a registered
    name or a Python function."""
    if isinstance(solvers, str):
        solvers = [solvers]
    if not isinstance(solvers, Mapping):
        try:
            solvers = {name: name for name in solvers}
        except TypeError:
            raise Error(f"solvers = {solvers!r}: give solver names or a mapping {{name: solver}}") from None
    for name, how in solvers.items():
        if not (callable(how) or isinstance(how, str)):
            raise Error(f"solvers[{name!r}] = {how!r}: give a registered solver's name or a function fn(problem, target)")
    return solvers


def _targets(targets) -> List[float]:
    try:
        out = [_number(t, "targets") for t in targets]
    except TypeError:
        raise Error(f"targets = {targets!r}: give a list of accuracies such as [1e-4, 1e-8]") from None
    if not out:
        raise Error("targets: give at least one accuracy, such as [1e-4]")
    return out


def _instance(problem: Problem) -> str:
    return f"{problem.name}, h = {problem.h}"


def _trial(name: str, how: Union[str, PythonSolver], problem: Problem, target: float) -> Trial:
    """One solver (registered, or a Python function) at one target, certified."""
    if callable(how):
        return _python_trial(name, how, problem, target)
    r = solve(problem, solver=how, target=target)
    return Trial(
        solver=name,
        target=target,
        certified=r.certificate.passed,
        certificate=r.certificate,
        seconds=r.seconds,
        status=r.status,
        problem=_instance(problem),
        solver_status=r.solver_status,
    )


def work_precision(
    problem: Problem,
    solvers: Union[Iterable[str], Mapping[str, Union[str, PythonSolver]]],
    targets: Sequence[float] = (1e-4, 1e-6, 1e-8),
    chart: Optional[str] = None,
) -> List[Trial]:
    """A work-precision study: each solver at each target accuracy, every
    answer certified by contactlab's certificate at that target, timed.

    ``solvers`` lists registered solvers' names, or maps display names to a
    registered name or to a Python function (see ``PythonSolver``): a
    Python solver's answers pass through the same certificate and are drawn
    in the same chart. With ``chart`` (a path ending in .svg) the trials are
    drawn as the command line draws its work-precision charts: the
    certificate's largest violation against seconds, certified points joined
    and failed ones as crosses.
    """
    if chart is not None:
        chart = _path(chart, "chart")
        if not chart.lower().endswith(".svg"):
            raise Error(f"chart = {chart!r}: charts are SVG; give a path ending in .svg")
    _problem(problem)
    solvers = _solvers(solvers)
    trials: List[Trial] = [
        _trial(name, how, problem, float(target))
        for name, how in solvers.items()
        for target in _targets(targets)
    ]
    if chart is not None:
        _contactlab._work_precision_chart(
            f"Work against precision: {problem.name}, h = {problem.h}",
            "largest violation in the certificate (relative)",
            [(t.solver, t.certificate.residual, t.seconds, t.certified) for t in trials],
            chart,
        )
    return trials


@dataclass(frozen=True)
class Comparison:
    """One solver in a comparison: its certified answer against the
    reference, the certified answer with the smallest largest violation."""

    solver: str
    certified: bool
    certificate: Certificate
    seconds: float
    status: str
    #: The solver's own claim ("answered" for a Python function).
    solver_status: str
    python: bool
    #: Whether this answer is the reference.
    reference: bool
    #: max|v − v_ref| / U and max|p − p_ref| / P, the problem's
    #: displacement and pressure scales (NaN when no answer is certified).
    displacement_difference: float
    pressure_difference: float


def compare(
    problem: Problem,
    solvers: Union[Iterable[str], Mapping[str, Union[str, PythonSolver]]],
    target: float = 1e-8,
) -> List[Comparison]:
    """Every solver on the problem's Coulomb law, each answer certified at
    ``target`` and timed, and compared with the reference: of these
    answers, the certified one whose largest violation is the smallest
    (``contactlab compare`` chooses its reference among its candidates by
    the same rule). ``solvers`` is as for
    ``work_precision``: a Python function's answer passes through the same
    certificate and is measured against the same reference; one that the
    certificate refuses is never the reference.
    """
    _problem(problem)
    solvers = _solvers(solvers)
    target = _number(target, "target")
    runs = []
    for name, how in solvers.items():
        if callable(how):
            c, seconds, completed, claim = _python_answer(how, problem, target)
            v, p, _ = completed if completed is not None else (None, None, None)
            runs.append((name, c, seconds, _python_status(c, claim), claim, True, v, p))
        else:
            r = solve(problem, solver=how, target=target)
            runs.append(
                (
                    name,
                    r.certificate,
                    r.seconds,
                    r.status,
                    r.solver_status,
                    False,
                    r.displacements,
                    r.pressure,
                )
            )
    certified = [k for k, run in enumerate(runs) if run[1].passed]
    best = min(certified, key=lambda k: runs[k][1].residual, default=None)
    scales = problem.scales
    out = []
    for k, (name, c, seconds, status, claim, python, v, p) in enumerate(runs):
        if best is None or v is None:
            dv = dp = math.nan
        else:
            v_ref, p_ref = runs[best][6], runs[best][7]
            dv = float(np.max(np.abs(v - v_ref), initial=0.0)) / scales["displacement"]
            dp = float(np.max(np.abs(p - p_ref), initial=0.0)) / scales["pressure"]
        out.append(
            Comparison(
                solver=name,
                certified=c.passed,
                certificate=c,
                seconds=seconds,
                status=status,
                solver_status=claim,
                python=python,
                reference=k == best,
                displacement_difference=dv,
                pressure_difference=dp,
            )
        )
    return out


@dataclass(frozen=True)
class BenchmarkSummary:
    """One solver at one target accuracy over every problem of a benchmark,
    as ``benchmark_summary.csv`` has it: success rate, runs its solver
    claimed but the certificate refused, and the shifted geometric mean of
    its time (shift 0.1 s, a failure counted at the time limit), also
    relative to the best solver's."""

    target: float
    solver: str
    runs: int
    successes: int
    success_rate: float
    claimed_but_failed: int
    shifted_geometric_mean: float
    relative_to_best: float


@dataclass(frozen=True)
class BenchmarkResult:
    """A benchmark's runs and the command line's views of them."""

    trials: List[Trial]
    summaries: List[BenchmarkSummary]
    #: The report ``benchmark.md`` holds: per target the table, the runs
    #: claimed but refused, which solver wins by how much.
    report: str


def benchmark(
    problems: Iterable[Problem],
    solvers: Union[Iterable[str], Mapping[str, Union[str, PythonSolver]]],
    targets: Sequence[float] = (1e-4, 1e-8),
    time_limit: float = 60.0,
    out: Optional[str] = None,
) -> BenchmarkResult:
    """A benchmark over ``problems``: every solver at every target accuracy
    on every problem, each answer certified at the target, timed; the
    summaries, report and performance profiles are computed by the code of
    ``contactlab benchmark``, so a Python solver stands in the same tables
    and charts as the registered ones.

    ``solvers`` is as for ``work_precision``. A registered solver runs with
    the benchmark's rule (its accuracy knob and ε below the target); a
    Python function is called as ``fn(problem, target)``. A run succeeds if
    its answer passes the certificate at the target within ``time_limit``
    seconds (a Python function is not interrupted: a slower run counts as
    failed, at the limit like every failure; one that raises or returns
    what cannot be judged is one failed run). A Python function's answer counts as its claim of convergence,
    so a refused one is "claimed but failed". With ``out`` (a folder,
    replaced whole, only if empty or a contactlab run) it writes what the
    command line writes: benchmark.csv, benchmark_summary.csv, benchmark.md,
    a LaTeX table per target and the performance profiles.
    """
    solvers = _solvers(solvers)
    targets = _targets(targets)
    problems = list(problems)
    for problem in problems:
        _problem(problem)
    if isinstance(time_limit, bool) or not (
        isinstance(time_limit, (int, float)) and math.isfinite(time_limit) and time_limit > 0
    ):
        raise Error(f"time_limit = {time_limit!r}: give a positive number of seconds")
    trials: List[Trial] = []
    rows = []
    for problem in problems:
        friction = float(np.max(problem.contact.coefficient, initial=0.0))
        for name, how in solvers.items():
            for target in targets:
                t = _trial(name, how, problem, float(target))
                trials.append(t)
                in_time = t.seconds <= time_limit
                rows.append(
                    {
                        "instance": t.problem,
                        "family": "python",
                        "h": problem.h,
                        "unknowns": problem.n,
                        "friction_coefficient": friction,
                        "solver": name,
                        "target": t.target,
                        "status": t.status if in_time else "time_limit",
                        "solver_status": t.solver_status,
                        "success": bool(t.certified and in_time),
                        "claimed_but_failed": bool(t.claimed and not t.certified),
                        "certificate": repr(float(t.certificate.residual)),
                        "failing": ";".join(
                            k for k, v in t.certificate.violations.items() if v > t.target
                        ),
                        "seconds": t.seconds,
                        "time_limit": float(time_limit),
                        "work": 0,
                        "detail": t.certificate.summary,
                    }
                )
    summaries_json, report = _contactlab._benchmark_report(
        json.dumps(rows), None if out is None else _path(out, "out")
    )
    summaries = [
        BenchmarkSummary(
            target=float(d["target"]),
            solver=str(d["solver"]),
            runs=int(d["runs"]),
            successes=int(d["successes"]),
            success_rate=float(d["success_rate"]),
            claimed_but_failed=int(d["claimed_but_failed"]),
            shifted_geometric_mean=float(d["shifted_geometric_mean"]),
            relative_to_best=float(d["relative_to_best"]),
        )
        for d in json.loads(summaries_json)
    ]
    return BenchmarkResult(trials=trials, summaries=summaries, report=report)
