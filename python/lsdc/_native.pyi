"""Type stubs of the extension module ``lsdc._native`` (re-exported by ``lsdc``)."""

import os
from typing import Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

from ._columns import Columns

_Path = Union[str, "os.PathLike[str]"]
_Array = npt.ArrayLike

class LsdcError(Exception):
    """A file that cannot be read, settings that cannot be used, a study that cannot be done."""

class ProgramError(LsdcError):
    """Errors in the program: ``args`` is ``(message, diagnostics)``."""

class RunError(LsdcError):
    """A run that cannot start or stopped: ``args`` is ``(message, time)``."""

class Diagnostic:
    """An error or warning about a program, as ``lsdc check`` reports it."""

    code: str
    severity: str
    message: str
    file: Optional[str]
    line: Optional[int]
    column: Optional[int]
    help: Optional[str]
    notes: List[str]
    @property
    def is_error(self) -> bool: ...

def load(path: _Path, *, library_path: Sequence[_Path] = ..., scene: Optional[str] = None) -> Program:
    """Loads a program (``.lsd``) or a URDF file, checks and elaborates it."""

def load_text(
    text: str,
    *,
    name: str = "<text>",
    directory: Optional[_Path] = None,
    library_path: Sequence[_Path] = ...,
    scene: Optional[str] = None,
) -> Program:
    """Checks and elaborates a program given as text."""

def gather(parts: Sequence[SweepTable]) -> SweepTable:
    """Merges the tables of a sweep's shards into the whole sweep's (``lsdc sweep gather``)."""

class Program:
    """A program checked and elaborated; its errors are in ``diagnostics``."""

    @property
    def diagnostics(self) -> List[Diagnostic]: ...
    @property
    def has_errors(self) -> bool: ...
    @property
    def scene_names(self) -> List[str]: ...
    def render(self) -> str:
        """The diagnostics as ``lsdc check`` prints them."""
    def check(self) -> List[Diagnostic]:
        """Raises ``ProgramError`` when the program has errors; its warnings otherwise."""
    def prepare(
        self,
        values: Optional[Mapping[str, float]] = None,
        *,
        initial: Optional[Mapping[str, float]] = None,
        integrator: Optional[str] = None,
        duration: Optional[float] = None,
        every: Optional[float] = None,
        tolerance: Optional[float] = None,
        step: Optional[float] = None,
        max_steps: Optional[int] = None,
        stabilisation: str = "projection",
        baumgarte_rate: float = 10.0,
        reactions: bool = False,
    ) -> Prepared:
        """Prepares the mechanism as ``lsdc simulate`` does (``values``: ``--set``)."""
    def simulate(
        self,
        values: Optional[Mapping[str, float]] = None,
        *,
        initial: Optional[Mapping[str, float]] = None,
        integrator: Optional[str] = None,
        duration: Optional[float] = None,
        every: Optional[float] = None,
        tolerance: Optional[float] = None,
        step: Optional[float] = None,
        max_steps: Optional[int] = None,
        stabilisation: str = "projection",
        baumgarte_rate: float = 10.0,
        reactions: bool = False,
    ) -> Columns:
        """Prepares and runs: the columns of ``lsdc simulate``'s CSV."""
    def linearize(
        self,
        values: Optional[Mapping[str, float]] = None,
        *,
        inputs: Sequence[str] = ...,
        coordinates: Sequence[str] = ...,
        at_time: Optional[float] = None,
        equilibrium: bool = False,
    ) -> Dict[str, object]:
        """The linear model of ``lsdc linearize``: ``A``, ``B``, ``C``, ``D``, names, eigenvalues."""
    def sweep(
        self,
        *,
        grid: Union[Sequence[str], Mapping[str, Tuple[float, float, int]], None] = None,
        values_file: Optional[_Path] = None,
        vary: Optional[Mapping[str, str]] = None,
        sample: Optional[int] = None,
        design: str = "random",
        seed: int = 0,
        values: Optional[Mapping[str, float]] = None,
        integrator: Optional[str] = None,
        duration: Optional[float] = None,
        every: Optional[float] = None,
        tolerance: Optional[float] = None,
        step: Optional[float] = None,
        max_steps: Optional[int] = None,
        shard: Optional[Tuple[int, int]] = None,
        threads: Optional[int] = None,
    ) -> SweepTable:
        """The table of runs of ``lsdc sweep`` (of one shard with ``shard=(k, n)``)."""

class Prepared:
    """A mechanism made ready to run."""

    @property
    def coordinate_names(self) -> List[str]: ...
    @property
    def column_names(self) -> List[str]: ...
    @property
    def duration(self) -> float: ...
    @property
    def warnings(self) -> List[Diagnostic]: ...
    @property
    def nq(self) -> int: ...
    @property
    def nv(self) -> int: ...
    @property
    def position_names(self) -> List[str]: ...
    @property
    def velocity_names(self) -> List[str]: ...
    @property
    def body_names(self) -> List[str]: ...
    def simulate(self) -> Columns:
        """Runs to the end of the duration: the columns of ``lsdc simulate``'s CSV."""
    def simulation(self, inputs: Sequence[str] = ...) -> Simulation:
        """A run stepped from Python, with efforts along ``inputs``."""
    def rnea(self, q: _Array, v: Optional[_Array] = None, a: Optional[_Array] = None) -> np.ndarray:
        """Inverse dynamics at N states: (N, nq), (N, nv), (N, nv) -> (N, nv)."""
    def aba(self, q: _Array, v: Optional[_Array] = None, tau: Optional[_Array] = None) -> np.ndarray:
        """Forward dynamics at N states: (N, nq), (N, nv), (N, nv) -> (N, nv)."""
    def crba(self, q: _Array) -> np.ndarray:
        """The mass matrix at N positions: (N, nq) -> (N, nv, nv)."""
    def jacobian(self, q: _Array, body: str) -> np.ndarray:
        """A body's Jacobian in its own frame at N positions: (N, nq) -> (N, 6, nv)."""

class Simulation:
    """A run advanced from Python, inputs set between steps."""

    @property
    def time(self) -> float: ...
    @property
    def input_names(self) -> List[str]: ...
    @property
    def column_names(self) -> List[str]: ...
    def coordinates(self) -> Tuple[np.ndarray, np.ndarray]: ...
    @property
    def value_input_names(self) -> List[str]: ...
    def set_input(self, name: str, value: float) -> None:
        """Sets the input `name` to `value`, held until set again: an effort input by its
        coordinate's name (``"swing.q"``), a value input by its name (``"voltage"``). Every
        input holds its declared start value until set. Raises `LsdcError` for a name that is
        not an input of the run."""
    def set_inputs(self, efforts: Sequence[float]) -> None: ...
    def step(self) -> None: ...
    def advance_to(self, t: float) -> None: ...
    def reset(
        self, coordinates: Optional[Sequence[float]] = None, rates: Optional[Sequence[float]] = None
    ) -> None: ...
    def take_samples(self) -> Dict[str, np.ndarray]: ...
    def finish(self) -> Columns: ...

class SweepTable:
    """A sweep's table of runs."""

    @staticmethod
    def from_csv(text: str) -> SweepTable: ...
    @property
    def csv(self) -> str: ...
    @property
    def names(self) -> List[str]: ...
    def __len__(self) -> int: ...
    def columns(self) -> Dict[str, Union[np.ndarray, List[Optional[str]]]]: ...
    def to_pandas(self) -> object: ...
    def write(self, path: _Path) -> None: ...
