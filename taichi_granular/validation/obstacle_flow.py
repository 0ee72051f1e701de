"""Chute flow past a single obstacle ([A] section 6, MODEL.md section 3): the circular cylinder
of Cui & Gray (2013) and the tetrahedral wedge of Tai et al. (2001) with a building block
behind it.

From each frame, on a grid of cells over the bed (s along the chute from its origin, y across),
with the material particles' height above the bed:
- flow depth per cell: the highest particle top (height + dp/2) in it, 0 where empty;
- bow shock, on the centre line (|y| < one cell) upstream of the obstacle's front s_f: the
  upstream depth h_0 (mean over s_f - 5 L .. s_f - 3 L, L the obstacle's width across the
  chute), the peak depth h_1 (max over s_f - 2 L .. s_f), the depth jump h_1/h_0, and the
  stand-off distance: from s_f up to the upstream end of the run of cells, adjacent to the
  obstacle, whose depth is at least (h_0 + h_1)/2 -- where the flow surface jumps;
- particle-free zone (wake / "vacuum") behind the obstacle: the empty cells connected (four
  neighbours) to the cell just behind its rear s_b on the centre line; its length (furthest
  s - s_b) and area; it is closed when it touches neither the chute's end nor its sides;
- protected zone (wedge): the number of material particles in the box behind the rear,
  ``PROTECTED_LENGTH`` long and as wide as the obstacle;
- oblique shocks (wedge), on the depth averaged over the steady frames (a sheet one or two
  grains deep leaves single cells empty in any one frame): in each row of cells across the chute
  between the tip and the rear, the raised layer along each face runs outward from the face to
  the first cell shallower than ``OBLIQUE_THRESHOLD`` h_0 (h_0 averaged alike); its outer edge |y|
  against the distance from the tip, fitted by a line through the tip, gives the shock's angle to
  the chute's axis (above the wedge's half-angle where a shock stands off the face), and the
  raised layer's mean depth over h_0 its depth jump.
A bow shock "appears" when the depth jump exceeds SHOCK_JUMP; steady state is the last
``STEADY_FRACTION`` of the frames, over which shock and closed wake must hold in at least
``PERSISTENCE`` of the frames (issue 26's 90 %: a stream a few grains deep may open the wake for
a frame).

Units: m, m^2, s.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Dict, List, Sequence

import numpy as np

from ..bodies import BoxObstacle, ChuteObstacle, CylinderObstacle, WedgeObstacle
from ..config import Scene
from ..output import left_domain
from .obstacles import along_chute, obstacle_of

SHOCK_JUMP = 1.5  # h_1/h_0 above which the frame has a bow shock
STEADY_FRACTION = 0.3  # the last 30 % of the frames make the steady state
PERSISTENCE = 0.9  # of the steady frames in which the shock (the closed wake) must stand
PROTECTED_LENGTH = 0.10  # [m] behind the rear that the wedge protects (our choice)
CELL_FACTOR = 1.5  # grid cell = 1.5 dp: a lattice of particles leaves no empty cell
OBLIQUE_THRESHOLD = 0.5 * (1.0 + SHOCK_JUMP)  # of h_0: the raised layer along a wedge's face ends below this


@dataclass
class ObstacleGeometry:
    front: float  # s of the face the flow meets [m]
    rear: float  # s of the rear of the obstacle (of the building behind a wedge) [m]
    width: float  # extent across the chute [m]
    tip_length: float = float("nan")  # a wedge's tip-to-rear length along the chute (NaN: a cylinder) [m]

    @property
    def half_angle(self) -> float:
        """A wedge's half-angle at its tip, atan(width / (2 tip_length))  [rad]."""
        return math.atan(0.5 * self.width / self.tip_length)


def obstacle_geometry(scene: Scene) -> ObstacleGeometry:
    """Front, rear and width of the scene's cylinder or wedge, along its chute."""
    chute = obstacle_of(scene, ChuteObstacle)
    solids = [o for o in scene.obstacles if isinstance(o, (CylinderObstacle, WedgeObstacle))]
    if not solids:
        raise ValueError(f"{scene.name}: no cylinder or wedge among the obstacles")
    solid = solids[0]
    origin = np.asarray(solid.origin if solid.origin is not None else np.zeros(scene.dimension), float)
    s0 = float(along_chute(chute, origin[None, :])[0][0])
    if isinstance(solid, CylinderObstacle):
        return ObstacleGeometry(front=s0 - solid.radius, rear=s0 + solid.radius, width=2.0 * solid.radius)
    rear = solid.length
    for box in scene.obstacles:  # a building laid in the wedge's own frame, right behind it
        if isinstance(box, BoxObstacle) and box.origin == solid.origin and box.tilt_deg == solid.tilt_deg:
            rear = max(rear, box.upper[0])
    return ObstacleGeometry(front=s0, rear=s0 + rear, width=solid.width, tip_length=solid.length)


@dataclass
class FlowFrame:
    time: float
    upstream_depth: float  # h_0 [m]
    peak_depth: float  # h_1 [m]
    standoff: float  # [m], nan without a shock
    wake_length: float  # [m]
    wake_area: float  # [m^2]
    wake_closed: bool
    protected_particles: int
    depth: np.ndarray = field(repr=False, default=None)  # flow depth per cell of ``flow_grid`` [m]

    @property
    def depth_jump(self) -> float:
        return self.peak_depth / self.upstream_depth if self.upstream_depth > 0 else float("nan")

    @property
    def shock(self) -> bool:
        return self.depth_jump > SHOCK_JUMP


def depth_grid(s: np.ndarray, y: np.ndarray, top: np.ndarray, s_edges: np.ndarray, y_edges: np.ndarray):
    """(count, depth) per cell: particles in it and their highest top (0 where empty)."""
    i = np.digitize(s, s_edges) - 1
    j = np.digitize(y, y_edges) - 1
    ok = (i >= 0) & (i < len(s_edges) - 1) & (j >= 0) & (j < len(y_edges) - 1)
    count = np.zeros((len(s_edges) - 1, len(y_edges) - 1), int)
    depth = np.zeros(count.shape)
    np.add.at(count, (i[ok], j[ok]), 1)
    np.maximum.at(depth, (i[ok], j[ok]), np.maximum(top[ok], 0.0))
    return count, depth


def bow_shock(s_centres: np.ndarray, centre_depth: np.ndarray, front: float, width: float):
    """(h_0, h_1, stand-off) on the centre line (module docstring)  [m]."""
    upstream = (s_centres >= front - 5 * width) & (s_centres <= front - 3 * width)
    near = (s_centres >= front - 2 * width) & (s_centres < front)
    if not upstream.any() or not near.any():
        return float("nan"), float("nan"), float("nan")
    h0 = float(centre_depth[upstream].mean())
    h1 = float(centre_depth[near].max())
    threshold = 0.5 * (h0 + h1)
    standoff = float("nan")
    cells = np.nonzero(s_centres < front)[0][::-1]  # from the obstacle upstream
    run_start = None
    for k in cells:
        if centre_depth[k] >= threshold:
            run_start = k
        elif run_start is not None or s_centres[k] < front - 2 * width:
            break
    if run_start is not None:
        standoff = float(front - s_centres[run_start])
    return h0, h1, standoff


def oblique_shocks(s_centres: np.ndarray, y_centres: np.ndarray, depth: np.ndarray, h0: float, tip: float,
                   length: float, half_angle: float):
    """(angle to the chute's axis [deg], depth jump [-]) of the raised layers along a wedge's two
    faces, fitted together (module docstring); NaN where no row has a raised layer."""
    cell = s_centres[1] - s_centres[0]
    threshold = OBLIQUE_THRESHOLD * h0
    along, edges, raised = [], [], []
    for i in np.nonzero((s_centres > tip + 2.0 * cell) & (s_centres < tip + length))[0]:
        face = (s_centres[i] - tip) * math.tan(half_angle)
        for side in (1.0, -1.0):
            outward = np.nonzero(side * y_centres > face)[0]
            order = outward[np.argsort(side * y_centres[outward])]
            shallow = np.nonzero(depth[i, order] < threshold)[0]
            width = int(shallow[0]) if len(shallow) else len(order)
            if width == 0:
                continue
            along.append(s_centres[i] - tip)
            edges.append(abs(y_centres[order[width - 1]]) + 0.5 * cell)
            raised.extend(depth[i, order[:width]])
    if not along or not h0 > 0.0:
        return float("nan"), float("nan")
    along, edges = np.array(along), np.array(edges)
    return math.degrees(math.atan(float(along @ edges) / float(along @ along))), float(np.mean(raised)) / h0


def empty_region(count: np.ndarray, start) -> np.ndarray:
    """Mask of the empty cells four-connected to ``start`` (none if it is occupied)."""
    region = np.zeros(count.shape, bool)
    if count[start] > 0:
        return region
    stack = [start]
    region[start] = True
    while stack:
        i, j = stack.pop()
        for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            a, b = i + di, j + dj
            if 0 <= a < count.shape[0] and 0 <= b < count.shape[1] and not region[a, b] and count[a, b] == 0:
                region[a, b] = True
                stack.append((a, b))
    return region


def flow_grid(scene: Scene):
    """(s edges, y edges) of the grid of cells over the chute's bed  [m]."""
    chute = obstacle_of(scene, ChuteObstacle)
    cell = CELL_FACTOR * scene.numerics.particle_spacing
    half = 0.5 * chute.width
    s_end = float(sum(seg.length for seg in chute.segments))
    return np.arange(0.0, s_end + cell, cell), np.linspace(-half, half, int(round(chute.width / cell)) + 1)


def measure_flow_frame(scene: Scene, frame: Dict[str, np.ndarray], time: float) -> FlowFrame:
    chute = obstacle_of(scene, ChuteObstacle)
    geo = obstacle_geometry(scene)
    dp = scene.numerics.particle_spacing
    cell = CELL_FACTOR * dp
    n = int(np.sum(frame["is_wall"] == 0))
    x = np.asarray(frame["position"][:n], float)
    keep = ~left_domain(frame, n)
    s, height = along_chute(chute, x[keep])
    y = x[keep, 1]
    s_edges, y_edges = flow_grid(scene)
    count, depth = depth_grid(s, y, height + 0.5 * dp, s_edges, y_edges)
    s_centres = 0.5 * (s_edges[1:] + s_edges[:-1])
    y_centres = 0.5 * (y_edges[1:] + y_edges[:-1])
    centre = np.abs(y_centres) < cell
    h0, h1, standoff = bow_shock(s_centres, depth[:, centre].max(axis=1), geo.front, geo.width)
    start = (int(np.searchsorted(s_centres, geo.rear)), int(np.argmin(np.abs(y_centres))))
    blocked = count.copy()
    blocked[s_centres < geo.rear, :] = 1  # the obstacle's own footprint and upstream are not wake
    wake = empty_region(blocked, start) if start[0] < len(s_centres) else np.zeros(count.shape, bool)
    length = float(s_centres[wake.any(axis=1)].max() - geo.rear + 0.5 * cell) if wake.any() else 0.0
    closed = bool(wake.any() and not wake[-1, :].any() and not wake[:, 0].any() and not wake[:, -1].any())
    behind = (s >= geo.rear) & (s < geo.rear + PROTECTED_LENGTH) & (np.abs(y) < 0.5 * geo.width)
    return FlowFrame(time=time, upstream_depth=h0, peak_depth=h1, standoff=standoff, wake_length=length,
                     wake_area=float(wake.sum() * cell * cell), wake_closed=closed,
                     protected_particles=int(behind.sum()), depth=depth)


@dataclass
class ObstacleFlowResult:
    name: str
    frames: List[FlowFrame] = field(default_factory=list)
    geometry: ObstacleGeometry = None
    grid: tuple = None  # flow_grid's (s edges, y edges)

    @property
    def steady(self) -> List[FlowFrame]:
        k = max(1, int(round(STEADY_FRACTION * len(self.frames))))
        return self.frames[-k:]

    def mean(self, key: str) -> float:
        values = np.array([getattr(f, key) for f in self.steady], float)
        return float(np.nanmean(values)) if np.isfinite(values).any() else float("nan")

    def count(self, key: str) -> int:
        """Steady frames in which the boolean ``key`` (shock, wake_closed) holds."""
        return sum(bool(getattr(f, key)) for f in self.steady)

    @property
    def shock_persists(self) -> bool:
        return self.count("shock") >= PERSISTENCE * len(self.steady)

    @property
    def wake_persists(self) -> bool:
        return self.count("wake_closed") >= PERSISTENCE * len(self.steady)

    def shock_text(self) -> str:
        """The bow shock over the steady frames, for the validation table."""
        return (f"shock in {self.count('shock')}/{len(self.steady)} frames (jump {self.mean('depth_jump'):.2f}, "
                f"stand-off {1e3 * self.mean('standoff'):.0f} mm)")

    @property
    def protected_max(self) -> int:
        return max(f.protected_particles for f in self.steady)

    def oblique(self):
        """(angle to the chute's axis [deg], depth jump [-]) of a wedge's oblique shocks on the depth
        averaged over the steady frames (module docstring); NaN for a cylinder or without a raised layer."""
        geo = self.geometry
        if geo is None or math.isnan(geo.half_angle):
            return float("nan"), float("nan")
        s_edges, y_edges = self.grid
        return oblique_shocks(0.5 * (s_edges[1:] + s_edges[:-1]), 0.5 * (y_edges[1:] + y_edges[:-1]),
                              np.mean([f.depth for f in self.steady], axis=0), self.mean("upstream_depth"),
                              geo.front, geo.tip_length, geo.half_angle)

    def row(self) -> str:
        angle, jump = self.oblique()
        return (f"{self.name:24s} {1e3 * self.mean('upstream_depth'):7.1f} {self.mean('depth_jump'):6.2f} "
                f"{1e3 * self.mean('standoff'):8.1f} {1e3 * self.mean('wake_length'):8.1f} "
                f"{1e4 * self.mean('wake_area'):8.1f} {'yes' if self.shock_persists else 'no':>6s} "
                f"{'yes' if self.wake_persists else 'no':>6s} {self.protected_max:6d} "
                f"{self.steady[0].time:6.2f} {self.frames[-1].time:6.2f} {angle:8.1f} {jump:6.2f}")


HEADER = (f"{'case':24s} {'h0 mm':>7s} {'jump':>6s} {'stand mm':>8s} {'wake mm':>8s} {'wake cm2':>8s} "
          f"{'shock':>6s} {'closed':>6s} {'inside':>6s} {'from s':>6s} {'end s':>6s} {'obl. deg':>8s} {'jump':>6s}")


def evaluate_obstacle_flow(scene: Scene, times: Sequence[float], frames: Sequence[Dict[str, np.ndarray]]
                           ) -> ObstacleFlowResult:
    return ObstacleFlowResult(name=scene.name,
                              frames=[measure_flow_frame(scene, f, t) for t, f in zip(times, frames)],
                              geometry=obstacle_geometry(scene), grid=flow_grid(scene))


# ---- the validate command's case (validation/__init__.py CASES) -------------------------------


def check(case, runs, base, args) -> bool:
    """Cylinder (Cui & Gray 2013) and wedge (Tai et al. 2001) of [A]: bow shock, depth jump,
    particle-free wake and protected zone; writes obstacle_flow.csv per case."""
    from ..output import atomic_write_text
    from .table import Row, cost, resolution, write_rows

    print(HEADER)
    ok, rows = True, []
    for scene, out, times, frames in runs:
        result = evaluate_obstacle_flow(scene, times, frames)
        atomic_write_text(out / "obstacle_flow.csv", "t,upstream_depth_m,depth_jump,standoff_m,wake_length_m,"
                          "wake_area_m2,wake_closed,protected_particles\n" + "".join(
                              f"{f.time:.4f},{f.upstream_depth:.5f},{f.depth_jump:.3f},{f.standoff:.5f},"
                              f"{f.wake_length:.5f},{f.wake_area:.6f},{int(f.wake_closed)},{f.protected_particles}\n"
                              for f in result.frames))
        print(result.row(), flush=True)
        where = (resolution(scene, frames, out), cost(out))
        if "wedge" in scene.name:
            passed = result.shock_persists and result.protected_max == 0
            measure, ours = "bow shock; protected zone empty", f"{result.shock_text()}; {result.protected_max} inside"
            reference = "Tai et al. (2001) experiment: shock, empty zone"
            angle, jump = result.oblique()
            reported = [Row(f"{case.name}: {scene.name}", "oblique shocks: angle to the chute's axis (the wedge's "
                            "half-angle); depth jump", f"{angle:.1f} deg ({math.degrees(result.geometry.half_angle):.1f});"
                            f" {jump:.2f}", "-", "Tai et al. (2001) experiment: oblique shocks", *where, "reported")]
        else:
            reported = []
            passed = result.shock_persists and result.wake_persists
            measure, ours = "bow shock; closed wake", (f"{result.shock_text()}; wake closed in "
                                                       f"{result.count('wake_closed')}/{len(result.steady)} "
                                                       f"({1e3 * result.mean('wake_length'):.0f} mm, "
                                                       f"{1e4 * result.mean('wake_area'):.0f} cm2)")
            reference = "Cui & Gray (2013) experiment: shock, closed wake"
        ok &= passed
        rows += [Row(f"{case.name}: {scene.name}", measure, ours, "-", reference, *where,
                     "PASS" if passed else "FAIL")] + reported
    print(f"steady state: the last {100 * STEADY_FRACTION:.0f} % of the frames; shock: depth jump > "
          f"{SHOCK_JUMP}; wedge: 'inside' counts particles within {PROTECTED_LENGTH} m behind the building")
    share = f">= {100 * PERSISTENCE:.0f} % of the steady frames"
    print(f"acceptance (cylinder: shock and closed wake in {share}; wedge: shock in {share}, protected zone empty "
          f"in all): "
          f"{'PASS' if ok else 'FAIL'}; per frame -> {base}/<case>/obstacle_flow.csv")
    write_rows(base, rows)
    return ok
