"""Never abort, never run away (issue 47), from Python: Ctrl-C stops a
long call, memory that would not suffice is refused up front, a failing
Python solver is one failed run, and every wrong argument is a
``contactlab.Error`` that names it.

Each test names the mistake it catches.
"""

import os
import signal
import subprocess
import sys
import textwrap
import threading
import time

import numpy as np
import pytest

import contactlab as cl
from contactlab import _contactlab


def _address_space_reserve() -> float:
    return _contactlab._address_space_reserve()


SCENE = os.path.join(os.path.dirname(__file__), "..", "..", "scenes", "problem1.toml")


@pytest.fixture(scope="module")
def p16():
    return cl.Problem.paper(1, h="1/16")


def test_ctrl_c_stops_a_long_solve_within_a_fraction_of_a_second(p16):
    # A solve that held the interpreter until its end (the issue: the
    # relaxation at omega 0.4 and epsilon 1e-8 ran on after Ctrl-C, then
    # surfaced as a PanicException) fails here.
    p = cl.Problem.paper(1, h="1/32")
    sent = []
    # Ctrl-C raises KeyboardInterrupt, as in any interactive session (a
    # process started in the background with SIGINT ignored, as a
    # non-interactive shell starts its `&` jobs, would otherwise ignore it).
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)

    def interrupt():
        time.sleep(1.0)
        sent.append(time.perf_counter())
        os.kill(os.getpid(), signal.SIGINT)

    try:
        threading.Thread(target=interrupt, daemon=True).start()
        with pytest.raises(KeyboardInterrupt):
            cl.solve(
                p,
                solver="relaxation",
                settings={"relaxation.omega": 0.4, "relaxation.epsilon": 1e-8},
            )
    finally:
        signal.signal(signal.SIGINT, previous)
    assert sent, "the solve ended before the interrupt: make it longer"
    assert time.perf_counter() - sent[0] < 0.5
    # The session is usable: the next solve runs and is certified.
    assert cl.solve(p16, solver="tnnmg").status == "converged"


def run_limited(code: str, limit_bytes: int) -> subprocess.CompletedProcess:
    """Python code in a fresh interpreter under an address-space limit."""
    prelude = textwrap.dedent(
        f"""
        import resource
        resource.setrlimit(resource.RLIMIT_AS, ({limit_bytes}, {limit_bytes}))
        import contactlab as cl
        """
    )
    return subprocess.run(
        [sys.executable, "-c", prelude + textwrap.dedent(code)],
        capture_output=True,
        text=True,
        timeout=600,
    )


def test_memory_that_would_not_suffice_is_refused_and_the_interpreter_lives():
    # Problem.paper(1, h="1/4096") under 3 GB killed the interpreter; a
    # solve whose factor would not fit aborted it.
    r = run_limited(
        """
        for make in (lambda: cl.Problem.paper(1, h="1/4096"),
                     lambda: cl.solve(cl.Problem.paper(1, h="1/1024"), solver="newton-coulomb")):
            try:
                make()
                print("ran")
            except cl.Error as e:
                print("refused:", e)
        print("alive")
        """,
        # 3 GB beyond what the library keeps aside for the dense products'
        # buffers, which grow with the L3 cache sysfs reports (2.9 GB where
        # it says 480 MiB: there a bare 3 GB refused even the assembly).
        (3 << 30) + int(_address_space_reserve()),
    )
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[-1] == "alive", r.stdout
    refused = [l for l in lines if l.startswith("refused:")]
    assert len(refused) == 2, r.stdout
    for line in refused:
        assert "not enough memory" in line and "needs about" in line and "may use" in line, line
    assert "leaner solver: tnnmg" in refused[1], refused[1]


def nan_solver(problem, target):
    return np.full(problem.n, np.nan)


def raising_solver(problem, target):
    raise RuntimeError("this solver fails")


def wrong_shape(problem, target):
    return np.zeros(3)


FAILING = {"nan": nan_solver, "raises": raising_solver, "shape": wrong_shape}


def test_a_failing_python_solver_is_one_failed_run_in_every_study(tmp_path, p16):
    # One failing function aborted work_precision, compare and benchmark,
    # and lost every other run.
    solvers = {"tnnmg": "tnnmg", **FAILING}
    r = cl.work_precision(p16, solvers, targets=[1e-4, 1e-6])
    assert len(r.rows) == 8
    by = {(t["solver"], t["value"]): t for t in r.rows}
    assert by[("tnnmg", 1e-6)]["status"] == "converged"
    assert by[("raises", 1e-4)]["status"] == "numerical_error"
    assert "RuntimeError: this solver fails" in by[("raises", 1e-4)]["detail"]
    assert by[("nan", 1e-4)]["status"] == "non_finite"
    assert by[("shape", 1e-4)]["status"] == "non_finite"
    assert "expected" in by[("shape", 1e-4)]["detail"]

    r = cl.compare(p16, solvers)
    for row in r.rows:
        if row["solver"] in FAILING:
            assert row["status"] != "converged"

    r = cl.benchmark([p16], solvers, targets=[1e-4], time_limit=30, out=tmp_path / "b")
    by = {s["solver"]: s for s in r.summaries}
    assert by["tnnmg"]["successes"] == 1
    for name in FAILING:
        assert by[name]["successes"] == 0 and by[name]["runs"] == 1
        assert by[name]["claimed_but_failed"] == 0
    assert (tmp_path / "b" / "benchmark.csv").is_file()


def test_a_run_past_the_time_limit_counts_at_the_limit(p16):
    # A Python run slower than the limit entered the shifted geometric mean
    # at its own time, while the report says failures count at the limit.
    def slow(problem, target):
        time.sleep(0.5)
        return cl.solve(problem, solver="newton-coulomb").displacements

    r = cl.benchmark([p16], {"slow": slow}, targets=[1e-4], time_limit=0.1)
    (s,) = r.summaries
    assert s["successes"] == 0
    assert abs(s["shifted_geometric_mean"] - 0.1) < 1e-9, s["shifted_geometric_mean"]


@pytest.mark.parametrize(
    "array",
    [
        lambda v: v + 1e3j * abs(v).max(),
        lambda v: v.astype(object),
        lambda v: v.astype(str),
        lambda v: v > 0,
    ],
    ids=["complex", "object", "str", "bool"],
)
def test_wrong_typed_arrays_are_refused_not_cast(p16, array):
    # A complex answer was cast to its real part with a warning and
    # certified.
    v = cl.solve(p16, solver="newton-coulomb").displacements
    with pytest.raises(cl.Error, match="give real numbers"):
        cl.certify(p16, displacements=array(v))


def test_settings_are_resolved_by_the_command_lines_code(p16):
    # A setting of a solver the solve does not use was silently accepted
    # (the command line refuses it); a scene file's settings were dropped.
    with pytest.raises(cl.Error, match="ignored: set tnnmg.tolerance instead"):
        cl.solve(p16, solver="tnnmg", settings={"newton-coulomb.tolerance": 1e-2})
    with pytest.raises(cl.Error, match="coulomb.forcing"):
        cl.solve(p16, solver="tnnmg", settings={"coulomb.forcing": 1e9})
    # The later of two changes of a setting wins, as on the command line.
    loose = cl.solve(p16, solver="tnnmg", settings=[("coulomb.max_iterations", 1), ("coulomb.max_iterations", 50)])
    assert loose.status == "converged"
    capped = cl.solve(p16, solver="tnnmg", settings=[("coulomb.max_iterations", 50), ("coulomb.max_iterations", 1)])
    assert capped.status == "max_iterations"
    with pytest.raises(cl.Error, match="settings: give a mapping"):
        cl.solve(p16, solver="tnnmg", settings=["tnnmg.tolerance"])


def test_a_scene_files_settings_are_the_problems(tmp_path):
    text = open(SCENE).read()
    scene = tmp_path / "capped.toml"
    scene.write_text(text + "\n[coulomb]\nmax_iterations = 1\n")
    p = cl.Problem.from_scene(scene, h="1/8")
    assert cl.solve(p, solver="tnnmg").status == "max_iterations"
    assert cl.solve(p, solver="tnnmg", settings={"coulomb.max_iterations": 50}).status == "converged"


def test_wrong_arguments_are_errors_that_name_them(tmp_path, p16):
    v = cl.solve(p16, solver="newton-coulomb")
    m = len(p16.contact)
    cases = [
        (lambda: cl.Problem.paper(-1), "number = -1"),
        (lambda: cl.Problem.paper(4), "problem"),
        (lambda: cl.Problem.paper(1, h=[1, 64]), "h = "),
        (lambda: cl.Problem.paper(1, h="1/8", plane="planar"), "plane"),
        (lambda: cl.certify(p16, displacements=v.displacements, bound=-np.ones(m)), "bound"),
        (lambda: cl.solve(p16, bound=-np.ones(m)), "bound"),
        (lambda: cl.certify(p16, forces={"p": v.pressure, "q": v.friction_traction}), "forces"),
        (lambda: cl.work_precision(p16, ["tnnmg"], targets=[1e-4], chart=tmp_path / "x.png"), "chart"),
        (lambda: cl.solve("not a problem"), "problem"),
        (lambda: cl.work_precision(p16, {"x": 3}), "solvers"),
        (lambda: cl.register("tnnmg", lambda p, t: None), "registered solver"),
        (lambda: cl.compare(p16, ["tnnmg"], settings={"newton-coulomb.tolerance": 1e-9}), "ignored"),
    ]
    for make, name in cases:
        with pytest.raises(cl.Error, match=name):
            make()


def test_arguments_in_the_forms_people_write_them(p16):
    # A bytes path was not found; forces as a mapping failed on its keys;
    # h = 1/64 was a TypeError.
    p = cl.Problem.from_scene(os.fsencode(SCENE), h=1 / 8)
    assert p.h == "1/8"
    assert cl.Problem.paper(1, h=8).h == "1/8" and cl.Problem.paper(1, h="1/8").h == "1/8"
    exact = cl.solve(p16, solver="newton-coulomb")
    c = cl.certify(p16, forces={"pressure": exact.pressure, "friction_traction": exact.friction_traction})
    assert c.passed


def test_the_multigrid_solvers_solve_the_coarsest_mesh():
    # At h = 1/2 tnnmg returned not_run and a profile of zeros, blaming an
    # imported instance.
    p = cl.Problem.paper(1, h="1/2")
    r = cl.solve(p, solver="tnnmg")
    assert r.status == "converged" and r.certificate.passed
    assert abs(r.pressure @ p.contact.weight - 20.0) < 1e-6
