"""Validation 2 of [M]: collapse of a 2D granular column (MODEL.md section 1, Table 3).

A column of half-width r0 (2D) or radius r0 (3D, a cylinder) and height H0 = a r0 is released
on a rough floor and spreads to a deposit of half-width or radius r_inf. Reference: the run-out scaling of Lube et al. (2004),
    (r_inf - r0)/r0 = 1.24 a (a < 1.7),  1.6 a^(1/2) (a > 1.7).
Measured per frame: the fronts (the outermost particle, plus its radius, of the main body:
the largest cluster of particles joined when closer than 1.5 dp, so that grains or clumps left
ahead of the flow are not the front) -- in 2D the
left and right ones, in 3D the outermost in each of SECTORS equal azimuthal sectors around
the axis -- their mean distance from the column axis, the deposit height (the highest particle top), and the
particles that have escaped: lost through an open face of the domain, or isolated (no other
particle within the kernel support 2h; e.g. a grain come to rest a little ahead of the toe).
r0 and H0 are measured the same way on the first frame (the column as laid on the particle
lattice), and a = H0/r0. Beside the front, the bulk run-out (R - R0)/R0 with R the distance from
the axis within which BULK_FRACTION of the mass lies: the outermost grain is known to +-1 dp
(a tenth of r0 at 10 particles per half-width), the mass distribution to far better, so schemes
and resolutions are compared on it as well (it is not Lube's quantity).

When the run-out is read: the regularised viscosity [M48] is finite below yield (about m_0 tau_y),
so a deposit whose surface slopes creeps at a strain rate of about (tau/tau_y)/m_0 that does not
decay, and its kinetic energy levels off instead of falling below REST_FRACTION of its peak.
Rest is therefore the front's: the front has stopped at the first frame after its peak speed
from which it runs ahead slower than FRONT_STOP_FRACTION of that peak for FRONT_STOP_WINDOW
seconds (measured as the advance from that frame to each frame of the window), and never
again faster than SURGE_FRACTION of the peak (a pause followed by a second surge is no stop),
nor stepping back by more than STEP_BACK particle spacings within the window (a grain that
leaves the deposit while still moving is not its front).
r_inf is read there, as an experimentalist reads it; the creep speed afterwards (also as a
share of the peak) and the kinetic-energy plateau (its median over the frames after the stop,
over its peak) are reported beside it. A deposit whose kinetic energy falls below REST_FRACTION of
its peak has stopped then, if its front had not before; a front that never stops is read at the end.
"""
from __future__ import annotations

import csv
import itertools
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional, Sequence

import numpy as np

from ..config import Scene
from ..output import left_domain

REST_FRACTION = 1e-3  # at rest: kinetic energy below this share of its peak
FRONT_STOP_FRACTION = 0.01  # the front has stopped: slower than this share of its peak speed ...
FRONT_STOP_WINDOW = 0.1  # [s] ... for this long
SURGE_FRACTION = 0.05  # ... and never again faster than this share of its peak (no second surge)
STEP_BACK = 0.5  # ... nor stepping back by more than this many particle spacings within the window
BULK_FRACTION = 0.98  # the bulk run-out: the distance from the axis within which this share of the mass lies
SECTORS = 16  # 3D: azimuthal sectors whose outermost particles make the front


def lube_runout(aspect_ratio: float) -> float:
    """(r_inf - r0)/r0 of Lube et al. (2004)."""
    return 1.24 * aspect_ratio if aspect_ratio < 1.7 else 1.6 * math.sqrt(aspect_ratio)


def column_axis(scene: Scene) -> np.ndarray:
    """Horizontal position of the axis of the scene's first particle block: x in 2D, (x, y) in 3D  [m]."""
    block = scene.particles[0]
    horizontal = scene.dimension - 1
    return 0.5 * (np.array(block.lower[:horizontal]) + np.array(block.upper[:horizontal]))


def close_pairs(position: np.ndarray, reach: float):
    """Index arrays (i, j), i != j, of the particle pairs closer than ``reach`` (each pair both ways).

    Cells of edge ``reach``: every close pair lies in the same or adjacent cells, so each
    particle is checked against the particles of its 3^dim cells only (vectorised)."""
    n, dim = position.shape
    if n == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    cell = np.floor((position - position.min(axis=0)) / reach).astype(np.int64)
    shape = tuple(int(v) for v in cell.max(axis=0) + 3)
    keys = np.ravel_multi_index((cell + 1).T, shape)
    order = np.argsort(keys, kind="stable")
    sorted_keys = keys[order]
    found_i, found_j = [], []
    for offset in itertools.product((-1, 0, 1), repeat=dim):
        neighbour_keys = np.ravel_multi_index((cell + 1 + np.array(offset)).T, shape)
        first = np.searchsorted(sorted_keys, neighbour_keys, side="left")
        count = np.searchsorted(sorted_keys, neighbour_keys, side="right") - first
        i = np.repeat(np.arange(n), count)
        within = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
        j = order[np.repeat(first, count) + within]
        close = (i != j) & (np.sum((position[i] - position[j]) ** 2, axis=1) < reach * reach)
        found_i.append(i[close])
        found_j.append(j[close])
    return np.concatenate(found_i), np.concatenate(found_j)


def connected(position: np.ndarray, reach: float) -> np.ndarray:
    """True for particles with at least one other particle closer than ``reach``."""
    ok = np.zeros(len(position), bool)
    ok[close_pairs(position, reach)[0]] = True
    return ok


def main_body(position: np.ndarray, reach: float) -> np.ndarray:
    """True for the particles of the largest cluster, particles joined when closer than ``reach``.

    Connected components by hooking each pair's larger root onto the smaller and pointer
    jumping (vectorised; a few sweeps even for long chains)."""
    n = len(position)
    if n == 0:
        return np.zeros(0, bool)
    i, j = close_pairs(position, reach)
    root = np.arange(n)
    while True:
        ri, rj = root[i], root[j]
        differ = ri != rj
        if not np.any(differ):
            break
        np.minimum.at(root, np.maximum(ri, rj)[differ], np.minimum(ri, rj)[differ])
        while True:  # pointer jumping: every particle points at its current root
            jumped = root[root]
            if np.array_equal(jumped, root):
                break
            root = jumped
    return root == np.argmax(np.bincount(root))


@dataclass
class FrameMeasure:
    time: float
    front_right: float  # [m] from the axis; 3D: the farthest sector front
    front_left: float  # [m] from the axis; 3D: the nearest sector front
    front_mean: float  # [m] from the axis: mean of the two fronts (2D) or of the sector fronts (3D)
    height: float  # [m]
    escaped: int  # particles with no other particle within the kernel support 2h, or out of the domain
    lost: int  # of those, out of the domain
    bulk_extent: float  # [m] from the axis: within it lies BULK_FRACTION of the mass


def measure_frame(arrays: Dict[str, np.ndarray], n_material: int, centre: np.ndarray, spacing: float,
                  time: float, support: float) -> FrameMeasure:
    x = np.asarray(arrays["position"][:n_material], float)
    dim = x.shape[1]
    # particle radius: half the edge of its lattice cell of volume m/rho, so that the column as
    # laid measures r0 = the block's half-width
    radius = 0.5 * (arrays["mass"][:n_material] / arrays["density"][:n_material]) ** (1.0 / dim)
    inside = ~left_domain(arrays, n_material)  # grains that slid off the floor through an open face
    ok = np.zeros(n_material, bool)
    ok[inside] = main_body(x[inside], 1.5 * spacing)
    rel = x[ok, : dim - 1] - centre
    distance_all = np.linalg.norm(x[inside, : dim - 1] - centre, axis=1)
    if dim == 2:
        fronts = np.array([np.max(rel[:, 0] + radius[ok]), np.max(-rel[:, 0] + radius[ok])])
    else:
        distance = np.hypot(rel[:, 0], rel[:, 1]) + radius[ok]
        sector = np.floor((np.arctan2(rel[:, 1], rel[:, 0]) + math.pi) / (2 * math.pi) * SECTORS).astype(int)
        sector = np.clip(sector, 0, SECTORS - 1)
        fronts = np.array([distance[sector == k].max() for k in range(SECTORS) if np.any(sector == k)])
    return FrameMeasure(time=time, front_right=float(fronts.max()), front_left=float(fronts.min()),
                        front_mean=float(fronts.mean()),
                        height=float(np.max(x[ok, dim - 1] + radius[ok])),
                        escaped=int(n_material - connected(x[inside], support).sum()),
                        lost=int(n_material - inside.sum()),
                        bulk_extent=mass_quantile(distance_all, arrays["mass"][:n_material][inside], BULK_FRACTION))


def mass_quantile(value: np.ndarray, mass: np.ndarray, fraction: float) -> float:
    """The value below which ``fraction`` of the mass lies (linear between sorted particles)."""
    if len(value) == 0:
        return 0.0
    order = np.argsort(value, kind="stable")
    cumulative = np.cumsum(mass[order]) - 0.5 * mass[order]
    return float(np.interp(fraction * mass.sum(), cumulative, value[order]))


@dataclass
class CollapseResult:
    name: str
    aspect_ratio: float
    r0: float
    runout: float  # (r_inf - r0)/r0 when the front stopped (at the end if it never did)
    runout_reference: float  # Lube et al. (2004)
    deposit_height: float  # [m], when the front stopped
    front_stop_time: Optional[float]  # [s], None if the front never stopped
    peak_front_speed: float  # [m/s] the front's fastest advance between two frames
    creep_speed: float  # [m/s] mean front speed from the stop to the end (0 if no frames after it)
    runout_end: float  # (r_inf - r0)/r0 at the last frame
    bulk_runout_end: float  # (R - R0)/R0 at the last frame, R the BULK_FRACTION mass extent
    time_to_rest: Optional[float]  # [s], kinetic energy below REST_FRACTION of its peak; None if never
    final_energy_fraction: float  # kinetic energy at the end over its peak
    energy_plateau: float  # median kinetic energy after the front stop (the last window if none) over its peak
    escaped: int  # at the end: particles that interact with no other (isolated, or lost)
    lost: int  # at the end: particles lost through an open face of the domain
    end_time: float
    read_at_end: bool  # the run-out read at the last frame (the deposit at rest), not at the front stop
    fronts: List[FrameMeasure] = field(default_factory=list)

    @property
    def error(self) -> float:
        return (self.runout - self.runout_reference) / self.runout_reference

    @property
    def creep_share(self) -> float:
        """Creep speed after the stop over the front's peak speed."""
        return self.creep_speed / self.peak_front_speed if self.peak_front_speed > 0 else 0.0

    def passes(self, bound: float) -> bool:
        """Run-out within ``bound`` of Lube's, no grain lost from the domain, and at rest: the
        deposit's kinetic energy below REST_FRACTION of its peak where the run-out is read at the
        end, else the front stopped. Isolated grains are reported, not failed: one at rest a few mm ahead of the toe
        is part of the deposit that the front ignores."""
        rest = self.time_to_rest is not None if self.read_at_end else self.front_stop_time is not None
        return abs(self.error) < bound and rest and self.lost == 0

    def row(self) -> str:
        def opt(t):
            return f"{t:6.3f}" if t is not None else "  none"
        return (f"{self.name:<16} {self.aspect_ratio:5.2f} {self.runout:8.3f} {self.runout_reference:8.3f} "
                f"{100 * self.error:+7.1f} % {1e3 * self.deposit_height:8.1f} {opt(self.front_stop_time)} "
                f"{1e3 * self.peak_front_speed:7.1f} {1e3 * self.creep_speed:8.2f} {100 * self.creep_share:6.2f} "
                f"{self.runout_end:7.3f} {self.bulk_runout_end:7.3f} {self.end_time:6.2f} "
                f"{opt(self.time_to_rest)} {self.final_energy_fraction:9.1e} {self.energy_plateau:9.1e} {self.escaped:7d} {self.lost:4d}")


HEADER = (f"{'case':<16} {'a':>5} {'run-out':>8} {'Lube':>8} {'error':>9} {'H_inf mm':>8} {'stop s':>6} "
          f"{'peak mm/s':>7} {'creep mm/s':>8} {'creep%':>6} {'at end':>7} {'bulk end':>7} {'end s':>6} {'rest s':>6} "
          f"{'KE_end/pk':>9} {'KE_plat':>9} {'escaped':>7} {'lost':>4}")


def peak_speed(times: Sequence[float], front: Sequence[float]) -> tuple:
    """(index k of the fastest frame interval, its speed): the front's peak speed, between frames
    k and k + 1. Measured on the front's running maximum: a tip that detaches (the reading steps
    back) and is caught up again within a frame or two is not a burst of speed."""
    t, x = np.asarray(times, float), np.maximum.accumulate(np.asarray(front, float))
    if len(t) < 2:
        return 0, 0.0
    speed = np.diff(x) / np.diff(t)
    peak = int(np.argmax(speed))
    return peak, float(speed[peak])


def front_stop(times: Sequence[float], front: Sequence[float], at_rest_at_end: bool = False,
               step_back: float = math.inf) -> Optional[int]:
    """Index of the frame at which the front stopped (module docstring): the first after its
    peak speed from which it runs ahead slower than FRONT_STOP_FRACTION of the peak for
    FRONT_STOP_WINDOW seconds and never again faster than SURGE_FRACTION of it; None if there is
    no such frame (a window must fit before the last frame, unless the run ended ``at_rest_at_end``:
    its kinetic energy below REST_FRACTION of the peak, so that the front moves no further). A
    front whose tip detaches steps back; a grain joining it steps on: both are measured as
    advances from the frame. A frame from which the front steps back by more than ``step_back``
    [m] within the window is no stop either: its front is a grain about to leave the deposit
    (measured on the a = 2.75 collapse at dp 19.44 mm: a grain that rolled over the stopped
    front slid 3 cm further at 0.3 m/s, half the front's peak speed, and the frame before it
    separated passed for the stop, reading it as the run-out: 8 points of Lube)."""
    t, x = np.asarray(times, float), np.asarray(front, float)
    if len(t) < 3:
        return None
    peak, top = peak_speed(t, x)
    if top <= 0.0:
        return None
    slack = 1e-9 * max(1.0, t[-1])
    for k in range(peak + 1, len(t) - 1):
        if t[-1] < t[k] + FRONT_STOP_WINDOW - slack and not at_rest_at_end:
            return None
        elapsed = t[k + 1:] - t[k]
        ahead = x[k + 1:] - x[k]
        window = elapsed <= FRONT_STOP_WINDOW + slack
        if (np.all(ahead[window] <= FRONT_STOP_FRACTION * top * elapsed[window])
                and np.all(ahead <= SURGE_FRACTION * top * elapsed)
                and np.all(-ahead[window] <= step_back)):
            return k
    return None


def time_to_rest(times: Sequence[float], kinetic_energy: Sequence[float]) -> Optional[float]:
    """First time after the kinetic-energy peak at which it is below REST_FRACTION of the peak."""
    ke = np.asarray(kinetic_energy, float)
    if len(ke) == 0 or ke.max() <= 0.0:
        return None
    peak = int(np.argmax(ke))
    below = np.nonzero(ke[peak:] < REST_FRACTION * ke[peak])[0]
    return float(times[peak + below[0]]) if len(below) else None


def evaluate(scene: Scene, times: Sequence[float], frames: Sequence[Dict[str, np.ndarray]],
             diagnostics: Sequence[dict], read_at_end: Optional[bool] = None) -> CollapseResult:
    """Measures of a collapse run; the run-out is read when the front stops, or with
    ``read_at_end`` at the last frame (default: :func:`reads_at_end` of the scene's model)."""
    if read_at_end is None:
        read_at_end = reads_at_end(scene)
    centre = column_axis(scene)
    spacing = scene.numerics.particle_spacing
    n_material = int(np.sum(frames[0]["is_wall"] == 0))
    support = 2.0 * scene.numerics.smoothing_length
    fronts = [measure_frame(f, n_material, centre, spacing, t, support) for t, f in zip(times, frames)]
    mean = [m.front_mean for m in fronts]
    first, final = fronts[0], fronts[-1]
    r0, height = mean[0], first.height  # as laid on the lattice
    ke = np.array([d["kinetic_energy"] for d in diagnostics], float)
    ke_times = np.array([d["t"] for d in diagnostics], float)
    rest = time_to_rest(ke_times, ke)
    stop = front_stop(times, mean, at_rest_at_end=rest is not None, step_back=STEP_BACK * spacing)
    if stop is None and rest is not None:  # the deposit came to rest before its front's window closed
        stop = int(np.searchsorted(np.asarray(times, float), rest - 1e-9))
    read = stop if stop is not None and not read_at_end else len(fronts) - 1
    t_end = float(times[-1])
    creep = (mean[-1] - mean[read]) / (t_end - times[read]) if t_end > times[read] else 0.0
    after = ke_times >= (times[stop] if stop is not None else t_end - FRONT_STOP_WINDOW)
    plateau = float(np.median(ke[after])) / ke.max() if ke.max() > 0 and np.any(after) else 0.0
    a = height / r0
    return CollapseResult(name=scene.name, aspect_ratio=a, r0=r0, runout=(mean[read] - r0) / r0,
                          runout_reference=lube_runout(a), deposit_height=fronts[read].height,
                          front_stop_time=None if stop is None else float(times[stop]),
                          peak_front_speed=peak_speed(times, mean)[1], creep_speed=creep,
                          runout_end=(mean[-1] - r0) / r0,
                          bulk_runout_end=(final.bulk_extent - first.bulk_extent) / first.bulk_extent,
                          time_to_rest=rest,
                          final_energy_fraction=float(ke[-1] / ke.max()) if ke.max() > 0 else 0.0,
                          energy_plateau=plateau,
                          escaped=final.escaped, lost=final.lost, end_time=t_end, read_at_end=read_at_end,
                          fronts=fronts)


def reads_at_end(scene: Scene) -> bool:
    """Where a collapse's run-out is read: when the front stops if the model's deposit creeps
    (mu(I)), else at the end of the run, the deposit at rest."""
    return not type(scene.material).deposit_creeps


def write_fronts_csv(result: CollapseResult, path: Path) -> None:
    from ..output import atomic_write_text
    import io

    buf = io.StringIO()
    writer = csv.writer(buf)
    # 2D: right and left fronts; 3D: the farthest and nearest of the sector fronts
    writer.writerow(["t", "front_right", "front_left", "front_mean", "runout_normalised", "height"])
    for m in result.fronts:
        writer.writerow([f"{m.time:.6g}", f"{m.front_right:.6g}", f"{m.front_left:.6g}", f"{m.front_mean:.6g}",
                         f"{(m.front_mean - result.r0) / result.r0:.6g}", f"{m.height:.6g}"])
    atomic_write_text(path, buf.getvalue())


# ---- the validate command's cases (validation/__init__.py CASES) ------------------------------

# per case: the bound on the run-out error (where it is read: reads_at_end)
ACCEPTANCE = {
    "column-collapse": 0.15,  # 2D mu(I), Table 3 of [M]
    "column-collapse-3d": 0.20,  # 3D [A], CPU variants
    "pile-collapse": 0.20,  # 2D [P], set 2, on [M]'s geometry
}


def markdown_rows(results: Sequence[CollapseResult], where: Sequence[tuple]) -> str:
    """The family's rows as a Markdown table (runout.md beside runout.csv; the docs' tables are
    copied from it): where = (resolution, cost) per result."""
    def opt(t, fmt):
        return "-" if t is None else format(t, fmt)

    lines = ["| case | a | run-out | Lube | error | front stops | deposit height | peak front speed | creep after "
             "(share of peak) | bulk at end | end | kinetic energy plateau | escaped / lost | resolution | cost |",
             "|" + "---|" * 15]
    for r, (res, run_cost) in zip(results, where):
        lines.append(f"| {r.name} | {r.aspect_ratio:.2f} | {r.runout:.3f} | {r.runout_reference:.3f} | "
                     f"{100 * r.error:+.1f} % | {opt(r.front_stop_time, '.2f')} s | {1e3 * r.deposit_height:.1f} mm | "
                     f"{r.peak_front_speed:.2f} m/s | {1e3 * r.creep_speed:.2f} mm/s ({100 * r.creep_share:.2f} %) | "
                     f"{r.bulk_runout_end:.3f} | {r.end_time:.2f} s{'' if r.time_to_rest is None else ' (at rest)'} | "
                     f"{r.energy_plateau:.1e} | {r.escaped} / {r.lost} | {res} | {run_cost} |")
    return "\n".join(lines) + "\n"


# the paper's own figure for the validation table: none of the three tabulates its run-outs
PAPER = {
    "column-collapse": "[M]: on Lube's line up to a = 3 (figure only)",
    "column-collapse-3d": "-",
    "pile-collapse": "-",
}


def _csv_value(value) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return f"{value:.5g}"
    return str(value)


def check(case, runs, base, args) -> bool:
    """Run-out against Lube et al. (2004) within the family's bound, at rest (mu(I): the front
    stopped), none lost; writes fronts.csv per case, runout.csv and runout.png for the family."""
    import io

    from ..output import atomic_write_text, read_diagnostics
    from ..render.frames import write_png
    from ..render.plot import plot_points_and_curve

    from .table import Row, cost, resolution, write_rows

    bound = ACCEPTANCE[case.name]
    results, where = [], []
    print(HEADER)
    for scene, out, times, frames in runs:
        result = evaluate(scene, times, frames, read_diagnostics(out))
        write_fronts_csv(result, out / "fronts.csv")
        results.append(result)
        where.append((resolution(scene, frames, out), cost(out)))
        print(result.row(), flush=True)
    columns = ["case", "aspect_ratio", "runout", "runout_lube", "error", "deposit_height", "front_stop_time",
               "peak_front_speed", "creep_speed", "creep_share", "runout_end", "bulk_runout_end", "end_time",
               "time_to_rest", "final_energy_fraction", "energy_plateau", "escaped", "lost"]
    buf = io.StringIO()
    writer = csv.writer(buf)
    writer.writerow(columns)
    for r in results:
        values = {"case": r.name, "runout_lube": r.runout_reference, "error": r.error, "creep_share": r.creep_share}
        writer.writerow([_csv_value(values[c] if c in values else getattr(r, c)) for c in columns])
    atomic_write_text(base / "runout.csv", buf.getvalue())
    atomic_write_text(base / "runout.md", markdown_rows(results, where))
    a = np.linspace(0.01, max(3.2, max(r.aspect_ratio for r in results) * 1.05), 200)
    image = plot_points_and_curve([(r.aspect_ratio, r.runout) for r in results],
                                  (a, np.array([lube_runout(x) for x in a])),
                                  "aspect ratio a", "(r_inf - r0)/r0", "line: lube et al. 2004, squares: sph")
    write_png(base / "runout.png", image)
    ok = all(r.passes(bound) for r in results)
    at_rest = results[-1].read_at_end  # one model per family
    if at_rest:
        print("run-out read at the end of the run (the deposit at rest: kinetic energy below "
              f"{REST_FRACTION:g} of its peak)")
    else:
        print(f"run-out read when the front stops (slower than {100 * FRONT_STOP_FRACTION:g} % of its peak speed "
              f"for {FRONT_STOP_WINDOW:g} s, never again faster than {100 * SURGE_FRACTION:g} %); afterwards the "
              "regularised viscosity lets the deposit creep at the speed shown (docs, column collapse)")
    rest = "at rest" if at_rest else "front stopped"
    print(f"acceptance (run-out within {100 * bound:.0f} % of Lube, {rest}, no grain lost from the domain): "
          f"{'PASS' if ok else 'FAIL'}; {base / 'runout.csv'}, {base / 'runout.png'}")
    write_rows(base, [Row(f"{case.name}: {r.name}", f"run-out (r_inf - r0)/r0 at a = {r.aspect_ratio:.2f}",
                          f"{r.runout:.3f} ({100 * r.error:+.1f} %)", PAPER[case.name],
                          f"Lube et al. (2004): {r.runout_reference:.3f}", res, run_cost,
                          "PASS" if r.passes(bound) else "FAIL")
                      for r, (res, run_cost) in zip(results, where)])
    return ok
