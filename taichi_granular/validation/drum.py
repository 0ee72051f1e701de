"""Rotating drum of [P] (MODEL.md section 2): free-surface inclination, flowing-layer depth, flux,
and the rigid rotation of the bed, measured on the drum's middle cross-section.

Per frame of the steady window (the last ``STEADY_FRACTION`` of the frames):
- the free surface: the highest grain in bins 2 dp wide over the middle ``SURFACE_SPAN`` of the
  drum's width, fitted by a straight line; its slope is the inclination;
- the middle cross-section: the line through the drum's centre normal to that surface. Grains
  within ``STRIP`` dp of it are binned by depth below the surface (bins of one dp), and their
  velocity is resolved along the surface, downhill positive;
then over the window: the mean inclination, the mean velocity profile u(depth), the flowing
depth delta where u changes sign (the flowing layer above, the bed carried up by the drum below),
the flux Q = integral of u from the surface to delta, and the bed's departure from the rigid
rotation, max |u - u_rigid| / (omega R) over the bins deeper than delta + 2 dp, u_rigid the
drum's velocity omega z x (x - c) resolved alike.
References, [P] for omega = 0.5 / 1 / 2 rad/s: inclination 21.48 / 22.43 / 24.81 deg, flowing
depth 0.046 / 0.054 / 0.065 m, and the kinematic flux Q = omega (R^2 - (R - H_0)^2)/2 =
0.0052 / 0.0104 / 0.0208 m2/s.
"""
import math
from dataclasses import dataclass, field
from typing import List

import numpy as np

STEADY_FRACTION = 0.5
SURFACE_SPAN = 0.6  # of the drum's diameter, centred: the straight middle of the surface
STRIP = 1.5  # half-width of the cross-section strip, in dp
REFERENCE = {0.5: (21.48, 0.046, 0.0052), 1.0: (22.43, 0.054, 0.0104), 2.0: (24.81, 0.065, 0.0208)}
INCLINATION_TOLERANCE_DEG = 1.5
DEPTH_TOLERANCE = 0.20


@dataclass
class DrumResult:
    name: str
    omega: float
    radius: float
    inclination_deg: float
    flowing_depth: float
    flux: float
    bed_departure: float
    frames: int
    depth: np.ndarray = field(repr=False, default=None)
    velocity: np.ndarray = field(repr=False, default=None)
    rigid_velocity: np.ndarray = field(repr=False, default=None)
    inclinations: List[float] = field(default_factory=list)

    @property
    def reference(self):
        return REFERENCE.get(round(self.omega, 6))

    def row(self) -> str:
        ref = self.reference
        if ref is None:
            return (f"{self.name:16s} {self.omega:5.2f} {self.inclination_deg:7.2f}      -  {self.flowing_depth:7.4f}"
                    f"      -  {self.flux:8.5f}       -  {self.bed_departure:6.3f} {self.frames:4d}")
        return (f"{self.name:16s} {self.omega:5.2f} {self.inclination_deg:7.2f} {ref[0]:6.2f} {self.flowing_depth:7.4f} "
                f"{ref[1]:6.3f} {self.flux:8.5f} {ref[2]:7.4f} {self.bed_departure:6.3f} {self.frames:4d}")


HEADER = "case             omega  incl deg   [P]  depth m    [P]   flux m2/s  kinem.  bed dev frames"


def surface_line(x: np.ndarray, centre: np.ndarray, radius: float, spacing: float):
    """(slope, intercept) of the straight fit to the top grain of each 2 dp bin across the middle
    ``SURFACE_SPAN`` of the drum, in coordinates relative to its centre  [-, m]."""
    rel = x - centre
    half = 0.5 * SURFACE_SPAN * 2.0 * radius
    width = 2.0 * spacing
    edges = np.arange(-half, half + 1e-12, width)
    tops_x, tops_y = [], []
    for lo, hi in zip(edges[:-1], edges[1:]):
        m = (rel[:, 0] >= lo) & (rel[:, 0] < hi)
        if np.any(m):
            tops_x.append(0.5 * (lo + hi))
            tops_y.append(rel[m, 1].max())
    if len(tops_x) < 3:
        raise ValueError("too few grains across the drum's middle to find its surface")
    slope, intercept = np.polyfit(tops_x, tops_y, 1)
    return float(slope), float(intercept)


def cross_section(x, v, centre, omega, slope, intercept, spacing, depth_bins):
    """Mean downhill velocity of the grains and of the rigid rotation in each depth bin of the
    strip along the normal through the centre (NaN where a bin is empty)  [m/s]."""
    rel = x - centre
    tangent = np.array([1.0, slope]) / math.hypot(1.0, slope)
    normal = np.array([-tangent[1], tangent[0]])  # up, out of the surface
    downhill = -tangent * math.copysign(1.0, slope) if slope != 0.0 else tangent
    # the surface point on the normal through the centre: s n with s n_y = intercept + slope s n_x
    s = intercept / (normal[1] - slope * normal[0])
    along = rel @ tangent
    depth = s - rel @ normal
    in_strip = np.abs(along) <= STRIP * spacing
    u = v @ downhill
    rigid = (omega * np.c_[-rel[:, 1], rel[:, 0]]) @ downhill
    k = np.digitize(depth, depth_bins) - 1
    n_bins = len(depth_bins) - 1
    u_mean, rigid_mean = np.full(n_bins, np.nan), np.full(n_bins, np.nan)
    for b in range(n_bins):
        m = in_strip & (k == b)
        if np.any(m):
            u_mean[b] = u[m].mean()
            rigid_mean[b] = rigid[m].mean()
    return u_mean, rigid_mean


def evaluate_drum(scene, times, frames) -> DrumResult:
    drum = next(o for o in scene.obstacles if o.shape == "drum")
    centre = np.asarray(drum.origin or (0.0, 0.0), float)
    omega, radius = drum.angular_velocity, drum.radius
    dp = scene.numerics.particle_spacing
    first = int(math.floor(len(frames) * (1.0 - STEADY_FRACTION)))
    window = frames[first:]
    depth_bins = np.arange(0.0, 2.0 * radius + dp, dp)
    inclinations, profiles, rigids = [], [], []
    for f in window:
        n = int(np.sum(f["is_wall"] == 0)) if "is_wall" in f else len(f["position"])
        x, v = f["position"][:n, :2], f["velocity"][:n, :2]
        slope, intercept = surface_line(x, centre, radius, dp)
        inclinations.append(math.degrees(math.atan(abs(slope))))
        u, rigid = cross_section(x, v, centre, omega, slope, intercept, dp, depth_bins)
        profiles.append(u)
        rigids.append(rigid)
    profiles, rigids = np.array(profiles), np.array(rigids)
    seen = np.any(~np.isnan(profiles), axis=0)  # bins below the drum's bottom stay empty
    u, rigid = np.full(profiles.shape[1], np.nan), np.full(profiles.shape[1], np.nan)
    u[seen] = np.nanmean(profiles[:, seen], axis=0)
    rigid[seen] = np.nanmean(rigids[:, seen], axis=0)
    depth = 0.5 * (depth_bins[:-1] + depth_bins[1:])
    filled = ~np.isnan(u)
    depth, u, rigid = depth[filled], u[filled], rigid[filled]
    flowing_depth, flux = _flowing_layer(depth, u)
    bed = depth > flowing_depth + 2.0 * dp
    departure = float(np.max(np.abs(u[bed] - rigid[bed])) / (abs(omega) * radius)) if np.any(bed) else math.nan
    return DrumResult(scene.name, abs(omega), radius, float(np.mean(inclinations)), flowing_depth, flux, departure,
                      len(window), depth, u, rigid, inclinations)


def _flowing_layer(depth: np.ndarray, u: np.ndarray):
    """(delta, Q): the first depth where u turns negative (linear interpolation) and the integral
    of u from the surface down to it (trapezoid, u at the surface taken as the top bin's)  [m, m2/s]."""
    below = np.where(u < 0.0)[0]
    if len(below) == 0 or below[0] == 0:
        return math.nan, math.nan
    k = below[0]
    delta = depth[k - 1] + (depth[k] - depth[k - 1]) * u[k - 1] / (u[k - 1] - u[k])
    z = np.r_[0.0, depth[:k], delta]
    uz = np.r_[u[0], u[:k], 0.0]
    return float(delta), float(np.sum(0.5 * (uz[1:] + uz[:-1]) * np.diff(z)))


def write_profile_csv(result: DrumResult, path) -> None:
    from ..output import atomic_write_text
    atomic_write_text(path, "depth_m,velocity_m_s,rigid_rotation_m_s\n" + "".join(
        f"{d:.5f},{u:.6f},{r:.6f}\n" for d, u, r in zip(result.depth, result.velocity, result.rigid_velocity)))


# ---- the validate command's case (validation/__init__.py CASES) -------------------------------


def check(case, runs, base, args) -> bool:
    """Rotating drum of [P] at omega = 0.5, 1, 2 rad/s: inclination, flowing depth, flux, rigid
    bed; writes velocity_profile.csv and .png per case."""
    from ..render.frames import write_png
    from ..render.plot import plot_points_and_curve
    from .table import Row, cost, resolution, write_rows

    results, where = [], []
    print(HEADER)
    for scene, out, times, frames in runs:
        result = evaluate_drum(scene, times, frames)
        results.append(result)
        where.append((resolution(scene, frames, out), cost(out)))
        write_profile_csv(result, out / "velocity_profile.csv")
        image = plot_points_and_curve(list(zip(result.depth, result.velocity)), (result.depth, result.rigid_velocity),
                                      "depth below the surface on the middle cross-section (m)",
                                      "downhill velocity (m/s)", f"{scene.name}: squares sph, line rigid rotation")
        write_png(out / "velocity_profile.png", image)
        print(result.row(), flush=True)
    print(f"steady window: the last {100 * STEADY_FRACTION:.0f} % of the frames; [P]: Peng et al. (2016); flux "
          "reference: the kinematic omega (R^2 - (R - H_0)^2)/2")
    ok = True
    for r in results:
        ref = r.reference
        if ref is not None:
            ok &= abs(r.inclination_deg - ref[0]) <= INCLINATION_TOLERANCE_DEG
            ok &= abs(r.flowing_depth / ref[1] - 1.0) <= DEPTH_TOLERANCE
        ok &= r.bed_departure < 0.1
    ordered = sorted((r for r in results if r.reference is not None), key=lambda r: r.omega)
    rising = all(a.inclination_deg < b.inclination_deg and a.flowing_depth < b.flowing_depth
                 for a, b in zip(ordered, ordered[1:]))
    ok &= rising
    print(f"acceptance (inclination within {INCLINATION_TOLERANCE_DEG} deg, depth within "
          f"{100 * DEPTH_TOLERANCE:.0f} %, both rising with omega, bed within 10 % of omega R of rigid rotation): "
          f"{'PASS' if ok else 'FAIL'}; profiles -> {base}/<case>/velocity_profile.csv, .png")
    write_rows(base, [Row(f"{case.name}: {r.name}", "mean inclination; flowing depth",
                          f"{r.inclination_deg:.1f} deg; {1e3 * r.flowing_depth:.0f} mm",
                          "-" if r.reference is None else f"{r.reference[0]} deg; {1e3 * r.reference[1]:.0f} mm",
                          "[P]'s table (out of this model's steady range: docs/models/hypoplastic.md)", res, run_cost,
                          "PASS" if ok else "FAIL") for r, (res, run_cost) in zip(results, where)])
    return ok
