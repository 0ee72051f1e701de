"""Open domain faces (``domain.outflow``): material that leaves the box is taken out of the flow.

Chute flows run off the end of the chute (the cylinder and wedge cases feed a steady stream
past the obstacle) or over its side; without this, the run-time guard stops the run at the
first particle that leaves the box. With it, such a particle is flagged (``outflow`` = 1),
parked two kernel supports beyond the face it crossed -- out of reach of every particle inside
the box, so it no longer takes part in any sum -- and held there at rest. It stays in the
output (ParaView can threshold on ``outflow``), the diagnostics count it, and the guard
ignores it. Periodic axes have no faces to leave by.
"""
import taichi as ti

from .. import runtime
from ..state import FieldSpec
from .stage import Stage


@ti.data_oriented
class Outflow(Stage):
    name = "outflow"
    slot = "outflow"
    category = "walls"
    equation = "open faces"
    fields = (FieldSpec("outflow", "scalar", "1 once the particle has left the domain through an open face", "-",
                        "material"),)

    def __init__(self, ctx):
        super().__init__(ctx)
        domain = ctx.domain
        self.dim = ctx.state.dim
        self.lower = tuple(float(v) for v in domain.lower)
        self.upper = tuple(float(v) for v in domain.upper)
        self.open_axes = tuple(not p for p in domain.periodic_mask)
        self.park_distance = 2.0 * ctx.smoothing.support  # beyond every neighbour search inside the box

    @ti.kernel
    def _run(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            x = self.state.position[i]
            outside = self.state.outflow[i] > 0.0
            for a in ti.static(range(self.dim)):
                if ti.static(self.open_axes[a]):
                    if x[a] < self.lower[a]:
                        outside = True
                        x[a] = ti.min(x[a], self.lower[a] - self.park_distance)
                    elif x[a] > self.upper[a]:
                        outside = True
                        x[a] = ti.max(x[a], self.upper[a] + self.park_distance)
            if outside:
                self.state.outflow[i] = 1.0
                self.state.position[i] = x
                self.state.velocity[i] = ti.Vector.zero(float, self.dim)
                self.state.acceleration[i] = ti.Vector.zero(float, self.dim)
