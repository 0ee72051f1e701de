"""Dynamic boundary particles (Dalrymple & Knio 2001), as used by [A] (MODEL.md section 3); the
measurements behind the rules below are in docs/models/elastoplastic.md.

Boundary particles stay where they are laid (staggered rows behind the wall plane, see scene/),
but their density obeys the continuity equation [A11] with the material around them and their
pressure the model's equation of state [A5] (mu(I): the grain EOS at rest). Material
approaching a wall compresses them, their pressure rises and pushes it back: the wall holds by
the momentum equation's own pressure term, with no wall-specific force.

In a pair (material i, boundary j) j's state is its own (``state_index(i, j) = j``), its velocity
zero (a fixed wall), its pressure that of its density, cut off at the model's tension limit (a
wall never pulls). Its deviatoric stress is that of the material particle it faces
(``stress_index(i, j) = i``): a rough wall, whose friction is the material's own, bounded by its
strength. Without it the stress form [A12] delivers only about half the wall traction, and the
first row reaches yield and slides.

``friction: pressure_only`` is [A]'s own wall ([A] section 4.3: boundary particles obey continuity and the
equation of state; "the frictional boundary condition is not implemented"): the boundary
particle carries its pressure and no deviatoric stress (``stress_index(i, j) = j``), and no
friction rule acts; what shear reaches the grain comes from its own stress in the pair sum and
from the artificial viscosity.

Coulomb wall friction (the default, per wall or obstacle: ``friction_angle_deg`` = delta, else the
material's friction angle; ``friction: rough`` for the rule above alone), not in [A]: a sheet at
the tension cut-off (p_i = 0) has no strength of its own, so the rough rule gives it no friction
although its weight presses on the wall. ``WallFriction`` adds a Coulomb contact:
its normal force is the boundary particles' pressure force on the particle,
f_n = -sum_w m_w (p_i/rho_i^2 + p_w/rho_w^2) grad_i W_iw; it stops the tangential velocity the
particle would have after the step when that takes less than tan(delta) |f_n| (sticking), and
otherwise opposes it with that limit (sliding). It acts after every other force.
"""
import math

import numpy as np
import taichi as ti

from ... import runtime

from ...state import FieldSpec
from ..stage import PairStage, Stage
from .ghost import NoWalls, boundary_sources


ROUGH = -1.0  # wall_friction of a boundary particle that carries the facing grain's s
NO_RULE = -2.0  # of one that carries only its pressure ([A]'s wall, friction: pressure_only)


@ti.data_oriented
class DynamicWalls(NoWalls):
    name = "dynamic"
    # boundary particles integrate their density: the rate and start copy span every particle
    fields = (
        FieldSpec("density_rate", "scalar", "d rho/dt from the last rate evaluation [A11]", "kg/m^3/s", "all"),
        FieldSpec("density_start", "scalar", "density at the start of the step", "kg/m^3", "all"),
        FieldSpec("wall_friction", "scalar", "tan(delta), Coulomb friction coefficient with the material "
                  f"({ROUGH:g}: a rough wall; {NO_RULE:g}: pressure only, [A]'s wall)", "-", "wall"),
    )

    @classmethod
    def position_stage_classes(cls, scene):
        return []

    def __init__(self, state, gravity=None):
        super().__init__(state, gravity)
        rules = state.wall_friction.to_numpy() if state.n_wall else np.zeros(0)
        # which boundary particles carry the facing grain's s, chosen at compile time where the
        # scene's walls all agree (the per-particle test is compiled only for a mix)
        rough = rules == ROUGH
        self.all_rough, self.none_rough = bool(rough.all()), bool(not rough.any())

    @classmethod
    def initial_fields(cls, scene, initial) -> dict:
        """tan(delta) of each boundary particle's source; ROUGH where it carries the facing grain's
        s (a rough wall; a ghost beside dynamic particles), NO_RULE for [A]'s wall."""
        fields = super().initial_fields(scene, initial)
        sources = boundary_sources(scene)
        coefficient = np.array([NO_RULE if scene.is_dynamic(source) and source.friction == "pressure_only" else
                                ROUGH if a is None else math.tan(math.radians(a))
                                for source, a in zip(sources, map(scene.boundary_friction_deg, sources))], float)
        fields["wall_friction"] = coefficient[initial.wall_of]
        return fields

    @ti.func
    def stress_index(self, i, j):
        """i (rough: the wall carries the facing particle's s) unless j's wall has a Coulomb
        friction angle (WallFriction supplies the shear, which would otherwise count twice) or
        pressure_only ([A]'s wall): then the wall carries no deviatoric stress."""
        k = j
        n = self.state.n_material
        if j >= n:
            if ti.static(self.all_rough):
                k = i
            elif ti.static(not self.none_rough):
                if self.state.wall_friction[j - n] == ROUGH:
                    k = i
        return k

    @classmethod
    def stage_classes(cls, scene):
        """The boundary particles' density rate; Coulomb wall friction only if some wall or
        obstacle has a friction angle."""
        coulomb = any(scene.boundary_friction_deg(source) is not None for source in boundary_sources(scene))
        return [WallContinuity] + ([WallFriction] if coulomb else [])


@ti.data_oriented
class WallContinuity(Stage):
    """d rho_j/dt = sum_i m_i (v_j - v_i) . grad_j W_ji over the material around boundary
    particle j [A11] (boundary-boundary pairs are at rest relative to each other: no term, and
    the loop visits the material only)."""

    name = "wall_continuity"
    slot = "wall_state"
    category = "walls"
    equation = "[A11] Dalrymple & Knio"

    @ti.func
    def pair(self, j, i, x_ji, r, rate: ti.template()):
        v_ji = self.state.velocity[j] - self.state.velocity[i]
        rate += self.state.mass[i] * v_ji.dot(self.smoothing.gradient(x_ji, r))

    @ti.kernel
    def _run(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for w in range(self.state.n_wall):
            j = self.state.n_material + w
            rate = 0.0
            self.grid.for_each_material_neighbour(j, self.pair, rate)
            self.state.density_rate[j] = rate


@ti.data_oriented
class WallFriction(PairStage):
    """Coulomb friction between material and dynamic boundaries (module docstring). For
    material particle i, F = the force per unit mass its boundary neighbours exert through the
    momentum equation (and artificial viscosity, when on); its normal n is the direction of
    their pressure force. The tangential part of F is replaced: the wall's shear force is
    what stops the tangential velocity after the step, at most tan(delta) max(F . n, 0),
    delta of the walls pushing (pressure-force-weighted mean where several meet)  [m/s^2]."""

    name = "wall_friction"
    slot = "wall_forces"
    category = "walls"
    reads = ("gradient_correction", "velocity_gradient", "strain_rate")  # the momentum pair's
    writes = ("acceleration",)
    equation = "Coulomb |f_t| <= tan(delta) |f_n|"
    def __init__(self, ctx):
        super().__init__(ctx)
        from ..artificial_viscosity import ArtificialViscosity
        from ..momentum import MOMENTUM
        self.dim = ctx.state.dim
        self.time_step = ctx.time_step
        # the same pair forces the momentum stages add, summed here over boundary neighbours only
        self.momentum = MOMENTUM[ctx.numerics.momentum](ctx)
        self.has_viscosity = ctx.numerics.artificial_viscosity.enabled
        self.viscosity = ArtificialViscosity(ctx) if self.has_viscosity else None
        self.prepares = self.momentum.prepares or self.has_viscosity

    @ti.func
    def prepare(self, i):
        """The per-particle values of the momentum and viscosity pair terms this stage re-evaluates."""
        if ti.static(self.momentum.prepares):
            self.momentum.prepare(i)
        if ti.static(self.has_viscosity):
            self.viscosity.prepare(i)

    @ti.func
    def pair(self, i, j, x_ij, r, acc: ti.template()):
        """For boundary j: acc[0] += pressure force, acc[1] += tan(delta_j) pressure force,
        acc[2] += the whole wall force (momentum and artificial viscosity), per unit mass."""
        s = self.state
        n = s.n_material
        if j >= n:
            grad_w = self.gradient.pairwise(i, j, x_ij, r)
            push = -s.mass[j] * (s.pressure[i] / s.density[i] ** 2 + s.pressure[j] / s.density[j] ** 2) * grad_w
            mu = s.wall_friction[j - n]
            if mu >= 0.0:  # walls without a friction angle (ROUGH, NO_RULE) keep their own shear
                acc[0, :] += push
                acc[1, :] += mu * push
                total = ti.Vector.zero(float, self.dim)
                self.momentum.pair(i, j, x_ij, r, total)
                if ti.static(self.has_viscosity):
                    self.viscosity.pair(i, j, x_ij, r, total)
                acc[2, :] += total

    @ti.func
    def initial(self, i):
        return ti.Matrix.zero(float, 3, self.dim)

    @ti.func
    def store(self, i, acc):
        """Replace the tangential wall force of the momentum (and artificial viscosity) stores,
        which run before this one in the same pass or earlier."""
        dt = self.time_step[None]
        push = ti.Vector([acc[0, a] for a in ti.static(range(self.dim))])
        push_norm = push.norm()
        if push_norm > 0.0 and dt > 0.0:
            normal = push / push_norm
            weighted = ti.Vector([acc[1, a] for a in ti.static(range(self.dim))])
            wall_force = ti.Vector([acc[2, a] for a in ti.static(range(self.dim))])
            normal_force = ti.max(wall_force.dot(normal), 0.0)
            limit = ti.max(weighted.dot(normal), 0.0) / push_norm * normal_force  # tan(delta) |f_n|
            a = self.state.acceleration[i] - (wall_force - wall_force.dot(normal) * normal)
            v_after = self.state.velocity[i] + dt * a
            v_t = v_after - v_after.dot(normal) * normal
            speed = v_t.norm()
            if speed > 0.0:
                a -= v_t / speed * ti.min(limit, speed / dt)
            self.state.acceleration[i] = a
