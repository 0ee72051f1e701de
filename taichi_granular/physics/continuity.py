"""Continuity equation [M26] / [A11]: d rho_i/dt = sum_j m_j v_ij . grad_i W_ij  [kg/m^3/s],
optionally with the density diffusion term of delta-SPH (Molteni & Colagrossi 2009), with
the hydrostatic part of the density difference removed (Fourtakas et al. 2019):
    + delta h c_0 sum_j 2 (rho_ji - rho_ji^H) (x_ji . grad_i W_ij) / (r_ij^2 + 0.01 h^2) V_j,
    rho_ji^H = rho_i (g . x_ji) / c_0^2   (c_0: the model's reference sound speed),
a Laplacian of the density over the neighbours a particle has; a ghost exchanges nothing (no
flux through walls). Diffusing into the free-surface row ties its density to the rows below,
and the layer then carries a pressure offset (Table 2: +25-30 Pa, 7 % of
the bed pressure; 2.3 % on a 2.5 cm layer). Excluding free-surface particles from the exchange
removes the offset on the 2.5 cm layer over 1.5 s but not on Table 2 over 30 s: its top rows
then loosen as without diffusion and the error turns into -30 Pa and grows (32 % at 25-30 s,
against 11 % with the exchange; measured), so the exchange stays. Without the hydrostatic
part the term flattens the weight-induced density gradient (0.7 % over the Table 2 layer),
which this stiff equation of state turns into a pressure error of up to 2x near the top and
a layer that swells by 8 % (measured).

Why: the density of [M26] is integrated, not summed, so once particles rearrange (shear,
shifting) nothing ties it to where the particles are. The mu(I) grains are soft in absolute
terms (1 % of density is 667 Pa at K_t = 1.5e-5 1/Pa, more than the weight of the Table 2
layer), so the drift shows as pressure error: in the Table 2 layer without diffusion the
surface rows loosen (their density falls below the packing while the layer top sinks) and the
pressure error grows ~1 %/s (measured).
"""
import taichi as ti

from .stage import PairStage


@ti.data_oriented
class Continuity(PairStage):
    name = "continuity"
    slot = "kinematics"
    category = "density"
    equation = "[M26]"
    reads = ("gradient_correction",)
    writes = ("density_rate",)

    def __init__(self, ctx):
        super().__init__(ctx)
        self.diffusion = ctx.numerics.density_diffusion
        self.h = ctx.smoothing.h
        self.eps2 = 0.01 * self.h**2
        self.gravity = tuple(ctx.gravity)
        self.c0 = ctx.model.reference_sound_speed()

    @ti.func
    def pair(self, i, j, x_ij, r, rate: ti.template()):
        s = self.state
        v_ij = self.walls.relative_velocity(i, j, x_ij)
        grad_w = self.gradient.pairwise(i, j, x_ij, r)
        rate += s.mass[j] * v_ij.dot(grad_w)  # [M26]
        if ti.static(self.diffusion > 0.0):
            if j < s.n_material:
                hydrostatic = s.density[i] * ti.Vector(self.gravity).dot(-x_ij) / self.c0**2
                # the plain kernel gradient: x_ji . grad W_ij <= 0 for every pair, so the term is a
                # true diffusion (a corrected gradient can flip the sign of single pairs)
                rate += self.diffusion * self.h * self.c0 * 2.0 * (s.density[j] - s.density[i] - hydrostatic) * \
                    (-x_ij).dot(self.smoothing.gradient(x_ij, r)) / (r * r + self.eps2) * s.mass[j] / s.density[j]

    @ti.func
    def initial(self, i):
        return 0.0

    @ti.func
    def store(self, i, rate):
        self.state.density_rate[i] = rate
