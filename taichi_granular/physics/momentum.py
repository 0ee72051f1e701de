"""Momentum of a viscous granular fluid [M27] / [M37]: pressure gradient, the Morris/Cleary
viscous term and gravity.

dv_i/dt = g - sum_j m_j (p_i/rho_i^2 + p_j/rho_j^2) grad_i W_ij
          + sum_j m_j 2(d+2) eta_ij (v_ij . x_ij) grad_i W_ij / (rho_i rho_j (r_ij^2 + 0.01 h^2))
with eta_ij = 2 eta_i eta_j/(eta_i + eta_j). Both sums are antisymmetric in (i, j), so momentum
is conserved to round-off between material particles.
"""
import taichi as ti

from ..state import FieldSpec
from .stage import Stage


@ti.data_oriented
class ViscousMomentum(Stage):
    name = "momentum"
    category = "forces"
    equation = "[M27]"
    fields = (FieldSpec("viscosity", "scalar", "dynamic viscosity eta", "Pa s", "material"),)

    def __init__(self, ctx):
        self.state, self.grid, self.smoothing, self.walls = ctx.state, ctx.grid, ctx.smoothing, ctx.walls
        self.dim = ctx.state.dim
        self.gravity = ti.Vector.field(self.dim, float, shape=())
        self.gravity[None] = ctx.scene.gravity_vector
        self.eps2 = 0.01 * ctx.smoothing.h**2  # keeps r^2 away from zero [M27]

    @ti.func
    def pair(self, i, j, x_ij, r, acc: ti.template()):
        s = self.state
        k = self.walls.state_index(i, j)
        rho_i, rho_j = s.density[i], s.density[k]
        eta_i, eta_j = s.viscosity[i], s.viscosity[k]
        eta_ij = 0.0
        if eta_i + eta_j > 0.0:
            eta_ij = 2.0 * eta_i * eta_j / (eta_i + eta_j)
        v_ij = self.walls.relative_velocity(i, j, x_ij)
        pressure_term = -(s.pressure[i] / rho_i**2 + self.walls.pressure(i, j, x_ij) / rho_j**2)
        viscous_term = 2.0 * (self.dim + 2) * eta_ij * v_ij.dot(x_ij) / (rho_i * rho_j * (r * r + self.eps2))
        acc += s.mass[j] * (pressure_term + viscous_term) * self.smoothing.gradient(x_ij, r)

    @ti.kernel
    def _run(self):
        for i in range(self.state.n_material):
            acc = self.gravity[None]
            self.grid.for_each_neighbor(i, self.pair, acc)
            self.state.acceleration[i] = acc

    def run(self) -> None:
        self._run()
