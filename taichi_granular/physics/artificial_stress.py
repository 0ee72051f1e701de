"""Artificial stress against the tensile instability (Gray, Monaghan & Swift 2001), an
optional scene effect for models with a stress tensor (``numerics.artificial_stress``), as
Bui et al. (2008) use it for soil (MODEL.md section 3).

Where a particle's stress is tensile, SPH particles attract and clump. Per particle the
total stress sigma = -p I + s (tension positive) is turned to its principal frame,
sigma = Q diag(sigma_a) Q^T, and each tensile principal stress gets an opposing
artificial stress
    R_a = -epsilon sigma_a / rho^2   where sigma_a > 0,   0 otherwise,   R = Q diag(R_a) Q^T.
The momentum equation gains a short-range repulsion that only acts between close pairs:
    dv_i/dt += sum_j m_j (R_i + R_j) f_ij^n . grad_i W_ij,   f_ij = W(r_ij)/W(dp)
(Gray et al.: epsilon ~ 0.3, n = 4). The tensile part of sigma is where the Mohr-Coulomb cone
is exceeded in extension or cohesion holds material in tension: for cohesionless sand under
the tension cut-off of physics/rheology/elastoplastic/model.py the principal stresses stay
compressive except where s nearly reaches the cone at small p, so the term is mostly idle
there and matters for cohesive soils (c > 0).

Boundary particles carry no artificial stress (R_j = 0 for them). Units: R in m^2/s^2 per
(kg/m^3) (stress over density squared, like the momentum terms), acceleration m/s^2.
"""
import taichi as ti

from .. import runtime
from ..state import FieldSpec
from .stage import Stage


@ti.data_oriented
class ArtificialStress(Stage):
    name = "artificial_stress"
    slot = "forces"
    category = "forces"
    equation = "Gray, Monaghan & Swift 2001"
    fields = (FieldSpec("artificial_stress", "matrix", "R = -epsilon Q diag(max(sigma_a, 0)) Q^T / rho^2",
                        "m^5/(kg s^2)", "material"),)

    def __init__(self, ctx):
        super().__init__(ctx)
        settings = ctx.numerics.artificial_stress
        self.epsilon = settings.epsilon
        self.exponent = settings.exponent
        self.dim = ctx.state.dim
        self.reference_kernel = float(self._kernel_at(ctx.numerics.particle_spacing))

    def _kernel_at(self, r: float) -> float:
        """W(dp), evaluated once in Python scope through a tiny kernel  [1/m^dim]."""
        out = ti.field(float, shape=())

        @ti.kernel
        def evaluate(distance: float):
            out[None] = self.smoothing.value(distance)

        evaluate(r)
        return out[None]

    @ti.func
    def principal_tension(self, i):
        """R_i from the principal stresses of sigma_i = -p_i I + s_i."""
        identity = ti.Matrix.identity(float, self.dim)
        sigma = self.model.deviatoric_stress(i) - self.state.pressure[i] * identity
        values, vectors = ti.sym_eig(sigma)
        tension = ti.Matrix.zero(float, self.dim, self.dim)
        for a in ti.static(range(self.dim)):
            if values[a] > 0.0:
                tension[a, a] = values[a]
        rho = self.state.density[i]
        return -self.epsilon * (vectors @ tension @ vectors.transpose()) / (rho * rho)

    @ti.func
    def pair(self, i, j, x_ij, r, acc: ti.template()):
        if j < self.state.n_material:
            f = self.smoothing.value(r) / self.reference_kernel
            term = (self.state.artificial_stress[i] + self.state.artificial_stress[j]) * f ** self.exponent
            acc += self.state.mass[j] * (term @ self.gradient.pairwise(i, j, x_ij, r))

    @ti.kernel
    def tensor(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            self.state.artificial_stress[i] = self.principal_tension(i)

    @ti.kernel
    def force(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            acc = ti.Vector.zero(float, self.dim)
            self.grid.for_each_neighbour(i, self.pair, acc)
            self.state.acceleration[i] += acc

    def run(self) -> None:
        self.tensor()
        self.force()
