"""contactlab from Python: the paper's contact problem, its certified solvers
and its studies (Zhiltsov & Namm 2019, two plane elastic bodies in unilateral
contact with Coulomb friction).

Everything numerical, and every study, is contactlab's own Rust code, the
code the command line runs: a ``Problem`` is the assembled scene (or an
algebraic problem checked like an imported instance), ``solve`` is
``contactlab solve``, ``certify`` is ``contactlab certify``, ``compare``,
``benchmark`` and ``work_precision`` run the command line's studies and
write the same files. A Python function can stand wherever a registered
solver stands (``register``). This module holds only conversions to numpy
and scipy, types and documentation.

    import contactlab as cl
    p = cl.Problem.paper(1, h=1/64)
    r = cl.solve(p, solver="newton-coulomb")
    r.status, r.certificate.passed, r.pressure.max()
"""

from __future__ import annotations

import enum
import functools
import json
import numbers
import os
from dataclasses import dataclass, field, replace
from typing import Callable, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import scipy.sparse

from . import _contactlab
from ._contactlab import Error, FileError, InputError, OutOfMemory

__all__ = [
    "Error",
    "InputError",
    "FileError",
    "OutOfMemory",
    "Status",
    "Problem",
    "Contact",
    "Certificate",
    "Result",
    "StudyResult",
    "BenchmarkResult",
    "studies",
    "study",
    "solvers",
    "register",
    "solve",
    "certify",
    "compare",
    "benchmark",
    "work_precision",
    "error_bound",
    "verify",
    "sweep",
    "side_by_side",
    "tuning_map",
]

#: A path as Python programs give one.
PathLike = Union[str, bytes, "os.PathLike[str]"]


class Status(str, enum.Enum):
    """How a solve ended, certified: ``converged`` only if the solver claimed
    convergence and the certificate passed. A member compares equal to its
    name as written in output files (``Status.CONVERGED == "converged"``)."""

    CONVERGED = "converged"
    REDUCED_ACCURACY = "reduced_accuracy"
    MAX_ITERATIONS = "max_iterations"
    TIME_LIMIT = "time_limit"
    INSUFFICIENT_PROGRESS = "insufficient_progress"
    INFEASIBLE = "infeasible"
    UNBOUNDED = "unbounded"
    NUMERICAL_ERROR = "numerical_error"
    NON_FINITE = "non_finite"
    NOT_RUN = "not_run"
    OUT_OF_MEMORY = "out_of_memory"
    INACCURATE = "inaccurate"

    def __str__(self) -> str:
        return self.value


def solvers() -> List[str]:
    """The registered solvers' names, as ``contactlab solve --solver`` takes
    them (Python solvers registered in this session among them)."""
    return list(_contactlab.solvers())


#: A solver written in Python: called as ``fn(problem, target)`` with a
#: ``Problem`` and the accuracy it is asked for, it returns the
#: displacements (an array of ``problem.n``), or a mapping with
#: ``displacements`` and/or ``forces`` = (pressure, friction_traction).
PythonSolver = Callable[["Problem", float], object]


def register(name: str, fn: PythonSolver) -> None:
    """Registers a Python function as the solver ``name``.

    From then on it stands wherever a registered solver stands: ``solve``,
    ``compare``, ``benchmark``, ``work_precision``. Its answers pass through
    the same certificate as every other's; a function that raises, or whose
    answer cannot be judged, is one failed run. It solves the whole Coulomb
    law. Registering a name again gives it the new function.

    Parameters
    ----------
    name : str
        Letters, digits, ``-`` and ``_``; not a built-in solver's name.
    fn : callable
        ``fn(problem, target)``; see ``PythonSolver``.
    """
    if not isinstance(name, str):
        raise InputError(f"name = {name!r}: give the solver's name as a word")
    if not callable(fn):
        raise InputError(f"fn = {fn!r}: give a function fn(problem, target)")
    _contactlab.register(name, fn)


@dataclass(frozen=True)
class Contact:
    """The contact nodes of a problem on Γ_K, one entry per node.

    ``t`` and ``s`` index the jump t = v'_2 − v''_2 and the slip
    s = v'_1 − v''_1 in the unknowns; ``weight`` is the trapezoid weight
    w_i, ``coefficient`` the friction coefficient 𝓕_i and ``x`` the node's
    abscissa (None for a problem given by its matrices).
    """

    t: np.ndarray
    s: np.ndarray
    weight: np.ndarray
    coefficient: np.ndarray
    x: Optional[np.ndarray]

    def __len__(self) -> int:
        return len(self.t)


def _h(h) -> Optional[str]:
    """A mesh size as the command line writes it, from "1/64", 1/64 or 64."""
    if h is None or isinstance(h, str):
        return h
    if isinstance(h, bool) or not isinstance(h, numbers.Real):
        raise InputError(f'h = {h!r}: give a mesh size such as "1/64", 1/64 or 64')
    if isinstance(h, numbers.Integral):
        return f"1/{int(h)}"
    h = float(h)
    if h > 0 and np.isfinite(h):
        n = round(1.0 / h)
        if n >= 1 and abs(n * h - 1.0) <= 1e-9:
            return f"1/{n}"
    raise InputError(f'h = {h!r}: give a mesh size 1/N such as "1/64", 1/64 or 64')


def _number(x, name: str) -> Optional[float]:
    if x is None:
        return None
    if isinstance(x, bool) or not isinstance(x, numbers.Real):
        raise InputError(f"{name} = {x!r}: give a number")
    return float(x)


def _text(x, name: str) -> Optional[str]:
    if x is None:
        return None
    if not isinstance(x, str):
        raise InputError(f"{name} = {x!r}: give a word")
    return x


def _path(p, name: str) -> str:
    """A path as str, bytes or os.PathLike."""
    try:
        return os.fsdecode(os.fspath(p))
    except TypeError:
        raise InputError(f"{name} = {p!r}: give a path (str, bytes or os.PathLike)") from None


def _overrides(h, young, poisson, plane, friction) -> tuple:
    """A scene's overrides, checked, in the binding's order (h, E, ν, the
    plane model, 𝓕), as the command line's --h, --young, --poisson,
    --plane, --friction."""
    return (
        _h(h),
        _number(young, "young"),
        _number(poisson, "poisson"),
        _text(plane, "plane"),
        _number(friction, "friction"),
    )


def _read_only(a: np.ndarray) -> np.ndarray:
    """A copy that cannot be written: the problem's arrays are cached, and
    a change in place would change what every later read shows."""
    a = np.array(a, copy=True)
    a.setflags(write=False)
    return a


def _csr(parts, shape) -> scipy.sparse.csr_array:
    indptr, indices, data = (_read_only(x) for x in parts)
    return scipy.sparse.csr_array((data, indices, indptr), shape=shape, copy=False)


def _csr_in(a, name: str, shape=None):
    """Any scipy sparse matrix or array (or a dense 2-D array) as canonical
    CSR parts (sorted indices, duplicates summed), float64."""
    if isinstance(a, np.ndarray) or not scipy.sparse.issparse(a):
        a = np.asarray(a)
        if a.ndim != 2 or a.dtype.kind not in "iuf":
            raise InputError(
                f"{name}: give a real matrix (scipy sparse, or a 2-D array)"
                + (": a complex one would lose its imaginary part" if a.dtype.kind == "c" else "")
            )
    elif a.dtype.kind not in "iufb":
        raise InputError(
            f"{name}: give a real matrix (a sparse matrix of dtype {a.dtype} was given"
            + (": its imaginary part would be lost)" if a.dtype.kind == "c" else ")")
        )
    rows, cols = a.shape
    stored = a.size if scipy.sparse.issparse(a) else rows * cols
    _contactlab._check_problem_size(f"reading {name} ({rows} × {cols}, {stored} entries)", max(rows, cols), stored)
    m = scipy.sparse.csr_array(a, dtype=np.float64)
    if shape is not None and m.shape != shape:
        raise InputError(f"{name} has shape {m.shape}, expected {shape}")
    m.sum_duplicates()
    m.sort_indices()
    return (
        m.shape,
        (m.indptr.astype(np.int64).tolist(), m.indices.astype(np.int64).tolist(), m.data.tolist()),
    )


class Problem:
    """The algebraic contact problem: A v = f under the contact conditions.

    Built from a scene (``paper``, ``from_scene``: assembled on its finest
    mesh, in the problem's own unknowns, boundary conditions and the (t, s)
    change of variables on Γ_K applied) or given as it is
    (``from_instance``, ``from_matrices``).

    Attributes
    ----------
    A, M : scipy.sparse.csr_array
        Stiffness and the mass matrix of the proximal term; built once per
        problem and cached, read-only (copy to modify). A scene's problem
        holds no M (a third of its memory): ``M`` assembles it on first use.
    f : numpy.ndarray
        The load vector.
    contact : Contact
        The contact nodes.
    rigid_mode : numpy.ndarray
        The kernel of A (the upper body's vertical translation).
    scales : dict
        The problem's own scales, in which the certificate measures.
    """

    def __init__(self, inner: "_contactlab.Problem"):
        self._p = inner

    @classmethod
    def paper(
        cls,
        number: int,
        h: Optional[Union[str, float, int]] = None,
        young: Optional[float] = None,
        poisson: Optional[float] = None,
        friction: Optional[float] = None,
        plane: Optional[str] = None,
    ) -> "Problem":
        """The paper's problem 1, 2 or 3.

        Parameters
        ----------
        number : int
            1, 2 or 3.
        h : str, float or int, optional
            The finest mesh: ``"1/64"``, ``1/64`` or ``64``.
        young, poisson, friction : float, optional
            Overrides of E, ν and 𝓕, as ``--young``, ``--poisson``,
            ``--friction``.
        plane : {"strain", "stress"}, optional
            The plane model, as ``--plane``.
        """
        if isinstance(number, bool) or not isinstance(number, numbers.Integral):
            raise InputError(f"number = {number!r}: give the paper's problem 1, 2 or 3")
        return cls(
            _contactlab.Problem.paper(int(number), *_overrides(h, young, poisson, plane, friction))
        )

    @classmethod
    def from_scene(
        cls,
        path: PathLike,
        h: Optional[Union[str, float, int]] = None,
        young: Optional[float] = None,
        poisson: Optional[float] = None,
        friction: Optional[float] = None,
        plane: Optional[str] = None,
    ) -> "Problem":
        """A scene file, as ``contactlab solve --scene`` reads it, with the
        settings it brings (every solve and study of the problem starts from
        them). The overrides are as for ``paper``."""
        return cls(
            _contactlab.Problem.from_scene(_path(path, "path"), *_overrides(h, young, poisson, plane, friction))
        )

    @classmethod
    def from_instance(cls, folder: PathLike) -> "Problem":
        """A folder written by ``contactlab export`` (or ``Problem.export``),
        read back with every file held to what its ``problem.json`` declares.
        It has no mesh: it can be solved and certified, not studied."""
        return cls(_contactlab.Problem.from_instance(_path(folder, "folder")))

    @classmethod
    def from_matrices(
        cls,
        A,
        f,
        contact: Mapping[str, Sequence],
        rigid_mode,
        M=None,
        prolongations: Optional[Sequence] = None,
        name: str = "matrices",
        gap=None,
        slip_offset=None,
    ) -> "Problem":
        """A problem posed from one's own matrices, checked as an imported
        instance is (symmetry, dimensions, index sets, A z = 0, the net load
        along z).

        Parameters
        ----------
        A : sparse matrix (any scipy format) or 2-D array, n × n
            Symmetric positive semidefinite, with kernel ``rigid_mode``.
        f : array of n
        contact : mapping
            ``t`` and ``s`` (indices of the jump and slip unknowns of each
            contact node), ``weight`` and ``coefficient`` (𝓕), one per node.
        rigid_mode : array of n, or a list of them
        M : sparse matrix, optional
            The mass matrix of the proximal term (for the paper's method).
        prolongations : list of sparse matrices, optional
            A nested hierarchy, coarse to fine, the last onto the n
            unknowns: multigrid solvers need one above 256 unknowns, and say
            so without it.
        gap : array of one value per contact node, optional
            The initial distance d_i ≥ 0 between the bodies at each contact
            node: the nonpenetration is t_i ≤ d_i (a curved body: Hertz).
            Without it the bodies touch everywhere at the start (d = 0).
            The problem's scales (and so the certificate's tolerances) are
            those of A and f alone, whatever the gap.
        slip_offset : array of one value per contact node, optional
            The slip σ_i at which friction holds: friction acts on
            s_i − σ_i. This poses a body moved sideways by δ without a
            load: take its rigid translation out of the unknowns (a rigid
            lift, which A does not see) and give σ = δ. The scales are
            those of A and f alone.

        Conventions: the lower body is primed, the upper double-primed;
        the normal of Γ_K is vertical; t_i = u2_lower − u2_upper (the
        jump: t_i < d_i is open), s_i = u1_lower − u1_upper (the slip);
        ``weight`` is the length of Γ_K each node stands for (trapezoid:
        h inside, h/2 at the ends); the pressure p_i ≥ 0 pushes the bodies
        apart and q_i is the tangential traction on the lower body. The
        paper's method (``relaxation``) needs ``M``; ``tnnmg`` needs a
        nested hierarchy above 256 unknowns.
        """
        shape, a = _csr_in(A, "A")
        if shape[0] != shape[1]:
            raise InputError(f"A has shape {shape}: give a square matrix")
        n = shape[0]
        fv = _array(f, "f")
        for key in ("t", "s", "weight", "coefficient"):
            if not isinstance(contact, Mapping) or key not in contact:
                raise InputError("contact: give a mapping with t, s, weight and coefficient per node")
        t = np.asarray(contact["t"])
        s = np.asarray(contact["s"])
        if t.dtype.kind not in "iu" or s.dtype.kind not in "iu":
            raise InputError("contact: t and s are indices of unknowns: give integers")
        for key, idx in (("t", t), ("s", s)):
            if idx.ndim != 1:
                raise InputError(f"contact {key}: give a one-dimensional array of indices (it has shape {idx.shape})")
            bad = [int(x) for x in idx if int(x) < 0 or int(x) >= n][:1]
            if bad:
                raise InputError(f"contact {key}: index {bad[0]} is out of range 0..{n}")
        raw_modes = np.asarray(rigid_mode)
        if raw_modes.dtype.kind not in "iuf":
            raise InputError(
                f"rigid_mode: give real numbers (an array of dtype {raw_modes.dtype} was given"
                + (": its imaginary part would be lost)" if raw_modes.dtype.kind == "c" else ")")
            )
        modes = raw_modes.astype(np.float64)
        if modes.ndim not in (1, 2) or (modes.ndim == 1 and modes.size == 0):
            raise InputError(
                f"rigid_mode: give the kernel of A as an array of n, or a list of them, or an array of shape (0, n) for an A without one (shape {modes.shape} was given)"
            )
        modes = [modes] if modes.ndim == 1 else list(modes)
        m = None if M is None else _csr_in(M, "M", (n, n))[1]
        ps = []
        for k, p in enumerate(prolongations or []):
            ps.append(_csr_in(p, f"prolongations[{k}]"))
        return cls(
            _contactlab.Problem.from_matrices(
                str(name),
                n,
                a,
                fv.tolist(),
                t.astype(np.int64).tolist(),
                s.astype(np.int64).tolist(),
                _array(contact["weight"], "contact weight").tolist(),
                _array(contact["coefficient"], "contact coefficient").tolist(),
                [_array(z, "rigid_mode").tolist() for z in modes],
                m,
                ps,
                None if gap is None else _array(gap, "gap").tolist(),
                None if slip_offset is None else _array(slip_offset, "slip_offset").tolist(),
            )
        )

    def export(self, folder: PathLike, bound: Optional[float] = None) -> None:
        """Writes the problem as ``contactlab export`` does, with the README
        that says what each file holds and how to hand an answer back to
        ``certify``. The folder is replaced whole, only if it is empty or a
        contactlab run."""
        _contactlab.export(self._p, _path(folder, "folder"), _number(bound, "bound"))

    @property
    def name(self) -> str:
        return self._p.name

    @property
    def h(self) -> Optional[str]:
        """The finest mesh as the command line writes it ("1/64"); None for
        a problem given by its matrices."""
        return self._p.h

    @property
    def n(self) -> int:
        """The number of unknowns."""
        return self._p.n

    @functools.cached_property
    def A(self) -> scipy.sparse.csr_array:
        return _csr(self._p._a(), (self.n, self.n))

    @functools.cached_property
    def M(self) -> scipy.sparse.csr_array:
        return _csr(self._p._m(), (self.n, self.n))

    @functools.cached_property
    def f(self) -> np.ndarray:
        return _read_only(self._p.f)

    @functools.cached_property
    def contact(self) -> Contact:
        return Contact(**{k: (None if v is None else _read_only(v)) for k, v in self._p._contact().items()})

    @property
    def scales(self) -> Dict[str, float]:
        """The problem's own scales: ``force``, ``contact_load``, ``length``
        (of Γ_K), ``stiffness``, ``pressure`` (P) and ``displacement`` (U),
        in which the certificate and ``compare`` measure."""
        return dict(self._p.scales)

    @functools.cached_property
    def rigid_mode(self) -> np.ndarray:
        return _read_only(self._p.rigid_mode)

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
    #: An upper bound on the answer's error (``solve`` and ``certify``): ``energy``
    #: (‖v − v*‖_A), ``displacement`` (the same over √K·U), ``pressure``
    #: (max|p − p*| over P), ``kind`` and ``summary``; or ``not_computed``
    #: saying why. See the README's "The error bound".
    error_bound: Optional[Dict] = None

    @classmethod
    def _of(cls, d: Mapping) -> "Certificate":
        return cls(
            passed=bool(d["passed"]),
            tolerance=float(d["tolerance"]),
            residual=float(d["residual"]),
            summary=str(d["summary"]),
            violations=dict(d["violations"]),
            law=str(d.get("law", "coulomb")),
            error_bound=dict(d["error_bound"]) if "error_bound" in d else None,
        )


@dataclass(frozen=True, repr=False)
class Result:
    """One certified solve.

    Attributes
    ----------
    status : Status
        The certified verdict; ``solver_status`` is the solver's own claim.
    success : bool
        ``status == Status.CONVERGED`` (as scipy's ``OptimizeResult``).
    message : str
        Why the solver stopped (``detail``).
    stopped_by_callback : bool
        The progress callback asked to stop.
    """

    solver: str
    status: Status
    solver_status: Status
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
    #: ``profile.csv`` (None for a problem without a mesh).
    profile_csv: Optional[str] = None
    stopped_by_callback: bool = False

    @property
    def success(self) -> bool:
        return self.status == Status.CONVERGED

    @property
    def message(self) -> str:
        return self.detail

    def __repr__(self) -> str:
        return (
            f"Result(solver={self.solver!r}, status={self.status.value!r}, "
            f"solver_status={self.solver_status.value!r}, residual={self.certificate.residual:.2e}, "
            f"iterations={self.iterations}, seconds={self.seconds:.3g})"
        )


def _problem(problem) -> None:
    if not isinstance(problem, Problem):
        raise InputError(f"problem: give a contactlab.Problem (got {type(problem).__name__})")


def _settings(settings) -> List[tuple]:
    """``{path: value}`` (or pairs) as text, in the order given, as
    ``--set path=value`` writes them: the engine resolves them with the
    library's one resolution (the later change of a setting wins; a setting
    of a solver that does not run is refused)."""
    if settings is None:
        return []
    if isinstance(settings, Mapping):
        pairs = list(settings.items())
    else:
        try:
            pairs = [tuple(item) for item in settings]
        except TypeError:
            raise InputError(
                f"settings = {settings!r}: give a mapping {{path: value}}, e.g. {{\"tnnmg.tolerance\": 1e-10}}"
            ) from None
        if any(len(pair) != 2 for pair in pairs):
            raise InputError("settings: give a mapping {path: value} or (path, value) pairs")
    out = []
    for path, value in pairs:
        if isinstance(value, bool):
            value = "true" if value else "false"
        out.append((str(path), str(value)))
    return out


def _options(options, solver: str, name: str = "options") -> List[tuple]:
    """A solver's own settings without its prefix, as scipy's ``options``
    of a ``method`` (``{"tolerance": 1e-12}`` for ``newton-coulomb.tolerance``):
    the pairs ``--set SOLVER.KNOB=VALUE`` writes. The engine validates them
    once, as every setting: a knob the solver does not have is refused with
    the list of those it has."""
    if options is None:
        return []
    if not isinstance(options, Mapping):
        raise InputError(f"{name} = {options!r}: give a mapping {{knob: value}}, e.g. {{\"tolerance\": 1e-10}}")
    out = []
    for knob, value in options.items():
        knob = str(knob)
        if "." in knob:
            raise InputError(
                f"{name}: `{knob}` is a path; give the knob alone ({knob.rsplit('.', 1)[-1]}), "
                f"or the path in settings="
            )
        out.extend(_settings({f"{solver}.{knob}": value}))
    return out


#: A progress callback: called with ``{"stage", "iteration", "residual",
#: "seconds"}`` for each step of the friction fixed point and of a solver's
#: outer loop; returning ``False`` (or raising) stops the solve.
Callback = Callable[[Dict[str, object]], Optional[bool]]


def solve(
    problem: Problem,
    solver: Optional[str] = None,
    settings: Optional[Mapping[str, object]] = None,
    bound: Optional[Sequence[float]] = None,
    target: Optional[float] = None,
    callback: Optional[Callback] = None,
    options: Optional[Mapping[str, object]] = None,
) -> Result:
    """Solves the problem and certifies the answer: ``contactlab solve``.

    Parameters
    ----------
    problem : Problem
    solver : str, optional
        A registered solver (the oracle if none).
    settings : mapping, optional
        ``OWNER.NAME`` paths to values, as ``--set`` does
        (``{"newton-coulomb.tolerance": 1e-12}``).
    bound : array, optional
        Solve the given-friction subproblem at this bound instead of the
        Coulomb law.
    target : float, optional
        Sets the solver's accuracy knob and ε below it and certifies at it,
        as the benchmark does.
    callback : callable, optional
        See ``Callback``; a raised exception is raised again here.
    options : mapping, optional
        The solver's own settings by knob, as scipy's ``options`` of a
        ``method`` (``solver="newton-coulomb", options={"tolerance": 1e-12}``
        is ``settings={"newton-coulomb.tolerance": 1e-12}``); applied after
        ``settings``. Needs ``solver``.

    Returns
    -------
    Result
    """
    _problem(problem)
    if solver is not None and not isinstance(solver, str):
        raise InputError(f"solver = {solver!r}: give a registered solver's name ({', '.join(solvers())})")
    if callback is not None and not callable(callback):
        raise InputError(f"callback = {callback!r}: give a function of the progress dict")
    if options is not None and solver is None:
        raise InputError("options: name the solver they are for (solver=...), or give paths in settings=")
    g = _array(bound, "bound")
    d = _contactlab.solve(
        problem._p,
        solver,
        _settings(settings) + _options(options, solver or ""),
        None if g is None else g.tolist(),
        _number(target, "target"),
        callback,
    )
    return Result(
        solver=d["solver"],
        status=Status(d["status"]),
        solver_status=Status(d["solver_status"]),
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
        stopped_by_callback=bool(d["stopped_by_callback"]),
    )


def _array(x, name: str) -> Optional[np.ndarray]:
    """A one-dimensional array of real numbers (integers or floats), as
    float64; complex values, booleans, objects and strings are refused
    rather than cast (a complex answer's imaginary part would be lost)."""
    if x is None:
        return None
    a = np.asarray(x)
    if a.dtype.kind not in "iuf":
        raise InputError(
            f"{name}: give real numbers (an array of dtype {a.dtype} was given"
            + (": its imaginary part would be lost)" if a.dtype.kind == "c" else ")")
        )
    a = np.ascontiguousarray(a, dtype=np.float64)
    if a.ndim != 1:
        raise InputError(f"{name}: give a one-dimensional array (it has shape {a.shape})")
    return a


def _forces(forces):
    """``(pressure, friction_traction)``, or a mapping with those keys."""
    if forces is None:
        return None, None
    if isinstance(forces, Mapping):
        keys = set(forces)
        if keys != {"pressure", "friction_traction"}:
            raise InputError(
                f"forces: give the keys 'pressure' and 'friction_traction' (got {sorted(map(str, keys))})"
            )
        return forces["pressure"], forces["friction_traction"]
    try:
        p, q = forces
    except (TypeError, ValueError):
        raise InputError("forces: give a pair (pressure, friction_traction) or a mapping with those keys") from None
    return p, q


def certify(
    problem: Problem,
    displacements=None,
    forces: Optional[tuple] = None,
    bound=None,
    tolerance: Optional[float] = None,
) -> Certificate:
    """The certificate of an answer computed anywhere: ``contactlab certify``.

    Parameters
    ----------
    displacements : array of n, optional
        The contact forces then follow from stationarity at the contact rows.
    forces : (pressure, friction_traction), optional
        Per contact node; the displacements then follow from the elastic
        response. Give either or both.
    bound : array, optional
        Check the given-friction law at this bound, else the Coulomb law.
    tolerance : float, optional
        The certificate's tolerance (default 1e-5).
    """
    _problem(problem)
    p, q = _forces(forces)
    if tolerance is not None:
        tolerance = _number(tolerance, "tolerance")
    d = _contactlab.certify(
        problem._p,
        _array(displacements, "displacements"),
        _array(p, "pressure"),
        _array(q, "friction_traction"),
        _array(bound, "bound"),
        tolerance,
    )
    return Certificate._of(d)


@dataclass(frozen=True, repr=False)
class StudyResult:
    """What a study gave: the rows of its main table, every table it wrote
    as rows, every file it wrote (the bytes the command line writes for the
    same inputs), its charts (SVG) and its report (its README section,
    Markdown).

    ``rows`` is the main table (``compare.csv``, ``benchmark.csv``,
    ``work_precision.csv``, ...) as one dict per row, in the file's column
    order, typed as the library computed them (numbers as numbers, a value
    the file leaves empty as None): the data itself, not the file read
    back. ``table(path)`` gives any other table it wrote; ``frame(path)``
    the same as a pandas DataFrame (``pip install ./python[pandas]``).
    """

    rows: List[Dict[str, object]]
    files: Dict[str, bytes]
    charts: Dict[str, bytes]
    report: str
    tables: Dict[str, List[Dict[str, object]]] = field(default_factory=dict)
    main: str = ""

    def table(self, path: str) -> List[Dict[str, object]]:
        """The rows of the table the study wrote as the CSV file ``path``."""
        if path not in self.tables:
            raise InputError(f"{path}: the study's tables are {', '.join(sorted(self.tables))}")
        return self.tables[path]

    def frame(self, path: Optional[str] = None):
        """The table ``path`` (the main one if None) as a pandas DataFrame,
        its columns in the file's order."""
        try:
            import pandas
        except ImportError:
            raise ImportError(
                "frame() needs pandas: pip install pandas (or ./python[pandas]); "
                "table() gives the same rows as dicts"
            ) from None
        path = self.main if path is None else path
        rows = self.table(path)
        columns = list(rows[0]) if rows else None
        return pandas.DataFrame.from_records(rows, columns=columns)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({len(self.rows)} rows, files: {', '.join(sorted(self.files))})"


def _result(d, main: str, cls=None, **extra) -> "StudyResult":
    """A study's result from what the library gave: its tables as the
    typed records the library serialized (JSON of the Rust rows), never a
    CSV file parsed back."""
    tables = {path: json.loads(text) for path, text in dict(d["tables"]).items()}
    return (cls or StudyResult)(
        rows=tables[main],
        files=dict(d["files"]),
        charts=dict(d["charts"]),
        report=d["report"],
        tables=tables,
        main=main,
        **extra,
    )


@dataclass(frozen=True, repr=False)
class BenchmarkResult(StudyResult):
    """A benchmark's runs and its views: ``summaries`` is
    ``benchmark_summary.csv`` (per target and solver: success rate, runs
    claimed but refused, shifted geometric mean of the time)."""

    summaries: List[Dict[str, object]] = ()


def _solver_names(solvers) -> List[str]:
    """Registered names, Python functions registered under their keys."""
    if isinstance(solvers, str):
        return [solvers]
    if isinstance(solvers, Mapping):
        names = []
        for name, how in solvers.items():
            if callable(how):
                register(name, how)
            elif how != name:
                raise InputError(
                    f"solvers[{name!r}] = {how!r}: give a function fn(problem, target), "
                    "or the registered solver's own name"
                )
            names.append(str(name))
        return names
    try:
        names = list(solvers)
    except TypeError:
        raise InputError(f"solvers = {solvers!r}: give solver names or a mapping {{name: function}}") from None
    if not all(isinstance(n, str) for n in names):
        raise InputError(f"solvers = {solvers!r}: give solver names or a mapping {{name: function}}")
    return names


def _targets(targets) -> List[float]:
    try:
        out = [_number(t, "targets") for t in targets]
    except TypeError:
        raise InputError(f"targets = {targets!r}: give a list of accuracies such as [1e-4, 1e-8]") from None
    return out


def _out(out) -> Optional[str]:
    return None if out is None else _path(out, "out")


Solvers = Union[str, Iterable[str], Mapping[str, Union[str, PythonSolver]]]


def compare(
    problem: Problem,
    solvers: Solvers,
    settings: Optional[Mapping[str, object]] = None,
    repeats: int = 0,
    out: Optional[PathLike] = None,
    reference: Optional[str] = None,
    options: Optional[Mapping[str, Mapping[str, object]]] = None,
) -> StudyResult:
    """Every solver against the earned reference: ``contactlab compare``.

    Each solver runs on the problem's given-friction subproblem at the
    reference's bound (if it solves it) and on the whole Coulomb problem;
    each answer is certified and measured against the reference (every
    exact solver at its tightest settings, the certified answer with the
    smallest certificate).

    Parameters
    ----------
    problem : Problem
        Built from a scene.
    solvers : names, or a mapping {name: function or name}
        A function is registered under its name (see ``register``).
    settings : mapping, optional
        As for ``solve``; applied on the scene file's settings.
    repeats : int
        Timed runs after the first (``--runs`` less one).
    out : path, optional
        Writes the run folder as ``contactlab compare --out`` does.
    reference : str, optional
        A solver whose answer (at its tightest settings, if certified) is
        the reference instead of the earned one (``--reference``).
    options : mapping {solver: {knob: value}}, optional
        Each solver's own settings by knob, as for ``solve``
        (``{"tnnmg": {"tolerance": 1e-10}}``); applied after ``settings``.

    Returns
    -------
    StudyResult
        ``rows``: ``compare.csv``.
    """
    _problem(problem)
    if isinstance(repeats, bool) or not isinstance(repeats, numbers.Integral) or repeats < 0:
        raise InputError(f"repeats = {repeats!r}: give a count ≥ 0")
    if options is not None and not isinstance(options, Mapping):
        raise InputError(f"options = {options!r}: give a mapping {{solver: {{knob: value}}}}")
    scoped = [
        pair
        for name, knobs in (options or {}).items()
        for pair in _options(knobs, str(name), f"options[{name!r}]")
    ]
    d = _contactlab._compare(
        problem._p,
        _solver_names(solvers),
        _settings(settings) + scoped,
        int(repeats),
        _out(out),
        None if reference is None else str(reference),
    )
    return _result(d, "compare.csv")


def benchmark(
    problems: Iterable[Problem],
    solvers: Solvers,
    targets: Sequence[float] = (1e-4, 1e-8),
    time_limit: float = 60.0,
    settings: Optional[Mapping[str, object]] = None,
    out: Optional[PathLike] = None,
) -> BenchmarkResult:
    """A benchmark over ``problems``: ``contactlab benchmark``'s study.

    Every solver at every target accuracy τ on every problem: its accuracy
    knob and ε at 0.1·τ, the certificate at τ; a run succeeds if its answer
    passes within ``time_limit`` seconds (a Python function cannot be
    interrupted: a slower run counts as failed at the limit).

    Returns
    -------
    BenchmarkResult
        ``rows``: ``benchmark.csv``; ``summaries``: ``benchmark_summary.csv``;
        ``report``: ``benchmark.md``'s tables. With ``out`` the folder the
        command line writes (LaTeX tables and performance profiles too).
    """
    problems = list(problems)
    for p in problems:
        _problem(p)
    limit = _number(time_limit, "time_limit")
    d = _contactlab._benchmark(
        [p._p for p in problems],
        _solver_names(solvers),
        _targets(targets),
        limit,
        _settings(settings),
        _out(out),
    )
    tables = dict(d["tables"])
    return _result(
        d, "benchmark.csv", BenchmarkResult, summaries=json.loads(tables["benchmark_summary.csv"])
    )


def work_precision(
    problem: Problem,
    solvers: Solvers,
    targets: Sequence[float] = (1e-4, 1e-6, 1e-8),
    settings: Optional[Mapping[str, object]] = None,
    repeats: int = 0,
    chart: Optional[PathLike] = None,
    out: Optional[PathLike] = None,
    x: str = "violation",
) -> StudyResult:
    """Work against precision: each solver at each target accuracy (the
    benchmark's rule), certified at the target, timed, and measured against
    the earned reference.

    Parameters
    ----------
    chart : path ending in .svg, optional
        Writes the chart: accuracy (``x``) against seconds, certified points
        joined, failed ones as crosses.
    x : str
        The chart's accuracy: ``"violation"``, the certificate's largest
        violation; ``"bound"``, the error bound on ‖v − v*‖_A over √K·U
        (issue 51: it needs no reference; computed up to
        ``certificate.bound_max_unknowns`` unknowns, h = 1/512 by default);
        or ``"bound-vs-error"``, the bound against the measured distance
        from the reference (no time axis). Every chart is also in
        ``charts`` of the result.

    Returns
    -------
    StudyResult
        ``rows``: ``work_precision.csv``.
    """
    _problem(problem)
    if chart is not None:
        chart = _path(chart, "chart")
        if not chart.lower().endswith(".svg"):
            raise InputError(f"chart = {chart!r}: charts are SVG; give a path ending in .svg")
    if isinstance(repeats, bool) or not isinstance(repeats, numbers.Integral) or repeats < 0:
        raise InputError(f"repeats = {repeats!r}: give a count ≥ 0")
    charts_of_x = {"violation": "work_precision", "bound": "work_precision_bound", "bound-vs-error": "work_precision_bound_vs_error"}
    if x not in charts_of_x:
        raise InputError(f"x = {x!r}: give one of {', '.join(repr(k) for k in charts_of_x)}")
    d = _contactlab._work_precision(
        problem._p,
        _solver_names(solvers),
        _targets(targets),
        _settings(settings),
        int(repeats),
        _out(out),
    )
    charts = dict(d["charts"])
    if chart is not None:
        name = charts_of_x[x]
        if name not in charts:
            raise InputError(
                f"x = {x!r}: no answer has an error bound{' and a reference' if x == 'bound-vs-error' else ''} to draw "
                "(the bound is computed up to certificate.bound_max_unknowns unknowns; raise it in settings)"
            )
        try:
            with open(chart, "wb") as fh:
                fh.write(charts[name])
        except OSError as e:
            raise FileError(f"cannot write {chart}: {e.strerror}") from None
    return _result(d, "work_precision.csv")


def error_bound(
    quick: bool = False,
    long: bool = False,
    settings: Optional[Mapping[str, object]] = None,
    out: Optional[PathLike] = None,
    **spec,
) -> StudyResult:
    """Does the certificate's error bound hold, and how sharp is it?
    ``contactlab error-bound`` (the catalogued study ``study("error-bound")``).

    Every solver's answers on the benchmark's core collection (given
    friction, targets 1e-4, 1e-6, 1e-8) and on problem 1 refined (both
    laws; the main job's ladder to h = 1/256, ``long``: to 1/1024), each
    answer's bound on ‖v − v*‖_A beside its measured distance from a
    reference (``quick``: the quick collection and h to 1/16, seconds).
    ``spec``: ``targets``, ``ladder_problem``, ``ladder_meshes``,
    ``ladder_targets``, ``time_limit``.

    Returns
    -------
    StudyResult
        ``rows``: ``error_bound.csv`` (one answer per row: its bound, its
        measured error, the reference's own bound); ``table`` also gives
        ``error_bound_sharpness.csv``.
    """
    return study("error-bound", quick=quick, long=long, settings=settings, out=out, **spec)


def verify(
    quick: bool = False,
    long: bool = False,
    solvers: Optional[Sequence[str]] = None,
    settings: Optional[Mapping[str, object]] = None,
    out: Optional[PathLike] = None,
    **spec,
) -> StudyResult:
    """The classical scenes against their closed forms: ``contactlab verify``
    (the catalogued study ``study("verify")``).

    Hertz's line contact, a flat punch and Cattaneo–Mindlin sheared by its
    sides and free to slide (``scenes/``) at h = 1/32 … 1/512, 10 s a solve
    (``long``: 1/64 … 1/1024, 300 s; ``quick``: 1/32, 1/64, 5 s), each
    solver's certified answer beside the half-plane closed form.
    ``spec``: ``meshes``, ``time_limit``.

    Returns
    -------
    StudyResult
        ``rows``: ``verification.csv`` (one row per scene, mesh and solver:
        status, L2 and max error of the pressure, observed order, half-width
        and p₀ beside their closed forms); ``files`` also holds each
        profile, ``profiles/SCENE_hN_SOLVER.csv``.
    """
    if solvers is not None:
        spec["solvers"] = [str(s) for s in solvers]
    r = study("verify", quick=quick, long=long, settings=settings, out=out, **spec)
    return replace(r, rows=r.tables["verification.csv"], main="verification.csv")


def studies() -> Dict[str, str]:
    """The catalogued studies: each one's name (its command,
    ``contactlab NAME``) and what it measures. Each is a call here too:
    ``study(NAME, ...)``, and a function of its own (``NAME`` with ``_``
    for ``-``) unless one of the calls above has that name."""
    return {command: about for command, about, _ in _contactlab._studies()}


def study(
    name: str,
    quick: bool = False,
    long: bool = False,
    settings: Optional[Mapping[str, object]] = None,
    out: Optional[PathLike] = None,
    **spec,
) -> StudyResult:
    """A catalogued study (``studies()``), as ``contactlab NAME`` runs it.

    Parameters
    ----------
    name : str
        The study's command, such as ``"discretization-error"``.
    quick, long : bool
        The run length whose budget it takes (``--quick``, ``--long``;
        neither: the main job's).
    **spec
        Its parameters, each a field of its spec (the command's flags,
        ``_`` for ``-``): ``meshes=["1/16", "1/32"]``. An unknown one is an
        ``InputError`` naming the parameters there are; each is checked in
        the library, where the command line's are.

    Returns
    -------
    StudyResult
        ``rows``: its main table (the one named after it, else its first);
        ``table(path)`` and ``frame(path)`` the others, all as the library
        computed them.
    """
    for flag, value in (("quick", quick), ("long", long)):
        if not isinstance(value, bool):
            raise InputError(f"{flag} = {value!r}: give True or False")
    if quick and long:
        raise InputError("quick and long: give one of them, or neither")
    length = "quick" if quick else "long" if long else "standard"
    d = _contactlab._study(str(name), length, json.dumps(spec), _settings(settings), _out(out))
    tables = list(dict(d["tables"]))
    if not tables:
        raise Error(f"{name}: the study wrote no table")
    # Its main table: the one named after it, else the first it wrote.
    main = name.replace("-", "_") + ".csv"
    return _result(d, main if main in tables else tables[0])


def _catalogued(command: str, about: str, spec: str):
    """The call of the catalogued study ``command``."""

    def call(quick: bool = False, long: bool = False, settings=None, out=None, **kwargs) -> StudyResult:
        return study(command, quick=quick, long=long, settings=settings, out=out, **kwargs)

    call.__name__ = call.__qualname__ = command.replace("-", "_")
    call.__doc__ = (
        f"{about}\n\n``contactlab {command}``: see ``study``. Its parameters at the main job's "
        f"budget: {spec}."
    )
    return call


def sweep(
    problem: Problem,
    solvers: Solvers,
    settings: Optional[Mapping[str, object]] = None,
    quick: bool = False,
    work_precision: bool = True,
    repeats: int = 2,
    out: Optional[PathLike] = None,
) -> StudyResult:
    """Each solver's settings swept on the problem's scene and mesh:
    ``contactlab sweep``.

    Every setting the registry's study plans vary for the solver (one at a
    time, on the Coulomb problem), and its accuracy knob on the
    given-friction subproblem (the work-precision diagram), each trial
    certified and measured against the earned reference.

    Parameters
    ----------
    quick : bool
        The registry's short value lists (``--quick``).
    work_precision : bool
        False skips the work-precision diagram (``--no-work-precision``).
    repeats : int
        Timed runs of each work-precision trial after the first (``--runs``).

    Returns
    -------
    StudyResult
        ``rows``: ``sweep.csv``; ``report``: the sweep's README section.
    """
    _problem(problem)
    if isinstance(repeats, bool) or not isinstance(repeats, numbers.Integral) or repeats < 0:
        raise InputError(f"repeats = {repeats!r}: give a count ≥ 0")
    d = _contactlab._sweep(
        problem._p,
        _solver_names(solvers),
        _settings(settings),
        bool(quick),
        bool(work_precision),
        int(repeats),
        _out(out),
    )
    return _result(d, "sweep.csv")


def side_by_side(
    problem: Problem,
    pairs: Sequence[Tuple[str, str]],
    settings: Optional[Mapping[str, object]] = None,
    out: Optional[PathLike] = None,
) -> StudyResult:
    """Pairs of answers node by node: ``contactlab compare --side-by-side``.

    Each side is a solver's name, ``"reference"`` (the earned reference:
    the exact solvers at their tightest settings, never the method under
    test) or the path of a ``profile.csv`` written by ``solve(..., out=)``
    or ``contactlab solve --out``.

    Parameters
    ----------
    problem : Problem
        Built from a scene.
    pairs : sequence of (a, b)
        E.g. ``[("relaxation", "clarabel"), ("relaxation", "reference")]``.
    settings : mapping, optional
        As for ``solve``.
    out : path, optional
        Writes the run folder as ``contactlab compare --side-by-side
        ... --out`` does.

    Returns
    -------
    StudyResult
        ``rows``: ``side_by_side.csv`` (per pair the largest differences in
        the problem's scales and the nodes whose contact states differ);
        ``table("side_by_side_<a>_<b>.csv")``: every contact node of a pair.
    """
    _problem(problem)
    pairs = [(str(a), str(b)) for a, b in pairs]
    d = _contactlab._side_by_side(problem._p, pairs, _settings(settings), _out(out))
    return _result(d, "side_by_side.csv")


def tuning_map(
    problem: Problem,
    solver: str,
    axes: Mapping[str, Sequence[object]],
    law: str = "coulomb",
    repeats: int = 2,
    settings: Optional[Mapping[str, object]] = None,
    out: Optional[PathLike] = None,
    time_limit: Optional[float] = None,
) -> StudyResult:
    """A solver on a joint grid of two or three of its settings:
    ``contactlab sweep --grid ...``.

    Parameters
    ----------
    problem : Problem
        Built from a scene.
    solver : str
        The solver mapped (its fast form beyond h = 1/64, e.g. the paper's
        method with ``inner = multigrid``, unless ``settings`` chooses).
    axes : mapping path -> values
        Two or three settings, e.g. ``{"relaxation.r": [1e3, 1e5, 1e7],
        "relaxation.epsilon": [1e-4, 1e-6]}``.
    law : "coulomb" or "given_friction"
    repeats : int
        Timed runs of each point after the first (``--runs``).
    time_limit : float, optional
        Seconds each point's solve may take (``--time-limit``): a point
        that hits it has the status ``time_limit`` and is not certified.

    Returns
    -------
    StudyResult
        ``rows``: the map (one row per point: its values, status, median
        and fastest seconds, work, certificate, and ``mark``: ``best``,
        ``tie`` within the run's timing noise, or empty); ``report``
        states the best setting with its margin.
    """
    _problem(problem)
    if isinstance(repeats, bool) or not isinstance(repeats, numbers.Integral) or repeats < 0:
        raise InputError(f"repeats = {repeats!r}: give a count ≥ 0")
    grid = [(str(path), [str(v) for v in values]) for path, values in axes.items()]
    d = _contactlab._tuning_map(
        problem._p,
        str(solver),
        grid,
        str(law),
        int(repeats),
        _settings(settings),
        _out(out),
        _number(time_limit, "time_limit"),
    )
    main = next(f for f in dict(d["tables"]) if f.startswith("tuning_map_") and "_trials" not in f)
    return _result(d, main)


for _command, _about, _spec in _contactlab._studies():
    _name = _command.replace("-", "_")
    if _name not in globals():
        globals()[_name] = _catalogued(_command, _about, _spec)
        __all__.append(_name)
