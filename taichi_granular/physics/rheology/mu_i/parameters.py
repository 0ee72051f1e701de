"""The keys of a mu(I) material (``material.model: mu_i``) and what the model supports."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar, Dict, FrozenSet, Literal, Tuple

from ....keys import ConfigError, scene_key
from ..base import MaterialParameters


@dataclass(frozen=True, kw_only=True)
class MuIMaterial(MaterialParameters):
    """mu(I) rheology with compressible grains, Minatti & Paris (2015), MODEL.md section 1."""

    # ghost walls are [M]'s [M34]-[M36]; solids of any shape are dynamic boundary particles, whose
    # pressure comes from the grain EOS at rest (docs/models/mu_i.md, walls and obstacles)
    wall_types: ClassVar[Tuple[str, ...]] = ("ghost", "dynamic")
    walls_note: ClassVar[str] = ("the mu(I) model's walls are ghost particles [M34]-[M36] or, with obstacles, "
                                 "dynamic boundary particles")
    obstacle_shapes: ClassVar[Tuple[str, ...]] = ("chute", "box", "post_rows", "cylinder", "wedge", "mesh")
    obstacle_walls: ClassVar[str] = "dynamic"  # the boundary model obstacles are laid as
    numerics_read: ClassVar[FrozenSet[str]] = frozenset({"implicit_viscosity"})
    deposit_creeps: ClassVar[bool] = True  # the regularised viscosity [M48] is finite below yield
    symbols: ClassVar[Dict[str, str]] = {
        "mu_s": "static_friction_deg (the angle arctan(mu_s))", "mu_2": "limit_friction_deg (the angle arctan(mu_2))",
        "I_0": "reference_inertial_number", "i_0": "reference_inertial_number",
        "phi_max": "solid_fraction_max", "phi_min": "solid_fraction_min",
        "K_t": "grain_compressibility", "k_t": "grain_compressibility",
        "tau_0": "max_yield_stress", "m_0": "regularisation_time",
        "rho_s0": "grain_density", "rho_s": "grain_density", "d0": "grain_diameter", "d": "grain_diameter",
    }

    model: Literal["mu_i"] = scene_key("constitutive model")
    grain_density: float = scene_key("rho_s0, density of the grain material at zero pressure", unit="kg/m^3",
                                     bounds="[100, 25000]")
    grain_diameter: float = scene_key("d0, grain diameter at zero pressure", unit="m", bounds="(0, 0.05]",
                                      hint="metres: 0.5 mm = 0.5e-3")
    static_friction_deg: float = scene_key("arctan(mu_s), static friction angle [M7]", unit="deg", bounds="[1, 90)",
                                           hint="degrees, not radians, not tan")
    limit_friction_deg: float = scene_key("arctan(mu_2), limiting friction angle at large I [M7]", unit="deg",
                                          bounds="[1, 90)", hint="degrees, not radians, not tan")
    reference_inertial_number: float = scene_key("I_0 of [M7]", unit="-", bounds="[1e-3, 10]",
                                                 hint="Table 1 of [M]: 0.279-2.65")
    solid_fraction_max: float = scene_key("phi_max, solid fraction at I = 0 [M8]", 0.6, "-", bounds="(0, 1]")
    solid_fraction_min: float = scene_key("phi_min, solid fraction at I = 1 [M8]", 0.5, "-", bounds="(0, 1)")
    grain_compressibility: float = scene_key("K_t, artificial grain compressibility [M41]", unit="1/Pa",
                                             bounds="[1e-12, 1e-3]", hint="1/Pa; the papers' K_t lie in 2e-6 to 9e-5")
    max_yield_stress: float = scene_key("tau_0, largest yield stress expected [M53]", unit="Pa", bounds="(0, 1e8]")
    regularisation_time: float = scene_key("m_0, regularisation parameter [M48], [M55]", 1.0, "s", bounds="(0, 1e4]")

    def check(self, path: str) -> None:
        """Relations between keys (each key's own range is checked by :func:`check_numbers`)."""
        if not self.limit_friction_deg > self.static_friction_deg:
            raise ConfigError(f"{path}.limit_friction_deg",
                              "mu_2 must exceed mu_s: limit_friction_deg > static_friction_deg")
        if not self.solid_fraction_min < self.solid_fraction_max:
            raise ConfigError(f"{path}.solid_fraction_min",
                              "phi_min must lie in (0, phi_max): solid_fraction_min < solid_fraction_max")

    def check_scene(self, scene) -> None:
        """The implicit viscous update runs in the symplectic Verlet kick and its operator knows
        ghost walls only; the [M27] pair form reads a boundary particle's viscosity, which only
        ghosts (carrying the material's) have."""
        dynamic = any(w.type == "dynamic" for w in scene.walls) or bool(scene.obstacles)
        if scene.numerics.viscosity == "implicit":
            if scene.numerics.integrator != "symplectic_verlet":
                raise ConfigError("numerics.viscosity", "the implicit viscous update runs in the symplectic Verlet "
                                                        "kick; set numerics.integrator: symplectic_verlet")
            theta_set = scene.numerics.viscous_theta != type(scene.numerics).viscous_theta  # not the default
            if scene.numerics.viscous_scheme != "theta" and theta_set:
                raise ConfigError("numerics.viscous_theta", "it weighs the theta-method's update, which "
                                                            "numerics.viscous_scheme: theta selects (tr_bdf2 has no theta)")
            if dynamic:
                raise ConfigError("numerics.viscosity", "the implicit viscous update supports ghost walls only, not "
                                                        "dynamic boundary particles (walls of type dynamic, "
                                                        "obstacles); set it to explicit")
        if dynamic and scene.numerics.momentum != "stress_divergence":
            raise ConfigError("numerics.momentum", "dynamic boundary particles (walls of type dynamic, obstacles) "
                                                   "need the stress_divergence form: the viscous_pair form reads "
                                                   "a viscosity that boundary particles do not carry")

    def speed_scale(self, scene):
        """A layer periodic along a slope in the steady range: the [M56] surface speed of its
        depth (m/s, and where it comes from); else None."""
        from .steady import analytic_velocity

        slope = math.radians(scene.gravity.tilt_deg)
        if "x" in scene.domain.periodic and scene.gravity.tilt_deg > 0.0 and self.mu_s < math.tan(slope) < self.mu_2:
            dim = scene.dimension
            height = max(b.upper[dim - 1] for b in scene.particles) - min(b.lower[dim - 1] for b in scene.particles)
            return (float(analytic_velocity(height, height, self, slope, scene.gravity.magnitude)),
                    f"[M56] surface speed of the {height:g} m layer")
        return None

    @property
    def wall_friction_deg(self) -> float:
        return self.static_friction_deg

    @property
    def mu_s(self) -> float:
        return math.tan(math.radians(self.static_friction_deg))

    @property
    def mu_2(self) -> float:
        return math.tan(math.radians(self.limit_friction_deg))

    @property
    def reference_density(self) -> float:
        """Bulk density of packed grains at zero pressure, phi_max rho_s0 [kg/m^3]."""
        return self.solid_fraction_max * self.grain_density


PARAMETERS = MuIMaterial
