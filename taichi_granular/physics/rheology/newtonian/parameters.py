"""The keys of a Newtonian fluid (``material.model: newtonian``) and what the model supports."""
from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar, Literal, Tuple

from ....keys import scene_key
from ..base import MaterialParameters


@dataclass(frozen=True, kw_only=True)
class NewtonianFluid(MaterialParameters):
    """Weakly compressible Newtonian fluid: p = c^2 (rho - rho_0), s = 2 eta dev(D)."""

    wall_types: ClassVar[Tuple[str, ...]] = ("ghost",)
    walls_note: ClassVar[str] = "the toy Newtonian fluid has ghost walls only"

    model: Literal["newtonian"] = scene_key("constitutive model")
    density: float = scene_key("rho_0, density at zero pressure", unit="kg/m^3", bounds="[1, 25000]")
    viscosity: float = scene_key("eta, dynamic viscosity", unit="Pa s", bounds="(0, 1e8]", hint="Pa s: water 1e-3")
    sound_speed: float = scene_key("c of p = c^2 (rho - rho_0); >= 10 times the fastest flow keeps the density "
                                   "within 1 %", unit="m/s", bounds="(0, 1e5]")

    @property
    def reference_density(self) -> float:
        return self.density


PARAMETERS = NewtonianFluid
