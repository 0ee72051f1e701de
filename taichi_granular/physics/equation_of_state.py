"""The equation-of-state stage of models whose pressure is a function of the density alone
(``model.pressure_of(rho)``: the elastoplastic [A5], the toy Newtonian fluid)."""
import taichi as ti

from .. import runtime
from .stage import Stage


@ti.data_oriented
class DensityPressure(Stage):
    """p = model.pressure_of(rho) for every particle whose density evolves: the material, and
    dynamic boundary particles where the scene has them (the density rate spans them then)."""

    name = "linear_pressure"
    slot = "eos"
    category = "eos"

    def __init__(self, ctx):
        super().__init__(ctx)
        self.equation = ctx.model.pressure_equation  # the tag or formula the model's docs give

    @ti.kernel
    def _run(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.density_rate.shape[0]):
            self.state.pressure[i] = self.model.pressure_of(self.state.density[i])
