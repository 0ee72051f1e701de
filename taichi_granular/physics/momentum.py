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

With ``numerics.viscosity: implicit`` (mu(I)) each viscosity splits in two (``viscosity_part``
for a particle's stress, ``pair_viscosity`` for a pair term's harmonic mean, split as a whole):
up to the explicit limit of [M39] at the step's dt it stays in the rate; the excess leaves every
term that is linear in the velocity through the viscosity (the deviatoric stress and the
residual damping, or the [M27] pair term), which offers that same sum as a linear operator:
``apply_viscous()`` writes L(operand) to ``image``, with the viscosity, densities, positions
and kernel corrections of the rate evaluation frozen. physics/implicit_viscosity.py solves
systems (I - c dt L) y = target with it (TR-BDF2 or the theta-method). Ghost walls enter L as they enter the
explicit term (their velocity is beta v_i, their deviatoric stress i's); the gravity part of an
extrapolated ghost stress does not depend on v and stays in the rate.
"""
import taichi as ti

from .. import runtime
from ..launch import launcher

from .stage import PairStage
from .strain_rate import velocity_gradient_term


@ti.data_oriented
class _Momentum(PairStage):
    category = "forces"
    reads = ("gradient_correction", "velocity_gradient", "strain_rate")
    writes = ("acceleration",)

    def __init__(self, ctx):
        super().__init__(ctx)
        self.dim = ctx.state.dim
        self.gravity = ti.Vector.field(self.dim, float, shape=())
        self.gravity[None] = ctx.gravity
        self.eps2 = 0.01 * ctx.smoothing.h**2  # keeps r^2 away from zero [M27]
        self.implicit = ctx.numerics.implicit_viscosity
        self.time_step = ctx.time_step
        # implicit: viscosities up to the explicit limit of [M39] at the step's dt stay explicit
        self.cap_factor = ctx.numerics.cfl * 0.1 * ctx.smoothing.h**2  # eta_cap = this rho/dt [m^2]
        if self.implicit:
            # the operand spans every particle so that any wall's velocity lookup stays in range
            self.operand = ti.Vector.field(self.dim, float, ctx.state.n_total)  # velocity-like [m/s]
            self.image = ti.Vector.field(self.dim, float, ctx.state.n_material)  # L(operand) [m/s^2]
            self.diagonal = ti.Matrix.field(self.dim, self.dim, float, ctx.state.n_material)  # d L_i/d v_i [1/s]

    @ti.func
    def _split(self, eta, density, part: ti.template()):
        """Part 0 of a viscosity eta [Pa s] is eta up to eta_cap = cfl 0.1 rho h^2/dt, the most the step
        can take explicitly ([M39]); part 1 the rest. Explicit scheme: all of it in part 0."""
        if ti.static(self.implicit):
            dt = self.time_step[None]
            cap = 0.0  # no step yet (the initial rates): all of it implicit, none in the first kick
            if dt > 0.0:
                cap = self.cap_factor * density / dt
            if ti.static(part == 0):
                eta = ti.min(eta, cap)
            else:
                eta = ti.max(eta - cap, 0.0)
        return eta

    @ti.func
    def viscosity_part(self, k, part: ti.template()):
        """The viscosity of particle k that the explicit term (part 0) or the implicit solve (part 1)
        takes [Pa s]: a grain that flows at the step's dt is stepped exactly as by the explicit
        scheme, and only the stiff excess (grains near or below yield, eta up to eta_hat_max) goes
        to the solve."""
        return self._split(self.state.viscosity[k], self.state.density[k], part)

    @ti.func
    def pair_viscosity(self, i, k, part: ti.template()):
        """The pair viscosity of [M27], the harmonic mean eta_ij = 2 eta_i eta_j/(eta_i + eta_j), split
        as a whole (not per particle), so that the parts sum to the pair's own eta_ij: splitting
        each particle's viscosity first lost up to a quarter of it at a flowing/static interface.
        The cap of the larger density keeps part 1 zero whenever every particle's is (the solve is
        skipped then)  [Pa s]."""
        s = self.state
        eta_i, eta_k = s.viscosity[i], s.viscosity[k]
        eta_ij = 0.0
        if eta_i + eta_k > 0.0:
            eta_ij = 2.0 * eta_i * eta_k / (eta_i + eta_k)
        return self._split(eta_ij, ti.max(s.density[i], s.density[k]), part)

    @ti.func
    def viscous_coefficient(self, i, j, k, v_ij, x_ij, r, part: ti.template()):
        """m_j 2(d+2) eta_ij (v_ij . x_ij) / (rho_i rho_j (r^2 + 0.01 h^2)) of [M27] with the pair
        viscosity's ``part`` [m^2/s^2, times grad W]."""
        s = self.state
        return s.mass[j] * 2.0 * (self.dim + 2) * self.pair_viscosity(i, k, part) * v_ij.dot(x_ij) / (
            s.density[i] * s.density[k] * (r * r + self.eps2))

    @ti.func
    def initial(self, i):
        return self.gravity[None]

    @ti.func
    def store(self, i, acc):
        self.state.acceleration[i] = acc

    # ---- the viscous operator of the implicit update ------------------------------------------

    @ti.func
    def diagonal_pair(self, i, j, x_ij, r, block: ti.template()):
        """d/dv_i of the [M27] pair term: the block-Jacobi preconditioner of the solve (of the
        stress form too, whose own diagonal it approximates)  [1/s]."""
        k = self.walls.state_index(i, j)
        unit = x_ij / (r * r)  # v_ij . x_ij = 1: the coefficient alone
        block += self.walls.self_factor(i, j, x_ij) * self.viscous_coefficient(i, j, k, unit, x_ij, r, 1) * \
            self.gradient.pairwise(i, j, x_ij, r).outer_product(x_ij)

    @ti.kernel
    def compute_diagonal(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            block = ti.Matrix.zero(float, self.dim, self.dim)
            self.grid.for_each_neighbour(i, self.diagonal_pair, block)
            self.diagonal[i] = block

    @ti.kernel
    def max_implicit_viscosity(self) -> float:
        """The largest viscosity part left to the solve [Pa s]: 0 when the step takes it all explicitly."""
        result = 0.0
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            ti.atomic_max(result, self.viscosity_part(i, 1))
        return result

    def apply_viscous(self) -> None:
        """image = L(operand): the viscous acceleration the explicit term would give the operand."""
        self._apply()


@ti.data_oriented
class ViscousMomentum(_Momentum):
    name = "momentum_viscous_pair"
    slot = "forces"
    equation = "[M27]"

    @ti.func
    def pair(self, i, j, x_ij, r, acc: ti.template()):
        s = self.state
        k = self.walls.state_index(i, j)
        coefficient = -s.mass[j] * (s.pressure[i] / s.density[i] ** 2
                                    + self.walls.pressure(i, j, x_ij) / s.density[k] ** 2)
        coefficient += self.viscous_coefficient(i, j, k, self.walls.relative_velocity(i, j, x_ij), x_ij, r, 0)
        acc += coefficient * self.gradient.pairwise(i, j, x_ij, r)

    @ti.func
    def viscous_pair(self, i, j, x_ij, r, acc: ti.template()):
        k = self.walls.state_index(i, j)
        v_ij = self.walls.relative(self.operand, i, j, x_ij)
        acc += self.viscous_coefficient(i, j, k, v_ij, x_ij, r, 1) * self.gradient.pairwise(i, j, x_ij, r)

    def _apply(self) -> None:
        launcher(self, "_apply_pairs")()

    @ti.kernel
    def _apply_pairs(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            acc = ti.Vector.zero(float, self.dim)
            self.grid.for_each_neighbour(i, self.viscous_pair, acc)
            self.image[i] = acc


@ti.data_oriented
class StressMomentum(_Momentum):
    name = "momentum_stress"
    slot = "forces"
    equation = "[A12]"

    prepares = True

    def __init__(self, ctx):
        super().__init__(ctx)
        # the residual damping needs a viscosity (mu(I)); elastic models are damped by [A16]
        self.viscous_residual = ctx.state.has("viscosity")
        # sigma_k / rho_k^2 of each material particle, computed once a pass rather than once a pair:
        # the stress, its deviator and the divisions were 40 % of the forces pass (measured)
        self.specific_stress = ti.Matrix.field(self.dim, self.dim, float, ctx.state.n_material)  # [Pa m^6/kg^2]
        if self.implicit:
            self.operand_gradient = ti.Matrix.field(self.dim, self.dim, float, ctx.state.n_material)  # [1/s]

    @ti.func
    def residual_damping(self, i, j, x_ij, r, grad_w, velocity: ti.template(), gradient: ti.template(),
                         part: ti.template()):
        """The [M27] pair term of the velocity residual v_ij - (grad v_i + grad v_j)/2 . x_ij (zero for
        quadratic fields). A boundary particle that is its own state (extrapolated walls) has no
        gradient or viscosity of its own: it lends i's  [m/s^2]."""
        k = self.walls.state_index(i, j)
        m = k
        if k >= self.state.n_material:
            m = i
        v_residual = self.walls.relative(velocity, i, j, x_ij) - 0.5 * (gradient[i] + gradient[m]) @ x_ij
        return self.viscous_coefficient(i, j, m, v_residual, x_ij, r, part) * grad_w

    @ti.func
    def rate_deviatoric(self, k):
        """The deviatoric stress of particle k in the rate [Pa]: the model's, or with the implicit
        viscous update the part of its viscous stress that stays explicit."""
        if ti.static(self.implicit):
            return self.model.viscous_stress(self.viscosity_part(k, 0), self.state.velocity_gradient[k])
        else:
            return self.model.deviatoric_stress(k)

    @ti.func
    def prepare(self, k):
        s = self.state
        sigma = self.rate_deviatoric(k) - s.pressure[k] * ti.Matrix.identity(float, self.dim)
        self.specific_stress[k] = sigma / s.density[k] ** 2

    @ti.func
    def pair(self, i, j, x_ij, r, acc: ti.template()):
        s = self.state
        grad_w = self.gradient.pairwise(i, j, x_ij, r)
        # a material neighbour is its own state and stress; a boundary one is built by the wall rule
        term_j = ti.Matrix.zero(float, self.dim, self.dim)
        if j < s.n_material:
            term_j = self.specific_stress[j]
        else:
            k = self.walls.state_index(i, j)
            sigma_j = self.walls.stress(i, j, x_ij, self.rate_deviatoric(self.walls.stress_index(i, j))
                                        - s.pressure[k] * ti.Matrix.identity(float, self.dim))
            term_j = sigma_j / s.density[k] ** 2
        acc += s.mass[j] * ((self.specific_stress[i] + term_j) @ grad_w)
        if ti.static(self.viscous_residual):
            acc += self.residual_damping(i, j, x_ij, r, grad_w, s.velocity, s.velocity_gradient, 0)

    @ti.func
    def operand_gradient_pair(self, i, j, x_ij, r, gradient: ti.template()):
        velocity_gradient_term(self, self.operand, i, j, x_ij, r, gradient)

    @ti.func
    def viscous_pair(self, i, j, x_ij, r, acc: ti.template()):
        s = self.state
        k = self.walls.state_index(i, j)
        sigma_i = self.model.viscous_stress(self.viscosity_part(i, 1), self.operand_gradient[i])
        m = self.walls.stress_index(i, j)
        sigma_j = self.model.viscous_stress(self.viscosity_part(m, 1), self.operand_gradient[m])
        grad_w = self.gradient.pairwise(i, j, x_ij, r)
        acc += s.mass[j] * ((sigma_i / s.density[i] ** 2 + sigma_j / s.density[k] ** 2) @ grad_w)
        acc += self.residual_damping(i, j, x_ij, r, grad_w, self.operand, self.operand_gradient, 1)

    @ti.kernel
    def _operand_gradient(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            gradient = ti.Matrix.zero(float, self.dim, self.dim)
            self.grid.for_each_neighbour(i, self.operand_gradient_pair, gradient)
            self.operand_gradient[i] = gradient

    @ti.kernel
    def _apply_divergence(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            acc = ti.Vector.zero(float, self.dim)
            self.grid.for_each_neighbour(i, self.viscous_pair, acc)
            self.image[i] = acc

    def _apply(self) -> None:
        """Two passes: the operand's velocity gradient [M31], then the divergence of its viscous
        stress and the residual damping."""
        launcher(self, "_operand_gradient")()
        launcher(self, "_apply_divergence")()


MOMENTUM = {"viscous_pair": ViscousMomentum, "stress_divergence": StressMomentum}
