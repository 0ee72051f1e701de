"""The sweep file: a base scene, the axes of the family, what to measure, where to write.

```yaml
scene: mu_i/collapse_a0_90.yaml         # a scene file, or a bundled scene's name
set: [numerics.particle_spacing=0.009]  # overrides every run shares (optional)
axes:                                   # a grid: every combination of the axes' values
  material.static_friction_deg: [26.0, 28.0, 30.5, 33.0, 35.0]
  numerics.cfl: {from: 0.3, to: 0.5, num: 3}   # a range: num values, both ends included
sample:                                 # or, instead of axes: a Latin-hypercube sample
  points: 20
  seed: 1
  ranges: {material.static_friction_deg: [25.0, 35.0], material.grain_compressibility: [2.0e-5, 9.0e-5]}
measures: [runout, deposit_height, max:max_speed]   # sweep/measures.py
out: output/sweeps/friction             # default: output/sweeps/<sweep file name>
timeout: 3600                           # s a run may take (default 6 h)
```

An axis key is a ``--set`` key path of the scene; each run is the base scene with ``set`` and its
own values applied, checked by the scene loader like any ``--set`` (so a value the scene refuses
is that run's recorded failure, not the sweep's).
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, List, Sequence, Tuple

import numpy as np

from ..keys import ConfigError

KEYS = ("scene", "set", "axes", "sample", "measures", "out", "timeout")
SAMPLE_KEYS = ("points", "seed", "ranges")
RANGE_KEYS = ("from", "to", "num")


@dataclass(frozen=True)
class Point:
    """One run of the sweep: its id (its output folder's name) and the values of its axes."""
    id: str
    values: Tuple[Tuple[str, Any], ...]  # (key path, value) in the axes' order

    def overrides(self) -> List[str]:
        return [f"{key}={_yaml_value(value)}" for key, value in self.values]


@dataclass
class Sweep:
    scene: str
    fixed: Tuple[str, ...]  # the overrides every run shares
    axes: Dict[str, List[Any]]  # grid axes (empty for a sample)
    sampled: Dict[str, Tuple[float, float]]  # Latin-hypercube ranges (empty for a grid)
    points_wanted: int  # sample size
    seed: int
    measures: Tuple[str, ...]
    out: Path
    timeout: float
    source: Path = field(default=None)
    raw: dict = field(default_factory=dict, repr=False)  # the sweep file as read

    @property
    def parameters(self) -> List[str]:
        return list(self.axes or self.sampled)

    @property
    def is_sample(self) -> bool:
        return bool(self.sampled)

    def points(self) -> List[Point]:
        """Every run, in a fixed order: the grid's product (the last axis fastest), or the sample."""
        if self.is_sample:
            values = latin_hypercube(list(self.sampled.values()), self.points_wanted, self.seed)
            rows = [tuple(zip(self.sampled, (float(v) for v in row))) for row in values]
        else:
            rows = [tuple(zip(self.axes, combo)) for combo in itertools.product(*self.axes.values())]
        width = max(4, len(str(len(rows) - 1)))
        return [Point(f"p{k:0{width}d}", row) for k, row in enumerate(rows)]


def latin_hypercube(ranges: Sequence[Tuple[float, float]], points: int, seed: int) -> np.ndarray:
    """``points`` x len(ranges) values: each range cut into ``points`` equal strata, one value
    drawn uniformly in each stratum, the strata shuffled independently per range (McKay et al.
    1979); reproducible from ``seed``."""
    rng = np.random.default_rng(seed)
    unit = np.empty((points, len(ranges)))
    for j in range(len(ranges)):
        unit[:, j] = (rng.permutation(points) + rng.random(points)) / points
    low = np.array([r[0] for r in ranges], float)
    high = np.array([r[1] for r in ranges], float)
    return low + unit * (high - low)


def _yaml_value(value) -> str:
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_yaml_value(v) for v in value) + "]"
    return str(value)


def _number(value, path: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ConfigError(path, f"expected a finite number, got {value!r}")
    return float(value)


def _axis_values(value, path: str) -> List[Any]:
    if isinstance(value, list):
        if not value:
            raise ConfigError(path, "an axis needs at least one value")
        return value
    if isinstance(value, dict):
        unknown = sorted(set(value) - set(RANGE_KEYS))
        if unknown or set(value) != set(RANGE_KEYS):
            raise ConfigError(path, f"a range is {{from: A, to: B, num: N}}; got keys {sorted(value)}")
        num = value["num"]
        if isinstance(num, bool) or not isinstance(num, int) or num < 1:
            raise ConfigError(f"{path}.num", f"expected a whole number >= 1, got {num!r}")
        start, stop = _number(value["from"], f"{path}.from"), _number(value["to"], f"{path}.to")
        return [float(v) for v in np.linspace(start, stop, num)]
    raise ConfigError(path, f"expected a list of values or {{from, to, num}}, got {value!r}")


def sweep_from_dict(data: Any, source: Path) -> Sweep:
    """The checked sweep; every error names its key path."""
    from .measures import check_measure

    if not isinstance(data, dict):
        raise ConfigError("", "a sweep file is a mapping (scene, axes or sample, measures, ...)")
    unknown = sorted(set(data) - set(KEYS))
    if unknown:
        raise ConfigError(unknown[0], f"unknown key; a sweep has {', '.join(KEYS)}")
    if not isinstance(data.get("scene"), str):
        raise ConfigError("scene", "the base scene: a scene file or a bundled scene's name")
    fixed = data.get("set", [])
    if not isinstance(fixed, list) or not all(isinstance(s, str) and "=" in s for s in fixed):
        raise ConfigError("set", "a list of key.path=value overrides")
    if ("axes" in data) == ("sample" in data):
        raise ConfigError("axes", "give either axes (a grid) or sample (a Latin-hypercube sample), not both or neither")
    axes, sampled, points_wanted, seed = {}, {}, 0, 0
    if "axes" in data:
        if not isinstance(data["axes"], dict) or not data["axes"]:
            raise ConfigError("axes", "a mapping of key path -> values")
        axes = {str(k): _axis_values(v, f"axes.{k}") for k, v in data["axes"].items()}
    else:
        sample = data["sample"]
        if not isinstance(sample, dict):
            raise ConfigError("sample", "a mapping: points, seed, ranges")
        unknown = sorted(set(sample) - set(SAMPLE_KEYS))
        if unknown:
            raise ConfigError(f"sample.{unknown[0]}", f"unknown key; a sample has {', '.join(SAMPLE_KEYS)}")
        points_wanted, seed = sample.get("points"), sample.get("seed", 0)
        if isinstance(points_wanted, bool) or not isinstance(points_wanted, int) or points_wanted < 1:
            raise ConfigError("sample.points", f"expected a whole number >= 1, got {points_wanted!r}")
        if isinstance(seed, bool) or not isinstance(seed, int):
            raise ConfigError("sample.seed", f"expected a whole number, got {seed!r}")
        ranges = sample.get("ranges")
        if not isinstance(ranges, dict) or not ranges:
            raise ConfigError("sample.ranges", "a mapping of key path -> [low, high]")
        for key, bounds in ranges.items():
            path = f"sample.ranges.{key}"
            if not isinstance(bounds, list) or len(bounds) != 2:
                raise ConfigError(path, f"expected [low, high], got {bounds!r}")
            low, high = _number(bounds[0], path), _number(bounds[1], path)
            if not low < high:
                raise ConfigError(path, f"low {low:g} must be below high {high:g}")
            sampled[str(key)] = (low, high)
    measures = data.get("measures")
    if not isinstance(measures, list) or not measures or not all(isinstance(m, str) for m in measures):
        raise ConfigError("measures", "a list of measure names (taichi-granular sweep --help lists them)")
    for k, name in enumerate(measures):
        check_measure(name, f"measures.{k}")
    timeout = _number(data.get("timeout", 6 * 3600.0), "timeout")
    if timeout <= 0:
        raise ConfigError("timeout", "seconds a run may take; must be positive")
    out = Path(data["out"]) if isinstance(data.get("out"), str) else Path("output/sweeps") / source.stem
    if "out" in data and not isinstance(data["out"], str):
        raise ConfigError("out", "a folder path")
    return Sweep(data["scene"], tuple(fixed), axes, sampled, points_wanted, seed, tuple(measures), out, timeout,
                 source, data)


def load_sweep(path) -> Sweep:
    from ..config import parse_yaml

    path = Path(path)
    try:
        text = path.read_text()
    except (OSError, UnicodeDecodeError) as err:
        raise ConfigError("", f"cannot read the sweep file {path}: {err}") from None
    return sweep_from_dict(parse_yaml(text, source=str(path)), path)
