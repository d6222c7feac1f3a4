"""The Python package against the command line and against the mechanics.

Each test names the mistake it catches.
"""

import os
import pathlib
import subprocess

import numpy as np
import pytest

import contactlab as cl

ROOT = pathlib.Path(__file__).resolve().parents[2]


def cli() -> pathlib.Path:
    """The command line built from the same checkout (built if missing)."""
    given = os.environ.get("CONTACTLAB_BIN")
    if given:
        return pathlib.Path(given)
    binary = ROOT / "target" / "release" / "contactlab"
    if not binary.exists():
        subprocess.run(["cargo", "build", "--release"], cwd=ROOT, check=True)
    return binary


def read_mtx_vector(path: pathlib.Path) -> np.ndarray:
    """A Matrix Market coordinate column, read by scipy."""
    import scipy.io

    return np.asarray(scipy.io.mmread(str(path)).todense()).ravel()


@pytest.fixture(scope="module")
def p32():
    return cl.Problem.paper(1, h="1/32")


def test_the_registry_is_the_command_lines():
    # A package that kept its own list of solvers would miss new ones.
    names = cl.solvers()
    assert "newton-coulomb" in names and "clarabel" in names and "tnnmg" in names
    assert len(names) == len(set(names))


def test_the_matrices_are_the_problems(p32):
    # A wrong CSR conversion (indices and indptr swapped, a transposed
    # block) breaks symmetry or the rigid mode.
    A, M, f = p32.A, p32.M, p32.f
    assert A.shape == (p32.n, p32.n) and M.shape == A.shape and f.shape == (p32.n,)
    assert abs(A - A.T).max() <= 1e-12 * abs(A).max()
    # A's kernel is the upper body's vertical translation (paper's
    # semicoercive problem): A z = 0 to round-off.
    z = p32.rigid_mode
    assert np.linalg.norm(z) > 0
    assert np.linalg.norm(A @ z) <= 1e-10 * abs(A).max() * np.linalg.norm(z)
    # M is positive definite: zᵀ M z > 0 for the rigid mode.
    assert z @ (M @ z) > 0
    c = p32.contact
    assert len(c) == 33  # nodes 0, 1/32, ..., 1 on Γ_K at h = 1/32
    assert np.all(np.diff(c.x) > 0) and np.all(c.weight > 0)
    assert set(c.t).isdisjoint(set(c.s))


def test_a_solve_is_the_command_lines_to_the_bit(tmp_path, p32):
    # A package that resolved settings or assembled the scene differently
    # from `contactlab solve` gives other bits.
    out = tmp_path / "run"
    subprocess.run(
        [
            str(cli()),
            "solve",
            "--problem",
            "1",
            "--h",
            "1/32",
            "--solver",
            "newton-coulomb",
            "--set",
            "newton-coulomb.tolerance=1e-12",
            "--out",
            str(out),
        ],
        check=True,
        capture_output=True,
    )
    r = cl.solve(p32, solver="newton-coulomb", settings={"newton-coulomb.tolerance": 1e-12})
    assert r.status == "converged" and r.certificate.passed
    assert (out / "profile.csv").read_text() == r.profile_csv
    v = read_mtx_vector(out / "displacements.mtx")
    assert v.shape == r.displacements.shape
    assert np.array_equal(v, r.displacements)
    forces = np.loadtxt(out / "forces.csv", delimiter=",", skiprows=1)
    assert np.array_equal(forces[:, 0], r.pressure)
    assert np.array_equal(forces[:, 1], r.friction_traction)


def test_the_mass_matrix_and_the_relaxation_are_the_command_lines(tmp_path, p32):
    # A scene's problem holds no M: `M` assembles it on first use, and a
    # relaxation solve (the one solver that reads it) assembles its own
    # finest level. An M on another pattern or in other unknowns than the
    # command line's, or a relaxation refused for want of M, fails it.
    import scipy.io

    out = tmp_path / "export"
    subprocess.run(
        [str(cli()), "export", "--problem", "1", "--h", "1/32", "--out", str(out)],
        check=True,
        capture_output=True,
    )
    M = scipy.io.mmread(str(out / "M.mtx")).tocsr()
    assert p32.M.shape == M.shape
    assert abs(p32.M - M).max() <= 1e-15 * abs(M).max()
    run = tmp_path / "run"
    subprocess.run(
        [str(cli()), "solve", "--problem", "1", "--h", "1/32", "--solver", "relaxation", "--out", str(run)],
        check=True,
        capture_output=True,
    )
    r = cl.solve(p32, solver="relaxation")
    assert r.status == "converged" and r.certificate.passed
    assert np.array_equal(read_mtx_vector(run / "displacements.mtx"), r.displacements)


def test_certify_accepts_the_true_answer_and_refuses_a_wrong_one(p32):
    # A certificate that trusted its input, or checked the wrong rows,
    # would pass the wrong answers.
    r = cl.solve(p32, solver="newton-coulomb", settings={"newton-coulomb.tolerance": 1e-12})
    assert cl.certify(p32, displacements=r.displacements).passed
    assert cl.certify(p32, forces=(r.pressure, r.friction_traction)).passed
    assert cl.certify(
        p32, displacements=r.displacements, forces=(r.pressure, r.friction_traction)
    ).passed

    # Push the bodies into each other at one contact node: penetration.
    u = r.displacements.copy()
    t = p32.contact.t
    u[t[t.size // 2]] = 1e-3
    c = cl.certify(p32, displacements=u)
    assert not c.passed
    assert c.violations["nonpenetration"] > c.tolerance

    # The frictionless answer is not the Coulomb answer at 𝓕 = 0.5.
    free = cl.solve(p32, solver="newton", bound=np.zeros(len(p32.contact)))
    assert free.certificate.passed  # it solves its own, frictionless, problem
    assert not cl.certify(p32, displacements=free.displacements).passed

    # A pressure that pulls (p < 0) is refused even with the matching v.
    p = r.pressure.copy()
    p[np.argmax(p)] *= -1
    assert not cl.certify(p32, forces=(p, r.friction_traction)).passed


def test_certify_bounds_the_error_and_the_bound_grows_with_it(p32):
    # The bound of issue 51, beside the verdict: tiny for the true answer
    # of its own given-friction problem, at least the true error of a
    # perturbed one (one node moved by 1e-3 U: error √A_kk · 1e-3 U).
    g = np.full(len(p32.contact), 5.0)
    r = cl.solve(p32, solver="newton", bound=g)
    c = cl.certify(p32, displacements=r.displacements, forces=(r.pressure, r.friction_traction), bound=g)
    b = c.error_bound
    assert b["kind"] == "rigorous", b
    u = r.displacements.copy()
    k = u.size // 3
    size = 1e-3 * np.abs(u).max()
    u[k] += size
    moved = cl.certify(p32, displacements=u, forces=(r.pressure, r.friction_traction), bound=g)
    a_kk = p32.A[k, k]
    assert moved.error_bound["energy"] >= np.sqrt(a_kk) * size - b["energy"]
    assert moved.error_bound["energy"] > 100 * b["energy"]
    # A Coulomb answer is bounded at its own g = 𝓕p, and says so.
    coulomb = cl.certify(p32, displacements=r.displacements)
    assert "fixed-point part not included" in coulomb.error_bound["kind"]
    # solve carries the same bound as the command line prints (issue 75:
    # it was None), and where it is not computed it says why.
    assert r.certificate.error_bound["kind"] == "rigorous", r.certificate.error_bound
    assert r.certificate.error_bound["energy"] == pytest.approx(b["energy"], rel=1e-6, abs=1e-300)
    skipped = cl.solve(p32, solver="newton", bound=g, settings={"certificate.bound_max_unknowns": 0})
    assert "bound_max_unknowns" in skipped.certificate.error_bound["not_computed"]


def test_errors_are_the_command_lines_one_line_messages(p32):
    with pytest.raises(cl.Error, match="unknown solver 'nope': the registered solvers are"):
        cl.solve(p32, solver="nope")
    with pytest.raises(cl.Error, match=r"apgd.tolerance = 'x' is invalid"):
        cl.solve(p32, solver="apgd", settings={"apgd.tolerance": "x"})
    with pytest.raises(cl.Error, match="unknown problem 4"):
        cl.Problem.paper(4)
    with pytest.raises(cl.Error, match="displacements has 3 values, expected 2162"):
        cl.certify(p32, displacements=np.zeros(3))
    with pytest.raises(cl.Error, match=r"displacements\[0\] is NaN: give finite values"):
        cl.certify(p32, displacements=np.full(p32.n, np.nan))
    with pytest.raises(cl.Error, match="no answer given"):
        cl.certify(p32)


def projected_gradient(problem, target):
    """FISTA on the given-friction subproblem (t ≤ 0 projected, w g|s|
    soft-thresholded) inside the friction fixed point g = 𝓕 p: the README's
    example of a solver written in numpy."""
    import scipy.sparse.linalg as sla

    A, f, c = problem.A, problem.f, problem.contact
    L = sla.eigsh(A, k=1, return_eigenvectors=False)[0]
    v, g = np.zeros(problem.n), np.zeros(len(c))
    for _ in range(30):
        y, v_old, a = v.copy(), v.copy(), 1.0
        for _ in range(20000):
            z = y - (A @ y - f) / L
            z[c.t] = np.minimum(z[c.t], 0.0)
            z[c.s] = np.sign(z[c.s]) * np.maximum(abs(z[c.s]) - c.weight * g / L, 0.0)
            a_new = (1 + np.sqrt(1 + 4 * a * a)) / 2
            y, v_old, v, a = z + (a - 1) / a_new * (z - v), v, z, a_new
            if np.linalg.norm(v - v_old) <= 1e-3 * target * np.linalg.norm(v):
                break
        p = -(A @ v - f)[c.t] / c.weight
        g_new = c.coefficient * np.maximum(p, 0.0)
        if np.max(abs(g_new - g)) <= target * max(np.max(abs(g_new)), 1e-300):
            break
        g = g_new
    return v


def test_a_python_solver_passes_through_a_study(tmp_path):
    # A study that skipped the certificate for Python solvers, or dropped
    # them from its trials or chart, fails here.
    p = cl.Problem.paper(1, h="1/8")

    def liar(problem, target):
        return np.zeros(problem.n)  # claims nothing, answers nothing

    chart = tmp_path / "wp.svg"
    r = cl.work_precision(
        p,
        {"newton-coulomb": "newton-coulomb", "numpy-fista": projected_gradient, "zeros": liar},
        targets=[1e-4],
        chart=str(chart),
    )
    by = {t["solver"]: t for t in r.rows}
    assert set(by) == {"newton-coulomb", "numpy-fista", "zeros"}
    assert by["numpy-fista"]["status"] == cl.Status.CONVERGED
    assert by["numpy-fista"]["certificate"] <= 1e-4
    assert by["newton-coulomb"]["status"] == "converged"
    # v = 0 leaves the load unbalanced: claimed, refused.
    assert by["zeros"]["status"] == "inaccurate" and by["zeros"]["solver_status"] == "converged"
    svg = chart.read_text()
    assert "numpy-fista" in svg and "zeros: not certified" in svg
    assert "numpy-fista" in cl.solvers()


def test_a_python_solver_stands_in_the_benchmarks_tables(tmp_path):
    # The benchmark's views must count a Python solver's runs as the
    # command line counts its own: a wrong answer claimed and refused, a
    # right one too slow for the time limit failed, the rows and the
    # performance profile written. A benchmark that trusted a Python
    # answer, ignored the limit or dropped the Python rows fails here.
    import time as clock

    problems = [cl.Problem.paper(1, h="1/8"), cl.Problem.paper(3, h="1/8")]

    def liar(problem, target):
        return np.zeros(problem.n)

    def slow_but_right(problem, target):
        clock.sleep(0.3)
        return cl.solve(problem, solver="newton-coulomb", target=target).displacements

    out = tmp_path / "bench"
    r = cl.benchmark(
        problems,
        {"newton-coulomb": "newton-coulomb", "zeros": liar, "slow": slow_but_right},
        targets=[1e-6],
        time_limit=0.2,
        out=str(out),
    )
    assert len(r.rows) == 6
    by = {s["solver"]: s for s in r.summaries}
    assert by["newton-coulomb"]["successes"] == 2 and by["newton-coulomb"]["relative_to_best"] == 1.0
    assert by["zeros"]["successes"] == 0 and by["zeros"]["claimed_but_failed"] == 2
    # Certified, but not within the limit: failed, and not a false claim.
    slow = [t for t in r.rows if t["solver"] == "slow"]
    assert all(t["status"] == "time_limit" and t["seconds"] > 0.2 for t in slow)
    assert by["slow"]["successes"] == 0 and by["slow"]["claimed_but_failed"] == 0
    assert (out / "benchmark.csv").read_bytes() == r.files["benchmark.csv"]
    assert "zeros" in (out / "benchmark.md").read_text()
    svg = (out / "charts" / "benchmark_profile_1e-6.svg").read_text()
    assert "newton-coulomb" in svg and "slow" in svg


def test_compare_measures_every_answer_against_the_earned_reference():
    # A comparison that took a Python answer as its reference, skipped the
    # certificate for a Python solver, or measured in other scales than
    # the command line's fails here.
    p = cl.Problem.paper(1, h="1/16")
    exact = cl.solve(p, solver="newton-coulomb", target=1e-10)

    def copy(problem, target):
        return {"forces": (exact.pressure, exact.friction_traction)}

    def zeros(problem, target):
        return np.zeros(problem.n)

    r = cl.compare(p, {"newton-coulomb": "newton-coulomb", "copy": copy, "zeros": zeros})
    coulomb = {row["solver"]: row for row in r.rows if row["law"] == "coulomb"}
    assert set(coulomb) == {"newton-coulomb", "copy", "zeros"}
    # The reference is earned by the exact registered solvers, never a
    # Python answer.
    assert {row["reference"] for row in r.rows} <= set(cl.solvers()) - {"copy", "zeros"}
    # The copy of a certified answer, given by its forces alone, is certified
    # and agrees with the reference far below the certificate's tolerance.
    assert coulomb["copy"]["status"] == "converged"
    assert coulomb["copy"]["pressure_error"] <= 1e-6
    assert coulomb["copy"]["displacement_error"] <= 1e-6
    # v = 0 leaves the load unbalanced: refused, and far from the reference.
    assert coulomb["zeros"]["status"] == "inaccurate"
    assert coulomb["zeros"]["pressure_error"] > 0.1
    assert "| copy |" in r.report


def test_compare_and_benchmark_write_the_command_lines_files(tmp_path):
    # Python re-implemented the studies with other numbers under the same
    # names. Now the same inputs give the command line's bytes: every
    # accuracy file of `contactlab compare` and `contactlab benchmark` on
    # the same problem, with a Python solver's rows added.
    p = cl.Problem.paper(1, h="1/16")

    def answer(problem, target):
        return cl.solve(problem, solver="newton-coulomb").displacements

    ours = tmp_path / "py"
    r = cl.compare(p, {"tnnmg": "tnnmg", "newton-coulomb": "newton-coulomb", "py-newton": answer}, out=ours)
    theirs = tmp_path / "cli"
    subprocess.run(
        [str(cli()), "compare", "--problem", "1", "--h", "1/16", "--solvers", "tnnmg,newton-coulomb", "--out", str(theirs)],
        check=True,
        capture_output=True,
    )
    for name in ("compare.csv", "references.csv"):
        mine = (ours / name).read_text().splitlines()
        cli_lines = (theirs / name).read_text().splitlines()
        assert [l for l in mine if ",py-newton," not in l] == cli_lines, name
    assert any(",py-newton," in l for l in (ours / "compare.csv").read_text().splitlines())
    assert (ours / "compare.csv").read_bytes() == r.files["compare.csv"]

    ours = tmp_path / "pyb"
    r = cl.benchmark([p], {"tnnmg": "tnnmg", "newton-coulomb": "newton-coulomb", "py-newton": answer},
                     targets=[1e-6], time_limit=20, out=ours)
    theirs = tmp_path / "clib"
    subprocess.run(
        [str(cli()), "benchmark", "--problem", "1", "--h", "1/16", "--solvers", "tnnmg,newton-coulomb",
         "--targets", "1e-6", "--time-limit", "20", "--out", str(theirs)],
        check=True,
        capture_output=True,
    )
    import csv

    def deterministic(path):
        # Every column but the measured seconds.
        return [{k: v for k, v in row.items() if k != "seconds"} for row in csv.DictReader(path.open())]

    mine = [row for row in deterministic(ours / "benchmark.csv") if row["solver"] != "py-newton"]
    assert mine == deterministic(theirs / "benchmark.csv")
    assert {row["solver"] for row in r.rows} == {"tnnmg", "newton-coulomb", "py-newton"}
    assert all(row["success"] for row in r.rows)


def test_sweep_writes_the_command_lines_sweep(tmp_path):
    # The sweep from Python is `contactlab sweep` on the same scene: its
    # accuracy file, row by row.
    p = cl.Problem.paper(1, h="1/8")
    r = cl.sweep(p, ["relaxation", "tnnmg"], quick=True, repeats=0, out=tmp_path / "py")
    subprocess.run(
        [str(cli()), "sweep", "--problem", "1", "--h", "1/8", "--solvers", "relaxation,tnnmg",
         "--quick", "--runs", "0", "--out", str(tmp_path / "cli")],
        check=True,
        capture_output=True,
    )
    assert (tmp_path / "py" / "sweep.csv").read_bytes() == (tmp_path / "cli" / "sweep.csv").read_bytes()
    assert {row["solver"] for row in r.rows} == {"relaxation", "tnnmg"}
    assert "## Speed against accuracy" in r.report
    with pytest.raises(cl.InputError, match="plans no trials"):
        cl.sweep(p, ["newton-coulomb"], work_precision=False)


def test_side_by_side_and_tuning_map_are_the_command_lines(tmp_path):
    # Side by side and the tuning map from Python are the command line's
    # studies: the same node-by-node file and the same map, the reference
    # the earned one (never the method under test).
    p = cl.Problem.paper(1, h="1/16")
    r = cl.side_by_side(p, [("relaxation", "reference")], out=tmp_path / "py")
    subprocess.run(
        [str(cli()), "compare", "--problem", "1", "--h", "1/16", "--side-by-side", "relaxation,reference",
         "--out", str(tmp_path / "cli")],
        check=True,
        capture_output=True,
    )
    name = "side_by_side_relaxation_reference.csv"
    assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes()
    (row,) = r.rows
    assert row["b"].startswith("reference (") and "relaxation" not in row["b"]
    assert 0 < row["max_dp_over_p"] < 1e-4 and row["states_differ"] == 0
    assert len(r.table(name)) == 17

    m = cl.tuning_map(p, "relaxation", {"relaxation.r": ["1e5", "1e7"], "relaxation.epsilon": ["1e-5", "1e-6"]},
                      law="given_friction", repeats=0, out=tmp_path / "map")
    subprocess.run(
        [str(cli()), "sweep", "--problem", "1", "--h", "1/16", "--grid", "relaxation.r=1e5,1e7",
         "--grid", "relaxation.epsilon=1e-5,1e-6", "--law", "given-friction", "--runs", "0",
         "--out", str(tmp_path / "mapcli")],
        check=True,
        capture_output=True,
    )
    assert len(m.rows) == 4 and sum(row["mark"] == "best" for row in m.rows) == 1
    deterministic = ("relaxation.r", "relaxation.epsilon", "status", "work", "certificate")
    import csv

    def table(folder):
        path = folder / "tuning_map_relaxation_given_friction_h16.csv"
        return [{k: row[k] for k in deterministic} for row in csv.DictReader(path.open())]

    assert table(tmp_path / "map") == table(tmp_path / "mapcli")
    assert "Least work, certified" in m.report
    # --time-limit: each point's solve stops there, with its status.
    limited = cl.tuning_map(p, "relaxation", {"relaxation.r": ["1e5", "1e7"], "relaxation.epsilon": ["1e-8", "1e-9"]},
                            repeats=0, time_limit=0.001)
    assert [row["status"] for row in limited.rows] == ["time_limit"] * 4
    with pytest.raises(cl.InputError, match="time_limit"):
        cl.tuning_map(p, "relaxation", {"relaxation.r": ["1e5", "1e7"], "relaxation.epsilon": ["1e-5", "1e-6"]},
                      time_limit=-1)
    with pytest.raises(cl.InputError, match="two or three"):
        cl.tuning_map(p, "relaxation", {"relaxation.r": [1e5, 1e7]})
    # A reference the user names is the reference of every row.
    named = cl.compare(p, ["relaxation"], reference="tnnmg")
    assert {row["reference"] for row in named.rows} == {"tnnmg"}


def test_status_is_an_enum_that_compares_equal_to_its_name(p32):
    # Statuses were strings; Clarabel users expect an enum.
    assert [s.value for s in cl.Status] == list(cl._contactlab.statuses())
    r = cl.solve(p32, solver="newton-coulomb")
    assert r.status is cl.Status.CONVERGED and r.status == "converged" and r.success
    assert "residual" in repr(r) and len(repr(r)) < 300


def test_errors_are_classes_python_catches():
    # An unreadable file arrived as a ValueError.
    with pytest.raises(cl.FileError) as e:
        cl.Problem.from_scene("/nonexistent/scene.toml")
    assert isinstance(e.value, OSError) and isinstance(e.value, cl.Error)
    with pytest.raises(ValueError):
        cl.Problem.paper(4)
    with pytest.raises(cl.InputError):
        cl.Problem.paper(1, h="1/3")


def test_a_callback_sees_the_fixed_point_and_can_stop_it(p32):
    seen = []

    def watch(progress):
        seen.append(progress)
        return len(seen) < 2

    r = cl.solve(p32, solver="tnnmg", callback=watch)
    assert len(seen) == 2 and r.stopped_by_callback and r.status != "converged"
    assert {"stage", "iteration", "residual", "seconds"} <= set(seen[0])
    full = cl.solve(p32, solver="tnnmg", callback=lambda p: None)
    assert full.status == "converged" and not full.stopped_by_callback

    def boom(progress):
        raise KeyError("from the callback")

    with pytest.raises(KeyError, match="from the callback"):
        cl.solve(p32, solver="tnnmg", callback=boom)


def test_an_exported_instance_and_ones_own_matrices_are_the_same_problem(tmp_path, p32):
    # Problem.from_instance and Problem.from_matrices did not exist: an
    # instance written from a scene file could not be rebuilt in Python.
    p32.export(tmp_path / "e")
    assert (tmp_path / "e" / "README.md").is_file()
    back = cl.Problem.from_instance(tmp_path / "e")
    # The problem holds no M: the export assembles it from the mesh.
    assert abs(back.M - p32.M).max() <= 1e-15 * abs(p32.M).max()
    c = p32.contact
    mine = cl.Problem.from_matrices(
        p32.A.tocoo(), p32.f, {"t": c.t, "s": c.s, "weight": c.weight, "coefficient": c.coefficient}, p32.rigid_mode
    )
    exact = cl.solve(p32, solver="newton-coulomb")
    for q in (back, mine):
        assert q.n == p32.n and q.h is None and q.contact.x is None
        assert abs(q.A - p32.A).max() == 0.0
        r = cl.solve(q, solver="newton-coulomb")
        assert r.status == "converged"
        assert np.max(np.abs(r.displacements - exact.displacements)) <= 1e-9 * np.max(np.abs(exact.displacements))
        assert cl.certify(q, displacements=exact.displacements).passed
    # A multigrid solver without a hierarchy says so.
    r = cl.solve(mine, solver="tnnmg")
    assert r.status == "not_run" and "hierarch" in r.detail
    # What cannot be posed is refused with its reason.
    with pytest.raises(cl.InputError, match="rigid"):
        cl.Problem.from_matrices(p32.A, p32.f, {"t": c.t, "s": c.s, "weight": c.weight, "coefficient": c.coefficient}, np.ones(p32.n))
    with pytest.raises(cl.InputError, match="studied|scene"):
        cl.compare(mine, ["tnnmg"])


def test_the_package_is_typed_and_holds_no_study_logic():
    # A package without py.typed is untyped to mypy and pyright; a package
    # that computed its own tables drifted from the command line's.
    import ast
    import inspect

    pkg = pathlib.Path(cl.__file__).parent
    assert (pkg / "py.typed").is_file() and (pkg / "_contactlab.pyi").is_file()
    stub = (pkg / "_contactlab.pyi").read_text()
    for name in ("solve", "certify", "register", "_compare", "_benchmark", "_work_precision", "from_matrices"):
        assert f"def {name}(" in stub, name
    # No arithmetic on results in the package: every number comes from the
    # engine (the studies' tables are parsed, never computed).
    tree = ast.parse(inspect.getsource(cl))
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute):
            assert node.func.attr not in {"max", "min", "mean", "abs", "log", "exp", "sqrt", "geomspace"}, ast.dump(node)


def test_work_precision_can_use_the_error_bound_as_its_accuracy(tmp_path):
    # Issue 51: every trial row carries the bound; the work-precision chart
    # can put it on its x axis (no reference needed) and draws it against
    # the measured error. A row without the bound, a chart still drawn on
    # the violation, or a silent empty chart when no bound exists fails.
    p = cl.Problem.paper(1, h="1/16")
    chart = tmp_path / "bound.svg"
    r = cl.work_precision(p, ["newton-coulomb", "nsgs"], targets=[1e-4, 1e-8], chart=chart, x="bound")
    for t in r.rows:
        assert t["bound_kind"] == "at-own-bound"
        assert 0 < t["bound_displacement"] < 1
        assert t["energy_error"] >= 0
    assert "error bound" in chart.read_text()
    assert "work_precision_bound_vs_error" in r.charts
    with pytest.raises(cl.InputError, match="bound_max_unknowns"):
        cl.work_precision(p, ["nsgs"], targets=[1e-4], chart=chart, x="bound", settings={"certificate.bound_max_unknowns": 0})
    with pytest.raises(cl.InputError, match="x = 'time'"):
        cl.work_precision(p, ["nsgs"], targets=[1e-4], x="time")


def test_the_error_bound_study_finds_no_given_friction_bound_below_its_error():
    # The study behind `contactlab error-bound`, run from Python: every
    # given-friction answer's bound at least its measured error less the
    # reference's own bound (the triangle inequality). A bound that fails,
    # or a study that drops the bounds from its rows, fails here.
    r = cl.error_bound(quick=True)
    given = [t for t in r.rows if t["law"] == "given_friction"]
    assert len(given) >= 100
    for t in given:
        assert t["kind"] == "rigorous"
        assert t["bound"] >= t["energy_error"] - t["reference_bound"], t
    assert "error_bound_sharpness.csv" in r.files


def test_a_uniform_gap_is_a_rigid_translation_of_the_upper_body(p32):
    # from_matrices(..., gap=) poses t_i <= d_i. A uniform gap d moves the
    # upper body down by d along its rigid mode z (+1 on its vertical
    # displacements, -1 on every jump): the pressures are those without a
    # gap and the displacements are v - d z. A gap on the wrong sign or the
    # wrong unknowns, or one the certificate ignored, breaks one of these.
    c = p32.contact
    contact = {"t": c.t, "s": c.s, "weight": c.weight, "coefficient": c.coefficient}
    z = np.asarray(p32.rigid_mode)
    flat = cl.Problem.from_matrices(p32.A, p32.f, contact, z)
    d = 1e-3
    gapped = cl.Problem.from_matrices(p32.A, p32.f, contact, z, gap=np.full(len(c.t), d))
    base = cl.solve(flat, solver="newton-coulomb")
    for solver in ("newton-coulomb", "clarabel"):
        r = cl.solve(gapped, solver=solver)
        assert r.status == "converged", (solver, r.detail)
        assert np.max(np.abs(r.pressure - base.pressure)) <= 1e-5 * np.max(base.pressure)
        moved = base.displacements - d * z
        assert np.max(np.abs(r.displacements - moved)) <= 1e-5 * np.max(np.abs(moved))
    # The gapped answer closes the gap (t = d > 0 where the bodies touch):
    # against the problem without it, that is a penetration.
    assert not cl.certify(flat, displacements=r.displacements).passed
    assert cl.certify(gapped, displacements=r.displacements).passed
    with pytest.raises(cl.InputError, match="gap"):
        cl.Problem.from_matrices(p32.A, p32.f, contact, z, gap=np.full(len(c.t), -1.0))
    with pytest.raises(cl.InputError, match="gap"):
        cl.Problem.from_matrices(p32.A, p32.f, contact, z, gap=[0.0])


def test_a_slip_offset_far_past_the_displacements_slides_every_node(p32):
    # from_matrices(..., slip_offset=) puts friction on s_i - sigma_i. An
    # offset far beyond the displacements (the upper body moved +x by a
    # rigid lift) slides every node that carries pressure towards it: the
    # traction on the lower body is +F p there (Coulomb's bound, along +x).
    # An offset read with the wrong sign, or ignored, or one the
    # certificate did not read, breaks one of these.
    c = p32.contact
    contact = {"t": c.t, "s": c.s, "weight": c.weight, "coefficient": c.coefficient}
    z = np.asarray(p32.rigid_mode)
    sigma = 1e-2
    moved = cl.Problem.from_matrices(p32.A, p32.f, contact, z, slip_offset=np.full(len(c.t), sigma))
    flat = cl.Problem.from_matrices(p32.A, p32.f, contact, z)
    # (clarabel ends AlmostSolved and nsgs at its sweep cap on this full
    # slide: neither claims convergence.)
    for solver in ("newton-coulomb", "newton"):
        r = cl.solve(moved, solver=solver)
        assert r.status == "converged", (solver, r.detail)
        loaded = r.pressure > 1e-3 * np.max(r.pressure)
        bound = np.asarray(c.coefficient) * r.pressure
        assert np.all(np.abs(r.friction_traction[loaded] - bound[loaded]) <= 1e-4 * np.max(bound)), solver
    assert cl.certify(moved, displacements=r.displacements).passed
    assert not cl.certify(flat, displacements=r.displacements).passed
    with pytest.raises(cl.InputError, match="slip offset"):
        cl.Problem.from_matrices(p32.A, p32.f, contact, z, slip_offset=[np.nan] * len(c.t))
    with pytest.raises(cl.InputError, match="slip offset"):
        cl.Problem.from_matrices(p32.A, p32.f, contact, z, slip_offset=[0.0])


def test_verify_runs_the_classical_scenes_from_python():
    # The study behind `contactlab verify`, from Python: Hertz's pressure
    # error falls from h = 1/32 to 1/64 for each solver named, and every
    # answer is certified. A closed form with a wrong E*, or a gap lost on
    # the way to a solver, keeps the error from falling.
    r = cl.verify(quick=True, solvers=["newton-coulomb", "tnnmg"])
    hertz = [t for t in r.rows if t["scene"] == "hertz"]
    assert len(hertz) == 4
    for t in hertz:
        assert t["status"] == "converged", t
    for s in ("newton-coulomb", "tnnmg"):
        e = {t["h"]: t["l2_error"] for t in hertz if t["solver"] == s}
        assert e["1/64"] < 0.6 * e["1/32"], e
    assert any(f.startswith("profiles/hertz_h64_") for f in r.files)


def test_a_studys_tables_are_the_data_of_its_files():
    # Python gets each table as the typed rows the library serialized, not
    # the CSV file parsed back: every cell of every file must be the same
    # value (numbers to the file's 10 digits, an empty field as None, the
    # columns in the file's order). Rows from another table, a column
    # dropped or renamed, a number left as text or a file that drifts from
    # its rows fail here.
    import csv
    import io

    r = cl.compare(cl.Problem.paper(1, h="1/8"), ["newton-coulomb", "tnnmg"])
    csvs = [path for path in r.files if path.endswith(".csv")]
    assert set(r.tables) == set(csvs) and "compare.csv" in r.tables
    assert r.rows is r.tables["compare.csv"] and r.main == "compare.csv"
    checked = 0
    for path in csvs:
        text = r.files[path].decode("utf-8")
        header = next(csv.reader(io.StringIO(text)))
        rows = r.table(path)
        for row in rows:
            assert list(row) == header, path
        lines = list(csv.DictReader(io.StringIO(text)))
        assert len(lines) == len(rows), path
        for line, row in zip(lines, rows):
            for k, cell in line.items():
                v = row[k]
                if cell == "":
                    assert v is None or v == "", (path, k, v)
                elif isinstance(v, bool):
                    assert cell == str(v).lower(), (path, k, cell, v)
                elif isinstance(v, (int, float)):
                    assert float(cell) == pytest.approx(v, rel=1e-9, abs=0), (path, k, cell, v)
                else:
                    assert isinstance(v, str) and cell == v, (path, k, cell, v)
                checked += 1
    assert checked > 200  # every column of every row of every table
    assert isinstance(r.rows[0]["certificate"], float)
    assert isinstance(r.rows[0]["friction_iterations"], int)
    with pytest.raises(cl.InputError, match="compare.csv"):
        r.table("nothing.csv")
    pandas = pytest.importorskip("pandas")
    frame = r.frame()
    assert isinstance(frame, pandas.DataFrame)
    assert list(frame.columns) == list(r.rows[0]) and len(frame) == len(r.rows)
    assert frame["certificate"].dtype.kind == "f"


def test_a_catalogued_study_is_one_call_with_the_command_lines_bytes(tmp_path):
    # Each catalogued study is a command and a call made from one entry:
    # the same spec from keywords as from flags gives the same file, byte
    # for byte; an unknown keyword is refused naming the parameters there
    # are. A call that wired its own defaults, or dropped a keyword, fails
    # here.
    assert {"stability", "discretization-error", "oracle", "error-bound", "verify"} <= set(cl.studies())
    m = cl.stability(quick=True, friction_values=[0.0, 0.5], uniqueness_values=[])
    assert m.main == "stability.csv" and {row["class"] for row in m.rows} >= {"converged"}
    assert {row["value"] for row in m.rows if row["knob"] == "friction"} >= {0.0, 0.5}
    r = cl.discretization_error(quick=True, problems=[1], meshes=["1/8"], reference="1/16")
    (row,) = r.rows
    assert r.main == "discretization_error.csv"
    assert row["problem"] == 1 and row["h"] == "1/8" and 0 < row["l2_error"] < 1
    subprocess.run(
        [str(cli()), "discretization-error", "--quick", "--problem", "1", "--meshes", "1/8",
         "--reference", "1/16", "--out", str(tmp_path / "cli")],
        check=True,
        capture_output=True,
    )
    name = "discretization_error.csv"
    assert r.files[name] == (tmp_path / "cli" / name).read_bytes()
    with pytest.raises(cl.InputError, match="its parameters are .*meshes"):
        cl.study("discretization-error", quick=True, mesh=["1/8"])
    with pytest.raises(cl.InputError, match="finer than the reference"):
        cl.study("discretization-error", quick=True, meshes=["1/64"], reference="1/32")
    with pytest.raises(cl.InputError, match="the studies are"):
        cl.study("no-such-study")
    with pytest.raises(cl.InputError, match="quick and long"):
        cl.oracle(quick=True, long=True)


def test_table1_is_catalogued_at_the_papers_settings(tmp_path):
    # Table 1 is a catalogued study: a call returning its rows, at the
    # paper's settings (the stopping rules the paper states), the same
    # bytes as the command; a setting of a solver it does not run is
    # refused. A call resolved on the defaults (relative stopping) gives
    # other counts than the command and fails here.
    assert "table1" in cl.studies()
    t = cl.table1(quick=True, h="1/8", problems=[1], schedules=["revisit"])
    (row,) = t.rows
    assert t.main == "table1.csv"
    assert row["problem"] == 1 and row["schedule"] == "revisit" and row["paper_mpp"] == 6
    subprocess.run(
        [str(cli()), "table1", "--h", "1/8", "--problem", "1", "--schedules", "revisit",
         "--out", str(tmp_path / "cli")],
        check=True,
        capture_output=True,
    )
    assert t.files["table1.csv"] == (tmp_path / "cli" / "table1.csv").read_bytes()
    relative = cl.table1(quick=True, h="1/8", problems=[1], schedules=["revisit"],
                         settings={"stopping": "relative"})
    assert relative.rows[0]["mu"] != row["mu"]
    with pytest.raises(cl.InputError, match="this run uses relaxation"):
        cl.table1(quick=True, h="1/8", problems=[1], settings={"clarabel.max_iter": 3})


def test_bench_is_catalogued_and_returns_its_timing_rows():
    # The speed study is a catalogued call: its timing rows (performance.csv)
    # typed as the library wrote them, its fresh processes run by
    # CONTACTLAB_BIN (Python is not contactlab); a bad --runs is refused
    # before anything runs.
    b = cl.bench(quick=True)
    assert b.main == "performance.csv"
    assert {"factorization", "coulomb"} <= {r["what"] for r in b.rows}
    assert all(isinstance(r["median_seconds"], float) for r in b.rows)
    assert any(r["what"] == "coulomb" and r["status"] == "converged" for r in b.rows)
    assert "performance_goals.md" in b.files
    with pytest.raises(cl.InputError, match="--runs"):
        cl.bench(quick=True, runs=0)


def test_options_are_a_solvers_settings_without_its_prefix(p32):
    """scipy's ``options`` of a ``method``: the knob alone, scoped to the
    solver named, the same setting as its path in ``settings``, validated
    by the same code. An option that did not reach the solver, or one
    applied to another solver, fails here."""
    by_path = cl.solve(p32, solver="newton-coulomb", settings={"newton-coulomb.tolerance": 1e-12})
    by_knob = cl.solve(p32, solver="newton-coulomb", options={"tolerance": 1e-12})
    assert np.array_equal(by_path.pressure, by_knob.pressure)
    assert by_path.iterations == by_knob.iterations
    loose = cl.solve(p32, solver="newton-coulomb", options={"tolerance": 1e-3})
    assert loose.iterations != by_knob.iterations or not np.array_equal(loose.pressure, by_knob.pressure)
    with pytest.raises(cl.InputError, match="no_such_knob"):
        cl.solve(p32, solver="newton-coulomb", options={"no_such_knob": 1})
    with pytest.raises(cl.InputError, match="name the solver"):
        cl.solve(p32, options={"tolerance": 1e-12})
    with pytest.raises(cl.InputError, match="give the knob alone"):
        cl.solve(p32, solver="newton-coulomb", options={"newton-coulomb.tolerance": 1e-12})
    with pytest.raises(cl.InputError, match="bogus"):
        cl.compare(cl.Problem.paper(1, h="1/8"), ["tnnmg"], options={"tnnmg": {"bogus": 1}})
