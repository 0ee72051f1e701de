"""Fixed ghost particles of Morris, Fox & Zhu (1997), as used by [M] (MODEL.md section 1).

Ghosts sit on the material lattice behind the wall plane. In a pair with material particle i
a ghost carries i's own state (density, pressure, viscosity: "the same total stress") and the
fictitious velocity v_j = -(d_j/d_i) v_i [M34], so that v_ij = beta v_i with
beta = min(beta_max, 1 + d_j/d_i) [M35]-[M36]: a no-slip wall.

Ghost pressure, per wall (``ghost_pressure``):
- ``mirror``: p_j = p_i, as in [M]. The ghosts then contribute nothing to the pressure
  gradient felt by i, so the first rows above the wall compress until their own gradient
  carries the load: at rest the bottom row sits ~9 % above hydrostatic (measured, h/dp = 1.3).
- ``hydrostatic``: p_j = p_i + rho_i (g . n)(n . (x_j - x_i)), the mirror pressure extrapolated
  along the wall normal with the normal component of gravity (after Adami, Hu & Adams 2012,
  restricted to the normal so that the along-wall pressure stays uniform on a slope).
"""
import taichi as ti

from ...state import FieldSpec
from ..stage import Stage


@ti.data_oriented
class NoWalls:
    """The boundary interface for scenes without walls: every neighbour is material."""

    name = "none"
    fields = ()

    @classmethod
    def position_stage_classes(cls):
        return []

    def __init__(self, state):
        self.state = state


    @ti.func
    def state_index(self, i, j):
        return j

    @ti.func
    def relative_velocity(self, i, j, x_ij):
        return self.state.velocity[i] - self.state.velocity[j]

    @ti.func
    def pressure(self, i, j, x_ij):
        return self.state.pressure[j]


@ti.data_oriented
class GhostWalls(NoWalls):
    name = "ghost"

    @classmethod
    def position_stage_classes(cls):
        return [WallImpermeability]
    fields = (
        FieldSpec("wall_normal", "vector", "unit normal of the ghost's wall, into the material", "-", "wall"),
        FieldSpec("wall_distance", "scalar", "d_j, distance of the ghost behind its wall [M34]", "m", "wall"),
        FieldSpec("wall_beta_max", "scalar", "beta_max of the ghost's wall [M36]", "-", "wall"),
        FieldSpec("wall_pressure_gradient", "scalar",
                  "g . n of the ghost's wall for hydrostatic ghost pressure, 0 for mirror", "m/s^2", "wall"),
    )

    @ti.func
    def state_index(self, i, j):
        k = j
        if j >= self.state.n_material:
            k = i
        return k

    @ti.func
    def relative_velocity(self, i, j, x_ij):
        v_ij = self.state.velocity[i] - self.state.velocity[j]
        if j >= self.state.n_material:
            w = j - self.state.n_material
            d_j = self.state.wall_distance[w]
            d_i = x_ij.dot(self.state.wall_normal[w]) - d_j  # x_ij . n = d_i + d_j
            beta = self.state.wall_beta_max[w]
            if d_i > 0.0:
                beta = ti.min(beta, 1.0 + d_j / d_i)  # [M35]-[M36]
            v_ij = beta * self.state.velocity[i]
        return v_ij

    @ti.func
    def pressure(self, i, j, x_ij):
        p = self.state.pressure[j]
        if j >= self.state.n_material:
            w = j - self.state.n_material
            # (g . n) (n . (x_j - x_i)) with n . x_ij = d_i + d_j > 0 and g . n < 0
            p = self.state.pressure[i] - self.state.density[i] * self.state.wall_pressure_gradient[w] * \
                x_ij.dot(self.state.wall_normal[w])
        return p


@ti.data_oriented
class WallImpermeability(Stage):
    """Keeps material on its side of every wall plane (a safeguard for disordered flow).

    Fixed ghosts hold a lattice-ordered layer at rest exactly, but once rows near a wall
    interpenetrate (sheared granular flow) a particle can slip through a gap of the ghost
    lattice. After every position update, a material particle found less than
    ``min_distance`` (dp/4) from a wall plane, inside that wall's box, is put back at
    min_distance and its velocity towards the wall is removed. Counted in ``corrections``.
    """

    name = "wall_impermeability"
    category = "walls"
    equation = "no-penetration"

    def __init__(self, ctx):
        super().__init__(ctx)
        walls = ctx.scene.walls
        dim = ctx.scene.dimension
        self.n_walls = len(walls)
        self.normal = [tuple(w.normal) for w in walls]
        self.point = [tuple(w.point) for w in walls]
        self.lower = [tuple(w.lower if w.lower is not None else ctx.scene.domain.lower) for w in walls]
        self.upper = [tuple(w.upper if w.upper is not None else ctx.scene.domain.upper) for w in walls]
        self.dim = dim
        self.min_distance = 0.25 * ctx.scene.numerics.particle_spacing
        self.corrections = ti.field(ti.i32, shape=())

    @ti.kernel
    def _run(self):
        for i in range(self.state.n_material):
            for w in ti.static(range(self.n_walls)):
                n = ti.Vector(self.normal[w])
                x = self.state.position[i]
                inside = True
                for a in ti.static(range(self.dim)):
                    if n[a] == 0.0 and (x[a] < self.lower[w][a] or x[a] > self.upper[w][a]):
                        inside = False
                d = (x - ti.Vector(self.point[w])).dot(n)
                if inside and d < self.min_distance:
                    self.state.position[i] = x + (self.min_distance - d) * n
                    v = self.state.velocity[i]
                    vn = v.dot(n)
                    if vn < 0.0:
                        self.state.velocity[i] = v - vn * n
                    self.corrections[None] += 1
