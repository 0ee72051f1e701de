"""Chute flow past a single obstacle ([A] section 6, MODEL.md section 3): the circular cylinder
of Cui & Gray (2013) and the tetrahedral wedge of Tai et al. (2001) with a building block
behind it.

From each frame, on a grid of cells over the bed (s along the chute from its origin, y across),
with the material particles' height above the bed:
- flow depth per cell: the highest particle top (height + dp/2) in it, 0 where empty; and the
  depth-averaged speed: the mean over its particles of their velocity along the bed (the
  down-slope axis of their segment), NaN where empty;
- bow shock, on the centre line (|y| < one cell) upstream of the obstacle's front s_f: the
  upstream depth h_0 (mean over s_f - 5 L .. s_f - 3 L, L the obstacle's width across the
  chute), the peak depth h_1 (max over s_f - 2 L .. s_f), the depth jump h_1/h_0, and the
  stand-off distance: from s_f up to the upstream end of the run of cells, adjacent to the
  obstacle, whose depth is at least (h_0 + h_1)/2 -- where the flow surface jumps;
- particle-free zone (wake / "vacuum") behind the obstacle: the empty cells connected (four
  neighbours) to the cell just behind its rear s_b on the centre line; its length (furthest
  s - s_b) and area; it is closed when it touches neither the chute's end nor its sides;
- protected zone (wedge): the number of material particles, at any height (grains over the
  building count), in the building's footprint and one building length L_b behind its rear, as
  wide as the building: s_0 <= s < s_0 + 2 L_b, |y| < w_b/2, s_0 the building's front (the
  wedge's rear), L_b and w_b its length along and width across the chute (the building is the
  box laid in the wedge's frame, centred on the centre line like the wedge; without one the
  wedge's own length and width stand for it);
- oblique shocks (wedge), on the depth and speed averaged over the steady frames (a sheet one or
  two grains deep leaves single cells empty in any one frame; a cell's speed is averaged over the
  frames that hold it): in each row of cells across the chute between the tip and the rear, the
  raised layer along each face runs outward from the face to the first cell shallower than
  ``OBLIQUE_THRESHOLD`` h_0 (h_0 averaged alike); its outer edge |y| against the distance from the
  tip, fitted by a line through the tip, gives the shock's angle beta to the chute's axis (above
  the wedge's half-angle where a shock stands off the face). Beside the shock, in the same rows,
  the ``BESIDE_CELLS`` cells outward of the raised layer's edge (none within ``WALL_CELLS`` of a
  side wall) give the upstream depth h_0' and speed u_0. The oblique depth ratio h_1/h_0' (h_1 the
  raised layer's mean depth) is judged against [A] Fig. 17 (about 3), and compared with the
  shallow-flow oblique jump condition (Gray & Cui 2007; Hakonardottir & Hogg 2005; earth pressure
  coefficient 1): h_1/h_0 = (sqrt(1 + 8 F_n^2) - 1)/2, F_n = F sin(beta), with the upstream Froude
  number F = u_0 / sqrt(g cos(zeta) h_0'), zeta the bed's slope at the wedge.
A bow shock "appears" when the depth jump exceeds SHOCK_JUMP; steady state is the last
``STEADY_FRACTION`` of the frames, over which shock and closed wake must hold in at least
``PERSISTENCE`` of the frames (issue 26's 90 %: a stream a few grains deep may open the wake for
a frame). Wedge acceptance: a bow shock in ``PERSISTENCE`` of the steady frames, the protected
zone empty in every one, and the oblique depth ratio within ``OBLIQUE_RATIO_TOLERANCE`` of
``OBLIQUE_RATIO_PAPER``.

Units: m, m^2, s.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Dict, List, Sequence

import numpy as np

from ..bodies import BoxObstacle, ChuteObstacle, CylinderObstacle, WedgeObstacle
from ..config import Scene
from ..local_frame import local_axes
from ..output import left_domain
from .obstacles import along_chute, obstacle_of

SHOCK_JUMP = 1.5  # h_1/h_0 above which the frame has a bow shock
STEADY_FRACTION = 0.3  # the last 30 % of the frames make the steady state
PERSISTENCE = 0.9  # of the steady frames in which the shock (the closed wake) must stand
CELL_FACTOR = 1.5  # grid cell = 1.5 dp: a lattice of particles leaves no empty cell
OBLIQUE_THRESHOLD = 0.5 * (1.0 + SHOCK_JUMP)  # of h_0: the raised layer along a wedge's face ends below this
BESIDE_CELLS = 3  # cells outward of the raised layer's edge that give the depth and speed beside the shock
WALL_CELLS = 2  # cells next to a side wall left out of the depth beside the shock
OBLIQUE_RATIO_PAPER = 3.0  # oblique shock's depth ratio h_1/h_0 on the wedge's flanks, [A] Fig. 17
OBLIQUE_RATIO_TOLERANCE = 0.3  # relative: ours within 30 % of it


@dataclass
class ObstacleGeometry:
    front: float  # s of the face the flow meets [m]
    rear: float  # s of the rear of the obstacle (of the building behind a wedge) [m]
    width: float  # extent across the chute [m]
    tip_length: float = float("nan")  # a wedge's tip-to-rear length along the chute (NaN: a cylinder) [m]
    building_front: float = float("nan")  # s of the building's front face behind a wedge [m]
    building_length: float = float("nan")  # its length along the chute [m]
    building_width: float = float("nan")  # its width across the chute [m]
    normal_gravity: float = float("nan")  # g cos(zeta), zeta the bed's slope at the obstacle [m/s^2]

    @property
    def half_angle(self) -> float:
        """A wedge's half-angle at its tip, atan(width / (2 tip_length))  [rad]."""
        return math.atan(0.5 * self.width / self.tip_length)

    @property
    def protected_zone(self):
        """(s from, s to, half-width) of the zone a wedge protects: the building's footprint and one
        building length behind it, as wide as the building (NaN for a cylinder)  [m]."""
        return self.building_front, self.building_front + 2.0 * self.building_length, 0.5 * self.building_width


def segment_at(chute: ChuteObstacle, s: np.ndarray) -> np.ndarray:
    """Index of the chute's segment whose span along the slope holds each s (the first before
    the chute, the last past its end)."""
    starts = np.cumsum([0.0] + [seg.length for seg in chute.segments[:-1]])
    return np.clip(np.searchsorted(starts, s, side="right") - 1, 0, len(chute.segments) - 1)


def along_bed(chute: ChuteObstacle, s: np.ndarray, velocity: np.ndarray) -> np.ndarray:
    """Velocity component down the bed of the segment at each s  [m/s]."""
    axes = np.array([local_axes(seg.slope_deg, velocity.shape[1])[:, 0] for seg in chute.segments])
    return np.sum(velocity * axes[segment_at(chute, s)], axis=1)


def obstacle_geometry(scene: Scene) -> ObstacleGeometry:
    """Front, rear and width of the scene's cylinder or wedge, along its chute; for a wedge, the
    building behind it and g cos(zeta) at its tip."""
    chute = obstacle_of(scene, ChuteObstacle)
    solids = [o for o in scene.obstacles if isinstance(o, (CylinderObstacle, WedgeObstacle))]
    if not solids:
        raise ValueError(f"{scene.name}: no cylinder or wedge among the obstacles")
    solid = solids[0]
    origin = np.asarray(solid.origin if solid.origin is not None else np.zeros(scene.dimension), float)
    s0 = float(along_chute(chute, origin[None, :])[0][0])
    if isinstance(solid, CylinderObstacle):
        return ObstacleGeometry(front=s0 - solid.radius, rear=s0 + solid.radius, width=2.0 * solid.radius)
    boxes = [box for box in scene.obstacles  # a building laid in the wedge's own frame, right behind it
             if isinstance(box, BoxObstacle) and box.origin == solid.origin and box.tilt_deg == solid.tilt_deg]
    if boxes:
        building = max(boxes, key=lambda box: box.upper[0])
        lower, upper, rear = building.lower, building.upper, max(solid.length, building.upper[0])
    else:  # the wedge's own length and width behind its rear stand for a building
        lower, upper, rear = (solid.length, -0.5 * solid.width), (2.0 * solid.length, 0.5 * solid.width), solid.length
    zeta = math.radians(chute.segments[int(segment_at(chute, np.array([s0]))[0])].slope_deg)
    return ObstacleGeometry(front=s0, rear=s0 + rear, width=solid.width,
                            tip_length=solid.length, building_front=s0 + lower[0], building_length=upper[0] - lower[0],
                            building_width=upper[1] - lower[1],
                            normal_gravity=scene.gravity.magnitude * math.cos(zeta))


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
    speed: np.ndarray = field(repr=False, default=None)  # mean speed along the bed per cell, NaN where empty [m/s]

    @property
    def depth_jump(self) -> float:
        return self.peak_depth / self.upstream_depth if self.upstream_depth > 0 else float("nan")

    @property
    def shock(self) -> bool:
        return self.depth_jump > SHOCK_JUMP


def depth_grid(s: np.ndarray, y: np.ndarray, top: np.ndarray, u: np.ndarray, s_edges: np.ndarray,
               y_edges: np.ndarray):
    """(count, depth, speed) per cell: particles in it, their highest top (0 where empty) [m] and
    their mean speed u along the bed (NaN where empty) [m/s]."""
    i = np.digitize(s, s_edges) - 1
    j = np.digitize(y, y_edges) - 1
    ok = (i >= 0) & (i < len(s_edges) - 1) & (j >= 0) & (j < len(y_edges) - 1)
    count = np.zeros((len(s_edges) - 1, len(y_edges) - 1), int)
    depth = np.zeros(count.shape)
    total = np.zeros(count.shape)
    np.add.at(count, (i[ok], j[ok]), 1)
    np.maximum.at(depth, (i[ok], j[ok]), np.maximum(top[ok], 0.0))
    np.add.at(total, (i[ok], j[ok]), u[ok])
    return count, depth, np.where(count > 0, total / np.maximum(count, 1), np.nan)


def nan_mean(values, axis=None):
    """Mean of the finite values (along ``axis``), NaN where there are none."""
    values = np.asarray(values, float)
    finite = np.isfinite(values)
    n = finite.sum(axis=axis)
    return np.where(n > 0, np.where(finite, values, 0.0).sum(axis=axis) / np.maximum(n, 1), np.nan)


def region_mean(grid: np.ndarray, cells: np.ndarray) -> float:
    """Mean of a per-cell grid (depth [m], speed [m/s]) over the cells of a mask, NaN if none."""
    return float(nan_mean(grid[cells]))


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
    """(angle to the chute's axis [deg], raised cells, cells beside) of the raised layers along a
    wedge's two faces, fitted together, and the cells just outward of them (module docstring):
    masks of ``depth``'s cells; the angle NaN where no row has a raised layer."""
    cell = s_centres[1] - s_centres[0]
    threshold = OBLIQUE_THRESHOLD * h0
    raised, beside = np.zeros(depth.shape, bool), np.zeros(depth.shape, bool)
    j = np.arange(len(y_centres))
    clear = (j >= WALL_CELLS) & (j < len(y_centres) - WALL_CELLS)  # off the side walls
    rows = np.nonzero((s_centres > tip + 2.0 * cell) & (s_centres < tip + length))[0] if h0 > 0.0 else []
    along, edges = [], []
    for i in rows:
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
            raised[i, order[:width]] = True
            outside = order[width:width + BESIDE_CELLS]
            beside[i, outside[clear[outside]]] = True
    if not along:
        return float("nan"), raised, beside
    along, edges = np.array(along), np.array(edges)
    return math.degrees(math.atan(float(along @ edges) / float(along @ along))), raised, beside


def oblique_jump_ratio(normal_froude: float) -> float:
    """Depth ratio h_1/h_0 across an oblique shock of normal Froude number F_n = F sin(beta): the
    shallow-flow jump condition with earth pressure coefficient 1 (Gray & Cui 2007; Hakonardottir
    & Hogg 2005), (sqrt(1 + 8 F_n^2) - 1)/2."""
    return 0.5 * (math.sqrt(1.0 + 8.0 * normal_froude**2) - 1.0)


@dataclass
class ObliqueShock:
    """A wedge's oblique shocks on the steady-averaged depth and speed (module docstring)."""
    angle: float  # beta: the shock's angle to the chute's axis [deg]
    raised_depth: float  # h_1: the raised layer's mean depth [m]
    upstream_depth: float  # h_0': mean depth beside the shock [m]
    upstream_speed: float  # u_0: depth-averaged speed along the bed there [m/s]
    normal_gravity: float  # g cos(zeta) [m/s^2]

    @property
    def ratio(self) -> float:
        """Measured oblique depth ratio h_1/h_0'  [-]."""
        return self.raised_depth / self.upstream_depth if self.upstream_depth > 0 else float("nan")

    @property
    def froude(self) -> float:
        """Upstream Froude number F = u_0 / sqrt(g cos(zeta) h_0')  [-]."""
        h_g = self.normal_gravity * self.upstream_depth
        return self.upstream_speed / math.sqrt(h_g) if h_g > 0 else float("nan")

    @property
    def predicted_ratio(self) -> float:
        """The jump condition's h_1/h_0 at F_n = F sin(beta)  [-]."""
        return oblique_jump_ratio(self.froude * math.sin(math.radians(self.angle)))

    @property
    def within(self) -> bool:
        """The measured ratio within OBLIQUE_RATIO_TOLERANCE of [A] Fig. 17's."""
        return abs(self.ratio - OBLIQUE_RATIO_PAPER) <= OBLIQUE_RATIO_TOLERANCE * OBLIQUE_RATIO_PAPER


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
    u = along_bed(chute, s, np.asarray(frame["velocity"][:n], float)[keep])
    s_edges, y_edges = flow_grid(scene)
    count, depth, speed = depth_grid(s, y, height + 0.5 * dp, u, s_edges, y_edges)
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
    s_from, s_to, half = geo.protected_zone
    protected = (s >= s_from) & (s < s_to) & (np.abs(y) < half)  # at any height: over the building too
    return FlowFrame(time=time, upstream_depth=h0, peak_depth=h1, standoff=standoff, wake_length=length,
                     wake_area=float(wake.sum() * cell * cell), wake_closed=closed,
                     protected_particles=int(protected.sum()), depth=depth, speed=speed)


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

    @property
    def protects(self) -> bool:
        """A wedge's bow shock persists and its protected zone is empty in every steady frame."""
        return self.shock_persists and self.protected_max == 0

    def wedge_accepted(self, oblique: ObliqueShock) -> bool:
        """Wedge acceptance: ``protects`` and the oblique depth ratio within tolerance of [A] Fig. 17."""
        return self.protects and oblique.within

    def oblique(self) -> ObliqueShock:
        """A wedge's oblique shocks on the depth and speed averaged over the steady frames (module
        docstring); NaN for a cylinder or without a raised layer."""
        geo = self.geometry
        if geo is None or math.isnan(geo.half_angle):
            return ObliqueShock(*[float("nan")] * 5)
        s_edges, y_edges = self.grid
        depth = nan_mean([f.depth for f in self.steady], axis=0)
        angle, raised, beside = oblique_shocks(0.5 * (s_edges[1:] + s_edges[:-1]), 0.5 * (y_edges[1:] + y_edges[:-1]),
                                               depth, self.mean("upstream_depth"), geo.front, geo.tip_length,
                                               geo.half_angle)
        return ObliqueShock(angle, region_mean(depth, raised), region_mean(depth, beside),
                            region_mean(nan_mean([f.speed for f in self.steady], axis=0), beside), geo.normal_gravity)

    def row(self) -> str:
        shock = self.oblique()
        wedge = self.geometry is not None and not math.isnan(self.geometry.tip_length)
        return (f"{self.name:24s} {1e3 * self.mean('upstream_depth'):7.1f} {self.mean('depth_jump'):6.2f} "
                f"{1e3 * self.mean('standoff'):8.1f} {1e3 * self.mean('wake_length'):8.1f} "
                f"{1e4 * self.mean('wake_area'):8.1f} {'yes' if self.shock_persists else 'no':>6s} "
                f"{'yes' if self.wake_persists else 'no':>6s} "
                f"{str(self.protected_max) if wedge else '-':>6s} "
                f"{self.steady[0].time:6.2f} {self.frames[-1].time:6.2f} {shock.angle:8.1f} {shock.ratio:6.2f} "
                f"{shock.predicted_ratio:6.2f} {shock.froude:5.2f}")


HEADER = (f"{'case':24s} {'h0 mm':>7s} {'jump':>6s} {'stand mm':>8s} {'wake mm':>8s} {'wake cm2':>8s} "
          f"{'shock':>6s} {'closed':>6s} {'inside':>6s} {'from s':>6s} {'end s':>6s} {'obl. deg':>8s} {'ratio':>6s} "
          f"{'cond.':>6s} {'F':>5s}")


def evaluate_obstacle_flow(scene: Scene, times: Sequence[float], frames: Sequence[Dict[str, np.ndarray]]
                           ) -> ObstacleFlowResult:
    return ObstacleFlowResult(name=scene.name,
                              frames=[measure_flow_frame(scene, f, t) for t, f in zip(times, frames)],
                              geometry=obstacle_geometry(scene), grid=flow_grid(scene))


# ---- the validate command's case (validation/__init__.py CASES) -------------------------------


def check(case, runs, base, args) -> bool:
    """Cylinder (Cui & Gray 2013) and wedge (Tai et al. 2001) of [A]: bow shock, depth jump,
    particle-free wake, protected zone and the oblique shocks' depth ratio ([A] Fig. 17);
    writes obstacle_flow.csv per case."""
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
        name, where = f"{case.name}: {scene.name}", (resolution(scene, frames, out), cost(out))
        if "wedge" in scene.name:
            geo, shock = result.geometry, result.oblique()
            s_from, s_to, half = geo.protected_zone
            passed = result.wedge_accepted(shock)
            rows += [Row(name, f"bow shock; protected zone empty (the building and {1e3 * geo.building_length:.0f} mm "
                               f"behind it, s {1e3 * s_from:.0f}-{1e3 * s_to:.0f} mm, |y| < {1e3 * half:.0f} mm)",
                         f"{result.shock_text()}; {result.protected_max} inside", "-",
                         "Tai et al. (2001) experiment: shock, empty zone", *where,
                         "PASS" if result.protects else "FAIL"),
                     Row(name, "oblique shocks: depth ratio raised layer / beside it; angle to the chute's axis "
                               "(the wedge's half-angle); jump condition at the upstream Froude number F",
                         f"{shock.ratio:.2f}; {shock.angle:.1f} deg ({math.degrees(geo.half_angle):.1f}); "
                         f"{shock.predicted_ratio:.2f} at F {shock.froude:.2f}",
                         f"~{OBLIQUE_RATIO_PAPER:.0f} ([A] Fig. 17)",
                         f"[A] Fig. 17 within {100 * OBLIQUE_RATIO_TOLERANCE:.0f} % (jump condition: Gray & Cui 2007)",
                         *where, "PASS" if shock.within else "FAIL")]
        else:
            passed = result.shock_persists and result.wake_persists
            rows.append(Row(name, "bow shock; closed wake", f"{result.shock_text()}; wake closed in "
                            f"{result.count('wake_closed')}/{len(result.steady)} "
                            f"({1e3 * result.mean('wake_length'):.0f} mm, {1e4 * result.mean('wake_area'):.0f} cm2)",
                            "-", "Cui & Gray (2013) experiment: shock, closed wake", *where, "PASS" if passed else "FAIL"))
        ok &= passed
    print(f"steady state: the last {100 * STEADY_FRACTION:.0f} % of the frames; shock: depth jump > {SHOCK_JUMP}; "
          "wedge: 'inside' counts particles, at any height, in the building's footprint and one building length "
          "behind it, as wide as the building; oblique shocks on the steady-averaged depth: angle to the chute's "
          "axis, depth ratio of the raised layer over the depth beside it, the jump condition's ratio "
          "(sqrt(1 + 8 F^2 sin^2 beta) - 1)/2 and the upstream Froude number F there")
    share = f">= {100 * PERSISTENCE:.0f} % of the steady frames"
    print(f"acceptance (cylinder: shock and closed wake in {share}; wedge: shock in {share}, protected zone empty "
          f"in all, oblique depth ratio within {100 * OBLIQUE_RATIO_TOLERANCE:.0f} % of {OBLIQUE_RATIO_PAPER:.0f}): "
          f"{'PASS' if ok else 'FAIL'}; per frame -> {base}/<case>/obstacle_flow.csv")
    write_rows(base, rows)
    return ok
