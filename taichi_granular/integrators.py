"""Time integration (MODEL.md section 0) and time-step control [M39].

Both integrators advance material particles (and the density of boundary particles whose
density evolves, MODEL.md section 3) and wrap positions along periodic axes; boundary particles
are moved, if at all, by their own stages. A model's integrated tensors (``model.history``:
the deviatoric stress of [A6]) are advanced like the density.

- Symplectic Verlet, kick-drift-kick [M, Sec. 3.5] (Kajtar & Monaghan 2008): one rate
  evaluation per step. Half step of positions, velocities and density with v(n), the last
  acceleration dv/dt(n-1/2) and d rho/dt; rates at n+1/2; v(n+1) = v(n) + dt a(n+1/2),
  x(n+1) = x(n) + dt (v(n) + v(n+1))/2, rho(n+1) = rho(n) + dt d rho/dt(n+1/2). The total
  momentum changes by dt sum_i m_i a_i, which vanishes to round-off for pairwise forces.
- Predictor-corrector [P], [A]: rates at n, predict to n+1/2, rates at n+1/2, correct.
  Two rate evaluations per step.
"""
import taichi as ti

from . import runtime
from .launch import launcher

from .physics.stage import Stage
from .state import FieldSpec

START_FIELDS = (
    FieldSpec("position_start", "vector", "position at the start of the step", "m", "material"),
    FieldSpec("velocity_start", "vector", "velocity at the start of the step", "m/s", "material"),
    FieldSpec("density_start", "scalar", "density at the start of the step", "kg/m^3", "material"),
)


MAX_SHIFT = 0.1  # largest particle shift in one step, in h (physics/shifting.py)
MOMENTUM_BLOCK = 256  # particles per partial sum of the shift's momentum


@ti.data_oriented
class _Update(Stage):
    """Shared kernels: keep the start-of-step state, and x/v/rho updates from it."""

    category = "integration"
    fields = START_FIELDS

    def __init__(self, ctx):
        super().__init__(ctx)
        self.shifting = ctx.numerics.particle_shifting.enabled
        self.h = ctx.smoothing.h
        self.taylor_velocity = self.shifting and "velocity_gradient" in ctx.state.specs
        self.conserve_momentum = self.taylor_velocity and ctx.numerics.particle_shifting.conserve_momentum
        self.implicit_viscosity = ctx.numerics.implicit_viscosity  # physics/implicit_viscosity.py
        # the model's integrated tensors (the elastoplastic deviatoric stress): (field, rate, start)
        self.history = [tuple(ctx.state.field(name) for name in names) for names in ctx.model.history]
        if self.conserve_momentum:  # the Taylor correction's momentum, summed in fixed blocks (deterministic)
            n_blocks = max(1, -(-ctx.state.n_material // MOMENTUM_BLOCK))
            self.block_momentum = ti.Vector.field(ctx.state.dim, float, n_blocks)
            self.block_mass = ti.field(float, n_blocks)
            self.mean_correction = ti.Vector.field(ctx.state.dim, float, ())

    @ti.func
    def wrap(self, i):
        self.state.position[i] = self.grid.wrap(self.state.position[i])

    @ti.kernel
    def half_step(self, dt: float):
        """Keep (x, v, rho, history) at n; x += dt/2 v(n); v += dt/2 a; rho += dt/2 d rho/dt."""
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            self.state.position_start[i] = self.state.position[i]
            self.state.velocity_start[i] = self.state.velocity[i]
            self.state.velocity[i] += 0.5 * dt * self.state.acceleration[i]
            if ti.static(self.implicit_viscosity):
                # the acceleration holds the explicit forces only: add the last solve's viscous part,
                # or a grain held by its viscous stress on a slope sees half a step of free sliding
                # as a strain rate (measured: the a = 0.9 deposit then creeps 3x faster)
                self.state.velocity[i] += 0.5 * dt * self.state.viscous_acceleration[i]
            self.state.position[i] += 0.5 * dt * self.drift_velocity(i)
            self.wrap(i)
            for field, rate, start in ti.static(self.history):
                start[i] = field[i]
                field[i] += 0.5 * dt * rate[i]
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.density_rate.shape[0]):  # material, and walls whose density evolves
            self.state.density_start[i] = self.state.density[i]
            self.state.density[i] += 0.5 * dt * self.state.density_rate[i]

    @ti.func
    def particle_shift(self, i, dt):
        """dt u_shift of particle i, capped at MAX_SHIFT h  [m] (physics/shifting.py)."""
        shift = dt * self.state.shift_velocity[i]
        length = shift.norm()
        if length > ti.static(MAX_SHIFT * self.h):
            shift *= ti.static(MAX_SHIFT * self.h) / length
        return shift

    @ti.func
    def taylor_correction(self, i, dt):
        """grad v . delta r: the velocity at the shifted position, to first order  [m/s]."""
        return self.state.velocity_gradient[i] @ self.particle_shift(i, dt)

    @ti.kernel
    def kick(self, dt: float):
        """v(n+1) = v(n) + dt a (with the implicit viscous update, v* of its solve, which follows)."""
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            self.state.velocity[i] = self.state.velocity_start[i] + dt * self.state.acceleration[i]

    @ti.kernel
    def drift(self, dt: float):
        """x(n+1) = x(n) + dt (v(n) + v(n+1))/2; rho(n+1) = rho(n) + dt d rho/dt
        (history fields alike); then the particle shift, if enabled: x += delta r and, where the
        model has a velocity gradient, v += grad v . delta r (the velocity at the new position).
        That correction moves momentum (measured: 4.3e-3 of |p| over 1e4 steps of a periodic
        box); ``particle_shifting.conserve_momentum`` removes its mass-weighted mean (6e-16)."""
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            v_new = self.state.velocity[i]
            x_new = self.state.position_start[i] + 0.5 * dt * (self.state.velocity_start[i] + v_new)
            if ti.static(self.shifting):  # physics/shifting.py: move by dt u_shift, carry v along
                x_new += self.particle_shift(i, dt)
            self.state.position[i] = x_new
            self.wrap(i)
            for field, rate, start in ti.static(self.history):
                field[i] = start[i] + dt * rate[i]
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.density_rate.shape[0]):
            self.state.density[i] = self.state.density_start[i] + dt * self.state.density_rate[i]
        if ti.static(self.conserve_momentum):
            n = self.state.n_material
            ti.loop_config(serialize=runtime.serial_loops)
            for b in range(self.block_mass.shape[0]):  # each block summed in order: the same bits every run
                momentum = ti.Vector.zero(float, self.state.dim)
                mass = 0.0
                for i in range(b * MOMENTUM_BLOCK, ti.min((b + 1) * MOMENTUM_BLOCK, n)):
                    momentum += self.state.mass[i] * self.taylor_correction(i, dt)
                    mass += self.state.mass[i]
                self.block_momentum[b] = momentum
                self.block_mass[b] = mass
            ti.loop_config(serialize=True)
            for _ in range(1):
                momentum = ti.Vector.zero(float, self.state.dim)
                mass = 0.0
                for b in range(self.block_mass.shape[0]):
                    momentum += self.block_momentum[b]
                    mass += self.block_mass[b]
                self.mean_correction[None] = momentum / ti.max(mass, 1e-300)
            ti.loop_config(serialize=runtime.serial_loops)
            for i in range(n):
                self.state.velocity[i] += self.taylor_correction(i, dt) - self.mean_correction[None]
        elif ti.static(self.taylor_velocity):
            ti.loop_config(serialize=runtime.serial_loops)
            for i in range(self.state.n_material):
                self.state.velocity[i] += self.taylor_correction(i, dt)


@ti.data_oriented
class SymplecticVerlet(_Update):
    name = "symplectic_verlet"
    equation = "[M Sec. 3.5]"
    rate_evaluations = 1

    @ti.func
    def drift_velocity(self, i):
        return self.state.velocity_start[i]  # positions drift with v(n)

    def prepare(self, evaluate_rates) -> None:
        """Rates at t = 0 stand in for a(-1/2) on the first step."""
        evaluate_rates()

    def step(self, dt: float, scheme) -> None:
        """The algorithm of a step, as run and as ``describe`` lists it (Scheme.stage_list records
        these calls)."""
        scheme.run(self, launcher(self, "half_step"), dt)  # x, v, rho to n+1/2 with a(n-1/2)
        scheme.after_move(0.5)
        scheme.evaluate_rates()  # a(n+1/2), d rho/dt(n+1/2)
        scheme.run(self, launcher(self, "kick"), dt)  # v(n+1)
        scheme.solve_viscosity()  # the implicit viscous update of v(n+1), where the scene has one
        scheme.run(self, launcher(self, "drift"), dt)  # x(n+1), rho(n+1), the particle shift
        scheme.after_move()


@ti.data_oriented
class PredictorCorrector(_Update):
    name = "predictor_corrector"
    equation = "[P]"
    rate_evaluations = 2

    @ti.func
    def drift_velocity(self, i):
        return self.state.velocity[i]  # x(1/2) = x + dt/2 v(1/2)

    def prepare(self, evaluate_rates) -> None:
        """Rates at t = 0, for the first step's stable time step only (the step evaluates its own).
        Why: the time step reads fields that the rate stages derive (mu(I)'s grain density sets its
        sound speed); left unset, the first mu(I) step was 1e27 s (measured) and the layer flew apart."""
        evaluate_rates()

    def step(self, dt: float, scheme) -> None:
        """The algorithm of a step, as run and as ``describe`` lists it."""
        scheme.evaluate_rates()  # rates at n
        scheme.run(self, launcher(self, "half_step"), dt)  # predictor: x, v, rho to n+1/2
        scheme.after_move(0.5)
        scheme.evaluate_rates()  # rates at n+1/2
        scheme.run(self, launcher(self, "kick"), dt)  # corrector: v(n+1) from v(n)
        scheme.solve_viscosity()
        scheme.run(self, launcher(self, "drift"), dt)  # x(n+1), rho(n+1)
        scheme.after_move()


INTEGRATORS = {cls.name: cls for cls in (SymplecticVerlet, PredictorCorrector)}


@ti.data_oriented
class StableTimeStep(Stage):
    """dt = CFL * min_i (model's stable step of particle i), e.g. [M39] for mu(I)  [s]."""

    name = "time_step"
    category = "integration"
    equation = "[M39]"

    def __init__(self, ctx):
        super().__init__(ctx)
        self.cfl = ctx.numerics.cfl
        self.last = float("nan")

    @ti.kernel
    def _run(self) -> float:
        result = 1e30
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            ti.atomic_min(result, self.model.stable_time_step(i))
        return result

    def run(self) -> None:
        self.last = self.cfl * launcher(self, "_run")()

    def value(self) -> float:
        """The stable time step found by the last run [s]."""
        return self.last
