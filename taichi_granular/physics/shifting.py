"""Particle shifting: keeps sheared particle arrangements from degenerating (after Lind, Xu,
Stansby & Rogers 2012, with the anti-clumping weight of Monaghan 2000).

Why: a layer sheared against a no-slip wall is unstable at the particle scale in this scheme.
Measured on the Table 2 layer started from the analytic profile [M56]: a row-wise zig-zag of
wavelength ~3 dp grows from round-off at a rate close to the wall shear rate (about 90 1/s
for gamma_dot = 170 1/s), first in the rows next to the wall, until the rows interpenetrate and
the continuity density of the disordered particles drifts away from their packing. The growth
is the same with h/dp = 1.3, 1.6 or 2.0, with K_t ten times smaller, with either momentum form,
with or without gradient correction and artificial viscosity, and with a constant Newtonian
viscosity in place of mu(I); it disappears with a free-slip wall. Shifting the particles
towards a uniform concentration removes it.

Each rate evaluation computes, for material particle i,
    grad C_i = sum_j V_j (1 + 0.2 (W_ij / W(dp))^4) grad_i W_ij     (boundary particles included),
    u_shift_i = -zeta h c_i grad C_i                                     [m/s],
and the integrator moves the particle by dt u_shift_i at the end of the step, carrying its
velocity with the first-order Taylor correction v_i += grad v_i . dr_i. Near a free surface
only the component along the surface is kept (Lind et al.'s treatment), so that shifting never
inflates a layer: a particle whose kernel sum S_i = sum_j V_j W_ij (self included) is below the
free-surface threshold is on the surface and its normal is along grad S_i; a particle with such
neighbours takes as normal the direction towards them. Shifting the surface particles along the
surface matters: left unshifted, a sheared free-surface row slowly loses its order (the layer
swelled by 8 % in 4 s on the 2.5 cm layer of the tests, against 2 % with the tangential shift;
measured).
The displacement per step is zeta CFL h^2 |grad C| ~ 0.1 h for zeta = 0.2, CFL = 0.5
(dt <= CFL h / c) where the arrangement is near a lattice; the integrator caps it at
MAX_SHIFT h = 0.1 h (integrators.py). Why the cap: the anti-clumping weight grows as
(W_ij/W(dp))^4, without bound for two grains at a fraction of dp, and a grain of zero stress
(a free-falling column, where nothing else keeps grains apart) can be that close. Measured on
the hypoplastic a = 6 column of tests/hard (c = 80 m/s, dp 5 mm): grains jumped 3-9 mm in one
step of 2e-5 s, onto neighbours 1.2 mm away, and one was thrown out at 3.7 m/s at 0.06 s;
with the cap the column runs to rest, its fastest grain at 0.97 m/s.
"""
import taichi as ti

from ..state import FieldSpec
from .stage import PairStage

ANTI_CLUMPING = 0.2  # R of Monaghan (2000)
ANTI_CLUMPING_POWER = 4  # n of Monaghan (2000)


@ti.data_oriented
class ParticleShifting(PairStage):
    name = "particle_shifting"
    slot = "shifting"
    category = "integration"
    equation = "Lind et al. (2012)"
    reads = ("kernel_sum",)
    writes = ("shift_velocity",)
    fields = (FieldSpec("shift_velocity", "vector", "particle shifting velocity -zeta h c grad C", "m/s",
                        "material"),)

    def __init__(self, ctx):
        super().__init__(ctx)
        cfg = ctx.numerics.particle_shifting
        self.dim = ctx.state.dim
        self.coefficient = cfg.coefficient
        self.threshold = cfg.free_surface_threshold
        self.spacing = ctx.numerics.particle_spacing
        self.h = ctx.smoothing.h

    @ti.func
    def pair(self, i, j, x_ij, r, acc: ti.template()):
        """acc[0] += V_j (1 + R (W_ij/W(dp))^n) grad W_ij; acc[1] += direction to free-surface j;
        acc[2] += V_j grad W_ij (the plain kernel-sum gradient: the surface normal)."""
        s = self.state
        volume = s.mass[j] / s.density[self.walls.state_index(i, j)]
        w = self.smoothing.value(r)
        weight = 1.0 + ANTI_CLUMPING * (w / self.smoothing.value(self.spacing)) ** ANTI_CLUMPING_POWER
        grad = self.smoothing.gradient(x_ij, r)
        surface = 0.0
        if j < s.n_material:
            if s.kernel_sum[j] < self.threshold:
                surface = w
        for a in ti.static(range(self.dim)):
            acc[0, a] += volume * weight * grad[a]
            acc[1, a] -= surface * x_ij[a]
            acc[2, a] += volume * grad[a]

    @ti.func
    def initial(self, i):
        return ti.Matrix.zero(float, 3, self.dim)

    @ti.func
    def store(self, i, acc):
        """Kernel sums come from the FreeSurface stage, earlier in the step."""
        s = self.state
        scale = -self.coefficient * self.h * self.model.sound_speed(i)
        shift = ti.Vector.zero(float, self.dim)
        towards_surface = ti.Vector.zero(float, self.dim)
        kernel_sum_gradient = ti.Vector.zero(float, self.dim)
        for a in ti.static(range(self.dim)):
            shift[a] = scale * acc[0, a]
            towards_surface[a] = acc[1, a]
            kernel_sum_gradient[a] = acc[2, a]
        # the surface normal: on the surface along the kernel-sum gradient, below it towards
        # the surface neighbours
        normal = towards_surface
        if s.kernel_sum[i] < self.threshold:
            normal = kernel_sum_gradient
        if normal.norm() > 0.0:
            n = normal.normalized()
            shift -= shift.dot(n) * n
        s.shift_velocity[i] = shift


@ti.data_oriented
class FreeSurface(PairStage):
    """Kernel (Shepard) sum S_i = sum_j V_j W_ij, self and boundary particles included [-].
    S_i falls from ~1 in the bulk to ~0.8 on a free surface (0.79 for the top row of a
    lattice at h/dp = 1.3 with Wendland C2, 1.006 one row below); particles below
    ``numerics.particle_shifting.free_surface_threshold`` count as free surface."""

    name = "free_surface"
    slot = "free_surface"
    category = "neighbours"
    equation = "Shepard sum"
    writes = ("kernel_sum",)
    fields = (FieldSpec("kernel_sum", "scalar", "Shepard sum S_i = sum_j V_j W_ij; free surface below the "
                        "threshold", "-", "material"),)

    @ti.func
    def pair(self, i, j, x_ij, r, acc: ti.template()):
        s = self.state
        acc += s.mass[j] / s.density[self.walls.state_index(i, j)] * self.smoothing.value(r)

    @ti.func
    def initial(self, i):
        return self.state.mass[i] / self.state.density[i] * self.smoothing.value(0.0)

    @ti.func
    def store(self, i, total):
        self.state.kernel_sum[i] = total
