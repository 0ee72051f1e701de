"""Validation 1 of [M]: steady uniform flow down an inclined plane (MODEL.md section 1).

Reference: the analytic mu(I) solution [M56],
    v_x(z) = (2 I_u/(3 d)) sqrt(phi_u g cos theta) (H^{3/2} - (H - z)^{3/2}),
    I_u = I_0 (tan theta - mu_s)/(mu_2 - tan theta),  phi_u = phi_max - (phi_max - phi_min) I_u,
and hydrostatic pressure p(z) = phi_u rho_s g cos theta (H - z).

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

from ..config import MuIMaterial, Scene


def steady_inertial_number(material: MuIMaterial, slope_rad: float) -> float:
    """I_u of [M56]; only slopes between arctan(mu_s) and arctan(mu_2) flow steadily."""
    tan = math.tan(slope_rad)
    if not material.mu_s < tan < material.mu_2:
        raise ValueError(f"slope {math.degrees(slope_rad):.2f} deg is outside the steady range "
                         f"({material.static_friction_deg}, {material.limit_friction_deg}) deg")
    return material.reference_inertial_number * (tan - material.mu_s) / (material.mu_2 - tan)


def steady_solid_fraction(material: MuIMaterial, slope_rad: float) -> float:
    I_u = steady_inertial_number(material, slope_rad)
    return material.solid_fraction_max - (material.solid_fraction_max - material.solid_fraction_min) * I_u


def analytic_velocity(z, height: float, material: MuIMaterial, slope_rad: float, g: float) -> np.ndarray:
    """[M56]: down-slope velocity at height z above the bed  [m/s]."""
    z = np.clip(np.asarray(z, float), 0.0, height)
    I_u = steady_inertial_number(material, slope_rad)
    phi_u = steady_solid_fraction(material, slope_rad)
    scale = 2.0 * I_u / (3.0 * material.grain_diameter) * math.sqrt(phi_u * g * math.cos(slope_rad))
    return scale * (height**1.5 - (height - z) ** 1.5)


def analytic_pressure(z, height: float, material: MuIMaterial, slope_rad: float, g: float) -> np.ndarray:
    """Hydrostatic pressure phi_u rho_s g cos(theta) (H - z)  [Pa]."""
    z = np.clip(np.asarray(z, float), 0.0, height)
    phi_u = steady_solid_fraction(material, slope_rad)
    return phi_u * material.grain_density * g * math.cos(slope_rad) * (height - z)


def steady_height(mass_per_length: float, material: MuIMaterial, slope_rad: float, g: float) -> float:
    """Height of the steady layer holding ``mass_per_length`` [kg/m (2D)]  [m]."""
    phi_u = steady_solid_fraction(material, slope_rad)
    height = mass_per_length / (phi_u * material.grain_density)
    for _ in range(20):  # grain compression under the mean pressure (tiny, ~K_t p)
        p_mean = 0.5 * phi_u * material.grain_density * g * math.cos(slope_rad) * height
        height = mass_per_length / (phi_u * material.grain_density * (1.0 + material.grain_compressibility * p_mean))
    return height


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
    heights = np.linspace(top - 2.0 * spacing, top + 2.0 * spacing, 401)
    colour = colour_function_profile(frame, n_material, length, spacing, heights)
    k = int(np.nonzero(colour >= 0.5)[0].max())  # C(top - 2 dp) ~ 1: k exists
    if k + 1 < len(heights):  # linear interpolation to C = 1/2
        k_frac = (colour[k] - 0.5) / (colour[k] - colour[k + 1])
        return float(heights[k] + k_frac * (heights[k + 1] - heights[k]) - bed)
    return float(heights[k] - bed)


def bed_height(scene: Scene) -> float:
    """Height of the bed: the lowest wall, else the bottom of the domain  [m]."""
    return min(w.point[-1] for w in scene.walls) if scene.walls else scene.domain.lower[-1]


def impose_analytic_velocity(sim) -> None:
    """Give every material particle of a fresh inclined-plane simulation the [M56] velocity at
    its height above the bed, with the height of the (packed) layer as H. The steady state does
    not depend on the start; this one is ~15 s closer to it than rest (the run from rest
    relaxes with a time constant of ~15 s: tan(theta) - mu_s is small)."""
    scene = sim.scene
    state = sim.state
    n = state.n_material
    x = state.position.to_numpy()
    v = state.velocity.to_numpy()
    bed = bed_height(scene)
    height = max(b.upper[-1] for b in scene.particles) - bed
    v[:n, 0] = analytic_velocity(x[:n, -1] - bed, height, scene.material, math.radians(scene.gravity.tilt_deg),
                                 scene.gravity.magnitude)
    state.load({"velocity": v})


def relative_l2(simulated: np.ndarray, reference: np.ndarray) -> float:
    """sqrt(sum (s - r)^2 / sum r^2)."""
    return float(np.sqrt(np.sum((simulated - reference) ** 2) / np.sum(reference**2)))


@dataclass
class InclinedPlaneResult:
    velocity_error: float  # relative L2 against [M56]
    pressure_error: float  # relative L2 against hydrostatic
    mach_number: float  # max over the window of |v_i|/c_i
    height: float  # measured flow depth H (colour function 1/2) [m]
    mass_height: float  # depth of the mass at phi_u [m]
    velocity_error_mass_height: float  # relative L2 against [M56] with H = mass_height
    pressure_error_mass_height: float  # relative L2 against hydrostatic with H = mass_height
    surface_velocity: float  # SPH, top layer [m/s]
    surface_velocity_reference: float  # [M56] at the same height [m/s]
    window: tuple  # (t_start, t_end) of the average [s]
    drift: float  # relative change of the profile between the two halves of the window
    profile: Dict[str, np.ndarray] = field(default_factory=dict)

    def report(self) -> str:
        return "\n".join([
            f"inclined plane: steady profile averaged over t = {self.window[0]:.2f}-{self.window[1]:.2f} s",
            f"  flow depth H (colour function 1/2)  {self.height * 1e3:.2f} mm",
            f"  surface velocity SPH / [M56]        {self.surface_velocity:.3f} / "
            f"{self.surface_velocity_reference:.3f} m/s",
            f"  velocity relative L2 error vs [M56] {100 * self.velocity_error:.2f} %",
            f"  pressure relative L2 error vs hydrostatic {100 * self.pressure_error:.2f} %",
            f"  max Mach number |v|/c               {self.mach_number:.3f}",
            f"  profile drift within the window     {100 * self.drift:.2f} %",
            f"  depth of the mass at phi_u          {self.mass_height * 1e3:.2f} mm "
            f"(swelling {100 * (self.height / self.mass_height - 1):+.2f} %)",
            f"  with that depth: velocity {100 * self.velocity_error_mass_height:.2f} %, "
            f"pressure {100 * self.pressure_error_mass_height:.2f} %",
        ])


def binned_profile(frames: Sequence[Dict[str, np.ndarray]], n_material: int, spacing: float,
                   height: float):
    """Mean height, down-slope velocity and pressure of material particles in layers of
    thickness ``spacing`` (over all given frames)."""
    edges = np.arange(0.0, height + spacing, spacing)
    sums = np.zeros((3, len(edges) - 1))
    counts = np.zeros(len(edges) - 1)
    for arrays in frames:
        z = arrays["position"][:n_material, -1]
        k = np.digitize(z, edges) - 1
        ok = (k >= 0) & (k < len(counts))
        counts += np.bincount(k[ok], minlength=len(counts))
        for row, values in enumerate((z, arrays["velocity"][:n_material, 0], arrays["pressure"][:n_material])):
            sums[row] += np.bincount(k[ok], weights=values[ok], minlength=len(counts))
    used = counts > 0
    z_mean, v_mean, p_mean = sums[:, used] / counts[used]
    return z_mean, v_mean, p_mean


def evaluate(scene: Scene, times: Sequence[float], frames: Sequence[Dict[str, np.ndarray]],
             window: float = 1.0) -> InclinedPlaneResult:
    """Errors of the frames within the last ``window`` seconds against [M56] and hydrostatic."""
    material = scene.material
    slope = math.radians(scene.gravity.tilt_deg)
    g = scene.gravity.magnitude
    times = np.asarray(times)
    t_end = float(times.max())
    chosen = [f for t, f in zip(times, frames) if t >= t_end - window - 1e-9]
    chosen_times = times[times >= t_end - window - 1e-9]
    n_material = int(np.sum(chosen[0]["is_wall"] == 0))
    length = scene.domain.size[0]
    mass_per_length = float(np.sum(chosen[-1]["mass"][:n_material])) / length
    mass_height = steady_height(mass_per_length, material, slope, g)
    dp = scene.numerics.particle_spacing
    bed = bed_height(scene)
    height = float(np.mean([flow_depth(f, n_material, length, dp, bed) for f in chosen]))

    top = max(height, mass_height) + dp  # bins reach every particle of the layer
    z, v, p = binned_profile(chosen, n_material, dp, top)
    v_ref = analytic_velocity(z, height, material, slope, g)
    p_ref = analytic_pressure(z, height, material, slope, g)
    half = len(chosen) // 2
    drift = 0.0
    if half >= 1:
        _, v_a, _ = binned_profile(chosen[:half], n_material, dp, top)
        _, v_b, _ = binned_profile(chosen[half:], n_material, dp, top)
        if len(v_a) == len(v_b):
            drift = relative_l2(v_a, v_b)
    mach = 0.0
    for arrays in chosen:
        phi = arrays["solid_fraction"][:n_material]
        c = 1.0 / np.sqrt(material.grain_compressibility * phi * material.grain_density)
        speed = np.linalg.norm(arrays["velocity"][:n_material], axis=1)
        mach = max(mach, float(np.max(speed / c)))
    return InclinedPlaneResult(
        velocity_error=relative_l2(v, v_ref), pressure_error=relative_l2(p, p_ref), mach_number=mach,
        height=height, mass_height=mass_height,
        velocity_error_mass_height=relative_l2(v, analytic_velocity(z, mass_height, material, slope, g)),
        pressure_error_mass_height=relative_l2(p, analytic_pressure(z, mass_height, material, slope, g)), surface_velocity=float(v[-1]), surface_velocity_reference=float(v_ref[-1]),
        window=(float(chosen_times.min()), t_end), drift=drift,
        profile={"z": z, "velocity": v, "velocity_reference": v_ref, "pressure": p, "pressure_reference": p_ref})


def write_profile_csv(result: InclinedPlaneResult, path: Path) -> None:
    from ..output import atomic_write_text
    cols = ["z", "velocity", "velocity_reference", "pressure", "pressure_reference"]
    lines = [",".join(cols)]
    for row in zip(*(result.profile[c] for c in cols)):
        lines.append(",".join(f"{v:.9g}" for v in row))
    atomic_write_text(path, "\n".join(lines) + "\n")
