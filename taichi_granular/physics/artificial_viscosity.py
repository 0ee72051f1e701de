"""Monaghan artificial viscosity [M38] / [A16]-[A19], a stage of its own so that a scene
without it neither compiles nor runs it.

For v_ij . x_ij < 0: phi_ij = h (v_ij . x_ij)/(r^2 + 0.01 h^2),
Pi_ij = (-alpha c_ij phi_ij + beta phi_ij^2)/rho_ij (bars: arithmetic means), and
dv_i/dt -= sum_j m_j Pi_ij grad_i W_ij.
"""
import taichi as ti

from .stage import PairStage


@ti.data_oriented
class ArtificialViscosity(PairStage):
    name = "artificial_viscosity"
    slot = "forces"
    category = "forces"
    equation = "[M38]"
    reads = ("gradient_correction",)
    writes = ("acceleration",)  # added to the momentum stage's (its store runs after that one)

    prepares = True

    def __init__(self, ctx):
        super().__init__(ctx)
        av = ctx.numerics.artificial_viscosity
        self.alpha, self.beta = av.alpha, av.beta
        self.h = ctx.smoothing.h
        self.eps2 = 0.01 * self.h**2
        # each material particle's sound speed, once a pass rather than once a pair (a square root
        # and a division in most models)
        self.sound_speed = ti.field(float, ctx.state.n_material)  # [m/s]

    @ti.func
    def prepare(self, k):
        self.sound_speed[k] = self.model.sound_speed(k)

    @ti.func
    def pair(self, i, j, x_ij, r, acc: ti.template()):
        v_ij = self.walls.relative_velocity(i, j, x_ij)
        approach = v_ij.dot(x_ij)
        if approach < 0.0:
            k = self.walls.state_index(i, j)
            phi = self.h * approach / (r * r + self.eps2)
            c_k = 0.0
            if k < self.state.n_material:
                c_k = self.sound_speed[k]
            else:
                c_k = self.model.sound_speed(k)
            c_ij = 0.5 * (self.sound_speed[i] + c_k)
            rho_ij = 0.5 * (self.state.density[i] + self.state.density[k])
            Pi = (-self.alpha * c_ij * phi + self.beta * phi * phi) / rho_ij
            acc -= self.state.mass[j] * Pi * self.gradient.pairwise(i, j, x_ij, r)

    @ti.func
    def initial(self, i):
        return ti.Vector.zero(float, self.state.dim)

    @ti.func
    def store(self, i, acc):
        self.state.acceleration[i] += acc
