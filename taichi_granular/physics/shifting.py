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
inflates a layer. The surface layer (SurfaceLayer) is the particles whose kernel sum
S_i = sum_j V_j W_ij (self included) is below the free-surface threshold and that are on the free
surface or have a neighbour there (FreeSurface: a low S_i and a direction free of neighbours);
their normal is grad S_i, and a particle with surface-layer neighbours takes as normal the
direction towards them. A particle of low S_i with no free surface within its support is in a
pocket of the bulk, outside the layer, and is shifted in full. Shifting the surface particles
along the surface matters: left unshifted, a sheared free-surface row slowly loses its order
(the layer swelled by 8 % in 4 s on the 2.5 cm layer of the tests, against 2 % with the
tangential shift; measured).
The displacement per step is zeta CFL h^2 |grad C| ~ 0.1 h for zeta = 0.2, CFL = 0.5
(dt <= CFL h / c) where the arrangement is near a lattice; the integrator caps it at
MAX_SHIFT h = 0.1 h (integrators.py). Why the cap: the anti-clumping weight grows as
(W_ij/W(dp))^4, without bound for two grains at a fraction of dp, and a grain of zero stress
(a free-falling column, where nothing else keeps grains apart) can be that close. Measured on
the hypoplastic a = 6 column of tests/hard (c = 80 m/s, dp 5 mm): grains jumped 3-9 mm in one
step of 2e-5 s, onto neighbours 1.2 mm away, and one was thrown out at 3.7 m/s at 0.06 s;
with the cap the column runs to rest, its fastest grain at 0.97 m/s.

The step is a gradient step on C, and it overshoots where C is stiff: moving i by
-k grad C_i (k = dt zeta h c) changes grad C_i by -k (d grad C_i/dx_i) grad C_i, so the step
lands past the local minimum of C where k |d grad C_i/dx_i| > 1 and alternates about it with
growing amplitude where > 2. The anti-clumping weight makes that curvature grow as
(W_ij/W(dp))^4: for a grain between two neighbours at 0.62 dp, k |d grad C/dx| = 3-10 at the
drum's dt (Wendland C6, cfl 0.3), and the capped step then flips the grain by 0.1 h from side
to side every step. Measured in the 2D drum (omega = 2, dp 5 mm): a grain of the flowing layer
so trapped jumped 0.65 mm back and forth every step for ~400 steps; the Taylor correction,
evaluated at the two alternating positions, does not cancel, and fed the pair's relative
velocity from 0.17 to 3.1 m/s in 3 ms (growth rate ~950 1/s), its stress from 18 Pa to 4.4 kPa:
the "grain bursts" that threw grains across the drum. So each particle's step is at most the
Newton step: k is cut to 1/|d grad C_i/dx_i| where larger (the Frobenius norm of the summed
pair Hessians V_j d/dx_i[(1 + R (W/W(dp))^n) grad W_ij], tangential w f I and radial d(w W')/dr,
f = W'/r, an upper bound of the largest eigenvalue), so the grain moves to the minimum and
stays there. The sum runs over the pairs closer than dp, where the weight makes C stiff: with
every pair, k |d grad C/dx| of the drum's grains had a median of 0.57 at the nominal h/c step
(0.21 at the drum's actual dt, where 0.2 % were cut), and the full sum cost 10-13 % of a 2D
mu(I) step (one thread, side by side); over the close pairs only it costs 2-4 %, and the drum's
flipping grains are gone the same (none in 400 steps, largest shift 0.032 h).
"""
import taichi as ti

from ..state import FieldSpec
from .stage import PairStage

ANTI_CLUMPING = 0.2  # R of Monaghan (2000)
ANTI_CLUMPING_POWER = 4  # n of Monaghan (2000)
BINNING_MARGIN = 0.05  # FreeSurface bins the neighbours of grains whose last kernel sum was below threshold + this


@ti.data_oriented
class ParticleShifting(PairStage):
    name = "particle_shifting"
    slot = "shifting"
    category = "integration"
    equation = "Lind et al. (2012)"
    reads = ("surface_layer",)
    writes = ("shift_velocity",)
    fields = (FieldSpec("shift_velocity", "vector", "particle shifting velocity -zeta h c grad C", "m/s",
                        "material"),)

    def __init__(self, ctx):
        super().__init__(ctx)
        cfg = ctx.numerics.particle_shifting
        self.dim = ctx.state.dim
        self.coefficient = cfg.coefficient
        self.spacing = ctx.numerics.particle_spacing
        self.h = ctx.smoothing.h
        self.time_step = ctx.time_step  # dt of the step being taken [s] (0 before the first)

    @ti.func
    def pair(self, i, j, x_ij, r, acc: ti.template()):
        """acc[0] += V_j (1 + R (W_ij/W(dp))^n) grad W_ij; acc[1] += direction to j where j is in
        the surface layer (SurfaceLayer); acc[2] += V_j grad W_ij (the plain kernel-sum gradient: the
        surface normal); rows 3 .. 2 + dim += V_j d/dx_i of the row-0 term for pairs closer than
        dp, the curvature of C that bounds the step (module docstring): tangential part w f I,
        radial part d(w W')/dr, f = W'/r."""
        s = self.state
        volume = s.mass[j] / s.density[self.walls.state_index(i, j)]
        w = self.smoothing.value(r)
        w_dp = self.smoothing.value(self.spacing)  # W(dp), the same for every pair
        ratio = w / w_dp
        weight = 1.0 + ANTI_CLUMPING * ratio ** ANTI_CLUMPING_POWER
        grad = self.smoothing.gradient(x_ij, r)
        surface = 0.0
        if j < s.n_material:
            if s.surface_layer[j] > 0.5:
                surface = w
        for a in ti.static(range(self.dim)):
            acc[0, a] += volume * weight * grad[a]
            acc[1, a] -= surface * x_ij[a]
            acc[2, a] += volume * grad[a]
        # the curvature of the row-0 term, of pairs closer than dp only: there the anti-clumping weight
        # makes C stiff; the lattice's own pairs (r >= dp) add k |d grad C/dx| ~ 0.5 at the nominal
        # step, which alone is stable, and skipping them keeps the pass's cost (module docstring)
        if r < self.spacing:
            # f = W'/r from grad W = f x_ij (W''(0) at r = 0, its limit); the radial term needs
            # r > 0 (a coincident pair has no direction: its curvature is isotropic, w f)
            f = self.smoothing.second_derivative(0.0)
            radial = 0.0
            if r > 0.0:
                f = grad.dot(x_ij) / (r * r)
                # d weight/dr
                weight_slope = ANTI_CLUMPING * ANTI_CLUMPING_POWER * ratio ** (ANTI_CLUMPING_POWER - 1) * f * r / w_dp
                radial = weight * self.smoothing.second_derivative(r) + weight_slope * f * r - weight * f
                radial /= r * r  # of x_ij (x) x_ij
            for a, b in ti.static(ti.ndrange(self.dim, self.dim)):
                acc[3 + a, b] += volume * (radial * x_ij[a] * x_ij[b] + (weight * f if a == b else 0.0))

    @ti.func
    def initial(self, i):
        return ti.Matrix.zero(float, 3 + self.dim, self.dim)

    @ti.func
    def store(self, i, acc):
        """The surface layer comes from the SurfaceLayer stage, earlier in the step."""
        s = self.state
        scale = -self.coefficient * self.h * self.model.sound_speed(i)
        shift = ti.Vector.zero(float, self.dim)
        towards_surface = ti.Vector.zero(float, self.dim)
        kernel_sum_gradient = ti.Vector.zero(float, self.dim)
        curvature = 0.0  # |d grad C/dx_i|, Frobenius (>= the largest eigenvalue)  [1/m^2]
        for a in ti.static(range(self.dim)):
            shift[a] = scale * acc[0, a]
            towards_surface[a] = acc[1, a]
            kernel_sum_gradient[a] = acc[2, a]
            for b in ti.static(range(self.dim)):
                curvature += acc[3 + a, b] ** 2
        # a step of dt zeta h c grad C overshoots the local minimum of C where dt zeta h c |d grad
        # C/dx| > 1 and oscillates where > 2 (module docstring): at most the Newton step
        stiffness = -scale * self.time_step[None] * ti.sqrt(curvature)
        if stiffness > 1.0:
            shift /= stiffness
        # the surface normal: in the surface layer along the kernel-sum gradient, below it towards
        # the surface-layer neighbours; a grain of low kernel sum in a pocket of the bulk is in
        # neither, and is shifted in full (SurfaceLayer)
        normal = towards_surface
        if s.surface_layer[i] > 0.5:
            normal = kernel_sum_gradient
        if normal.norm() > 0.0:
            n = normal.normalized()
            shift -= shift.dot(n) * n
        s.shift_velocity[i] = shift


@ti.data_oriented
class FreeSurface(PairStage):
    """Kernel (Shepard) sum S_i = sum_j V_j W_ij, self and boundary particles included [-], and
    the free-surface flag. S_i falls from ~1 in the bulk to ~0.8 on a free surface (0.79 for the
    top row of a lattice at h/dp = 1.3 with Wendland C2, 1.006 one row below). i is on the free
    surface where S_i < ``numerics.particle_shifting.free_surface_threshold`` and it has an open
    direction: one of the eight 45 deg sectors round it holds no neighbour (boundary particles
    included) within the kernel's support. An empty half-plane (a free surface of any
    orientation) holds a whole sector with 45 deg or more to spare on either side, so grains of a
    rough surface a little above its plane do not hide it. In 3D, the octants of a frame turned
    so that no axis lies in a level or upright plane: an empty half-space holds the octant of its
    normal's signs (35 deg to spare for a level surface). Why sectors: binning a neighbour costs
    a few comparisons, where cones round eight directions (a dot product each) made this pass
    2.3x dearer (the hypoplastic 2D step +25-30 %, `bench throughput`, one thread side by side);
    measured against the cones, wider bins hide rough surfaces: with quadrants, or two
    neighbouring sectors both empty, the coarse a = 0.9 collapse's deposit crept on at 8-12 mm/s
    (its front never stopped by 0.6 s), with one sector it stops at 0.35 s as with the cones.

    Why not the kernel sum alone: it also marks grains round a pocket in the bulk (a hole of a
    missing grain or two, neighbours all round at 1.3-1.5 dp), and the surface's shift, along the
    "surface" only, can never close the pocket. Measured in the 2D drum (omega = 2, dp 5 mm, at
    3.0 s): 286 of 1 212 grains had S < 0.9 where the surface and the row below hold ~120;
    first-row grains in such pockets keep the plain kernel gradient (renormalisation determinant
    0.10), read the bed's rigid rotation as strain and wound their stress up 1 -> 22 kPa, which
    shrank the step 2.5-fold (docs/models/hypoplastic.md, What slowed the drum)."""

    name = "free_surface"
    slot = "free_surface"
    category = "neighbours"
    equation = "Shepard sum, open sector"
    writes = ("kernel_sum", "free_surface")
    fields = (FieldSpec("kernel_sum", "scalar", "Shepard sum S_i = sum_j V_j W_ij", "-", "material"),
              FieldSpec("free_surface", "scalar", "1 on the free surface (S_i below the threshold and a direction "
                        "free of neighbours), else 0", "-", "material"))

    def __init__(self, ctx):
        super().__init__(ctx)
        self.threshold = ctx.numerics.particle_shifting.free_surface_threshold
        self.dim = ctx.state.dim
        self.binning_below = self.threshold + BINNING_MARGIN
        # 3D: the frame's axes (rows), the cube's diagonal turned onto the vertical
        self.frame = ((0.7071067811865476, -0.7071067811865476, 0.0),
                      (0.4082482904638631, 0.4082482904638631, -0.8164965809277260),
                      (0.5773502691896258, 0.5773502691896258, 0.5773502691896258))

    @ti.func
    def pair(self, i, j, x_ij, r, acc: ti.template()):
        """acc[0] += V_j W_ij; acc[1]: the bit mask of the sectors (3D: octants) holding a neighbour,
        binned only where i's kernel sum of the last evaluation was near or below the threshold
        (the bulk's grains, most of them, skip it: the pass costs as without it there; a grain
        whose sum fell from above the margin in one step finds every sector empty, and counts as
        free surface, as by the kernel sum alone)."""
        s = self.state
        acc[0] += s.mass[j] / s.density[self.walls.state_index(i, j)] * self.smoothing.value(r)
        if s.kernel_sum[i] < self.binning_below:
            self.bin(x_ij, acc)

    @ti.func
    def bin(self, x_ij, acc: ti.template()):
        sector = 0
        if ti.static(self.dim == 2):
            # 45 deg sectors of d = x_j - x_i, counter-clockwise from +x: turn d by 180 deg, then
            # by 90 deg, into the first quadrant, then split it at 45 deg
            dx, dy = -x_ij[0], -x_ij[1]
            if dy < 0.0:
                sector += 4
                dx, dy = -dx, -dy
            if dx <= 0.0:
                sector += 2
                dx, dy = dy, -dx
            if dy > dx:
                sector += 1
        else:
            for a in ti.static(range(3)):
                along = 0.0
                for b in ti.static(range(3)):
                    along -= ti.static(self.frame[a][b]) * x_ij[b]
                if along > 0.0:
                    sector += 1 << a
        acc[1] = float(int(acc[1]) | (1 << sector))

    @ti.func
    def initial(self, i):
        acc = ti.Vector.zero(float, 2)
        acc[0] = self.state.mass[i] / self.state.density[i] * self.smoothing.value(0.0)
        return acc

    @ti.func
    def store(self, i, acc):
        self.state.kernel_sum[i] = acc[0]
        empty = ~int(acc[1]) & 255  # the sectors (octants) with no neighbour
        surface = 0.0
        if acc[0] < self.threshold and empty != 0:
            surface = 1.0
        self.state.free_surface[i] = surface


@ti.data_oriented
class SurfaceLayer(PairStage):
    """The grains shifted along the surface only: a kernel sum below the threshold, and on the
    free surface or with a neighbour there (FreeSurface). Its own pass would cost a neighbour
    loop; in the kinematics slot it rides in the pass of the continuity and the strain rate.

    Why the neighbours: grains of a thin layer (the spreading tongue of a column collapse) have
    neighbours all round and a low kernel sum because the surface is a row away; shifted in full
    they push the tongue outwards (measured on the coarse a = 0.9 collapse of
    tests/test_column_collapse.py: its front kept creeping at 24-36 mm/s after 0.4 s and stopped
    short, -29.3 % against -24.0 %). Why not every grain of low kernel sum: grains round a pocket
    of the bulk (below all of the drum's wall row, whose grains land at the toe loosely packed)
    then project their neighbours' shift too, and the pocket is never filled (measured, dp 5 mm
    drum at omega = 2: the wall row's median kernel sum fell 0.89 -> 0.72 within 2.5 s and the
    step with it, 2.3e-5 -> 1.0e-5 s, as without the open-direction test)."""

    name = "surface_layer"
    slot = "kinematics"
    category = "neighbours"
    equation = "Lind et al. (2012) surface layer"
    reads = ("free_surface", "kernel_sum")
    writes = ("surface_layer",)
    fields = (FieldSpec("surface_layer", "scalar", "1 where shifted along the surface only (kernel sum below the "
                        "threshold, on the free surface or next to it), else 0", "-", "material"),)

    def __init__(self, ctx):
        super().__init__(ctx)
        self.threshold = ctx.numerics.particle_shifting.free_surface_threshold

    @ti.func
    def pair(self, i, j, x_ij, r, acc: ti.template()):
        # only a grain of low kernel sum can be in the layer: the others skip the read
        if self.state.kernel_sum[i] < self.threshold and j < self.state.n_material:
            acc += self.state.free_surface[j]

    @ti.func
    def initial(self, i):
        return self.state.free_surface[i]

    @ti.func
    def store(self, i, surface_neighbours):
        layer = 0.0
        if self.state.kernel_sum[i] < self.threshold and surface_neighbours > 0.5:
            layer = 1.0
        self.state.surface_layer[i] = layer
