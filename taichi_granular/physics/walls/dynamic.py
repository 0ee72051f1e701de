"""Dynamic boundary particles (Dalrymple & Knio 2001), as used by [A] (MODEL.md section 3).

Boundary particles stay where they are laid (staggered rows behind the wall plane, see
scene/), but their density obeys the continuity equation [A11] with the material around them
and their pressure the model's equation of state [A5]. Material approaching a wall compresses
the boundary particles, their pressure rises and pushes it back: the wall holds by the same
pressure term of the momentum equation as the material itself, with no wall-specific force.

In a pair (material i, boundary j) the boundary particle is a particle of its own: its state is
its own (``state_index(i, j) = j``), its velocity is zero (a fixed wall), and it carries the
pressure of its density. Its deviatoric stress is that of the material particle it faces
(``stress_index(i, j) = i``), as a ghost's is: the wall then resists shear as the material
next to it does (a rough wall, whose friction is the material's own, bounded by the plastic
correction). With no deviatoric stress on the wall the stress form [A12] delivers only about
half the wall traction for the stress of the first row, which then rises to twice the bulk
value, reaches the yield surface first and slides: measured, a 2D layer on a 20 deg slope
(phi = 30 deg) slid at 1-1.4 cm/s with its first row at yield, and holds with this rule.
The pressure is cut off at the model's tension limit (p >= 0 for dry sand), so a wall never
pulls material towards it.
"""
import taichi as ti

from ... import runtime

from ...state import FieldSpec
from ..stage import Stage
from .ghost import NoWalls


@ti.data_oriented
class DynamicWalls(NoWalls):
    name = "dynamic"
    # boundary particles integrate their density: the rate and start copy span every particle
    fields = (
        FieldSpec("density_rate", "scalar", "d rho/dt from the last rate evaluation [A11]", "kg/m^3/s", "all"),
        FieldSpec("density_start", "scalar", "density at the start of the step", "kg/m^3", "all"),
    )

    @classmethod
    def position_stage_classes(cls):
        return []

    @ti.func
    def stress_index(self, i, j):
        k = j
        if j >= self.state.n_material:
            k = i
        return k

    @classmethod
    def stage_classes(cls, scene):
        return [WallContinuity]


@ti.data_oriented
class WallContinuity(Stage):
    """d rho_j/dt = sum_i m_i (v_j - v_i) . grad_j W_ji over the material around boundary
    particle j [A11] (boundary-boundary pairs are at rest relative to each other: no term)."""

    name = "wall_continuity"
    category = "walls"
    equation = "[A11] Dalrymple & Knio"

    @ti.func
    def pair(self, j, i, x_ji, r, rate: ti.template()):
        if i < self.state.n_material:
            v_ji = self.state.velocity[j] - self.state.velocity[i]
            rate += self.state.mass[i] * v_ji.dot(self.smoothing.gradient(x_ji, r))

    @ti.kernel
    def _run(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for w in range(self.state.n_wall):
            j = self.state.n_material + w
            rate = 0.0
            self.grid.for_each_neighbor(j, self.pair, rate)
            self.state.density_rate[j] = rate
