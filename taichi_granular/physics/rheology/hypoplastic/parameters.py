"""The keys of a hypoplastic + Bagnold material (``material.model: hypoplastic``), the parameter tables of
[P] and what the model supports."""
from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, FrozenSet, Literal, Optional, Tuple

from ....keys import ConfigError, scene_key
from ..base import MaterialParameters


# The parameter tables of [P] (MODEL.md section 2): c1..c4, e_min, (p1, p2, p3), (q1, q2, q3),
# k_v, alpha_i. p3 and q3 in 1/kPa. The annular shear cell takes k_v from its solid fraction.
PARAMETER_SETS = {
    "set1": dict(constants=(-50.0, -629.6, -629.6, 1220.8), min_void_ratio=0.597,
                 critical_void_ratio=(0.53, 0.45, -0.0018), density_exponent=(1.0, -0.4, -0.0001),
                 bagnold_coefficient=0.01, dispersion_angle_deg=35.0),
    "set2": dict(constants=(-66.7, -832.9, -832.9, 1594.5), min_void_ratio=0.597,
                 critical_void_ratio=(0.53, 0.45, -0.0011), density_exponent=(1.0, -0.4, -0.0001),
                 bagnold_coefficient=0.1, dispersion_angle_deg=33.0),
    "annular": dict(constants=(-50.0, -746.6, -746.6, 1855.1), min_void_ratio=0.563,
                    critical_void_ratio=(0.65, 0.55, -0.11), density_exponent=(1.0, -0.24, -0.013),
                    bagnold_coefficient=None, dispersion_angle_deg=27.0),
}


@dataclass(frozen=True, kw_only=True)
class HypoplasticMaterial(MaterialParameters):
    """Unified hypoplastic + Bagnold model of Peng et al. (2016), MODEL.md section 2.

    ``parameter_set`` fills every constant from a [P] table (set1: simple shear; set2: incline,
    drum, pile; annular: the shear cell); a constant given explicitly overrides the table."""

    wall_types: ClassVar[Tuple[str, ...]] = ("extrapolated",)
    walls_note: ClassVar[str] = ("the hypoplastic model of [P] uses extrapolated walls, and extrapolated walls "
                                 "need its stress (MODEL.md section 2)")
    obstacle_shapes: ClassVar[Tuple[str, ...]] = ("drum", "chute", "box", "post_rows", "cylinder", "wedge", "mesh")
    obstacle_walls: ClassVar[str] = "extrapolated"  # [P]'s wall particles, extrapolated from the material
    numerics_read: ClassVar[FrozenSet[str]] = frozenset({"artificial_stress", "stress_diffusion", "stress_increment",
                                                         "bulk_viscosity", "residual_damping"})

    model: Literal["hypoplastic"] = scene_key("constitutive model")
    parameter_set: Optional[Literal["set1", "set2", "annular"]] = scene_key(
        "a parameter table of [P] supplying the constants below (set1, set2, annular)", None)
    grain_density: float = scene_key("rho_s, density of the grain material", unit="kg/m^3", bounds="[100, 25000]")
    grain_diameter: float = scene_key("d, grain diameter of the Bagnold stress", unit="m", bounds="(0, 0.05]",
                                      hint="metres: 3 mm = 3e-3")
    initial_void_ratio: float = scene_key("e_0, void ratio at t = 0 (bulk density rho_s/(1 + e_0))", unit="-",
                                          bounds="(0, 5]")
    constants: Optional[Tuple[float, ...]] = scene_key("c1, c2, c3, c4 of the Wu-Bauer-Kolymbas rate law", None, "-",
                        bounds="[-1e5, 1e5]")
    min_void_ratio: Optional[float] = scene_key("e_min of D_c = (e - e_min)/(e_crt - e_min)", None, "-", bounds="(0, 5]")
    critical_void_ratio: Optional[Tuple[float, ...]] = scene_key(
        "p1, p2, p3 of e_crt = p1 + p2 exp(p3 |tr T_s|), |tr T_s| in kPa, p3 in 1/kPa", None, bounds="[-100, 100]")
    density_exponent: Optional[Tuple[float, ...]] = scene_key(
        "q1, q2, q3 of a = q1 + q2 exp(q3 |tr T_s|) in I_e = (1 - a) D_c + a, q3 in 1/kPa", None, bounds="[-100, 100]")
    bagnold_coefficient: Optional[float] = scene_key("k_v of the collisional (Bagnold) stress", None, "-", bounds="[0, 10]")
    dispersion_angle_deg: Optional[float] = scene_key(
        "alpha_i, p_v = tau_v/tan(alpha_i) of the Bagnold stress", None, "deg", bounds="(0, 90)", hint="degrees, not radians")
    wave_speed: float = scene_key("c of the time step dt = chi h/c (chi: numerics.cfl) and of the artificial "
                                  "viscosity [P]", 80.0, "m/s", bounds="[1, 1e4]", hint="m/s; [P] uses 80")
    tension_guard: float = scene_key("eps: where tr T_s > -eps, T_s is reset to -(eps/3) I (choice, MODEL.md section 2)",
                                     1.0, "Pa", bounds="(0, 1e4]", hint="Pa: a few")

    def __post_init__(self):
        if self.parameter_set is not None:
            for key, value in PARAMETER_SETS[self.parameter_set].items():
                if getattr(self, key) is None:
                    object.__setattr__(self, key, value)

    def check(self, path: str) -> None:
        for key in ("constants", "min_void_ratio", "critical_void_ratio", "density_exponent",
                    "bagnold_coefficient", "dispersion_angle_deg"):
            if getattr(self, key) is None:
                raise ConfigError(f"{path}.{key}", "missing: give it, or a parameter_set that supplies it")
        for key, n in (("constants", 4), ("critical_void_ratio", 3), ("density_exponent", 3)):
            if len(getattr(self, key)) != n:
                raise ConfigError(f"{path}.{key}", f"expected {n} numbers, got {len(getattr(self, key))}")
        if not self.initial_void_ratio > self.min_void_ratio:
            raise ConfigError(f"{path}.initial_void_ratio",
                              f"e_0 = {self.initial_void_ratio} must exceed e_min = {self.min_void_ratio}")
        p1, p2, p3 = self.critical_void_ratio
        if p3 > 0.0 or self.density_exponent[2] > 0.0:
            raise ConfigError(f"{path}.critical_void_ratio" if p3 > 0.0 else f"{path}.density_exponent",
                              "the exponent (third number, 1/kPa) must be <= 0: e_crt and a fall with pressure")
        if not p1 + p2 > self.min_void_ratio:
            raise ConfigError(f"{path}.critical_void_ratio", "e_crt at zero stress (p1 + p2) must exceed e_min")

    @property
    def reference_density(self) -> float:
        """Bulk density at the initial void ratio, rho_s/(1 + e_0)  [kg/m^3]."""
        return self.grain_density / (1.0 + self.initial_void_ratio)


PARAMETERS = HypoplasticMaterial
