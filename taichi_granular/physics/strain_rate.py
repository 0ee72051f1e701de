"""Velocity gradient and strain-rate modulus [M31] / [A13].

grad v_i^{ab} = - sum_j (m_j/rho_j) v_ij^a d W_ij/d x_i^b, which reproduces a linear velocity
field exactly on a full lattice (tested). The strain rate is its symmetric part eps, and
gamma_dot = sqrt(2 eps:eps) (= |dv_x/dz| in simple shear)  [1/s].
"""
import taichi as ti

from ..state import FieldSpec
from .stage import PairStage


@ti.func
def deviator(tensor):
    """Deviatoric part, taking the out-of-plane component as zero in 2D (plane strain)."""
    return tensor - (tensor.trace() / 3.0) * ti.Matrix.identity(float, tensor.n)


@ti.func
def strain_rate_modulus(velocity_gradient):
    """gamma_dot = sqrt(2 eps:eps) with eps = sym(grad v)  [1/s]."""
    eps = 0.5 * (velocity_gradient + velocity_gradient.transpose())
    return ti.sqrt(2.0 * (eps * eps).sum())


@ti.func
def velocity_gradient_term(stage: ti.template(), velocity: ti.template(), i, j, x_ij, r, gradient: ti.template()):
    """Pair j's share of grad v_i [M31] for any velocity-like field (the state's velocity, or the
    implicit viscous solve's operand), through ``stage``'s walls and kernel gradient."""
    k = stage.walls.state_index(i, j)
    volume_j = stage.state.mass[j] / stage.state.density[k]
    v_ij = stage.walls.relative(velocity, i, j, x_ij)
    gradient -= volume_j * v_ij.outer_product(stage.gradient.one_sided(i, j, x_ij, r))


@ti.data_oriented
class StrainRate(PairStage):
    name = "strain_rate"
    slot = "kinematics"
    category = "rheology"
    equation = "[M31]"
    fields = (FieldSpec("strain_rate", "scalar", "strain-rate modulus gamma_dot = sqrt(2 eps:eps)", "1/s",
                        "material"),
              FieldSpec("velocity_gradient", "matrix", "grad v, component ab = d v_a/d x_b [M31]", "1/s",
                        "material"))
    reads = ("gradient_correction",)
    writes = ("velocity_gradient", "strain_rate")

    def __init__(self, ctx):
        super().__init__(ctx)
        self.dim = ctx.state.dim

    @ti.func
    def pair(self, i, j, x_ij, r, gradient: ti.template()):
        velocity_gradient_term(self, self.state.velocity, i, j, x_ij, r, gradient)  # [M31]

    @ti.func
    def initial(self, i):
        return ti.Matrix.zero(float, self.dim, self.dim)

    @ti.func
    def store(self, i, gradient):
        self.state.velocity_gradient[i] = gradient
        self.state.strain_rate[i] = strain_rate_modulus(gradient)
