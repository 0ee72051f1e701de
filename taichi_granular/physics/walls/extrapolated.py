"""Boundary particles with extrapolated state, Peng et al.'s improved wall treatment
(MODEL.md section 2).

Boundary particles sit on a lattice behind the wall (as many rows as the kernel support needs)
and carry, at every rate evaluation, a state extrapolated from the material around them:

- velocity, no slip: v_w = 2 v_wall - sum_f v_f W_wf / sum_f W_wf, so that the velocity
  interpolated across the wall vanishes relative to the wall;
- stress, a Shepard average with the hydrostatic correction on the diagonal,
      sigma_w = [sum_f sigma_f W_wf V_f - diag(rho_f g (x_w - x_f)) W_wf V_f] / sum_f W_wf V_f,
  one gravity component per diagonal entry (written here with the package's sigma = -p I + s,
  the same stress as the tension-positive T of MODEL.md): a wall under a layer at rest then
  carries the layer's stress continued below the surface, and the momentum equation [A12]
  of the first rows sees a full, hydrostatic neighbourhood;
- density, the Shepard average of the material's, sum_f m_f W_wf / sum_f W_wf V_f.

The stress is stored as p_w = -tr(sigma_w)/d and s_w = sigma_w + p_w I, so that every pair
term that builds sigma_j = s_j - p_j I sees sigma_w. A boundary particle with no material in
reach carries zero stress, the wall's velocity and the reference density.

Drums keep a safeguard like the ghost walls' (physics/walls/ghost.py): a material particle found
closer than dp/4 to the drum's radius is put back and loses its outward radial velocity
(counted in ``corrections``). Measured: without it a small drum (R = 5 cm, omega = 2 pi rad/s)
lost a grain through its wall within a revolution -- a grain whose stress has fallen to the
tension guard has no stiffness (the law is of degree one in T_s) and nothing stops it at the wall.

The velocity is extrapolated before the material's rates (continuity and velocity gradient see
the no-slip wall), the stress after the material's stress and before the momentum equation.
Walls that move (the rotating drum) carry their prescribed velocity in ``wall_velocity``.
"""
import numpy as np
import taichi as ti

from ... import runtime

from ...state import FieldSpec
from ..stage import Stage
from .ghost import NoWalls, boundary_sources

EXTRAPOLATED_FIELDS = (
    FieldSpec("wall_velocity", "vector", "v_wall, the prescribed velocity of the wall at the particle", "m/s",
              "wall"),
    # boundary particles carry a deviatoric stress of their own
    FieldSpec("deviatoric_stress", "matrix", "s of the total stress (boundary particles: extrapolated)", "Pa",
              "all"),
)


@ti.data_oriented
class ExtrapolatedWalls(NoWalls):
    name = "extrapolated"
    fields = EXTRAPOLATED_FIELDS

    @classmethod
    def initial_fields(cls, scene, initial) -> dict:
        """The rigid rotation of each boundary particle's source (a drum's omega about its origin;
        0 for fixed walls), its rest position and, in 2D, the wall velocity omega z x (x - c)."""
        fields = super().initial_fields(scene, initial)
        sources = boundary_sources(scene)
        x_wall = initial.position[initial.n_material:]
        dim = x_wall.shape[1]
        omega = np.array([sources[w].angular_velocity for w in initial.wall_of], float)
        centre = np.array([sources[w].origin or (0.0,) * dim if sources[w].angular_velocity else (0.0,) * dim
                           for w in initial.wall_of], float).reshape(-1, dim)
        fields.update({"wall_rest_position": x_wall, "wall_angular_velocity": omega, "wall_rotation_centre": centre})
        if dim == 2:
            arm = x_wall - centre
            fields["wall_velocity"] = omega[:, None] * np.c_[-arm[:, 1], arm[:, 0]]
        return fields

    @classmethod
    def position_stage_classes(cls, scene):
        """The drum's rigid rotation, if some obstacle turns; the impermeability safeguards of the
        drum and of plane walls (the ghost walls' stage: a grain at the tension guard carries no
        stress, so nothing else stops it at a wall; measured: the corner grain of the pile
        collapse fell through the floor at 0.06 s)."""
        from .ghost import WallImpermeability
        turning = any(o.angular_velocity != 0.0 for o in scene.obstacles)
        drums = any(o.shape == "drum" for o in scene.obstacles)
        return ([WallRotation] if turning else []) + ([DrumImpermeability] if drums else []) + \
            ([WallImpermeability] if scene.walls else [])

    @classmethod
    def stage_classes(cls, scene):
        return [WallVelocityExtrapolation, WallStressExtrapolation]


@ti.data_oriented
class WallVelocityExtrapolation(Stage):
    """No slip [P]: v_w = v_wall(x_w) - sum_f (v_f - v_wall(x_f)) W_wf / sum_f W_wf, the material's
    velocity relative to the wall's rigid motion mirrored across the wall. For a wall at rest or
    in translation (v_wall uniform) this is [P]'s v_w = 2 v_wall - sum_f v_f W_wf / sum_f W_wf.
    For a turning wall v_wall differs from point to point: [P]'s form with v_wall taken at the
    boundary particle gives a material turning rigidly with the drum a spurious slip of omega
    (r_w - r_f) ~ 2 omega dp, which shears the grains next to the wall without end."""

    name = "wall_velocity_extrapolation"
    slot = "wall_state"
    category = "walls"
    equation = "[P] improved wall"

    def __init__(self, ctx):
        super().__init__(ctx)
        self.dim = ctx.state.dim
        self.turning = any(o.angular_velocity != 0.0 for o in ctx.obstacles)

    @ti.func
    def wall_motion(self, k, x):
        """v_wall at point x of the rigid motion of boundary particle k (2D turning walls:
        omega z x (x - c); otherwise its own, uniform, velocity)  [m/s]."""
        v = self.state.wall_velocity[k]
        if ti.static(self.turning):
            omega = self.state.wall_angular_velocity[k]
            if omega != 0.0:
                arm = x - self.state.wall_rotation_centre[k]
                v = omega * ti.Vector([-arm[1], arm[0]])
        return v

    @ti.func
    def pair(self, w, f, x_wf, r, acc: ti.template()):
        weight = self.smoothing.value(r)
        relative = self.state.velocity[f] - self.wall_motion(w - self.state.n_material, self.state.position[f])
        acc[self.dim] += weight
        for a in ti.static(range(self.dim)):
            acc[a] += weight * relative[a]

    @ti.kernel
    def _run(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for k in range(self.state.n_wall):
            w = self.state.n_material + k
            acc = ti.Vector.zero(float, self.dim + 1)
            self.grid.for_each_material_neighbour(w, self.pair, acc)
            v = self.state.wall_velocity[k]
            if acc[self.dim] > 0.0:
                mean = ti.Vector([acc[a] for a in ti.static(range(self.dim))]) / acc[self.dim]
                v -= mean
            self.state.velocity[w] = v


@ti.data_oriented
class WallStressExtrapolation(Stage):
    """sigma_w and rho_w as Shepard averages of the material, with the hydrostatic correction [P]."""

    name = "wall_stress_extrapolation"
    slot = "wall_stress"
    category = "walls"
    equation = "[P] improved wall"

    def __init__(self, ctx):
        super().__init__(ctx)
        self.dim = ctx.state.dim
        self.gravity = ti.Vector(ctx.gravity)
        self.reference_density = ctx.model.reference_density()

    @ti.func
    def pair(self, w, f, x_wf, r, acc: ti.template()):
        """acc rows 0..d-1: sum sigma W V - diag(rho g x_wf) W V; row d: [sum W V, sum m W, 0...]."""
        s = self.state
        volume_weight = self.smoothing.value(r) * s.mass[f] / s.density[f]
        sigma = self.model.deviatoric_stress(f) - s.pressure[f] * ti.Matrix.identity(float, self.dim)
        for a in ti.static(range(self.dim)):
            sigma[a, a] -= s.density[f] * self.gravity[a] * x_wf[a]  # x_wf = x_w - x_f
        for a, b in ti.static(ti.ndrange(self.dim, self.dim)):
            acc[a, b] += sigma[a, b] * volume_weight
        acc[self.dim, 0] += volume_weight
        acc[self.dim, 1] += self.smoothing.value(r) * s.mass[f]

    @ti.kernel
    def _run(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for k in range(self.state.n_wall):
            w = self.state.n_material + k
            acc = ti.Matrix.zero(float, self.dim + 1, max(self.dim, 2))
            self.grid.for_each_material_neighbour(w, self.pair, acc)
            sigma = ti.Matrix.zero(float, self.dim, self.dim)
            density = self.reference_density
            if acc[self.dim, 0] > 0.0:
                for a, b in ti.static(ti.ndrange(self.dim, self.dim)):
                    sigma[a, b] = acc[a, b] / acc[self.dim, 0]
                density = acc[self.dim, 1] / acc[self.dim, 0]
            pressure = -sigma.trace() / self.dim
            if pressure < 0.0:  # no tension: the correction pulls where the wall is above the material
                sigma = ti.Matrix.zero(float, self.dim, self.dim)
                pressure = 0.0
            self.state.pressure[w] = pressure
            self.state.deviatoric_stress[w] = sigma + pressure * ti.Matrix.identity(float, self.dim)
            self.state.density[w] = density


@ti.data_oriented
class WallRotation(Stage):
    """Turns rotating boundary particles (2D drums) rigidly to the angle omega t of the time the
    scene is moved to, x = c + R(omega t)(x_0 - c), and sets v_wall = omega z x (x - c). The
    positions follow from t, not from a sum of steps: no drift over many revolutions, and a
    resumed run lands exactly where it left."""

    name = "wall_rotation"
    slot = "wall_motion"
    category = "walls"
    equation = "rigid rotation"
    moves_boundary = True  # the neighbour grid tracks the boundary particles' moves (neighbours.py)
    fields = (
        FieldSpec("wall_rest_position", "vector", "x_0, the boundary particle's position at t = 0", "m", "wall"),
        FieldSpec("wall_angular_velocity", "scalar", "omega of the rotating wall (0: fixed)", "rad/s", "wall"),
        FieldSpec("wall_rotation_centre", "vector", "c, centre of the wall's rotation", "m", "wall"),
    )

    def __init__(self, ctx):
        super().__init__(ctx)
        self.time = ctx.time

    def run(self) -> None:
        super().run()
        self.grid.fixed_moved()  # boundary particles moved: the list's rebuild check counts them

    @ti.kernel
    def _run(self):
        t = self.time[None]
        ti.loop_config(serialize=runtime.serial_loops)
        for k in range(self.state.n_wall):
            omega = self.state.wall_angular_velocity[k]
            if omega != 0.0:
                c = self.state.wall_rotation_centre[k]
                arm0 = self.state.wall_rest_position[k] - c
                cos_a, sin_a = ti.cos(omega * t), ti.sin(omega * t)
                arm = ti.Vector([cos_a * arm0[0] - sin_a * arm0[1], sin_a * arm0[0] + cos_a * arm0[1]])
                self.state.position[self.state.n_material + k] = c + arm
                self.state.wall_velocity[k] = omega * ti.Vector([-arm[1], arm[0]])


@ti.data_oriented
class DrumImpermeability(Stage):
    """After every position update: material beyond R - dp/4 from a drum's centre goes back to
    R - dp/4 with its outward radial velocity removed (module docstring)."""

    name = "drum_impermeability"
    slot = "wall_motion"
    category = "walls"
    equation = "no-penetration"

    def __init__(self, ctx):
        super().__init__(ctx)
        drums = [o for o in ctx.obstacles if o.shape == "drum"]
        self.centres = [tuple(o.origin or (0.0, 0.0)) for o in drums]
        self.limits = [o.radius - 0.25 * ctx.numerics.particle_spacing for o in drums]
        self.corrections = ti.field(ti.i32, shape=())

    @ti.kernel
    def _run(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            for d in ti.static(range(len(self.limits))):
                arm = self.state.position[i] - ti.Vector(self.centres[d])
                r = arm.norm()
                if r > self.limits[d]:
                    radial = arm / r
                    self.state.position[i] = ti.Vector(self.centres[d]) + self.limits[d] * radial
                    v = self.state.velocity[i]
                    outward = v.dot(radial)
                    if outward > 0.0:
                        self.state.velocity[i] = v - outward * radial
                    self.corrections[None] += 1
