"""Type stubs of the compiled half of contactlab (``contactlab._contactlab``).
The documented interface is ``contactlab`` itself; these are its bindings."""

from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple

import numpy as np

class Error(Exception): ...
class InputError(Error, ValueError): ...
class FileError(Error, OSError): ...
class OutOfMemory(Error, MemoryError): ...

_Csr = Tuple[np.ndarray, np.ndarray, np.ndarray]
_CsrIn = Tuple[List[int], List[int], List[float]]

class Problem:
    @staticmethod
    def paper(
        number: int,
        h: Optional[str] = ...,
        young: Optional[float] = ...,
        poisson: Optional[float] = ...,
        plane: Optional[str] = ...,
        friction: Optional[float] = ...,
    ) -> Problem: ...
    @staticmethod
    def from_scene(
        path: str,
        h: Optional[str] = ...,
        young: Optional[float] = ...,
        poisson: Optional[float] = ...,
        plane: Optional[str] = ...,
        friction: Optional[float] = ...,
    ) -> Problem: ...
    @staticmethod
    def from_instance(path: str) -> Problem: ...
    @staticmethod
    def from_matrices(
        name: str,
        n: int,
        a: _CsrIn,
        f: List[float],
        t: List[int],
        s: List[int],
        weight: List[float],
        coefficient: List[float],
        rigid_modes: List[List[float]],
        m: Optional[_CsrIn] = ...,
        prolongations: List[Tuple[Tuple[int, int], _CsrIn]] = ...,
        gap: Optional[List[float]] = ...,
        slip_offset: Optional[List[float]] = ...,
    ) -> Problem: ...
    @property
    def name(self) -> str: ...
    @property
    def h(self) -> Optional[str]: ...
    @property
    def n(self) -> int: ...
    @property
    def f(self) -> np.ndarray: ...
    @property
    def scales(self) -> Dict[str, float]: ...
    @property
    def rigid_mode(self) -> np.ndarray: ...
    @property
    def levels(self) -> int: ...
    def _a(self) -> _Csr: ...
    def _m(self) -> _Csr: ...
    def _contact(self) -> Dict[str, Any]: ...

def solvers() -> List[str]: ...
def statuses() -> List[str]: ...
def _check_problem_size(what: str, n: int, nnz: int) -> None: ...
def _address_space_reserve() -> float: ...
def register(name: str, f: Callable[..., object]) -> None: ...
def solve(
    problem: Problem,
    solver: Optional[str] = ...,
    settings: Sequence[Tuple[str, str]] = ...,
    bound: Optional[List[float]] = ...,
    target: Optional[float] = ...,
    callback: Optional[Callable[[Dict[str, object]], Optional[bool]]] = ...,
) -> Dict[str, Any]: ...
def certify(
    problem: Problem,
    displacements: Optional[np.ndarray] = ...,
    pressure: Optional[np.ndarray] = ...,
    friction_traction: Optional[np.ndarray] = ...,
    bound: Optional[np.ndarray] = ...,
    tolerance: Optional[float] = ...,
) -> Dict[str, Any]: ...
def export(problem: Problem, out: str, bound: Optional[float] = ...) -> None: ...
def _compare(
    problem: Problem,
    solvers: List[str],
    settings: Sequence[Tuple[str, str]] = ...,
    repeats: int = ...,
    out: Optional[str] = ...,
    reference: Optional[str] = ...,
) -> Dict[str, Any]: ...
def _side_by_side(
    problem: Problem,
    pairs: List[Tuple[str, str]],
    settings: Sequence[Tuple[str, str]] = ...,
    out: Optional[str] = ...,
) -> Dict[str, Any]: ...
def _tuning_map(
    problem: Problem,
    solver: str,
    axes: List[Tuple[str, List[str]]],
    law: str,
    repeats: int,
    settings: Sequence[Tuple[str, str]] = ...,
    out: Optional[str] = ...,
    time_limit: Optional[float] = ...,
) -> Dict[str, Any]: ...
def _benchmark(
    problems: List[Problem],
    solvers: List[str],
    targets: List[float],
    time_limit: float,
    settings: Sequence[Tuple[str, str]] = ...,
    out: Optional[str] = ...,
) -> Dict[str, Any]: ...
def _work_precision(
    problem: Problem,
    solvers: List[str],
    targets: List[float],
    settings: Sequence[Tuple[str, str]] = ...,
    repeats: int = ...,
    out: Optional[str] = ...,
) -> Dict[str, Any]: ...
def _studies() -> List[Tuple[str, str, str]]: ...
def _study(
    command: str,
    length: str,
    spec: str,
    settings: Sequence[Tuple[str, str]] = ...,
    out: Optional[str] = ...,
) -> Dict[str, Any]: ...
def _sweep(
    problem: Problem,
    solvers: List[str],
    settings: Sequence[Tuple[str, str]] = ...,
    quick: bool = ...,
    work_precision: bool = ...,
    repeats: int = ...,
    out: Optional[str] = ...,
) -> Dict[str, Any]: ...
