"""Rotating drum of [P] (MODEL.md section 2): free-surface inclination, flowing-layer depth, flux,
and the rigid rotation of the bed, measured on the drum's middle cross-section, and judged
against the model's own steady prediction.

Per frame of the steady window (the last revolution, and at most the second half of the run):
- the free surface: the highest grain in bins 2 dp wide over the middle ``SURFACE_SPAN`` of the
  drum's width, fitted by a straight line; its slope is the inclination;
- the middle cross-section: the line through the drum's centre normal to that surface. Grains
  within ``STRIP`` dp of it are binned by depth below the surface (bins of one dp), and their
  velocity is resolved along the surface, downhill positive;
then over the window: the mean inclination and its standard deviation (continuous rolling: below
``STEADY_SPREAD_DEG``), the mean velocity profile u(depth), the flowing depth delta where u
changes sign (the flowing layer above, the bed carried up by the drum below), the flux Q =
integral of u from the surface to delta, and the bed's departure from the rigid rotation,
max |u - u_rigid| / (omega R) over the bins deeper than delta + 2 dp, u_rigid the drum's
velocity omega z x (x - c) resolved alike.

What the drum adds beyond that relation is measured by the depth-integrated momentum balance
along the surface of the flowing layer over the middle of the drum (``BUDGET_SPAN`` R either side
of the cross-section, from the surface down to the flowing depth; per unit length, averaged over
the window): the weight along the surface is carried by the shear traction on the layer's base
(its stress ratio there is the friction the law delivers in the drum's flow), by the difference of
the along-surface normal stress between the column's downhill and uphill faces (the layer is
stretched where grains join it and compressed where they leave), by the layer's acceleration,
and what is left (the closure residual) measures how well the continuum balance describes the
particles. In steady uniform flow on a plane the base traction alone carries the weight.

The reference is the model's steady prediction: the slope on which a steady layer of the
measured depth carries the measured flux (the inclined-plane relation of MODEL.md section 2,
validation/inclined_plane.py ``BagnoldReference.slope_for_flux``): arctan(mu_h) = 26.3 deg with
set 2 plus the Bagnold part's fraction of a degree at these fluxes. [P]'s table (inclination
21.48 / 22.43 / 24.81 deg, flowing depth 0.046 / 0.054 / 0.065 m at omega = 0.5 / 1 / 2 rad/s) is
reported beside it and not judged: it lies below the lowest slope on which this law flows
steadily (MODEL.md section 2, "Reachability"). The flux is compared with the kinematic
Q = omega (R^2 - (R - H_0)^2)/2, H_0 the fill depth of the measured fill area.

The fill's swelling: the area under the fitted surface line inside the drum against the grains'
own volume sum_i m_i/rho_i, their ratio over the window relative to the first frame's. The
particles of SPH carry their volume in their continuity density; where they drift apart (or
together) without that density changing, the fill occupies more (less) of the drum than its
grains' volumes say, the surface rises (sinks) and every measure above shifts with it
(docs/models/hypoplastic.md, "The fill swells").

The faces against the law: at the budget's two faces, the layer's along-surface shortening per
unit shear (from the grains' velocity gradient) and its measured sigma_tt/sigma_nn, beside the
ratio that a single point of the rate law carries in its stationary state under that strain
(``FaceStates``); with the law's ratios the balance gives the slope the drum's along-surface
strain adds to the plane relation's.

The bed's creep: the strain rate the rate law needs for the bed to turn rigidly under its own
window-averaged stress field, steady in the lab, against the strain rate its grains have
(``bed_creep``); where the grains deform far more than the law asks, the bed's departure from
rigid rotation is the scheme's, not the model's.
"""
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import List

import numpy as np

STEADY_SPAN = 0.5  # the window never reaches into the first half of the run (the spin-up)
SURFACE_SPAN = 0.6  # of the drum's diameter, centred: the straight middle of the surface
STRIP = 1.5  # half-width of the cross-section strip, in dp
BUDGET_SPAN = 0.3  # half-length of the momentum budget's control volume along the surface, of R
PAPER = {0.5: (21.48, 0.046), 1.0: (22.43, 0.054), 2.0: (24.81, 0.065)}  # [P]: inclination deg, depth m
INCLINATION_TOLERANCE_DEG = 1.5  # mean inclination against the model's steady prediction
STEADY_SPREAD_DEG = 2.0  # standard deviation of the inclination over the window: continuous rolling
RIGID_TOLERANCE = 0.05  # the bed's departure from rigid rotation, of omega R
TRANSIENT_VOID_RATIO = 0.05  # a fill started this much looser than e* is a loose start: its angles are transient
SETTLED_VOID_RATIO = 0.01  # a loose start has compacted once its mean void ratio is this close to e*
PAPER_OUT_OF_REACH = ("[P]'s inclinations lie below arctan(mu_h), the lowest slope on which this law flows "
                      "steadily; they need I_e = 1.21 / 1.14 / 0.99, states that lose their frictional stress "
                      "within 1-3 % shear strain (MODEL.md section 2, Reachability): reported, not judged")


@dataclass
class DrumResult:
    name: str
    omega: float  # rad/s
    radius: float  # m
    inclination_deg: float  # mean over the window
    inclination_spread_deg: float  # its standard deviation
    flowing_depth: float  # m
    flux: float  # m2/s, through the middle cross-section
    kinematic_flux: float  # m2/s, omega (R^2 - (R - H_0)^2)/2
    fill_depth: float  # H_0, m
    bed_departure: float  # of omega R
    predicted_deg: float  # the model's steady slope at the measured flux and depth
    window: tuple  # (start, end) s
    void_ratio: float  # mean over the material and the window
    critical_void_ratio: float  # e* of the stationary state at zero pressure
    initial_void_ratio: float
    froude: float  # omega^2 R / g
    frames: int
    budget: "MomentumBudget" = None  # the layer's momentum balance over the middle (None: frames without stresses)
    swelling: float = math.nan  # the fill's area under its surface per grain volume, window over first frame, - 1
    creep_needed: float = math.nan  # the bed's |D| the law needs to turn rigidly under its stress field, per omega
    creep_measured: float = math.nan  # the bed grains' median |D|, per omega
    faces: "FaceStates" = None  # the budget's faces against the law (None: frames without stresses)
    depth: np.ndarray = field(repr=False, default=None)
    velocity: np.ndarray = field(repr=False, default=None)
    rigid_velocity: np.ndarray = field(repr=False, default=None)
    times: List[float] = field(default_factory=list)
    inclinations: List[float] = field(default_factory=list)  # every frame of the run, deg
    void_ratios: List[float] = field(default_factory=list)  # every frame: the material's mean (volume-weighted)

    @property
    def paper(self):
        return PAPER.get(round(self.omega, 6))

    @property
    def loose_start(self) -> bool:
        return self.initial_void_ratio > self.critical_void_ratio + TRANSIENT_VOID_RATIO

    def transient(self):
        """(time the fill's mean void ratio first comes within ``SETTLED_VOID_RATIO`` of e*, and the
        lowest and highest inclination after the start up to then) of a loose start  [s, deg, deg]."""
        t, inc, e = np.asarray(self.times), np.asarray(self.inclinations), np.asarray(self.void_ratios)
        settled = np.where(e <= self.critical_void_ratio + SETTLED_VOID_RATIO)[0]
        end = settled[0] if len(settled) else len(t) - 1
        span = inc[1:end + 1] if end >= 1 else inc[:1]
        return float(t[end]), float(np.nanmin(span)), float(np.nanmax(span))

    def faces_slope_deg(self) -> float:
        """The slope with the law's faces (``FaceStates.slope_deg``) over the budget's length; NaN
        without them  [deg]."""
        if self.faces is None:
            return math.nan
        return self.faces.slope_deg(self.predicted_deg, self.flowing_depth, 2.0 * BUDGET_SPAN * self.radius)

    def misses(self) -> List[str]:
        """The acceptance criteria this drum misses, each with its figure and tolerance (none: it
        passes): continuous rolling, a rigid bed, the mean inclination at the model's steady
        prediction."""
        misses = []
        if self.inclination_spread_deg >= STEADY_SPREAD_DEG:
            misses.append(f"inclination sd {self.inclination_spread_deg:.1f} deg ({STEADY_SPREAD_DEG})")
        if self.bed_departure >= RIGID_TOLERANCE:
            misses.append(f"bed {100 * self.bed_departure:.1f} % off rigid rotation ({100 * RIGID_TOLERANCE:.0f})")
        off = self.inclination_deg - self.predicted_deg
        if abs(off) > INCLINATION_TOLERANCE_DEG:
            misses.append(f"inclination {off:+.1f} deg off the model ({INCLINATION_TOLERANCE_DEG})")
        return misses

    def passed(self) -> bool:
        return not self.misses()

    def verdict(self) -> str:
        """The table's acceptance cell: transient (a loose start), PASS, or FAIL with what it misses."""
        if self.loose_start:
            return "transient"
        return "PASS" if self.passed() else "FAIL: " + "; ".join(self.misses())

    def row(self) -> str:
        paper = self.paper or (math.nan, math.nan)
        return (f"{self.name:22s} {self.omega:5.2f} {self.froude:6.4f} {self.inclination_deg:6.2f} "
                f"{self.inclination_spread_deg:5.2f} {self.predicted_deg:6.2f} {paper[0]:6.2f} "
                f"{1e3 * self.flowing_depth:6.1f} {1e3 * paper[1]:5.0f} {self.flux:8.5f} {self.kinematic_flux:8.5f} "
                f"{100 * self.bed_departure:5.1f} {self.void_ratio:6.3f} {self.critical_void_ratio:6.3f} "
                f"{self.window[0]:6.2f}-{self.window[1]:<6.2f} {100 * self.swelling:+6.1f}")


HEADER = ("case                   omega  Fr     incl   sd    model  [P]    depth  [P]   flux     kinem.   "
          "bed%  e      e*     window s      swell\n"
          "                       rad/s         deg    deg   deg    deg    mm     mm    m2/s     m2/s"
          "                                    %")


def fill_depth(area: float, radius: float) -> float:
    """H_0 of a circular segment of the given area: A(H) = R^2 acos((R - H)/R) - (R - H)
    sqrt(2 R H - H^2), solved by bisection  [m]."""
    low, high = 0.0, 2.0 * radius
    for _ in range(60):
        H = 0.5 * (low + high)
        segment = radius**2 * math.acos((radius - H) / radius) - (radius - H) * math.sqrt(max(2 * radius * H - H * H, 0))
        low, high = (H, high) if segment < area else (low, H)
    return 0.5 * (low + high)


def critical_void_ratio(scene) -> float:
    """e* of the stationary simple shear at zero pressure: e_min + (I_e* - a)/(1 - a) (e_crt - e_min)
    with e_crt = p1 + p2 and a = q1 + q2 (MODEL.md section 2)  [-]."""
    from .inclined_plane import stationary_shear_of
    m = scene.material
    density_factor, _ = stationary_shear_of(scene)
    e_crt = m.critical_void_ratio[0] + m.critical_void_ratio[1]
    a = m.density_exponent[0] + m.density_exponent[1]
    return m.min_void_ratio + (density_factor - a) / (1.0 - a) * (e_crt - m.min_void_ratio)


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


def surface_frame(x, centre, slope, intercept):
    """(distance along the surface from the middle cross-section, downhill positive; depth below the
    surface; downhill unit vector; upward unit normal) of the points ``x`` for the fitted surface
    line  [m, m, -, -]."""
    rel = x - centre
    tangent = np.array([1.0, slope]) / math.hypot(1.0, slope)
    normal = np.array([-tangent[1], tangent[0]])  # up, out of the surface
    downhill = -tangent * math.copysign(1.0, slope) if slope != 0.0 else tangent
    # the surface point on the normal through the centre: s n with s n_y = intercept + slope s n_x
    s = intercept / (normal[1] - slope * normal[0])
    return rel @ downhill, s - rel @ normal, downhill, normal


def cross_section(x, v, centre, omega, slope, intercept, spacing, depth_bins):
    """Mean downhill velocity of the grains and of the rigid rotation in each depth bin of the
    strip along the normal through the centre (NaN where a bin is empty)  [m/s]."""
    rel = x - centre
    along, depth, downhill, _ = surface_frame(x, centre, slope, intercept)
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


BUDGET_FIELDS = ("mass", "density", "pressure", "deviatoric_stress", "acceleration")
FACE_FIELDS = ("pressure", "deviatoric_stress", "velocity_gradient")


@dataclass
class MomentumBudget:
    """Momentum balance along the surface of the flowing layer's column over the middle of the drum
    (``BUDGET_SPAN`` R either side of the cross-section, from the surface to ``depth``), per unit
    length, averaged over the window; stresses tension positive in the frames, reported here as
    forces on the column  [Pa, i.e. N per m of surface per m of drum]."""
    depth: float  # m, the column's base (the flowing depth)
    weight: float  # the column's weight along the surface, downhill +
    load: float  # its weight normal to the surface
    base_shear: float  # shear traction of the grains below on the base, uphill +
    base_normal: float  # normal stress on the base, compression +
    faces: float  # along-surface normal force on the uphill face minus that on the downhill face, over the length: uphill +
    inertia: float  # mass times acceleration along the surface, downhill +

    @property
    def residual(self) -> float:
        """What the continuum balance weight = base shear + faces + inertia leaves  [Pa]."""
        return self.weight - self.base_shear - self.faces - self.inertia

    @property
    def friction_deg(self) -> float:
        """arctan of the base's stress ratio: the friction the law delivers in the drum's flow  [deg]."""
        return math.degrees(math.atan2(self.base_shear, self.base_normal))

    def shares(self):
        """(base shear, faces, inertia, residual) as fractions of the weight along the surface."""
        return tuple(x / self.weight for x in (self.base_shear, self.faces, self.inertia, self.residual))

    def line(self, predicted_deg: float) -> str:
        shear, faces, inertia, residual = self.shares()
        return (f"  momentum along the surface, middle {2 * BUDGET_SPAN:.1f} R, layer 0-{1e3 * self.depth:.0f} mm "
                f"(shares of its weight): base shear {100 * shear:.0f} % (stress ratio "
                f"{math.tan(math.radians(self.friction_deg)):.3f}, {self.friction_deg:.1f} deg against the "
                f"model's {predicted_deg:.1f}; base normal stress {100 * self.base_normal / self.load:.0f} % of the "
                f"load), faces {100 * faces:.0f} % (along-surface normal force, uphill face minus downhill), "
                f"inertia {100 * inertia:.0f} %, "
                f"residual {100 * residual:.0f} %")


def momentum_terms(frame, centre, radius, spacing, gravity, slope, intercept, depth):
    """The terms of ``MomentumBudget`` (after depth) for one frame, in its field order  [Pa]."""
    n = _material_count(frame)
    x = frame["position"][:n, :2]
    along, below, downhill, normal = surface_frame(x, centre, slope, intercept)
    mass = frame["mass"][:n]
    volume = mass / frame["density"][:n]
    stress = _total_stress(frame, n)
    half = BUDGET_SPAN * radius
    column = (np.abs(along) < half) & (below < depth)
    base = (np.abs(along) < half) & (np.abs(below - depth) < 0.5 * spacing)
    up, down = _faces(along, below, half, spacing, depth)
    g = np.asarray(gravity, float)[:2]
    traction = stress @ normal  # on a face whose outward normal is up (tension positive)
    base_volume = np.sum(volume[base])
    along_stress = volume * np.einsum("i,nij,j->n", downhill, stress, downhill)  # sigma_tt dV
    length = 2.0 * half
    return (np.sum(mass[column]) * (g @ downhill) / length,
            -np.sum(mass[column]) * (g @ normal) / length,
            np.sum(volume[base] * (traction[base] @ downhill)) / base_volume,
            -np.sum(volume[base] * (traction[base] @ normal)) / base_volume,
            (np.sum(along_stress[up]) - np.sum(along_stress[down])) / (2.0 * spacing) / length,
            np.sum(mass[column] * (frame["acceleration"][:n, :2][column] @ downhill)) / length)


def _faces(along, below, half, spacing, depth):
    """Masks of the grains in the budget's uphill and downhill faces: strips 2 dp wide at -half and
    +half along the surface, from the surface down to ``depth``."""
    return ((np.abs(along + half) < spacing) & (below < depth),
            (np.abs(along - half) < spacing) & (below < depth))


def _total_stress(frame, n):
    """Total stress of the first n grains, tension positive (n, 2, 2)  [Pa]."""
    return frame["deviatoric_stress"][:n].reshape(-1, 2, 2) - frame["pressure"][:n, None, None] * np.eye(2)


def face_sums(frame, centre, radius, spacing, slope, intercept, depth):
    """Sums over the uphill face, then the downhill face, of the budget's column of (dv_t/dt,
    dv_t/dn, sigma_tt, sigma_nn): t downhill along the surface, n up out of it  [1/s, Pa]."""
    n = _material_count(frame)
    along, below, downhill, normal = surface_frame(frame["position"][:n, :2], centre, slope, intercept)
    L = frame["velocity_gradient"][:n].reshape(n, 2, 2)  # L_ij = dv_i/dx_j
    stress = _total_stress(frame, n)
    per_grain = np.stack([np.einsum("i,nij,j->n", downhill, L, downhill), np.einsum("i,nij,j->n", downhill, L, normal),
                          np.einsum("i,nij,j->n", downhill, stress, downhill),
                          np.einsum("i,nij,j->n", normal, stress, normal)], axis=1)
    return np.concatenate([per_grain[m].sum(axis=0) for m in _faces(along, below, BUDGET_SPAN * radius, spacing,
                                                                      depth)])


@dataclass
class FaceStates:
    """The budget's uphill and downhill faces against the rate law: the layer's along-surface
    shortening per unit shear there, c = -(dv_t/dt)/(dv_t/dn) (> 0 where it shortens downhill), its
    measured along-surface over normal stress sigma_tt/sigma_nn, and the ratio of the law's
    stationary state under that strain (element_tests.along_slope_friction: a point of the rate law,
    no SPH). Where the two ratios agree, the faces' share of the weight is the law's answer to the
    drum's kinematics, not the scheme's  [-]."""
    strain: tuple  # (uphill, downhill) c
    ratio: tuple  # (uphill, downhill) measured sigma_tt/sigma_nn, window sums
    law_ratio: tuple  # (uphill, downhill) the law's stationary sigma_xx/sigma_zz at c (NaN: none for I_e in [0.7, 1])

    def slope_deg(self, plane_deg: float, depth: float, length: float) -> float:
        """The slope of a layer of ``depth`` whose base runs at the plane's friction and whose faces,
        ``length`` apart, carry the law's ratios on a hydrostatic normal stress: the depth-integrated
        balance along the surface gives tan theta = tan(plane) + (K_down - K_up) depth / (2 length)
        (inertia left out)  [deg]."""
        up, down = self.law_ratio
        return math.degrees(math.atan(math.tan(math.radians(plane_deg)) + (down - up) * depth / (2.0 * length)))

    def line(self, plane_deg: float, slope: float) -> str:
        """The printed line, with the plane relation's slope and ``slope_deg``'s  [deg]."""
        return (f"  faces: along-surface shortening per unit shear {self.strain[0]:+.3f} uphill / "
                f"{self.strain[1]:+.3f} downhill; sigma_tt/sigma_nn {self.ratio[0]:.3f} / {self.ratio[1]:.3f} "
                f"measured, {self.law_ratio[0]:.3f} / {self.law_ratio[1]:.3f} the law's stationary state at "
                f"that strain (a point of the rate law); a layer with the law's faces and the plane's base "
                f"friction stands at {slope:.1f} deg (the plane's {plane_deg:.1f} + {slope - plane_deg:.1f} the "
                f"drum's along-surface strain adds)")


def _rate_law(scene):
    """The scene's hypoplastic rate law, for point integrations (Taichi started if it is not)."""
    from .. import runtime
    from ..physics.rheology.hypoplastic.model import HypoplasticBagnold
    runtime.ensure(scene.precision)
    return HypoplasticBagnold.from_scene(scene)


def face_states(scene, frames, window, centre, radius, spacing, depth, lines):
    """``FaceStates`` over the window (None for frames without velocity gradients or stresses)."""
    from .element_tests import along_slope_friction
    if math.isnan(depth) or not all(name in frames[k] for k in window for name in FACE_FIELDS):
        return None
    sums = np.sum([face_sums(frames[k], centre, radius, spacing, slope, intercept, depth)
                   for k, (slope, intercept) in zip(window, lines)], axis=0).reshape(2, 4)
    strain = -sums[:, 0] / sums[:, 1]
    model = _rate_law(scene)
    law = []
    for c in strain:
        try:
            law.append(along_slope_friction(model, float(c))[1])
        except ValueError:
            law.append(math.nan)
    return FaceStates(tuple(map(float, strain)), tuple(map(float, sums[:, 2] / sums[:, 3])), tuple(law))


def segment_area_below(slope: float, intercept: float, radius: float) -> float:
    """Area of the drum's disc below the line y = slope x + intercept (coordinates relative to the
    centre): R^2 (pi - acos(d/R)) + d sqrt(R^2 - d^2), d the line's signed height above the centre
    along its normal  [m^2]."""
    d = min(max(intercept / math.hypot(1.0, slope), -radius), radius)
    return radius**2 * (math.pi - math.acos(d / radius)) + d * math.sqrt(radius**2 - d * d)


def grain_volume(frame, spacing) -> float:
    """The grains' own volume sum m/rho (one dp^2 a grain in frames without density)  [m^2]."""
    n = _material_count(frame)
    if "mass" in frame and "density" in frame:
        return float(np.sum(frame["mass"][:n] / frame["density"][:n]))
    return n * spacing * spacing


def fill_occupancy(frame, centre, radius, spacing) -> float:
    """The area under the fitted surface line per unit of the grains' own volume; NaN where the
    surface is not found  [-]."""
    n = _material_count(frame)
    try:
        slope, intercept = surface_line(frame["position"][:n, :2], centre, radius, spacing)
    except ValueError:
        return math.nan
    return segment_area_below(slope, intercept, radius) / grain_volume(frame, spacing)


CREEP_CELL = 2.0  # the lab grid of the bed's steady stress field, in dp
CREEP_FIELDS = ("frictional_stress", "density_factor", "velocity_gradient")


def bed_creep(scene, frames, window, centre, radius, spacing, omega, flowing_depth, lines):
    """(|D| the law needs, |D| the grains have) in the bed, medians over its cells and grains, per
    omega  [-, -]. The law's need: the bed turning rigidly (v = omega z x (x - c), spin omega)
    under the frictional stress field T_s(x) of the window, averaged on a lab grid of CREEP_CELL
    dp, as a steady field: dT_s/dt = v . grad T_s at each cell with full neighbours deeper than
    the flowing depth + 2 dp and 1.5 dp off the wall, solved for the plane strain rate D that
    gives it (element_tests.plane_strain_rate_for). The grains': |D| of their SPH velocity
    gradient in the same cells. NaN for frames without stresses (synthetic ones)."""
    from .element_tests import RateProbe, plane_strain_rate_for
    if math.isnan(flowing_depth) or not all(name in frames[k] for k in window for name in CREEP_FIELDS):
        return math.nan, math.nan
    cell = CREEP_CELL * spacing
    count = int(math.ceil(2.0 * radius / cell))
    total, factor, weight = np.zeros((count, count, 3, 3)), np.zeros((count, count)), np.zeros((count, count))
    slope, intercept = np.mean(lines, axis=0)
    grains_D, grains_cell = [], []
    for k in window:
        f = frames[k]
        n = _material_count(f)
        index = np.floor((f["position"][:n, :2] - centre + radius) / cell).astype(int).clip(0, count - 1)
        np.add.at(total, (index[:, 0], index[:, 1]), f["frictional_stress"][:n].reshape(-1, 3, 3))
        np.add.at(factor, (index[:, 0], index[:, 1]), f["density_factor"][:n])
        np.add.at(weight, (index[:, 0], index[:, 1]), 1.0)
        L = f["velocity_gradient"][:n].reshape(n, 2, 2)
        grains_D.append(np.sqrt((0.25 * (L + L.transpose(0, 2, 1)) ** 2).sum(axis=(1, 2))))  # |D|
        grains_cell.append(index)
    filled = weight > 0
    T = np.where(filled[..., None, None], total / np.maximum(weight, 1)[..., None, None], 0.0)
    I_e = np.where(filled, factor / np.maximum(weight, 1), 0.0)
    mid = (np.arange(count) + 0.5) * cell - radius
    X, Y = np.meshgrid(mid, mid, indexing="ij")
    _, depth, _, _ = surface_frame(np.stack([X, Y], -1).reshape(-1, 2) + centre, centre, slope, intercept)
    bed = filled & (depth.reshape(count, count) > flowing_depth + 2.0 * spacing) & \
        (np.hypot(X, Y) < radius - 1.5 * spacing)
    inner = np.zeros_like(bed)
    inner[1:-1, 1:-1] = bed[1:-1, 1:-1] & bed[:-2, 1:-1] & bed[2:, 1:-1] & bed[1:-1, :-2] & bed[1:-1, 2:]
    probe = RateProbe(_rate_law(scene))
    spin = np.array([[0.0, -omega, 0.0], [omega, 0.0, 0.0], [0.0, 0.0, 0.0]])
    needed = []
    for a, b in zip(*np.nonzero(inner)):
        gradient_x = (T[a + 1, b] - T[a - 1, b]) / (2.0 * cell)
        gradient_y = (T[a, b + 1] - T[a, b - 1]) / (2.0 * cell)
        rate = omega * (-Y[a, b] * gradient_x + X[a, b] * gradient_y)
        D = plane_strain_rate_for(probe, T[a, b], spin, I_e[a, b], rate)
        needed.append(math.sqrt((D * D).sum()))
    have = np.concatenate([d[inner[c[:, 0], c[:, 1]]] for d, c in zip(grains_D, grains_cell)])
    if not needed or not len(have):
        return math.nan, math.nan
    return float(np.median(needed)) / abs(omega), float(np.median(have)) / abs(omega)


def steady_window(times, omega: float):
    """Indices of the frames of the steady window: the last revolution, within the second half of
    the run."""
    times = np.asarray(times, float)
    end = times[-1]
    start = max(end - 2.0 * math.pi / abs(omega), STEADY_SPAN * end)
    return np.where(times >= start - 1e-9)[0]


def surface_inclination(frame, centre, radius, spacing) -> float:
    """The inclination of the free surface in one frame, NaN where too few grains span the middle  [deg]."""
    n = _material_count(frame)
    try:
        slope, _ = surface_line(frame["position"][:n, :2], centre, radius, spacing)
    except ValueError:
        return math.nan
    return math.degrees(math.atan(abs(slope)))


def evaluate_drum(scene, times, frames) -> DrumResult:
    from .inclined_plane import BagnoldReference
    drum = next(o for o in scene.obstacles if o.shape == "drum")
    centre = np.asarray(drum.origin or (0.0, 0.0), float)
    omega, radius = drum.angular_velocity, drum.radius
    dp = scene.numerics.particle_spacing
    window = steady_window(times, omega)
    depth_bins = np.arange(0.0, 2.0 * radius + dp, dp)
    every = [surface_inclination(f, centre, radius, dp) for f in frames]
    every_e = [mean_void_ratio(f, scene.material.grain_density) for f in frames]
    profiles, rigids, areas, lines = [], [], [], []
    for k in window:
        f = frames[k]
        n = _material_count(f)
        x, v = f["position"][:n, :2], f["velocity"][:n, :2]
        slope, intercept = surface_line(x, centre, radius, dp)
        lines.append((slope, intercept))
        u, rigid = cross_section(x, v, centre, omega, slope, intercept, dp, depth_bins)
        profiles.append(u)
        rigids.append(rigid)
        areas.append(grain_volume(f, dp))
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
    H0 = fill_depth(float(np.mean(areas)), radius)
    budget = None
    if not math.isnan(flowing_depth) and all(name in frames[k] for k in window for name in BUDGET_FIELDS):
        terms = np.mean([momentum_terms(frames[k], centre, radius, dp, scene.gravity_vector, slope, intercept,
                                        flowing_depth) for k, (slope, intercept) in zip(window, lines)], axis=0)
        budget = MomentumBudget(flowing_depth, *map(float, terms))
    creep = bed_creep(scene, frames, window, centre, radius, dp, omega, flowing_depth, lines)
    faces = face_states(scene, frames, window, centre, radius, dp, flowing_depth, lines)
    occupancy = [segment_area_below(slope, intercept, radius) / area for (slope, intercept), area in zip(lines, areas)]
    swelling = float(np.mean(occupancy) / fill_occupancy(frames[0], centre, radius, dp) - 1.0)
    inclinations, void_ratios = np.array(every)[window], np.array(every_e)[window]
    has_density = not np.all(np.isnan(void_ratios))
    try:
        predicted = math.degrees(BagnoldReference(scene, [frames[k] for k in window] if has_density else None,
                                                  _material_count(frames[window[0]])).slope_for_flux(flux, flowing_depth))
    except ValueError:
        predicted = math.nan
    return DrumResult(scene.name, abs(omega), radius, float(np.nanmean(inclinations)), float(np.nanstd(inclinations)),
                      flowing_depth, flux, 0.5 * abs(omega) * (radius**2 - (radius - H0) ** 2), H0, departure,
                      predicted, (float(times[window[0]]), float(times[-1])),
                      float(np.mean(void_ratios)) if has_density else math.nan, critical_void_ratio(scene),
                      scene.material.initial_void_ratio, omega**2 * radius / scene.gravity.magnitude, len(window),
                      budget, swelling, *creep, faces, depth, u, rigid, list(map(float, times)), every, every_e)


def mean_void_ratio(frame, grain_density: float) -> float:
    """The material's volume-weighted mean void ratio, NaN for frames without density  [-]."""
    if "mass" not in frame or "density" not in frame:
        return math.nan
    n = _material_count(frame)
    volume = frame["mass"][:n] / frame["density"][:n]
    return float(np.sum(volume * (grain_density / frame["density"][:n] - 1.0)) / np.sum(volume))


def _material_count(frame) -> int:
    return int(np.sum(frame["is_wall"] == 0)) if "is_wall" in frame else len(frame["position"])


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


def revolution_strip(out, times, window, count: int = 6):
    """The run's own PNG frames at ``count`` times spread over the window, side by side (small:
    the frames are the scene's render width)  [image array, or None without frames]."""
    import imageio.v2 as imageio

    from ..render.frames import png_name
    picks = [window[int(round(k * (len(window) - 1) / (count - 1)))] for k in range(count)]
    paths = [Path(out) / "frames" / png_name(int(k), times[k]) for k in picks]
    if not all(p.exists() for p in paths):
        return None
    images = [imageio.imread(p)[..., :3] for p in paths]
    height = min(i.shape[0] for i in images)
    return np.concatenate([i[:height] for i in images], axis=1)


def check(case, runs, base, args) -> bool:
    """Rotating drum at omega = 0.5, 1, 2 rad/s: continuous rolling (the inclination's spread over
    the last revolution), a rigid bed, the mean inclination against the model's steady prediction
    at the measured flux and depth; flowing depth and flux against the kinematic flux; [P]'s table
    beside, not judged. Writes velocity_profile.csv and .png and revolution.png per case."""
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
        strip = revolution_strip(out, times, steady_window(times, result.omega))
        if strip is not None:
            write_png(out / "revolution.png", strip)
        print(result.row(), flush=True)
        if result.budget is not None:
            print(result.budget.line(result.predicted_deg), flush=True)
        if result.faces is not None:
            print(result.faces.line(result.predicted_deg, result.faces_slope_deg()), flush=True)
        if not math.isnan(result.creep_needed):
            print(f"  bed: the law needs |D| = {result.creep_needed:.4f} omega to turn rigidly under its own stress "
                  f"field; its grains deform at {result.creep_measured:.4f} omega (medians)", flush=True)
        if result.loose_start:
            settled, low, high = result.transient()
            print(f"  loose start (e_0 {result.initial_void_ratio:.3f} against e* {result.critical_void_ratio:.3f}): "
                  f"compacted to within {SETTLED_VOID_RATIO} of e* by {settled:.2f} s, the inclination "
                  f"{low:.1f}-{high:.1f} deg until then (transient, not judged)")
    print(f"steady window: the last revolution (at most the second half of the run); model: the steady slope of "
          f"MODEL.md section 2 at the measured flux and depth; kinematic flux omega (R^2 - (R - H_0)^2)/2; "
          f"[P]: Peng et al. (2016) -- {PAPER_OUT_OF_REACH}")
    judged = [r for r in results if not r.loose_start]
    ok = all(r.passed() for r in judged)
    ordered = sorted(judged, key=lambda r: r.omega)
    rising = all(a.flowing_depth < b.flowing_depth for a, b in zip(ordered, ordered[1:]))
    ok &= rising
    print(f"acceptance (inclination sd < {STEADY_SPREAD_DEG} deg over the last revolution, bed within "
          f"{100 * RIGID_TOLERANCE:.0f} % of omega R of rigid rotation, mean inclination within "
          f"{INCLINATION_TOLERANCE_DEG} deg of the model, flowing depth rising with omega): "
          f"{'PASS' if ok else 'FAIL'}; profiles -> {base}/<case>/velocity_profile.csv, .png")
    write_rows(base, [Row(f"{case.name}: {r.name}", "mean inclination (sd); flowing depth; friction at the layer's base",
                          f"{r.inclination_deg:.1f} deg ({r.inclination_spread_deg:.1f}); {1e3 * r.flowing_depth:.0f} mm; "
                          + ("-" if r.budget is None else f"{r.budget.friction_deg:.1f} deg"),
                          "-" if r.paper is None else f"{r.paper[0]} deg; {1e3 * r.paper[1]:.0f} mm (out of reach)",
                          f"model's steady slope {r.predicted_deg:.1f} deg"
                          + ("" if r.faces is None else f"; with the law's faces {r.faces_slope_deg():.1f} deg"),
                          res, run_cost, r.verdict())
                      for r, (res, run_cost) in zip(results, where)])
    return ok
