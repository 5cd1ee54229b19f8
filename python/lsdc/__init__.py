"""lsdc from Python: LSD mechanisms (and URDF robots) loaded, checked, simulated, stepped,
evaluated on NumPy arrays, linearised and swept.

>>> import lsdc
>>> program = lsdc.load("examples/pendulum.lsd")
>>> columns = program.simulate(duration=2.0, every=0.5)
>>> columns["swing.q"]            # NumPy arrays under the CSV header's names
>>> prepared = program.prepare()
>>> prepared.aba(q, v, tau)       # (N, nq), (N, nv), (N, nv) -> (N, nv), in Rust

The numbers are those of the command line: ``simulate`` equals ``lsdc simulate``'s CSV,
``rnea``/``crba``/``aba`` equal ``lsdc eval``'s, ``Program.sweep`` equals ``lsdc sweep``'s
table. ``lsdc.dask.sweep`` spreads a sweep's shards over a Dask cluster.
"""

from ._columns import Columns
from ._native import (
    Diagnostic,
    LsdcError,
    Prepared,
    Program,
    ProgramError,
    RunError,
    Simulation,
    SweepTable,
    gather,
    load,
    load_text,
)


def check(path, **options):
    """Loads ``path`` and returns its diagnostics (errors and warnings, each with ``file``,
    ``line``, ``column``, ``code`` and ``message``), as ``lsdc check`` reports them."""
    return load(path, **options).diagnostics


__all__ = [
    "Columns",
    "Diagnostic",
    "LsdcError",
    "Prepared",
    "Program",
    "ProgramError",
    "RunError",
    "Simulation",
    "SweepTable",
    "check",
    "gather",
    "load",
    "load_text",
]
