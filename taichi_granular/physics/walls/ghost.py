"""Fixed ghost particles of Morris, Fox & Zhu (1997), as used by [M] (MODEL.md section 1).

Ghosts sit on the material lattice behind the wall plane. In a pair with material particle i
a ghost carries i's own state (density, pressure, viscosity: "the same total stress") and the
fictitious velocity v_j = -(d_j/d_i) v_i [M34], so that v_ij = beta v_i with
beta = min(beta_max, 1 + d_j/d_i) [M35]-[M36]: a no-slip wall.

Ghost stress, per wall (``ghost_stress``):
- ``mirror``: sigma_j = sigma_i, as in [M]. The ghosts then contribute nothing to the stress
  gradient felt by i, so the first rows carry the wall load with their own gradient: at rest
  the bottom row sits ~9 % above hydrostatic, and in the flowing Table 2 layer the wall
  shear stress goes missing (measured, h/dp = 1.3).
- ``extrapolated``: the traction on planes parallel to the wall is carried across it with the
  static momentum balance d(sigma . n)/dn = -rho g (after Adami, Hu & Adams 2012, who do this
  for the pressure): sigma_j = sigma_i + s (g n + n g - (g . n) n n), s = rho_i n . x_ij, so that
  sigma_j . n = sigma_i . n + s g while the components along the wall stay those of i. For the
  pressure alone (viscous_pair momentum) this is p_j = p_i - s (g . n).

Ghost velocity: beta_max = 6 by default rather than Morris's 1.5. The first material row sits
at d_i = dp/2 over ghost rows at d_j = dp/2, 3dp/2, 5dp/2, whose exact linear extrapolation
needs beta = 2, 4, 6; capped at 1.5 the wall strain rate of the Table 2 layer came out 15 % low
and its first row felt a net down-slope force of 5 g sin(theta) (measured).
"""
import numpy as np
import taichi as ti

from ... import runtime

from ...state import FieldSpec
from ..stage import Stage


def boundary_sources(scene) -> list:
    """The scene's walls, then its obstacles: what ``InitialParticles.wall_of`` indexes."""
    return list(scene.walls) + list(scene.obstacles)


@ti.data_oriented
class NoWalls:
    """The boundary interface for scenes without walls: every neighbour is material."""

    name = "none"
    fields = ()

    @classmethod
    def position_stage_classes(cls, scene):
        """Stages after every position update (moving walls, impermeability)."""
        return []

    @classmethod
    def stage_classes(cls, scene):
        """Stages of a rate evaluation (their slots place them: the boundary's own state, stresses
        carried to the wall, wall friction)."""
        return []

    def __init__(self, state, gravity=None):
        self.state = state
        self.gravity = tuple(gravity) if gravity is not None else (0.0,) * state.dim

    @classmethod
    def initial_fields(cls, scene, initial) -> dict:
        """The boundary particles' fields at t = 0 (name -> (n_wall, ...) array), from where they
        were laid (``initial.wall_layout``) and from the keys of their source (the scene's walls,
        then its obstacles: :func:`sources`, indexed by ``initial.wall_of``). Every boundary model
        has the plane geometry (the impermeability safeguard reads it); subclasses add theirs."""
        return dict(initial.wall_layout)

    @ti.func
    def state_index(self, i, j):
        return j

    @ti.func
    def relative_velocity(self, i, j, x_ij):
        return self.relative(self.state.velocity, i, j, x_ij)

    @ti.func
    def relative(self, velocity: ti.template(), i, j, x_ij):
        """v_ij of any velocity-like field (the implicit viscous solve's search directions)."""
        return velocity[i] - velocity[j]

    @ti.func
    def self_factor(self, i, j, x_ij):
        """d v_ij / d v_i: 1 (a scalar times the identity)."""
        return 1.0

    @ti.func
    def pressure(self, i, j, x_ij):
        return self.state.pressure[j]

    @ti.func
    def stress_index(self, i, j):
        """The particle whose deviatoric stress j carries in the pair."""
        return self.state_index(i, j)

    @ti.func
    def stress(self, i, j, x_ij, sigma_k):
        """Stress of neighbour j given sigma_k = s(stress_index) - p(state_index)  [Pa]."""
        return sigma_k


@ti.data_oriented
class GhostWalls(NoWalls):
    name = "ghost"

    @classmethod
    def initial_fields(cls, scene, initial) -> dict:
        """beta_max [M36] and the ghost stress rule of each ghost's wall (1 and mirror, both unused,
        for a dynamic particle beside ghosts: walls/mixed.py)."""
        fields = super().initial_fields(scene, initial)
        ghosts = [None if scene.is_dynamic(source) else source for source in boundary_sources(scene)]
        beta = np.array([1.0 if g is None else g.max_velocity_factor for g in ghosts], float)
        extrapolated = np.array([float(g is not None and g.ghost_stress == "extrapolated") for g in ghosts])
        fields["wall_beta_max"] = beta[initial.wall_of]
        fields["wall_extrapolation"] = extrapolated[initial.wall_of]
        return fields

    @classmethod
    def position_stage_classes(cls, scene):
        return [WallImpermeability]
    fields = (
        FieldSpec("wall_normal", "vector", "unit normal of the ghost's wall, into the material", "-", "wall"),
        FieldSpec("wall_distance", "scalar", "d_j, distance of the ghost behind its wall [M34]", "m", "wall"),
        FieldSpec("wall_beta_max", "scalar", "beta_max of the ghost's wall [M36]", "-", "wall"),
        FieldSpec("wall_extrapolation", "scalar",
                  "1 if the ghost's stress is extrapolated with gravity, 0 for mirror stress", "-", "wall"),
    )

    @ti.func
    def state_index(self, i, j):
        k = j
        if j >= self.state.n_material:
            k = i
        return k

    @ti.func
    def beta(self, i, j, x_ij):
        """beta = min(beta_max, 1 + d_j/d_i) of ghost j seen from material i [M35]-[M36]."""
        w = j - self.state.n_material
        d_j = self.state.wall_distance[w]
        d_i = x_ij.dot(self.state.wall_normal[w]) - d_j  # x_ij . n = d_i + d_j
        beta = self.state.wall_beta_max[w]
        if d_i > 0.0:
            beta = ti.min(beta, 1.0 + d_j / d_i)
        return beta

    @ti.func
    def relative(self, velocity: ti.template(), i, j, x_ij):
        v_ij = velocity[i] - velocity[j]
        if j >= self.state.n_material:
            v_ij = self.beta(i, j, x_ij) * velocity[i]
        return v_ij

    @ti.func
    def self_factor(self, i, j, x_ij):
        factor = 1.0
        if j >= self.state.n_material:
            factor = self.beta(i, j, x_ij)
        return factor

    @ti.func
    def extrapolation(self, i, j, x_ij):
        """(n, s) for ghost j seen from material i: the wall normal and s = rho_i n . x_ij
        (n . x_ij = d_i + d_j), zero for a mirror-stress wall  [kg/m^2]."""
        w = j - self.state.n_material
        n = self.state.wall_normal[w]
        return n, self.state.wall_extrapolation[w] * self.state.density[i] * x_ij.dot(n)

    @ti.func
    def pressure(self, i, j, x_ij):
        p = self.state.pressure[j]
        if j >= self.state.n_material:
            n, s = self.extrapolation(i, j, x_ij)
            p = self.state.pressure[i] - s * ti.Vector(self.gravity).dot(n)
        return p

    @ti.func
    def stress(self, i, j, x_ij, sigma_k):
        sigma = sigma_k
        if j >= self.state.n_material:
            n, s = self.extrapolation(i, j, x_ij)
            g = ti.Vector(self.gravity)
            sigma += s * (g.outer_product(n) + n.outer_product(g) - g.dot(n) * n.outer_product(n))
        return sigma


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
    slot = "wall_motion"
    category = "walls"
    equation = "no-penetration"

    def __init__(self, ctx):
        super().__init__(ctx)
        walls = ctx.plane_walls
        dim = ctx.state.dim
        self.n_walls = len(walls)
        self.normal = [tuple(w.normal) for w in walls]
        self.point = [tuple(w.point) for w in walls]
        self.lower = [tuple(w.lower if w.lower is not None else ctx.domain.lower) for w in walls]
        self.upper = [tuple(w.upper if w.upper is not None else ctx.domain.upper) for w in walls]
        self.dim = dim
        self.min_distance = 0.25 * ctx.numerics.particle_spacing
        self.corrections = ti.field(ti.i32, shape=())

    @ti.kernel
    def _run(self):
        ti.loop_config(serialize=runtime.serial_loops)
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
