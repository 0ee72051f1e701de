"""Validation 2 of [M]: collapse of a 2D granular column (MODEL.md section 1, Table 3).

A column of half-width r0 and height H0 = a r0 is released on a rough floor and spreads to a
deposit of half-width r_inf. Reference: the run-out scaling of Lube et al. (2004),
    (r_inf - r0)/r0 = 1.24 a (a < 1.7),  1.6 a^(1/2) (a > 1.7).
Measured per frame: the two fronts (the outermost particle, plus its radius, among particles
with a neighbour within 1.5 dp: a grain left ahead of the flow is not the front), their mean
distance from the column axis, the deposit height (the highest particle top), and the
particles that have escaped (no other particle within the kernel support 2h).
r0 and H0 are measured the same way on the first frame (the column as laid on the particle
lattice), and a = H0/r0. The column is at rest when the kinetic energy has fallen below 1e-3 of its peak.
"""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional, Sequence

import numpy as np

from ..config import Scene

REST_FRACTION = 1e-3  # at rest: kinetic energy below this share of its peak


def lube_runout(aspect_ratio: float) -> float:
    """(r_inf - r0)/r0 of Lube et al. (2004)."""
    return 1.24 * aspect_ratio if aspect_ratio < 1.7 else 1.6 * math.sqrt(aspect_ratio)


def column_axis(scene: Scene) -> float:
    """x of the axis of the scene's first particle block  [m]."""
    block = scene.particles[0]
    return 0.5 * (block.lower[0] + block.upper[0])


def connected(position: np.ndarray, reach: float) -> np.ndarray:
    """True for particles with at least one other particle closer than ``reach``."""
    n = len(position)
    order = np.argsort(position[:, 0])
    x = position[order]
    ok = np.zeros(n, bool)
    for k in range(n):  # sweep in x: only the next particles within reach can be close
        j = k + 1
        while j < n and x[j, 0] - x[k, 0] < reach:
            if np.sum((x[j] - x[k]) ** 2) < reach * reach:
                ok[k] = ok[j] = True
            j += 1
    result = np.zeros(n, bool)
    result[order] = ok
    return result


@dataclass
class FrameMeasure:
    time: float
    front_right: float  # [m] from the axis
    front_left: float  # [m] from the axis
    height: float  # [m]
    escaped: int  # particles with no other particle within the kernel support 2h


def measure_frame(arrays: Dict[str, np.ndarray], n_material: int, centre: float, spacing: float,
                  time: float, support: float) -> FrameMeasure:
    x = np.asarray(arrays["position"][:n_material], float)
    radius = 0.5 * np.sqrt(arrays["mass"][:n_material] / arrays["density"][:n_material])
    ok = connected(x, 1.5 * spacing)
    rel = x[ok, 0] - centre
    return FrameMeasure(time=time, front_right=float(np.max(rel + radius[ok])),
                        front_left=float(np.max(-rel + radius[ok])),
                        height=float(np.max(x[ok, 1] + radius[ok])),
                        escaped=int(n_material - connected(x, support).sum()))


@dataclass
class CollapseResult:
    name: str
    aspect_ratio: float
    r0: float
    runout: float  # (r_inf - r0)/r0, simulated
    runout_reference: float  # Lube et al. (2004)
    deposit_height: float  # [m]
    time_to_rest: Optional[float]  # [s], None if never at rest
    escaped: int  # at the end: particles that interact with no other
    end_time: float
    fronts: List[FrameMeasure] = field(default_factory=list)

    @property
    def error(self) -> float:
        return (self.runout - self.runout_reference) / self.runout_reference

    def row(self) -> str:
        rest = f"{self.time_to_rest:6.3f}" if self.time_to_rest is not None else "  none"
        return (f"{self.name:<16} {self.aspect_ratio:5.2f} {self.runout:8.3f} {self.runout_reference:8.3f} "
                f"{100 * self.error:+7.1f} % {1e3 * self.deposit_height:8.1f} {rest} {self.escaped:7d}")


HEADER = (f"{'case':<16} {'a':>5} {'run-out':>8} {'Lube':>8} {'error':>9} {'H_inf mm':>8} {'rest s':>6} "
          f"{'escaped':>7}")


def time_to_rest(times: Sequence[float], kinetic_energy: Sequence[float]) -> Optional[float]:
    """First time after the kinetic-energy peak at which it is below REST_FRACTION of the peak."""
    ke = np.asarray(kinetic_energy, float)
    if len(ke) == 0 or ke.max() <= 0.0:
        return None
    peak = int(np.argmax(ke))
    below = np.nonzero(ke[peak:] < REST_FRACTION * ke[peak])[0]
    return float(times[peak + below[0]]) if len(below) else None


def evaluate(scene: Scene, times: Sequence[float], frames: Sequence[Dict[str, np.ndarray]],
             diagnostics: Sequence[dict]) -> CollapseResult:
    centre = column_axis(scene)
    spacing = scene.numerics.particle_spacing
    n_material = int(np.sum(frames[0]["is_wall"] == 0))
    support = 2.0 * scene.numerics.smoothing_length
    fronts = [measure_frame(f, n_material, centre, spacing, t, support) for t, f in zip(times, frames)]
    first, final = fronts[0], fronts[-1]
    r0, height = 0.5 * (first.front_right + first.front_left), first.height  # as laid on the lattice
    r_inf = 0.5 * (final.front_right + final.front_left)
    rest = time_to_rest([d["t"] for d in diagnostics], [d["kinetic_energy"] for d in diagnostics])
    a = height / r0
    return CollapseResult(name=scene.name, aspect_ratio=a, r0=r0, runout=(r_inf - r0) / r0,
                          runout_reference=lube_runout(a), deposit_height=final.height, time_to_rest=rest,
                          escaped=final.escaped, end_time=float(times[-1]), fronts=fronts)


def write_fronts_csv(result: CollapseResult, path: Path) -> None:
    from ..output import atomic_write_text
    import io

    buf = io.StringIO()
    writer = csv.writer(buf)
    writer.writerow(["t", "front_right", "front_left", "front_mean", "runout_normalised", "height"])
    for m in result.fronts:
        mean = 0.5 * (m.front_right + m.front_left)
        writer.writerow([f"{m.time:.6g}", f"{m.front_right:.6g}", f"{m.front_left:.6g}", f"{mean:.6g}",
                         f"{(mean - result.r0) / result.r0:.6g}", f"{m.height:.6g}"])
    atomic_write_text(path, buf.getvalue())
