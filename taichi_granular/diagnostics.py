"""Whole-system diagnostics written at every frame, and the per-step run-time guard."""
import numpy as np
import taichi as ti

from . import runtime
from .launch import launcher

GUARD_CODES = {
    1: "non-finite position",
    2: "non-finite velocity",
    3: "non-finite or non-positive density",
    4: "non-finite pressure",
    5: "outside the domain",
    6: "density outside the plausible band",
}

# The guard's band of plausible densities, as fractions of the model's reference density. Below:
# a splash of grains is a dilute spray, but a bulk density of a tenth of the packing's means the
# density equation has lost the particle (measured: a mu(I) grain splashing off a 5 m/s impact
# reached 0.16); above: no grain packing is twice as dense as its reference.
DENSITY_BAND = (0.1, 2.0)


@ti.data_oriented
class Diagnostics:
    """Kinetic energy [J (per m in 2D)], max speed [m/s], max |density error| [-], Mach number
    max |v| / c_0 [-] (c_0 the model's reference sound speed, mach.py), and with open faces the number of particles that have left the domain."""

    def __init__(self, state, model):
        self.state, self.model = state, model
        self.sound_speed = model.reference_sound_speed()  # [m/s], the c of the Mach number (mach.py)
        self.outflow = state.has("outflow")
        self.outflow_count = ti.field(ti.i32, shape=())
        self.kinetic_energy = ti.field(float, shape=())
        self.max_speed = ti.field(float, shape=())
        self.max_density_error = ti.field(float, shape=())

    @ti.kernel
    def _measure(self):
        self.kinetic_energy[None] = 0.0
        self.max_speed[None] = 0.0
        self.max_density_error[None] = 0.0
        self.outflow_count[None] = 0
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            if ti.static(self.outflow):
                if self.state.outflow[i] > 0.0:
                    self.outflow_count[None] += 1
                    continue
            v = self.state.velocity[i]
            self.kinetic_energy[None] += 0.5 * self.state.mass[i] * v.norm_sqr()
            ti.atomic_max(self.max_speed[None], v.norm())
            ti.atomic_max(self.max_density_error[None], ti.abs(self.model.density_error(i)))

    def measure(self) -> dict:
        self._measure()
        result = {"kinetic_energy": float(self.kinetic_energy[None]), "max_speed": float(self.max_speed[None]),
                  "max_density_error": float(self.max_density_error[None]), "mach": float(self.max_speed[None]) / self.sound_speed}
        if self.outflow:
            result["outflow"] = int(self.outflow_count[None])
        return result


@ti.data_oriented
class Guard:
    """Finds the first material particle with a non-finite or out-of-domain state, or a density
    outside DENSITY_BAND times ``reference_density`` [kg/m^3]."""

    def __init__(self, state, domain, reference_density: float):
        self.state = state
        self.density_range = (DENSITY_BAND[0] * reference_density, DENSITY_BAND[1] * reference_density)
        self.dim = state.dim
        self.lower = tuple(domain.lower)
        self.upper = tuple(domain.upper)
        self.periodic = domain.periodic_mask
        self.outflow = state.has("outflow")  # particles that left by an open face are not checked
        self.first_bad = ti.field(ti.i32, shape=())
        self.code = ti.field(ti.i32, shape=state.n_material)

    @ti.func
    def finite(self, value):
        return ti.abs(value) < 1e300  # false for NaN and Inf

    @ti.kernel
    def _check(self) -> ti.i32:
        n = self.state.n_material
        self.first_bad[None] = n
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(n):
            code = 0
            if ti.static(self.outflow):
                if self.state.outflow[i] > 0.0:
                    self.code[i] = 0
                    continue
            x = self.state.position[i]
            v = self.state.velocity[i]
            for a in ti.static(range(self.dim)):
                if not self.finite(x[a]):
                    code = 1
                elif not self.finite(v[a]):
                    code = 2
                elif ti.static(not self.periodic[a]):
                    if x[a] < self.lower[a] or x[a] > self.upper[a]:
                        code = 5
            if code == 0:
                rho = self.state.density[i]
                if not (self.finite(rho) and rho > 0.0):
                    code = 3
                elif not self.finite(self.state.pressure[i]):
                    code = 4
                elif rho < ti.static(self.density_range[0]) or rho > ti.static(self.density_range[1]):
                    code = 6
            self.code[i] = code
            if code != 0:
                ti.atomic_min(self.first_bad[None], i)
        return self.first_bad[None]

    def check(self):
        """None if every particle is sound, else (particle id, reason, values)."""
        bad = int(launcher(self, "_check")())
        if bad >= self.state.n_material:
            return None
        code = int(self.code[bad])
        values = {name: np.asarray(self.state.field(name)[bad]).tolist()
                  for name in ("position", "velocity", "density", "pressure")}
        return bad, GUARD_CODES[code], values
