"""Momentum equation, in one of two forms (``numerics.momentum``).

``viscous_pair`` -- the viscous-fluid form of [M27] / [M37]: pressure gradient, the
Morris/Cleary pairwise viscous term and gravity,
    dv_i/dt = g - sum_j m_j (p_i/rho_i^2 + p_j/rho_j^2) grad_i W_ij
              + sum_j m_j 2(d+2) eta_ij (v_ij . x_ij) grad_i W_ij / (rho_i rho_j (r_ij^2 + 0.01 h^2)),
    eta_ij = 2 eta_i eta_j/(eta_i + eta_j).
  On a lattice at h/dp = 1.3 this operator returns only 80 % of eta lap v with Wendland C2
  (53 % with C6, 86 % with the cubic spline; measured, see tests/test_operators.py).

``stress_divergence`` -- the stress form [A12] / [A20] used by every model:
    dv_i/dt = g + sum_j m_j (sigma_i/rho_i^2 + sigma_j/rho_j^2) . grad_i W_ij,
    sigma = -p I + s, s the model's deviatoric stress (2 eta dev(eps) for mu(I)).
  With kernel gradient renormalisation it is exact for linear stress fields. Because the
  viscous stress is built from an SPH velocity gradient, a velocity pattern alternating from
  particle to particle has zero gradient and the stress form alone never damps it (measured:
  a sheared layer fills with such noise within ~1 s). So the stress form adds the pairwise
  viscous term of [M27] applied to the velocity *residual*
      v_ij - (grad v_i + grad v_j)/2 . x_ij,
  which vanishes for every quadratic velocity field (the smooth flow is left to the stress)
  and damps the particle-scale modes; like the rest it is antisymmetric in (i, j). The
  hypoplastic model lends its secant viscosity |T*|/gamma_dot (capped); models without a
  viscosity (elastoplastic) leave this to Monaghan's artificial viscosity [A16].

Both sums are antisymmetric in (i, j): momentum is conserved to round-off between material
particles.
"""
import taichi as ti

from .. import runtime

from .stage import Stage


@ti.data_oriented
class _Momentum(Stage):
    category = "forces"

    def __init__(self, ctx):
        super().__init__(ctx)
        self.dim = ctx.state.dim
        self.gravity = ti.Vector.field(self.dim, float, shape=())
        self.gravity[None] = ctx.scene.gravity_vector
        self.eps2 = 0.01 * ctx.smoothing.h**2  # keeps r^2 away from zero [M27]

    @ti.func
    def viscous_coefficient(self, i, j, k, v_ij, x_ij, r):
        """m_j 2(d+2) eta_ij (v_ij . x_ij) / (rho_i rho_j (r^2 + 0.01 h^2)) of [M27], with the
        harmonic mean eta_ij = 2 eta_i eta_j/(eta_i + eta_j)  [m^2/s^2, times grad W]."""
        s = self.state
        eta_i, eta_j = s.viscosity[i], s.viscosity[k]
        eta_ij = 0.0
        if eta_i + eta_j > 0.0:
            eta_ij = 2.0 * eta_i * eta_j / (eta_i + eta_j)
        return s.mass[j] * 2.0 * (self.dim + 2) * eta_ij * v_ij.dot(x_ij) / (
            s.density[i] * s.density[k] * (r * r + self.eps2))

    @ti.kernel
    def _run(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            acc = self.gravity[None]
            self.grid.for_each_neighbor(i, self.pair, acc)
            self.state.acceleration[i] = acc


@ti.data_oriented
class ViscousMomentum(_Momentum):
    name = "momentum_viscous_pair"
    equation = "[M27]"

    @ti.func
    def pair(self, i, j, x_ij, r, acc: ti.template()):
        s = self.state
        k = self.walls.state_index(i, j)
        v_ij = self.walls.relative_velocity(i, j, x_ij)
        pressure_term = -s.mass[j] * (s.pressure[i] / s.density[i] ** 2
                                      + self.walls.pressure(i, j, x_ij) / s.density[k] ** 2)
        acc += (pressure_term + self.viscous_coefficient(i, j, k, v_ij, x_ij, r)) * \
            self.gradient.pairwise(i, j, x_ij, r)


@ti.data_oriented
class StressMomentum(_Momentum):
    name = "momentum_stress"
    equation = "[A12]"

    def __init__(self, ctx):
        super().__init__(ctx)
        # the residual damping needs a viscosity (mu(I)); elastic models are damped by [A16]
        self.viscous_residual = ctx.state.has("viscosity")

    @ti.func
    def pair(self, i, j, x_ij, r, acc: ti.template()):
        s = self.state
        k = self.walls.state_index(i, j)
        identity = ti.Matrix.identity(float, self.dim)
        sigma_i = self.model.deviatoric_stress(i) - s.pressure[i] * identity
        sigma_j = self.walls.stress(i, j, x_ij, self.model.deviatoric_stress(self.walls.stress_index(i, j))
                                    - s.pressure[k] * identity)
        term = sigma_i / s.density[i] ** 2 + sigma_j / s.density[k] ** 2
        grad_w = self.gradient.pairwise(i, j, x_ij, r)
        acc += s.mass[j] * (term @ grad_w)
        if ti.static(self.viscous_residual):
            # pairwise viscous damping of the velocity residual (zero for quadratic fields); a
            # boundary particle that is its own state (extrapolated walls) has no gradient or
            # viscosity of its own: it lends i's
            m = k
            if k >= s.n_material:
                m = i
            v_residual = self.walls.relative_velocity(i, j, x_ij) - \
                0.5 * (s.velocity_gradient[i] + s.velocity_gradient[m]) @ x_ij
            acc += self.viscous_coefficient(i, j, m, v_residual, x_ij, r) * grad_w


MOMENTUM = {"viscous_pair": ViscousMomentum, "stress_divergence": StressMomentum}
