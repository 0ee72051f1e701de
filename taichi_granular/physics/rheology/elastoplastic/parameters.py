"""The keys of an elastoplastic Mohr-Coulomb material (``material.model: elastoplastic``) and what the model
supports."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar, FrozenSet, Literal, Optional, Tuple

from ....keys import scene_key
from ..base import MaterialParameters


@dataclass(frozen=True, kw_only=True)
class ElastoplasticMaterial(MaterialParameters):
    """Elastic-perfectly-plastic Mohr-Coulomb, Abdelrazek et al. (2016) after Bui et al.
    (2008), MODEL.md section 3."""

    wall_types: ClassVar[Tuple[str, ...]] = ("ghost", "dynamic")
    walls_note: ClassVar[str] = ("extrapolated walls need the hypoplastic model's stress (MODEL.md section 2); "
                                 "the elastoplastic model's walls are dynamic boundary particles")
    obstacle_shapes: ClassVar[Tuple[str, ...]] = ("chute", "box", "post_rows", "cylinder", "wedge", "mesh")
    obstacle_walls: ClassVar[str] = "dynamic"
    numerics_read: ClassVar[FrozenSet[str]] = frozenset({"artificial_stress", "stress_diffusion"})

    model: Literal["elastoplastic"] = scene_key("constitutive model")
    density: float = scene_key("rho_0, bulk density of the unstressed material [A5]", unit="kg/m^3", bounds="[100, 25000]")
    youngs_modulus: float = scene_key("E, Young's modulus [A6]", unit="Pa", bounds="[1e3, 1e12]")
    poisson_ratio: float = scene_key("nu, Poisson's ratio [A6]", unit="-", bounds="[0, 0.5)")
    friction_angle_deg: float = scene_key("phi, internal friction angle of the Mohr-Coulomb strength", unit="deg",
                                          bounds="[0, 90)", hint="degrees, not radians")
    cohesion: float = scene_key("c of S_f = c + p tan(phi) (0 for dry sand; of the order of E keeps the material "
                                "elastic)", 0.0, "Pa", bounds="[0, 1e12]")
    bulk_modulus: Optional[float] = scene_key(
        "K of p = K (rho/rho_0 - 1) [A5]; default 50 rho_0 g H_max, H_max the tallest block", None, "Pa", bounds="(0, 1e12]")

    sound_speed: Literal["longitudinal", "eos"] = scene_key(
        "c of Monaghan's artificial viscosity [A16-19], which [A] calls the speed of sound: longitudinal, the "
        "elastic wave speed sqrt((K + 4G/3)/rho_0) (alpha c then grows as sqrt(E)), or eos, the sound speed "
        "sqrt(K/rho_0) of the soft equation of state [A5] (independent of E). The time step respects the "
        "longitudinal speed either way", "longitudinal")

    def check(self, path: str) -> None:
        """Each key's range is checked by :func:`check_numbers`; no relations between keys."""

    @property
    def wall_friction_deg(self) -> float:
        return self.friction_angle_deg

    @property
    def shear_modulus(self) -> float:
        """G = E/(2(1 + nu))  [Pa]."""
        return self.youngs_modulus / (2.0 * (1.0 + self.poisson_ratio))

    @property
    def friction_coefficient(self) -> float:
        return math.tan(math.radians(self.friction_angle_deg))

    @property
    def reference_density(self) -> float:
        return self.density


PARAMETERS = ElastoplasticMaterial
