"""The sections of a scene that are not about the material or the solids: the domain, gravity,
numerics, the run and the frames (keys.py says how a key is declared)."""
from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import Literal, Optional, Tuple

from .keys import AXES, ConfigError, check_vector, scene_key


@dataclass(frozen=True, kw_only=True)
class Domain:
    """Axis-aligned box holding every particle (walls included)."""

    lower: Tuple[float, ...] = scene_key("lower corner of the box", unit="m", bounds="[-1e5, 1e5]")
    upper: Tuple[float, ...] = scene_key("upper corner of the box", unit="m", bounds="[-1e5, 1e5]")
    periodic: Tuple[str, ...] = scene_key("periodic axes, e.g. [x]", ())
    outflow: bool = scene_key("open faces: material leaving the box is taken out of the flow and counted "
                              "(physics/outflow.py) instead of stopping the run", False)

    def check(self, path: str, dim: int) -> None:
        check_vector(f"{path}.lower", self.lower, dim)
        check_vector(f"{path}.upper", self.upper, dim)
        for a, (lo, hi) in enumerate(zip(self.lower, self.upper)):
            if not hi > lo:
                raise ConfigError(f"{path}.upper", f"upper[{a}]={hi} must exceed lower[{a}]={lo}")
        for name in self.periodic:
            if name not in AXES[:dim]:
                raise ConfigError(f"{path}.periodic", f"unknown axis {name!r}; use {list(AXES[:dim])}")
        if len(set(self.periodic)) != len(self.periodic):
            raise ConfigError(f"{path}.periodic", "axis listed twice")

    @property
    def periodic_mask(self) -> Tuple[bool, ...]:
        return tuple(ax in self.periodic for ax in AXES[: len(self.lower)])

    @property
    def size(self) -> Tuple[float, ...]:
        return tuple(hi - lo for lo, hi in zip(self.lower, self.upper))


@dataclass(frozen=True, kw_only=True)
class Gravity:
    """Gravity of the given magnitude, tilted from -y (2D) or -z (3D) towards +x.

    A tilt of theta models a slope of angle theta whose down-slope direction is +x and
    whose bed normal is the vertical axis of the domain.
    """

    magnitude: float = scene_key("magnitude of gravitational acceleration", 9.81, "m/s^2", bounds="[0, 1000]",
                                 hint="m/s^2: 9.81 on Earth, up to 100 g in a centrifuge")
    tilt_deg: float = scene_key("slope angle: tilt of gravity towards +x", 0.0, "deg", bounds="(-90, 90)",
                                hint="degrees, not radians")

    def vector(self, dim: int) -> Tuple[float, ...]:
        t = math.radians(self.tilt_deg)
        g = [0.0] * dim
        g[0] = self.magnitude * math.sin(t)
        g[dim - 1] = -self.magnitude * math.cos(t)
        return tuple(g)


@dataclass(frozen=True, kw_only=True)
class ArtificialViscosity:
    """Monaghan artificial viscosity [M38]; alpha = beta = 0 removes the stage altogether."""

    alpha: float = scene_key("linear coefficient (0.05 on the inclined plane of [M])", 0.0, "-", bounds="[0, 10]")
    beta: float = scene_key("quadratic coefficient (0 in [M], 1 in [A])", 0.0, "-", bounds="[0, 10]")

    @property
    def enabled(self) -> bool:
        return self.alpha > 0 or self.beta > 0


@dataclass(frozen=True, kw_only=True)
class ArtificialStress:
    """Artificial stress against the tensile instability (Gray, Monaghan & Swift 2001), for
    models with a stress tensor; epsilon = 0 removes the stage altogether."""

    epsilon: float = scene_key("epsilon of R_a = -epsilon sigma_a/rho^2 for tensile principal stresses (0 = off; "
                               "Gray et al. use 0.3)", 0.0, "-", bounds="[0, 1]")
    exponent: float = scene_key("n of the weight (W(r)/W(dp))^n", 4.0, "-", bounds="[1, 8]")

    @property
    def enabled(self) -> bool:
        return self.epsilon > 0.0


@dataclass(frozen=True, kw_only=True)
class ParticleShifting:
    """Particle shifting (after Lind et al. 2012): each step a particle moves by
    dr_i = -coefficient h c_i dt grad C_i down its concentration gradient, at most the Newton
    step on C (where C is stiff a longer step overshoots and flips the particle back and forth:
    physics/shifting.py), its velocity is carried along by a Taylor correction; on and next to
    a free surface only the component along the surface is kept.
    coefficient = 0 removes the stage altogether."""

    coefficient: float = scene_key("zeta in dr = -zeta h c dt grad C (0 = off; 0.2 keeps sheared layers ordered)",
                                   0.2, "-", bounds="[0, 1]")
    free_surface_threshold: float = scene_key(
        "particles whose kernel sum (Shepard) falls below this, with a direction free of neighbours, are on the free surface (shift along it only)",
        0.9, "-", bounds="[0.5, 1]")
    conserve_momentum: bool = scene_key(
        "remove the net momentum the Taylor velocity correction adds (exact conservation in closed systems; in a "
        "sheared layer whose particles drift across the shear it slows the whole layer: the Table 2 plane ran "
        "6.7 % off [M56] with it, 2.8 % without, measured)", False)

    @property
    def enabled(self) -> bool:
        return self.coefficient > 0


@dataclass(frozen=True, kw_only=True)
class Numerics:
    particle_spacing: float = scene_key("dp, initial lattice spacing of particles", unit="m", bounds="[1e-5, 10]",
                                        hint="metres")
    smoothing_length_ratio: float = scene_key("h/dp", 1.3, "-", bounds="[1, 3]")
    smoothing_function: Literal["wendland_c2", "wendland_c6", "cubic_spline"] = scene_key(
        "SPH smoothing function (MODEL.md section 0)", "wendland_c2")
    cfl: float = scene_key("Courant number of the time step [M39]", 0.5, "-", bounds="(0, 1]", hint="a stable explicit step")
    integrator: Literal["symplectic_verlet", "predictor_corrector"] = scene_key(
        "time integration scheme", "symplectic_verlet")
    momentum: Literal["stress_divergence", "viscous_pair"] = scene_key(
        "stress_divergence: sum m (sigma_i/rho_i^2 + sigma_j/rho_j^2) grad W; viscous_pair: [M27]",
        "stress_divergence")
    viscosity: Literal["explicit", "implicit"] = scene_key(
        "mu(I) viscous term: explicit (the step obeys the viscous limit of [M39]) or implicit (the viscosity above "
        "that limit solved each step by TR-BDF2 or the theta-method (numerics.viscous_scheme), BiCGSTAB: only the acoustic limit sets the step, 90-270x "
        "fewer steps on the collapses; physics/implicit_viscosity.py). The run-outs and front stops of the coarse "
        "study match the explicit ones with TR-BDF2, but the implicit deposits creep faster after the front stops "
        "(a = 0.9 at dp 9 mm: 13 against 3.5 mm/s; measured), so explicit stays the default (docs, column collapse)",
        "explicit")
    viscous_tolerance: float = scene_key(
        "implicit viscosity: the solve stops when |residual| <= this x |v*| (the velocities before the viscous "
        "update; against 1e-6, 1e-4 moves the velocities of a collapse by 5e-4 of their largest, measured)",
        1e-4, "-", bounds="[1e-14, 0.1]")
    viscous_max_iterations: int = scene_key("implicit viscosity: the most BiCGSTAB iterations of one solve; a solve "
                                            "that needs more stops the run", 200, bounds="[1, 1e5]")
    viscous_picard_iterations: int = scene_key(
        "implicit viscosity: solves per step; after each but the last the strain rate and the viscosity are "
        "re-evaluated at the mid-step velocity (v(n) + v(n+1))/2 (Picard iteration on eta, which one solve "
        "lags by half a step)", 1, bounds="[1, 20]")
    viscous_scheme: Literal["theta", "tr_bdf2"] = scene_key(
        "implicit viscosity: the time integration of the viscous term: tr_bdf2 (a trapezoidal stage and a BDF2 "
        "stage, two solves a step of the same matrix: second order, and damping the stiff modes fully like backward "
        "Euler; the a = 2.75 collapse's front stops within 2.4 % of the explicit one's at 14.58 mm) or theta (the "
        "theta-method, numerics.viscous_theta, one solve a step; physics/implicit_viscosity.py)", "tr_bdf2")
    viscous_theta: float = scene_key(
        "implicit viscosity with viscous_scheme theta: the weight of the new velocity in the viscous update, "
        "v(n+1) = v* + dt L (theta v(n+1) + "
        "(1 - theta) v(n)); 1 is backward Euler (first order: at the acoustic step the a = 2.75 collapse's front "
        "stopped 13 % earlier than the explicit one), 0.6 removes four fifths of that error and still damps the stiff "
        "modes (by 0.67 a step; 1/2 would not damp them: physics/implicit_viscosity.py)", 0.6, "-",
        bounds="(0.5, 1]")
    neighbour_skin: float = scene_key(
        "Verlet-list skin as a fraction of h: each particle's neighbours within 2h + skin are listed and the "
        "list rebuilt only when a particle has moved more than half the skin (neighbours.py; 0.3: 3D coarse collapse "
        "1.5x, 2D 160k block 1.1-1.4x faster than scanning the cells, measured); 0 scans the cells in every pair "
        "loop", 0.3, "-", bounds="[0, 2]")
    reorder_every: int = scene_key(
        "every this many steps the material particles' fields are sorted by neighbour cell (counting sort), so that "
        "neighbours lie close in memory as the flow mixes them (state.py ParticleOrder; outputs stay in the initial "
        "order, by particle_id); 0 never", 100, "steps", bounds="[0, 1e9]")
    gradient_correction: Literal["scalar", "matrix", "none"] = scene_key(
        "kernel gradient renormalisation: full matrix M^-1 (exact for linear fields, also at walls and "
        "free surfaces), scalar d/tr(M), or none", "matrix")
    artificial_viscosity: ArtificialViscosity = scene_key("Monaghan artificial viscosity [M38]", ArtificialViscosity())
    density_diffusion: float = scene_key(
        "delta of the delta-SPH density diffusion term in the continuity equation (0 = off)", 0.02, "-", bounds="[0, 1]")
    stress_diffusion: float = scene_key(
        "delta_s of the diffusion of integrated stress tensors (physics/stress_diffusion.py; 0 = off; "
        "models with a stress history only)", 0.0, "-", bounds="[0, 1]")
    bulk_viscosity: float = scene_key(
        "alpha_b of a numerical bulk viscosity, T += alpha_b rho c h tr(D) I, that resists compaction and dilation "
        "but not shear (hypoplastic model only; 0 = off; physics/rheology/hypoplastic/model.py)", 0.0, "-", bounds="[0, 5]")
    stress_increment: float = scene_key(
        "largest relative change |dT_s/dt| dt / |T_s| of the frictional stress in one step, a time-step bound "
        "(hypoplastic model only; 0 = off; physics/rheology/hypoplastic/model.py)", 0.0, "-", bounds="[0, 10]")
    residual_damping: float = scene_key(
        "strength of the momentum equation's damping of the particle-scale velocity residual, as a fraction of the "
        "secant viscosity |T*|/gamma_dot (hypoplastic model only; 1 = the full secant; "
        "physics/rheology/hypoplastic/model.py)", 1.0, "-", bounds="(0, 1]")
    particle_shifting: ParticleShifting = scene_key("particle shifting against particle-scale disorder",
                                                    ParticleShifting())
    artificial_stress: ArtificialStress = scene_key("artificial stress against the tensile instability (models with "
                                                    "a stress tensor)", ArtificialStress())
    min_time_step: float = scene_key("the run stops if the stable time step falls below this", 1e-9, "s", bounds="(0, 0.1]")

    @property
    def smoothing_length(self) -> float:
        return self.particle_spacing * self.smoothing_length_ratio

    @property
    def implicit_viscosity(self) -> bool:
        """Whether the viscous term is solved implicitly (physics/implicit_viscosity.py)."""
        return self.viscosity == "implicit"


@dataclass(frozen=True, kw_only=True)
class Run:
    end_time: float = scene_key("simulated time to reach", unit="s", bounds="(0, 1e6]")
    output_interval: float = scene_key("simulated time between frames (VTU, diagnostics)", unit="s", bounds="(0, 1e6]")
    output_dir: Optional[str] = scene_key("where outputs go (default output/<scene name>)", None)
    write_vtu: bool = scene_key("write a VTU particle file per frame (a .pvd series)", True)
    max_steps: Optional[int] = scene_key("stop after this many steps (default: no limit)", None, bounds="[1, 1e12]")
    mach_warning: float = scene_key(
        "warn once when the max Mach number |v|/c of a frame exceeds this, with the compressibility that "
        "keeps the flow below it (weakly compressible SPH wants Mach < ~0.3; mach.py)", 0.3, "-", bounds="(0, 10]")
    stop_at_rest: Optional[float] = scene_key(
        "stop once the kinetic energy, checked at each output, has fallen below this fraction of its peak "
        "(e.g. 1e-3 for a collapse at rest; default: run to end_time)", None, "-", bounds="(0, 1)")
    checkpoint_every: int = scene_key(
        "write the checkpoint (checkpoint.npz, atomically) every this many frames; `taichi-granular resume` "
        "continues from it", 1, bounds="[1, 1e9]")
    guard: Literal["step", "stage"] = scene_key(
        "when the run-time guard checks every particle for NaN/Inf, leaving the domain and an implausible "
        "density: after each step, or after every stage of it (names the stage that went wrong; slower)", "step")
    guard_every: int = scene_key(
        "with guard: step, check every this many steps (and before every frame): one host synchronisation "
        "fewer per step on a GPU; a failure then names the steps within which it arose", 1, bounds="[1, 1e6]")



@dataclass(frozen=True, kw_only=True)
class Camera:
    """Pinhole camera of 3D frames."""

    position: Tuple[float, ...] = scene_key("eye position", unit="m", bounds="[-1e5, 1e5]")
    look_at: Tuple[float, ...] = scene_key("point at the centre of the image", unit="m", bounds="[-1e5, 1e5]")
    up: Tuple[float, ...] = scene_key("direction that appears upwards", (0.0, 0.0, 1.0), bounds="[-1e3, 1e3]")
    field_of_view_deg: float = scene_key("vertical field of view", 40.0, "deg", bounds="[1, 170]")

    def check(self, path: str) -> None:
        for key in ("position", "look_at", "up"):
            check_vector(f"{path}.{key}", getattr(self, key), 3)
        if math.dist(self.position, self.look_at) == 0.0:
            raise ConfigError(f"{path}.look_at", "must differ from the camera position")


BYTES_PER_PARTICLE = 1024  # host + device bytes per particle, with margin (``describe``: 0.3-0.6 KiB of fields)
BYTES_PER_CELL = 16  # neighbour grid: start, count, cursor, fixed start (int32)


def max_particles() -> int:
    """The most particles this machine's memory holds (at BYTES_PER_PARTICLE each)."""
    try:
        memory = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, OSError, ValueError):  # not POSIX: assume 16 GiB
        memory = 16 * 2**30
    return int(memory // BYTES_PER_PARTICLE)


COLOUR_BAR_MARGIN = 120  # px right of a 2D view for the colour bar and its labels
MIN_VIEW_PX = 32  # px: the narrowest particle view worth rendering
MAX_FRAME_PX = 8192  # px: the largest frame side


@dataclass(frozen=True, kw_only=True)
class Render:
    """PNG frames (render/): particles coloured by a field, walls grey, time and colour bar."""

    frames: bool = scene_key("write a PNG frame at every output time of a run", True)
    width: int = scene_key("image width", 800, "px", bounds="[32, 8192]")
    height: Optional[int] = scene_key("image height (default: 2D from the view's aspect, 3D 3/4 of the width)", None,
                                      "px", bounds="[32, 8192]")
    colour_by: str = scene_key("particle field to colour by: speed, pressure, inertial_number, any output field "
                               "(vectors by magnitude)", "speed")
    range: Optional[Tuple[float, float]] = scene_key("fixed colour range [min, max] (default: each frame's own)", None,
                    bounds="[-1e15, 1e15]")
    view_lower: Optional[Tuple[float, ...]] = scene_key("2D: lower corner of the view (default domain)", None, "m",
                         bounds="[-1e5, 1e5]")
    view_upper: Optional[Tuple[float, ...]] = scene_key("2D: upper corner of the view (default domain)", None, "m",
                         bounds="[-1e5, 1e5]")
    camera: Optional[Camera] = scene_key("3D: camera (default: from the front-left, above the domain)", None)

    def view_box(self, domain: Domain) -> Tuple[Tuple[float, ...], Tuple[float, ...]]:
        """2D: the (lower, upper) corners in metres that the frame shows."""
        return (self.view_lower or domain.lower, self.view_upper or domain.upper)

    def frame_size(self, domain: Domain, dim: int) -> Tuple[int, int, int]:
        """(frame width, frame height, width of the particle view) in pixels; a 2D frame keeps
        COLOUR_BAR_MARGIN px on the right for the colour bar and its labels."""
        if dim == 3:
            return self.width, self.height or int(0.75 * self.width), self.width
        view_width = self.width - COLOUR_BAR_MARGIN
        lower, upper = self.view_box(domain)
        pixel = (upper[0] - lower[0]) / max(view_width, 1)  # metres per pixel
        height = self.height or max(2 * COLOUR_BAR_MARGIN, int(math.ceil((upper[1] - lower[1]) / pixel)))
        return self.width, height, view_width

    def check(self, path: str, dim: int, domain: Domain) -> None:
        if dim == 2 and self.width < COLOUR_BAR_MARGIN + MIN_VIEW_PX:
            raise ConfigError(f"{path}.width", f"a 2D frame needs at least {COLOUR_BAR_MARGIN + MIN_VIEW_PX} px: "
                                               f"{COLOUR_BAR_MARGIN} px for the colour bar and {MIN_VIEW_PX} for the "
                                               f"particles; got {self.width}")
        if self.range is not None and not self.range[0] < self.range[1]:
            raise ConfigError(f"{path}.range", f"needs min < max, got {list(self.range)}")
        for key in ("view_lower", "view_upper"):
            if getattr(self, key) is not None:
                check_vector(f"{path}.{key}", getattr(self, key), 2)
        if (self.view_lower is None) != (self.view_upper is None):
            raise ConfigError(f"{path}.view_lower", "give both view_lower and view_upper, or neither")
        if self.view_lower is not None and not all(a < b for a, b in zip(self.view_lower, self.view_upper)):
            raise ConfigError(f"{path}.view_upper", "must lie above view_lower on every axis")
        if self.camera is not None:
            if dim != 3:
                raise ConfigError(f"{path}.camera", "only 3D scenes have a camera")
            self.camera.check(f"{path}.camera")
        height = self.frame_size(domain, dim)[1]
        if height > MAX_FRAME_PX:
            raise ConfigError(f"{path}.height", f"the view's aspect gives frames {height} px high (at most "
                                                f"{MAX_FRAME_PX}); set render.height or a narrower view")
