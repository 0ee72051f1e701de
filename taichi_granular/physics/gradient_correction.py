"""Kernel gradients as every pair loop sees them: plain, or renormalised (MODEL.md section 2).

With M_i = sum_j V_j (x_j - x_i) (x) grad_i W_ij (the identity in the continuum; 0.974 I on a
square lattice at h/dp = 1.3 with Wendland C2), ``numerics.gradient_correction`` selects

- ``matrix`` (Bonet & Lok 1999; [P]): L_i = M_i^-1, so sum_j V_j (f_j - f_i) L_i grad_i W_ij is
  exact for every linear field f, walls and free surfaces included. In momentum the pair forces
  then need not be central: once a sheared layer loses its row order, particles clump
  (measured on the inclined plane: pairs at 0.18 dp within 0.5 s of the rows mixing).
- ``scalar``: L_i = (d / tr M_i) I, exact for linear fields wherever M_i is isotropic (the bulk,
  near-lattice order), and central, so it cannot pull particles together.
- ``none``: the plain gradient.

Where the moment matrix is nearly singular (free-surface particles) L_i falls back to the
identity: the guard is det(M_i) < ``min_determinant`` = 0.5 (full support gives 1). With 0.1
the top rows of a layer at rest jitter; with 0.5 every row holds within 1.6 % of rho g H. The
guard also sets how well a free-surface flow keeps its volume: in the continuity, the plain
gradient of a cut support (det 0.3-0.5, the rows under the surface) lets a sheared fill swell
(the coarse drum +8.3 % in 1 s), the renormalised one makes it shrink (-5.7 % with the guard at
0.1 in the continuity only), measured in docs/models/hypoplastic.md, "The fill swells" (open).

Two forms are offered to the stages:
- ``one_sided(i, j, x_ij, r)`` = L_i grad_i W_ij, for gradients of fields at i (velocity gradient);
- ``pairwise(i, j, x_ij, r)`` = (L_i + L_j)/2 grad_i W_ij, antisymmetric in (i, j), for the
  momentum equation, so that linear momentum stays conserved to round-off.
Without correction both are the plain grad_i W_ij and no field is allocated.
"""
import taichi as ti

from ..state import FieldSpec
from .stage import PairStage


@ti.data_oriented
class PlainGradient:
    """grad_i W_ij as it comes from the smoothing function."""

    name = "plain"
    fields = ()

    def __init__(self, ctx):
        self.smoothing = ctx.smoothing

    @classmethod
    def stage_classes(cls):
        return []

    @ti.func
    def one_sided(self, i, j, x_ij, r):
        return self.smoothing.gradient(x_ij, r)

    @ti.func
    def pairwise(self, i, j, x_ij, r):
        return self.smoothing.gradient(x_ij, r)


@ti.data_oriented
class CorrectedGradient(PlainGradient):
    name = "renormalised"
    fields = (FieldSpec("gradient_correction", "matrix", "L_i, kernel gradient renormalisation matrix", "-",
                        "material"),)
    min_determinant = 0.5  # free-surface particles (det ~ 0.5 and below) keep the plain gradient

    def __init__(self, ctx):
        super().__init__(ctx)
        self.state, self.walls = ctx.state, ctx.walls
        self.scalar = ctx.numerics.gradient_correction == "scalar"

    @classmethod
    def stage_classes(cls):
        return [GradientCorrection]

    @ti.func
    def matrix(self, i, j):
        """L of the particle whose state j carries in the pair (ghosts mirror i)."""
        k = self.walls.state_index(i, j)
        L = ti.Matrix.identity(float, self.state.dim)
        if k < self.state.n_material:
            L = self.state.gradient_correction[k]
        return L

    @ti.func
    def one_sided(self, i, j, x_ij, r):
        return self.state.gradient_correction[i] @ self.smoothing.gradient(x_ij, r)

    @ti.func
    def pairwise(self, i, j, x_ij, r):
        L = 0.5 * (self.state.gradient_correction[i] + self.matrix(i, j))
        return L @ self.smoothing.gradient(x_ij, r)


@ti.data_oriented
class GradientCorrection(PairStage):
    """Computes L_i for every material particle (positions and densities only)."""

    name = "gradient_correction"
    slot = "correction"
    category = "neighbours"
    equation = "renormalisation [P]"
    fields = CorrectedGradient.fields
    writes = ("gradient_correction",)

    def __init__(self, ctx):
        super().__init__(ctx)
        self.dim = ctx.state.dim
        self.min_determinant = CorrectedGradient.min_determinant
        self.scalar = ctx.numerics.gradient_correction == "scalar"

    @ti.func
    def pair(self, i, j, x_ij, r, moment: ti.template()):
        k = self.walls.state_index(i, j)
        volume_j = self.state.mass[j] / self.state.density[k]
        moment -= volume_j * x_ij.outer_product(self.smoothing.gradient(x_ij, r))  # (x_j - x_i) (x) grad W

    @ti.func
    def initial(self, i):
        return ti.Matrix.zero(float, self.dim, self.dim)

    @ti.func
    def store(self, i, moment):
        L = ti.Matrix.identity(float, self.dim)
        if moment.determinant() > self.min_determinant:
            if ti.static(self.scalar):
                L = (self.dim / moment.trace()) * ti.Matrix.identity(float, self.dim)
            else:
                L = moment.inverse()
        self.state.gradient_correction[i] = L


GRADIENTS = {"none": PlainGradient, "scalar": CorrectedGradient, "matrix": CorrectedGradient}
