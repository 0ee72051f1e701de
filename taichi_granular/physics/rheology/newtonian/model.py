"""The Newtonian fluid's physics: a linear equation of state and a constant viscosity, on the
stages every model shares (continuity, velocity gradient, momentum)."""

import numpy as np
import taichi as ti

from ....state import FieldSpec
from ...strain_rate import deviator
from ..base import Model


@ti.data_oriented
class NewtonianModel(Model):
    """Units: densities kg/m^3, pressures Pa, viscosity Pa s, speeds m/s."""

    name = "newtonian"
    pressure_equation = "p = c^2 (rho - rho_0)"
    # the constant viscosity, in the field the momentum stage's residual damping reads
    fields = (FieldSpec("viscosity", "scalar", "dynamic viscosity eta", "Pa s", "material"),)

    def __init__(self, material, dim: int, smoothing_length: float, state=None):
        super().__init__(material, dim, smoothing_length, state)
        self.rho_0 = material.density
        self.eta = material.viscosity
        self.c = material.sound_speed

    @classmethod
    def from_scene(cls, scene):
        return cls(scene.material, scene.dimension, scene.numerics.smoothing_length)

    def initial_fields(self, initial) -> dict:
        return {"viscosity": np.full(initial.n_material, self.eta)}

    @ti.func
    def pressure_of(self, density):
        """p = c^2 (rho - rho_0)  [Pa]."""
        return self.c * self.c * (density - self.rho_0)

    @ti.func
    def viscous_stress(self, viscosity, grad_v):
        """s = 2 eta dev(D) of a velocity gradient  [Pa]."""
        return viscosity * deviator(grad_v + grad_v.transpose())

    @ti.func
    def deviatoric_stress(self, k):
        return self.viscous_stress(self.eta, self.state.velocity_gradient[k])

    @ti.func
    def sound_speed(self, k):
        return self.c

    @ti.func
    def stable_time_step(self, i):
        """min(h/c, 0.1 rho h^2/eta), the acoustic and viscous limits (the CFL factor is applied by
        the caller)  [s]."""
        return ti.min(self.h / self.c, 0.1 * self.state.density[i] * self.h**2 / self.eta)

    @ti.func
    def density_error(self, i):
        return self.state.density[i] / self.rho_0 - 1.0

    def initial_density(self, pressure: np.ndarray) -> np.ndarray:
        return self.rho_0 + np.asarray(pressure, float) / self.c**2

    def reference_density(self) -> float:
        return self.rho_0

    def reference_sound_speed(self) -> float:
        return self.c

    def faster_sound(self, factor: float) -> list:
        return [("material.sound_speed", self.c * factor)]

    def stage_classes(self, scene):
        from ...continuity import Continuity
        from ...equation_of_state import DensityPressure
        from ...momentum import MOMENTUM
        from ...strain_rate import StrainRate
        return [Continuity, StrainRate, DensityPressure, MOMENTUM[scene.numerics.momentum]]


MODEL = NewtonianModel
