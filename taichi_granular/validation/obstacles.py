"""Avalanche obstacles on a chute ([A] section 6, MODEL.md section 3): stake rows.

Measures, from the particle positions of a run:
- the distance ``s`` of every material particle along the chute bed (from the chute's origin,
  on its centre line), and its height above the bed; particles below the bed have crossed it;
- the leading edge: the largest s, over time, among particles still on the chute (within its
  width, not taken out at an open face of the domain);
- the efficiency factor of the stake rows: the mass retained on the chute in area 1 (the lower
  panel upstream of the first row, from the slope break on) plus area 2 (from the first row to
  ``LEE`` past the last one: among the rows and in their lee), over the mass of every grain.
  A grain is on the chute when it is within its width and its length, above its bed and still in
  the domain: grains that fell over the sides or off the end, crossed the bed or left at an open
  face are not retained,
  wherever their distance along the chute falls (they are ``lost``). [A] section 6.1.2 reports
  its SPH at dp 5 mm against Yellin et al. (2013) as [A]'s Table 1 does: area 1, area 2 and the
  rest; the case is judged against [A]'s SPH at [A]'s resolution, the experiment printed beside.

Units: m, kg, s.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, List, Sequence

import numpy as np

from ..bodies import ChuteObstacle, PostRowsObstacle
from ..config import Scene
from ..local_frame import local_axes, to_local
from ..output import left_domain

LEE = 0.10  # [m] past the last row that still counts as retained (area 2; our choice)
LEE_BRACKET = (0.05, 0.20)  # [m] area 2's lee also read at these ([A] Fig. 7 is the only source of its extent)
EXPERIMENT = {"case1": 0.76, "case2": 0.48, "case3": 0.80}  # Yellin et al. (2013), via [A]
SPH_IN_PAPER = {"case1": 0.72, "case2": 0.43, "case3": 0.76}  # [A]'s own SPH at dp 5 mm (section 6.1.2)
# area 1's share: experiment ([A] Table 1: 0.45 / 0.06 / 0.38 kg of 2.04) and [A]'s SPH
AREA1_EXPERIMENT = {"case1": 0.22, "case2": 0.03, "case3": 0.19}
AREA1_SPH_IN_PAPER = {"case1": 0.24, "case2": 0.00, "case3": 0.17}
ACCEPTANCE_POINTS = 0.10  # efficiency and area 1 within 10 points of [A]'s SPH


def obstacle_of(scene: Scene, kind: type):
    found = [o for o in scene.obstacles if isinstance(o, kind)]
    if not found:
        raise ValueError(f"{scene.name}: no {kind.__name__} among the obstacles")
    return found[0]


def along_chute(chute: ChuteObstacle, points: np.ndarray):
    """(s, height above the bed) of ``points``: each point is referred to the segment whose
    span along the slope holds it (the last one past the end)  [m]."""
    dim = points.shape[1]
    origin = np.zeros(dim) if chute.origin is None else np.asarray(chute.origin, float)
    s = np.full(len(points), np.nan)
    height = np.full(len(points), np.nan)
    start = 0.0
    for k, seg in enumerate(chute.segments):
        local = to_local(points, origin, seg.slope_deg)
        last = k == len(chute.segments) - 1
        on = np.isnan(s) & ((local[:, 0] < seg.length) | last)
        s[on] = start + local[on, 0]
        height[on] = local[on, -1]
        origin = origin + seg.length * local_axes(seg.slope_deg, dim)[:, 0]
        start += seg.length
    return s, height


def post_rows_span(scene: Scene):
    """(s of the first row's front, s of the last row's rear) along the chute  [m]."""
    chute = obstacle_of(scene, ChuteObstacle)
    posts = obstacle_of(scene, PostRowsObstacle)
    origin = np.asarray(posts.origin if posts.origin is not None else np.zeros(scene.dimension), float)
    s0, _ = along_chute(chute, origin[None, :])
    return float(s0[0]), float(s0[0] + (posts.rows - 1) * posts.row_spacing + posts.post_size)


@dataclass
class StakeRowResult:
    name: str
    case: str
    efficiency: float  # (area 1 + area 2)/total
    area1: float  # mass fractions
    area2: float
    passed: float  # beyond area 2
    upper_panel: float  # still on the first (steep) panel
    lost: float  # mass fraction not on the chute: over its sides or off its end, through its bed, out of the domain
    crossed: int  # material particles below the bed, within its width
    fell_off: int  # material particles that left the chute over its side (3D chutes without side walls)
    departed: int  # material particles taken out at an open face of the domain (off the chute's end
    # or over a side, outside the domain)
    front_stop_time: float  # [s] after which the leading edge moves slower than 0.1 m/s (nan: still moving)
    efficiency_bracket: tuple = (float("nan"), float("nan"))  # the efficiency with area 2 to LEE_BRACKET's lees
    times: List[float] = field(default_factory=list)
    leading_edge: List[float] = field(default_factory=list)  # [m] along the chute

    @property
    def not_retained(self) -> float:
        return 1.0 - self.efficiency

    @property
    def reference(self) -> float:
        """[A]'s SPH efficiency at [A]'s dp, which the case is judged against."""
        return SPH_IN_PAPER.get(self.case, float("nan"))

    @property
    def experiment(self) -> float:
        return EXPERIMENT.get(self.case, float("nan"))

    @property
    def error_points(self) -> float:
        return self.efficiency - self.reference

    @property
    def area1_error_points(self) -> float:
        return self.area1 - AREA1_SPH_IN_PAPER.get(self.case, float("nan"))

    @property
    def within(self) -> bool:
        """Efficiency and area 1 within ACCEPTANCE_POINTS of [A]'s SPH, no grain through the bed."""
        return abs(self.error_points) <= ACCEPTANCE_POINTS and abs(self.area1_error_points) <= ACCEPTANCE_POINTS \
            and self.crossed == 0

    def row(self) -> str:
        pct = lambda table: 100 * table.get(self.case, float("nan"))  # noqa: E731
        return (f"{self.name:28s} {100 * self.efficiency:6.1f} {100 * self.reference:6.1f} {100 * self.experiment:6.1f} "
                f"{100 * self.error_points:+7.1f}  {100 * self.area1:5.1f} {pct(AREA1_SPH_IN_PAPER):5.1f} "
                f"{pct(AREA1_EXPERIMENT):5.1f}  {100 * self.area2:5.1f} {100 * self.not_retained:5.1f} "
                f"{100 * self.passed:5.1f} {100 * self.upper_panel:5.1f} {100 * self.lost:5.1f}  "
                f"{self.leading_edge[-1]:6.3f} {self.front_stop_time:6.2f} {self.times[-1]:6.2f} {self.crossed:4d} "
                f"{self.fell_off:4d} {self.departed:4d}  {100 * self.efficiency_bracket[0]:5.1f} "
                f"{100 * self.efficiency_bracket[1]:5.1f}")


HEADER = (f"{'case':28s} {'eff%':>6s} {'[A]%':>6s} {'exp%':>6s} {'err pt':>7s}  {'a1%':>5s} {'[A]':>5s} "
          f"{'exp':>5s}  {'a2%':>5s} {'not%':>5s} {'pass%':>5s} {'45deg':>5s} {'lost':>5s}  {'edge m':>6s} "
          f"{'stop s':>6s} {'end s':>6s} {'xed':>4s} {'off':>4s} {'out':>4s}  "
          f"{f'lee{100 * LEE_BRACKET[0]:.0f}':>5s} {f'lee{100 * LEE_BRACKET[1]:.0f}':>5s}")


def case_of(name: str) -> str:
    for case in EXPERIMENT:
        if case in name:
            return case
    return name


def evaluate_stake_rows(scene: Scene, times: Sequence[float], frames: Sequence[Dict[str, np.ndarray]]
                        ) -> StakeRowResult:
    chute = obstacle_of(scene, ChuteObstacle)
    first_row, last_row = post_rows_span(scene)
    break_s = chute.segments[0].length
    edges = []
    for f in frames:
        n = int(np.sum(f["is_wall"] == 0))
        on_chute = ~left_domain(f, n)
        if scene.dimension == 3:
            on_chute &= np.abs(f["position"][:n, 1]) <= 0.5 * chute.width
        s, _ = along_chute(chute, f["position"][:n][on_chute])
        edges.append(float(np.nanmax(s)) if len(s) else float("nan"))
    final = frames[-1]
    n = int(np.sum(final["is_wall"] == 0))
    s, height = along_chute(chute, final["position"][:n])
    departed = left_domain(final, n)
    beside = np.abs(final["position"][:n, 1]) > 0.5 * chute.width if scene.dimension == 3 else np.zeros(n, bool)
    beside &= ~departed
    off_end = (s > sum(seg.length for seg in chute.segments)) & ~beside & ~departed  # ran off the chute's end
    crossed = (height < 0.0) & ~beside & ~departed & ~off_end
    on_chute = ~(beside | departed | crossed | off_end)
    mass = final["mass"][:n]
    total = mass.sum()  # every grain: the lost ones are not retained

    def share(where):
        return mass[on_chute & where].sum() / total

    area1 = share((s >= break_s) & (s < first_row))
    area2 = share((s >= first_row) & (s < last_row + LEE))
    bracket = tuple(area1 + share((s >= first_row) & (s < last_row + lee)) for lee in LEE_BRACKET)
    passed = share(s >= last_row + LEE)
    upper = share(s < break_s)
    stop = float("nan")
    t = np.asarray(times, float)
    e = np.asarray(edges)
    moving = [k for k in range(1, len(t)) if (e[k] - e[k - 1]) > 0.1 * (t[k] - t[k - 1])]  # 0.1 m/s
    if moving and moving[-1] < len(t) - 1:
        stop = float(t[moving[-1]])
    return StakeRowResult(name=scene.name, case=case_of(scene.name), efficiency=area1 + area2, area1=area1,
                          area2=area2, passed=passed, upper_panel=upper, lost=mass[~on_chute].sum() / total,
                          crossed=int(np.sum(crossed)), fell_off=int(np.sum(beside)), departed=int(np.sum(departed)),
                          front_stop_time=stop, times=list(map(float, times)), leading_edge=edges,
                          efficiency_bracket=bracket)


# ---- the validate command's case (validation/__init__.py CASES) -------------------------------


def check(case, runs, base, args) -> bool:
    """Stake rows cases 1-3 of [A]: efficiency factor and area 1 against [A]'s SPH at its dp (the
    experiment beside), within ACCEPTANCE_POINTS, case 2 the lowest, none crossed; writes
    leading_edge.csv per case."""
    from ..output import atomic_write_text
    from .table import Row, cost, resolution, write_rows

    results, where = [], []
    print(HEADER)
    for scene, out, times, frames in runs:
        result = evaluate_stake_rows(scene, times, frames)
        results.append(result)
        where.append((resolution(scene, frames, out), cost(out)))
        atomic_write_text(out / "leading_edge.csv", "t,leading_edge_m\n" + "".join(
            f"{t:.4f},{e:.5f}\n" for t, e in zip(result.times, result.leading_edge)))
        print(result.row(), flush=True)
    print(f"areas ([A] Table 1): 1 = lower panel above the first row, 2 = first row to {LEE} m past the last; "
          "efficiency = (1 + 2)/every grain; not retained = passed + upper (45 deg) panel + lost (over the sides, "
          "through the bed, out of the domain); judged against [A] = Abdelrazek et al.'s SPH at dp 5 mm, "
          f"exp = Yellin et al. (2013); lee5 / lee20: the efficiency with area 2 reaching {LEE_BRACKET[0]} / "
          f"{LEE_BRACKET[1]} m past the last row")
    close = all(r.within for r in results)
    by_case = {r.case: r.efficiency for r in results}
    lowest = set(by_case) != set(EXPERIMENT) or min(by_case, key=by_case.get) == "case2"
    ok = close and lowest
    print(f"acceptance (efficiency and area 1 within {100 * ACCEPTANCE_POINTS:.0f} points of [A]'s SPH, case 2 "
          f"lowest, none crossed): {'PASS' if ok else 'FAIL'}; leading edge over time -> "
          f"{base}/<case>/leading_edge.csv")
    verdict = "PASS" if ok else "FAIL"
    rows = []
    for r, (res, run_cost) in zip(results, where):
        name = f"{case.name}: {r.name}"
        rows.append(Row(name, "efficiency factor (retained share)", f"{100 * r.efficiency:.1f} % (area 2's lee "
                        f"{LEE_BRACKET[0]:g} / {LEE_BRACKET[1]:g} m: {100 * r.efficiency_bracket[0]:.1f} / "
                        f"{100 * r.efficiency_bracket[1]:.1f} %)",
                        f"{100 * r.reference:.0f} %",
                        f"[A]'s SPH at dp 5 mm (Yellin et al. 2013 experiment: {100 * r.experiment:.0f} %)",
                        res, run_cost, verdict))
        rows.append(Row(name, "area 1; area 2; not retained (of it lost)",
                        f"{100 * r.area1:.1f}; {100 * r.area2:.1f}; {100 * r.not_retained:.1f} "
                        f"({100 * r.lost:.1f}) %", f"{100 * AREA1_SPH_IN_PAPER.get(r.case, float('nan')):.0f} % "
                        "in area 1", f"[A]'s SPH (experiment: {100 * AREA1_EXPERIMENT.get(r.case, float('nan')):.0f} "
                        "% in area 1, [A] Table 1)",
                        res, run_cost, verdict))
    write_rows(base, rows)
    return ok
