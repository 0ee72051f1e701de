"""Diffusion of the integrated stress (``numerics.stress_diffusion``), the stress analogue of
the delta-SPH density diffusion (physics/continuity.py):

    ds_i/dt += delta_s h c sum_j 2 (s_j - s_i) (x_ji . grad_i W_ij) / (r_ij^2 + 0.01 h^2) V_j,

over material neighbours, for every tensor the model integrates in time (``model.history``:
the deviatoric stress of [A6]); c is the model's elastic wave speed.

Why: the SPH velocity gradient [A13] of a particle does not see a pattern that alternates
from one lattice row to the next (the rows above and below cancel), and the stress-form
momentum [A12] exerts no force for such a stress pattern either. Once the start-up transient
(walls taking up the load, the free surface) excites it, it stays: measured on a 2D layer of
8 rows at rest, s_xx alternates +-100 Pa from row to row (15 % of rho g H), so that every
other row sits at 40-70 % of its strength, and on a 20 deg slope (phi = 30 deg) the rows
alternate between 30 % and 100 % mobilised and the layer creeps down-slope at 5-8 mm/s,
accelerating. The term is a Laplacian of s: it vanishes for linear stress fields (the
hydrostatic and the slope's stress) and damps the row-to-row mode fastest.
"""
import taichi as ti

from .. import runtime

from .stage import Stage


@ti.data_oriented
class StressDiffusion(Stage):
    name = "stress_diffusion"
    slot = "rheology"
    category = "rheology"
    equation = "delta-SPH on s"

    def __init__(self, ctx):
        super().__init__(ctx)
        self.h = ctx.smoothing.h
        self.eps2 = 0.01 * self.h**2
        self.dim = ctx.state.dim
        self.coefficient = ctx.numerics.stress_diffusion * self.h * ctx.model.wave_speed  # [m^2/s]
        if len(ctx.model.history) != 1:
            raise ValueError("stress diffusion acts on a model with one integrated stress tensor")
        names = ctx.model.history[0]
        self.stress, self.stress_rate = ctx.state.field(names[0]), ctx.state.field(names[1])

    @ti.func
    def pair(self, i, j, x_ij, r, laplacian: ti.template()):
        if j < self.state.n_material:
            weight = 2.0 * (-x_ij).dot(self.smoothing.gradient(x_ij, r)) / (r * r + self.eps2) * \
                self.state.mass[j] / self.state.density[j]
            laplacian += weight * (self.stress[j] - self.stress[i])

    @ti.kernel
    def _run(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            laplacian = ti.Matrix.zero(float, self.dim, self.dim)
            self.grid.for_each_neighbour(i, self.pair, laplacian)
            self.stress_rate[i] += self.coefficient * laplacian
