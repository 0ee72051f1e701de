"""Continuity equation [M26] / [A11]: d rho_i/dt = sum_j m_j v_ij . grad_i W_ij  [kg/m^3/s]."""
import taichi as ti

from .stage import Stage


@ti.data_oriented
class Continuity(Stage):
    name = "continuity"
    category = "density"
    equation = "[M26]"

    @ti.func
    def pair(self, i, j, x_ij, r, rate: ti.template()):
        v_ij = self.walls.relative_velocity(i, j, x_ij)
        rate += self.state.mass[j] * v_ij.dot(self.gradient.pairwise(i, j, x_ij, r))  # [M26]

    @ti.kernel
    def _run(self):
        for i in range(self.state.n_material):
            rate = 0.0
            self.grid.for_each_neighbor(i, self.pair, rate)
            self.state.density_rate[i] = rate
