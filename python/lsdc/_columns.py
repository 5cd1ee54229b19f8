"""A run's samples as columns: a dict of the CSV header's names to NumPy arrays."""

from __future__ import annotations

import warnings
from typing import Any, Dict

import numpy as np


class Columns(Dict[str, np.ndarray]):
    """The samples of a run, column by column, under the names of ``lsdc simulate``'s CSV
    header (``time``, ``swing.q``, ``swing.q'``, ``kinetic_energy``, ``potential_energy``,
    reactions, outputs), each a NumPy array of float64 equal to the CSV's numbers bit for bit
    (a potential energy the run cannot give is NaN where the CSV leaves the field empty).

    ``report`` holds the run's report: the integrator, its steps, the CPU time, the energy
    drift and ``failure``, ``None`` or ``(time, message)`` for a run that stopped (its rows
    before the failure kept).
    """

    report: Dict[str, Any]

    def __init__(self, columns: Dict[str, np.ndarray], report: Dict[str, Any]):
        super().__init__(columns)
        self.report = report
        failure = report.get("failure")
        if failure is not None:
            time, message = failure
            warnings.warn(f"the run failed at t = {time}: {message}", RuntimeWarning, stacklevel=3)

    def to_pandas(self):
        """The columns as a pandas DataFrame (pandas must be installed)."""
        try:
            import pandas
        except ImportError as error:  # pragma: no cover - depends on the environment
            raise ImportError("to_pandas() needs pandas: pip install pandas") from error
        return pandas.DataFrame(dict(self))
