"""Steady uniform flow down an inclined plane, for the mu(I) model (validation 1 of [M], MODEL.md
section 1) and the hypoplastic + Bagnold model ([P], MODEL.md section 2).

mu(I) reference: the analytic solution [M56],
    v_x(z) = (2 I_u/(3 d)) sqrt(phi_u g cos theta) (H^{3/2} - (H - z)^{3/2}),
    I_u = I_0 (tan theta - mu_s)/(mu_2 - tan theta),  phi_u = phi_max - (phi_max - phi_min) I_u,
and hydrostatic pressure p(z) = phi_u rho_s g cos theta (H - z).

Hypoplastic reference (MODEL.md section 2): steady flow only for mu_h < tan theta < tan alpha_i,
mu_h the stationary tau/sigma_n of the hypoplastic part in simple shear (found by point
integration of the package's own rate law, validation/element_tests.py), with the Bagnold-like
profile gamma_dot = A sqrt(H - z), u(z) = (2/3) A (H^{3/2} - (H - z)^{3/2}),
A^2 = rho g (sin theta - mu_h cos theta) / (k_v rho_s d^2 (sin alpha_i - mu_h cos alpha_i)),
and normal stress rho g cos theta (H - z), rho the layer's mean bulk density.
The normal stress compared is -sigma_yy = p - s_yy of the frames (= p for the mu(I) model,
whose frames carry no deviatoric stress).

Both references are written for a layer of flow depth H. The depth is measured as an
experimentalist measures it, at the free surface: the height where the SPH colour function
C(z) = sum_j V_j W(x - x_j), averaged along the bed, falls to 1/2 (the standard SPH definition
of an interface; it gives H to 0.1 % on the initial lattice). The SPH profile is the mean over
particles in layers of thickness dp, averaged over the frames of the last ``window`` seconds,
each compared with the reference at the mean height of its particles.

The depth the mass would have at phi_u, H_mass = M / (L phi_u rho_s0 (1 + K_t p_mean)), is
reported beside it: the swelling H/H_mass - 1 measures how far the particle volumes m/rho of the
integrated continuity density have drifted from the area the particles cover (a volume error of
the scheme, which mass conservation alone does not catch), and the errors against the
references at H_mass are reported too.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Sequence

import numpy as np

from ..config import Scene
from ..physics.rheology.mu_i.steady import analytic_pressure, analytic_velocity, steady_height


class MuIReference:
    """[M56] and hydrostatic pressure for a mu(I) scene."""

    name = "[M56]"

    def __init__(self, scene: Scene, frames=None, n_material=None):
        self.material, self.g = scene.material, scene.gravity.magnitude
        self.slope = math.radians(scene.gravity.tilt_deg)

    def velocity(self, z, height: float) -> np.ndarray:
        return analytic_velocity(z, height, self.material, self.slope, self.g)

    def normal_stress(self, z, height: float) -> np.ndarray:
        return analytic_pressure(z, height, self.material, self.slope, self.g)

    def mass_height(self, mass_per_length: float) -> float:
        return steady_height(mass_per_length, self.material, self.slope, self.g)

    def wave_speed(self, frame, n_material: int) -> np.ndarray:
        phi = frame["solid_fraction"][:n_material]
        return 1.0 / np.sqrt(self.material.grain_compressibility * phi * self.material.grain_density)


_STATIONARY_SHEAR = {}  # (I_e, mu_h) per set of rate-law constants: solved once per process


def stationary_shear_of(scene: Scene):
    """(I_e, mu_h) of the stationary simple shear of the scene's hypoplastic material, by point
    integration of the package's rate law (validation/element_tests.py), solved once per
    process and set of constants  [-, -]."""
    m = scene.material
    key = (tuple(m.constants), m.min_void_ratio, tuple(m.critical_void_ratio), tuple(m.density_exponent))
    if key not in _STATIONARY_SHEAR:
        from .. import runtime
        from ..physics.rheology.hypoplastic.model import HypoplasticBagnold
        from .element_tests import stationary_simple_shear
        runtime.ensure(scene.precision)
        _STATIONARY_SHEAR[key] = stationary_simple_shear(HypoplasticBagnold.from_scene(scene))
    return _STATIONARY_SHEAR[key]


class BagnoldReference:
    """The Bagnold-like steady profile of the hypoplastic + Bagnold model (MODEL.md section 2),
    for the layer's mean bulk density (from ``frames``, else rho_s/(1 + e_0))."""

    name = "Bagnold-type [P]"

    def __init__(self, scene: Scene, frames=None, n_material=None):
        m = scene.material
        self.material, self.g = m, scene.gravity.magnitude
        self.slope = math.radians(scene.gravity.tilt_deg)
        self.density_factor, self.friction = stationary_shear_of(scene)
        self.density = m.reference_density
        if frames:
            self.density = float(np.mean([np.sum(f["mass"][:n_material]) / np.sum(f["mass"][:n_material] /
                                                                                 f["density"][:n_material])
                                          for f in frames]))

    @property
    def bounding_angles_deg(self):
        """(arctan mu_h, alpha_i): steady flow exists only between them  [deg]."""
        return math.degrees(math.atan(self.friction)), self.material.dispersion_angle_deg

    def shear_rate_scale(self, slope_rad: float = None) -> float:
        """A of gamma_dot = A sqrt(H - z)  [1/(s m^1/2)]."""
        slope = self.slope if slope_rad is None else slope_rad
        low, high = self.bounding_angles_deg
        if not low < math.degrees(slope) < high:
            raise ValueError(f"slope {math.degrees(slope):.2f} deg is outside the steady range ({low:.2f}, "
                             f"{high:.2f}) deg of the hypoplastic + Bagnold model")
        m, mu = self.material, self.friction
        alpha_i = math.radians(m.dispersion_angle_deg)
        drive = self.density * self.g * (math.sin(slope) - mu * math.cos(slope))
        resistance = m.bagnold_coefficient * m.grain_density * m.grain_diameter**2 * \
            (math.sin(alpha_i) - mu * math.cos(alpha_i))
        return math.sqrt(drive / resistance)

    def slope_for_flux(self, flux: float, depth: float) -> float:
        """The slope on which a steady layer of depth H carries the flux q (per unit width) over a
        bed at rest: q = int_0^H u dz = (2/5) A H^(5/2), so A = 5 q / (2 H^(5/2)), and
        sin theta - mu_h cos theta = sqrt(1 + mu_h^2) sin(theta - arctan mu_h) = A^2 k_v rho_s d^2
        (sin alpha_i - mu_h cos alpha_i) / (rho g): the inverse of ``shear_rate_scale``  [rad]."""
        m, mu = self.material, self.friction
        alpha_i = math.radians(m.dispersion_angle_deg)
        A = 2.5 * flux / depth**2.5
        resistance = m.bagnold_coefficient * m.grain_density * m.grain_diameter**2 * \
            (math.sin(alpha_i) - mu * math.cos(alpha_i))
        excess = A * A * resistance / (self.density * self.g * math.sqrt(1.0 + mu * mu))
        if not 0.0 <= excess < 1.0:
            raise ValueError(f"no steady slope carries {flux:.3g} m2/s in a {depth:.3g} m layer")
        return math.atan(mu) + math.asin(excess)

    def velocity(self, z, height: float) -> np.ndarray:
        z = np.clip(np.asarray(z, float), 0.0, height)
        return 2.0 / 3.0 * self.shear_rate_scale() * (height**1.5 - (height - z) ** 1.5)

    def normal_stress(self, z, height: float) -> np.ndarray:
        z = np.clip(np.asarray(z, float), 0.0, height)
        return self.density * self.g * math.cos(self.slope) * (height - z)

    def mass_height(self, mass_per_length: float) -> float:
        return mass_per_length / self.density

    def wave_speed(self, frame, n_material: int) -> np.ndarray:
        return np.full(n_material, self.material.wave_speed)


REFERENCES = {"mu_i": MuIReference, "hypoplastic": BagnoldReference}


def reference_for(scene: Scene, frames=None, n_material=None):
    """The analytic steady state of the scene's model on its slope."""
    if scene.material.model not in REFERENCES:
        raise ValueError(f"no inclined-plane reference for the {scene.material.model} model")
    return REFERENCES[scene.material.model](scene, frames, n_material)


def normal_stress(frame: Dict[str, np.ndarray]) -> np.ndarray:
    """-sigma_yy = p - s_yy (the bed-normal stress, compression positive)  [Pa]."""
    p = frame["pressure"]
    if "deviatoric_stress" not in frame:
        return p
    s = frame["deviatoric_stress"]
    dim = int(round(math.sqrt(s.shape[1]))) if s.ndim == 2 else s.shape[-1]
    s_yy = s.reshape(len(s), dim, dim)[:, dim - 1, dim - 1]
    return p - s_yy


def colour_function_profile(frame: Dict[str, np.ndarray], n_material: int, length: float, spacing: float,
                            heights: np.ndarray) -> np.ndarray:
    """C(z) = sum_j V_j W(x - x_j), V_j = m_j/rho_j, averaged over 4 points per dp along the
    (periodic) bed, at each of ``heights`` [-]. W is the 2D Wendland C2 of [M20] with h = 1.3 dp,
    whatever the scene used: this is a measurement, the same for every run."""
    h = 1.3 * spacing
    x = frame["position"][:n_material]
    volume = frame["mass"][:n_material] / frame["density"][:n_material]
    near = x[:, 1] > heights.min() - 2.0 * h  # only particles within reach of the sampled heights
    x, volume = x[near], volume[near]
    samples = np.arange(0.0, length, 0.25 * spacing)
    colour = np.zeros_like(heights)
    for xs in samples:
        dx = (xs - x[:, 0] + 0.5 * length) % length - 0.5 * length
        R = np.sqrt(dx[None, :] ** 2 + (heights[:, None] - x[None, :, 1]) ** 2) / h
        w = np.where(R < 2.0, (1.0 + 2.0 * R) * np.clip(2.0 - R, 0.0, None) ** 4, 0.0)
        colour += (w * volume[None, :]).sum(axis=1)
    return colour * 7.0 / (64.0 * math.pi * h * h) / len(samples)


def flow_depth(frame: Dict[str, np.ndarray], n_material: int, length: float, spacing: float,
               bed: float = 0.0) -> float:
    """Height above the bed of the free surface, where the colour function falls to 1/2  [m]."""
    top = float(frame["position"][:n_material, 1].max())
    while True:  # windows of 4 dp from the highest particle down: grains splashed above the layer are skipped
        heights = np.linspace(top - 2.0 * spacing, top + 2.0 * spacing, 401)
        colour = colour_function_profile(frame, n_material, length, spacing, heights)
        if np.any(colour >= 0.5) or top < bed:
            break
        top -= 4.0 * spacing
    if not np.any(colour >= 0.5):
        raise ValueError("the layer has no free surface: its colour function stays below 1/2 at every height "
                         "(the layer has come apart)")
    k = int(np.nonzero(colour >= 0.5)[0].max())
    if k + 1 < len(heights):  # linear interpolation to C = 1/2
        k_frac = (colour[k] - 0.5) / (colour[k] - colour[k + 1])
        return float(heights[k] + k_frac * (heights[k + 1] - heights[k]) - bed)
    return float(heights[k] - bed)


def bed_height(scene: Scene) -> float:
    """Height of the bed: the lowest wall, else the bottom of the domain  [m]."""
    return min(w.point[-1] for w in scene.walls) if scene.walls else scene.domain.lower[-1]


def impose_analytic_velocity(sim, slope_deg: float = None) -> None:
    """Give every material particle of a fresh inclined-plane simulation the analytic steady
    velocity at its height above the bed (the scene's model's reference, on the scene's slope or
    on ``slope_deg``), with the height of the (packed) layer as H. The steady state does not
    depend on the start; this one is ~15 s closer to it than rest for [M]'s beads (the run from
    rest relaxes with a time constant of ~15 s: tan(theta) - mu_s is small)."""
    scene = sim.scene
    if slope_deg is not None:
        from dataclasses import replace
        scene = replace(scene, gravity=replace(scene.gravity, tilt_deg=slope_deg))
    state = sim.state
    n = state.n_material
    x = state.position.to_numpy()
    v = state.velocity.to_numpy()
    bed = bed_height(scene)
    height = max(b.upper[-1] for b in scene.particles) - bed
    v[:n, 0] = reference_for(scene).velocity(x[:n, -1] - bed, height)
    state.load({"velocity": v})


def relative_l2(simulated: np.ndarray, reference: np.ndarray) -> float:
    """sqrt(sum (s - r)^2 / sum r^2)."""
    return float(np.sqrt(np.sum((simulated - reference) ** 2) / np.sum(reference**2)))


@dataclass
class InclinedPlaneResult:
    velocity_error: float  # relative L2 against the analytic profile
    pressure_error: float  # relative L2 of the normal stress against hydrostatic
    mach_number: float  # max over the window of |v_i|/c_i
    height: float  # measured flow depth H (colour function 1/2) [m]
    mass_height: float  # depth of the mass at phi_u [m]
    velocity_error_mass_height: float  # relative L2 against [M56] with H = mass_height
    pressure_error_mass_height: float  # relative L2 against hydrostatic with H = mass_height
    surface_velocity: float  # SPH, top layer [m/s]
    surface_velocity_reference: float  # [M56] at the same height [m/s]
    window: tuple  # (t_start, t_end) of the average [s]
    drift: float  # relative change of the profile between the two halves of the window
    reference: str = "[M56]"  # the analytic solution compared with
    profile: Dict[str, np.ndarray] = field(default_factory=dict)

    def report(self) -> str:
        return "\n".join([
            f"inclined plane: steady profile averaged over t = {self.window[0]:.2f}-{self.window[1]:.2f} s",
            f"  flow depth H (colour function 1/2)  {self.height * 1e3:.2f} mm",
            f"  surface velocity SPH / {self.reference:12s} {self.surface_velocity:.3f} / "
            f"{self.surface_velocity_reference:.3f} m/s",
            f"  velocity relative L2 error vs {self.reference} {100 * self.velocity_error:.2f} %",
            f"  normal stress relative L2 error vs hydrostatic {100 * self.pressure_error:.2f} %",
            f"  max Mach number |v|/c               {self.mach_number:.3f}",
            f"  profile drift within the window     {100 * self.drift:.2f} %",
            f"  depth of the mass (steady density)  {self.mass_height * 1e3:.2f} mm "
            f"(swelling {100 * (self.height / self.mass_height - 1):+.2f} %)",
            f"  with that depth: velocity {100 * self.velocity_error_mass_height:.2f} %, "
            f"pressure {100 * self.pressure_error_mass_height:.2f} %",
        ])


def binned_profile(frames: Sequence[Dict[str, np.ndarray]], n_material: int, spacing: float,
                   height: float, keep_empty: bool = False):
    """Mean height, down-slope velocity and normal stress of material particles in layers of
    thickness ``spacing`` (over all given frames); layers without particles are left out, or
    with ``keep_empty`` kept as NaN (so that two profiles line up layer by layer)."""
    edges = np.arange(0.0, height + spacing, spacing)
    sums = np.zeros((3, len(edges) - 1))
    counts = np.zeros(len(edges) - 1)
    for arrays in frames:
        z = arrays["position"][:n_material, -1]
        k = np.digitize(z, edges) - 1
        ok = (k >= 0) & (k < len(counts))
        counts += np.bincount(k[ok], minlength=len(counts))
        for row, values in enumerate((z, arrays["velocity"][:n_material, 0],
                                         normal_stress(arrays)[:n_material])):
            sums[row] += np.bincount(k[ok], weights=values[ok], minlength=len(counts))
    used = counts > 0
    if keep_empty:
        means = np.full_like(sums, np.nan)
        means[:, used] = sums[:, used] / counts[used]
        return means[0], means[1], means[2]
    z_mean, v_mean, p_mean = sums[:, used] / counts[used]
    return z_mean, v_mean, p_mean


def evaluate(scene: Scene, times: Sequence[float], frames: Sequence[Dict[str, np.ndarray]],
             window: float = 1.0) -> InclinedPlaneResult:
    """Errors of the frames within the last ``window`` seconds against [M56] and hydrostatic."""
    times = np.asarray(times)
    t_end = float(times.max())
    chosen = [f for t, f in zip(times, frames) if t >= t_end - window - 1e-9]
    chosen_times = times[times >= t_end - window - 1e-9]
    n_material = int(np.sum(chosen[0]["is_wall"] == 0))
    length = scene.domain.size[0]
    reference = reference_for(scene, chosen, n_material)
    mass_per_length = float(np.sum(chosen[-1]["mass"][:n_material])) / length
    mass_height = reference.mass_height(mass_per_length)
    dp = scene.numerics.particle_spacing
    bed = bed_height(scene)
    height = float(np.mean([flow_depth(f, n_material, length, dp, bed) for f in chosen]))

    top = max(height, mass_height) + dp  # bins reach every particle of the layer
    z, v, p = binned_profile(chosen, n_material, dp, top)
    v_ref = reference.velocity(z, height)
    p_ref = reference.normal_stress(z, height)
    half = len(chosen) // 2
    drift = 0.0
    if half >= 1:  # on the layers both halves fill (a sparse top layer may hold particles in one only)
        _, v_a, _ = binned_profile(chosen[:half], n_material, dp, top, keep_empty=True)
        _, v_b, _ = binned_profile(chosen[half:], n_material, dp, top, keep_empty=True)
        both = np.isfinite(v_a) & np.isfinite(v_b)
        if np.any(both):
            drift = relative_l2(v_a[both], v_b[both])
    mach = 0.0
    for arrays in chosen:
        c = reference.wave_speed(arrays, n_material)
        speed = np.linalg.norm(arrays["velocity"][:n_material], axis=1)
        mach = max(mach, float(np.max(speed / c)))
    return InclinedPlaneResult(
        velocity_error=relative_l2(v, v_ref), pressure_error=relative_l2(p, p_ref), mach_number=mach,
        height=height, mass_height=mass_height,
        velocity_error_mass_height=relative_l2(v, reference.velocity(z, mass_height)),
        pressure_error_mass_height=relative_l2(p, reference.normal_stress(z, mass_height)),
        reference=reference.name, surface_velocity=float(v[-1]), surface_velocity_reference=float(v_ref[-1]),
        window=(float(chosen_times.min()), t_end), drift=drift,
        profile={"z": z, "velocity": v, "velocity_reference": v_ref, "pressure": p, "pressure_reference": p_ref})


def write_profile_csv(result: InclinedPlaneResult, path: Path) -> None:
    from ..output import atomic_write_text
    cols = ["z", "velocity", "velocity_reference", "pressure", "pressure_reference"]
    lines = [",".join(cols)]
    for row in zip(*(result.profile[c] for c in cols)):
        lines.append(",".join(f"{v:.9g}" for v in row))
    atomic_write_text(path, "\n".join(lines) + "\n")


# ---- the bounding slopes of the hypoplastic + Bagnold model (MODEL.md section 2) ------------------

BOUND_MARGIN_DEG = 2.0  # the slopes tried below arctan(mu_h) and above alpha_i
BOUND_DURATION = 0.2  # s of flow from the steady profile of the scene's slope
BOUND_INTERVAL = 0.02  # s between samples of the layer's mean velocity


def mean_velocity(frame: Dict[str, np.ndarray], n_material: int) -> float:
    """Mass-weighted mean down-slope velocity of the layer  [m/s]."""
    m = frame["mass"][:n_material]
    return float(np.sum(m * frame["velocity"][:n_material, 0]) / np.sum(m))


def layer_acceleration(times: Sequence[float], frames: Sequence[Dict[str, np.ndarray]], n_material: int) -> float:
    """Least-squares slope of the layer's mean down-slope velocity over the frames  [m/s^2]."""
    u = [mean_velocity(f, n_material) for f in frames]
    return float(np.polyfit(np.asarray(times, float), u, 1)[0])


def run_in_memory(scene: Scene, duration: float, interval: float, prepare=None):
    """(times, frames, diagnostics) of ``scene`` run for ``duration`` without writing files: a
    snapshot of every particle field (with ``is_wall``) every ``interval`` seconds, from t = 0
    (initial rates evaluated, no step), and the diagnostics row of each stretch between them;
    ``prepare(sim)`` sets the start."""
    from ..simulation import Simulation
    sim = Simulation(scene)
    if prepare is not None:
        prepare(sim)
    is_wall = np.r_[np.zeros(sim.state.n_material, int), np.ones(sim.state.n_wall, int)]
    times, frames, diagnostics = [], [], []
    sim.run(end_time=0.0)  # initial rates, no step
    while True:
        times.append(sim.t)
        frames.append({**sim.scheme.snapshot(), "is_wall": is_wall})
        if sim.t >= duration - 1e-9:
            break
        sim.run(end_time=min(duration, sim.t + interval))
        diagnostics.append(sim.last_diagnostics)
    return times, frames, diagnostics


@dataclass
class BoundingSlope:
    slope_deg: float
    acceleration: float  # measured, of the layer's mean velocity [m/s^2]
    bound: float  # g (sin theta - mu cos theta) with mu = mu_h below, tan(alpha_i) above [m/s^2]

    @property
    def passed(self) -> bool:
        """No steady flow: decelerating below arctan(mu_h), accelerating above alpha_i."""
        return self.acceleration < 0.0 if self.bound < 0.0 else self.acceleration > 0.0

    def row(self) -> str:
        side = "above alpha_i: accelerates" if self.bound > 0 else "below arctan(mu_h): stops"
        relation = ">=" if self.bound > 0 else "<="
        return (f"  slope {self.slope_deg:5.2f} deg ({side}): mean acceleration {self.acceleration:+.3f} m/s2 "
                f"(analytic bound {relation} {self.bound:+.3f})")


def bounding_slopes(scene: Scene, duration: float = BOUND_DURATION) -> List[BoundingSlope]:
    """Run the scene on a slope BOUND_MARGIN_DEG below arctan(mu_h) and one as far above
    alpha_i, each from the steady profile of the scene's own slope, and measure the layer's
    acceleration: steady flow exists only between the two (MODEL.md section 2). Analytic bounds:
    below, every frictional state carries at least mu_h, so a <= g (sin - mu_h cos) < 0; above,
    no state carries more than tan(alpha_i), so a >= g (sin - tan(alpha_i) cos) > 0."""
    from dataclasses import replace
    reference = reference_for(scene)
    low, high = reference.bounding_angles_deg
    g = scene.gravity.magnitude
    results = []
    for slope_deg, mu in ((low - BOUND_MARGIN_DEG, reference.friction),
                          (high + BOUND_MARGIN_DEG, math.tan(math.radians(high)))):
        tilted = replace(scene, gravity=replace(scene.gravity, tilt_deg=slope_deg))
        times, frames, _ = run_in_memory(tilted, duration, BOUND_INTERVAL,
                                         lambda sim: impose_analytic_velocity(sim, scene.gravity.tilt_deg))
        n = int(np.sum(frames[0]["is_wall"] == 0))
        theta = math.radians(slope_deg)
        results.append(BoundingSlope(slope_deg, layer_acceleration(times, frames, n),
                                     g * (math.sin(theta) - mu * math.cos(theta))))
    return results


# ---- the validate command's case (validation/__init__.py CASES) -------------------------------


def prepare(args):
    """Before the run: start from the [M56] profile (``--start analytic``) or from rest."""
    return impose_analytic_velocity if args.start == "analytic" else None


def check(case, runs, base, args) -> bool:
    """mu(I) ([M56], both errors < 5 %) or hypoplastic + Bagnold (MODEL.md section 2: velocity
    within 10 % of the Bagnold-type profile, and no steady flow outside the bounding slopes).
    Writes profile.csv beside the run."""
    from .table import Row, cost, resolution, write_rows

    ok, rows = True, []
    for scene, out, times, frames in runs:
        result = evaluate(scene, times, frames, window=args.window)
        passed = _check_plane(scene, out, times, frames, args, result)
        ok &= passed
        name, verdict = f"{case.name}: {scene.name}", "PASS" if passed else "FAIL"
        where = (resolution(scene, frames, out), cost(out), verdict)
        rows.append(Row(name, "velocity profile, relative L2", f"{100 * result.velocity_error:.2f} %", "-",
                        f"{result.reference} profile", *where))
        rows.append(Row(name, "normal stress, relative L2", f"{100 * result.pressure_error:.2f} %", "-",
                        "hydrostatic", *where))
    write_rows(base, rows)
    return ok


def _check_plane(scene, out, times, frames, args, result) -> bool:
    print(result.report())
    write_profile_csv(result, out / "profile.csv")
    if scene.material.model != "hypoplastic":
        ok = result.velocity_error < 0.05 and result.pressure_error < 0.05
        print(f"  acceptance (both errors < 5 %): {'PASS' if ok else 'FAIL'}; profile -> {out / 'profile.csv'}")
        return ok
    reference = reference_for(scene)
    low, high = reference.bounding_angles_deg
    n = int(sum(frames[0]["is_wall"] == 0))
    window = [(t, f) for t, f in zip(times, frames) if t >= max(times) - args.window - 1e-9]
    steady = layer_acceleration([t for t, _ in window], [f for _, f in window], n)
    print(f"  mu_h = {reference.friction:.4f} (I_e {reference.density_factor:.4f}): steady flow between "
          f"{low:.2f} and {high:.2f} deg; at {scene.gravity.tilt_deg:.2f} deg the layer's mean acceleration over "
          f"the window is {steady:+.3f} m/s2")
    bounds = bounding_slopes(scene)
    for b in bounds:
        print(b.row())
    ok = result.velocity_error < 0.10 and all(b.passed for b in bounds)
    print(f"  acceptance (velocity within 10 %, no steady flow outside the bounds): {'PASS' if ok else 'FAIL'}; "
          f"profile -> {out / 'profile.csv'}")
    return ok
