"""What a sweep extracts from each run: validation measures, or a reduced diagnostics column.

- ``runout``, ``runout_error``, ``front_stop_time``, ``deposit_height``: a column collapse
  (validation/column_collapse.py): (r_inf - r0)/r0, its relative error against Lube et al.
  (2004), the time the front stopped [s] (NaN if it never did), the deposit height [m]; read
  as ``validate`` reads them (mu(I): at the front stop; the other models: at the end);
- ``efficiency_factor``: stake rows (validation/obstacles.py): retained mass over total;
- ``max:COLUMN``, ``min:COLUMN``, ``mean:COLUMN``, ``final:COLUMN``: a column of the run's
  diagnostics.csv (docs/reference/outputs.md), e.g. ``max:max_speed`` [m/s].

Every run also records its steps and wall time.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Callable, Dict

import numpy as np

from ..keys import ConfigError

REDUCERS: Dict[str, Callable[[np.ndarray], float]] = {
    "max": lambda v: float(np.max(v)), "min": lambda v: float(np.min(v)),
    "mean": lambda v: float(np.mean(v)), "final": lambda v: float(v[-1]),
}


def _collapse(scene, run) -> dict:
    from ..validation import column_collapse

    result = column_collapse.evaluate(scene, run.times, run.frames, run.diagnostics)  # read as validate reads it
    return {"runout": result.runout, "runout_error": result.error,
            "front_stop_time": math.nan if result.front_stop_time is None else result.front_stop_time,
            "deposit_height": result.deposit_height}


def _stake_rows(scene, run) -> dict:
    from ..validation.obstacles import evaluate_stake_rows

    return {"efficiency_factor": evaluate_stake_rows(scene, run.times, run.frames).efficiency}


# measure name -> the function that computes it (and its siblings from the same evaluation)
NAMED = {"runout": _collapse, "runout_error": _collapse, "front_stop_time": _collapse, "deposit_height": _collapse,
         "efficiency_factor": _stake_rows}


def check_measure(name: str, path: str) -> None:
    """ConfigError at ``path`` unless ``name`` is a known measure."""
    if name in NAMED:
        return
    reducer, _, column = name.partition(":")
    if reducer in REDUCERS and column:
        return
    raise ConfigError(path, f"unknown measure {name!r}; known: {', '.join(NAMED)}, or "
                            f"{'|'.join(REDUCERS)}:COLUMN of diagnostics.csv")


class RunFiles:
    """A finished run's frames and diagnostics, read from its output folder once, when asked."""

    def __init__(self, out: Path):
        self.out = Path(out)
        self._series = None
        self._diagnostics = None

    def _load_series(self):
        if self._series is None:
            from ..output import read_frame, read_series
            series = read_series(self.out)
            self._series = ([t for t, _ in series], [read_frame(p) for _, p in series])
        return self._series

    @property
    def times(self):
        return self._load_series()[0]

    @property
    def frames(self):
        return self._load_series()[1]

    @property
    def diagnostics(self):
        if self._diagnostics is None:
            from ..output import read_diagnostics
            self._diagnostics = read_diagnostics(self.out)
        return self._diagnostics


def measure(names, scene, out: Path) -> Dict[str, float]:
    """The measures ``names`` of the run of ``scene`` written in ``out``."""
    run = RunFiles(out)
    values: Dict[str, float] = {}
    for name in names:
        if name in values:
            continue
        if name in NAMED:
            values.update({k: v for k, v in NAMED[name](scene, run).items() if k in names})
            continue
        reducer, _, column = name.partition(":")
        rows = run.diagnostics
        if not rows or column not in rows[0]:
            known = ", ".join(rows[0]) if rows else "none"
            raise KeyError(f"measure {name!r}: diagnostics.csv has no column {column!r} (columns: {known})")
        values[name] = REDUCERS[reducer](np.array([float(r[column]) for r in rows]))
    return values
