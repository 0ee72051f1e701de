"""Implicit (TR-BDF2 or theta-method) viscous update of the mu(I) momentum equation
(``numerics.viscosity: implicit``).

Why: the regularised viscosity reaches eta_hat_max = eta_0 + tau_0 m_0 [M53] in every
sub-yield grain, and the explicit viscous limit 0.1 rho h^2/eta of [M39] then sits 250-800
times below the acoustic one (measured on the Table 3 collapses). The stiff term is linear in
the velocity once eta is known, so it is taken at the new velocity:

    v* = v(n) + dt a_explicit(n+1/2)              (pressure, gravity: the rate stage's kick)
    v(n+1) = v* + dt L y,   y = theta v(n+1) + (1 - theta) v(n),
    i.e.  (I - theta dt L) y = theta v* + (1 - theta) v(n),

L the viscous sum of the momentum stage (physics/momentum.py ``apply_viscous``) over the part of
each viscosity above eta_cap = cfl 0.1 rho h^2/dt, the most the step could take explicitly
([M39]); up to eta_cap the viscosity stays in the explicit rate, so grains that flow at the
acoustic step are stepped exactly as by the explicit scheme (measured: with the whole viscosity
in the solve, the Table 2 plane ran 2.6 points off the explicit velocity error and the coarse
a = 2.75 collapse 11.5 points of Lube off its run-out; with the split, 0 and 0.9) and only the
stiff excess of the grains near or below yield is solved. The sum is the stress
divergence of 2 eta dev(eps) and the residual damping, or the [M27] pair term, with the
viscosity, densities, positions and kernel corrections of the half-step rate evaluation: eta
is lagged by half a step (one Picard iteration). ``numerics.viscous_picard_iterations`` > 1
re-evaluates the strain rate, pressure and viscosity at the mid-step velocity (v(n) + v(n+1))/2
after each solve and solves again from the same v*: the changes shrink ~6x per iteration (tested),
and on the coarse a = 2.75 collapse the second solve moves the velocities by 1-4e-4 of |v*|, the
solve's own tolerance, after the first steps (measured): the lag costs nothing worth a second
solve, so one stays the default. The time step then keeps [M39]'s acoustic limit only
(physics/rheology/mu_i/model.py).

``numerics.viscous_scheme`` chooses how the stiff term is integrated over the step.

theta (``numerics.viscous_theta``; 1 is backward Euler): the update above. Backward Euler's
error is first order in dt, and at the acoustic step it is large where a grain's excess
viscosity makes lambda dt ~ 1 (lambda the rate at which L relaxes it): the grains that are
starting to yield. Measured on the coarse a = 2.75 collapse (dp 14.58 mm) without particle
shifting, where the explicit run is deterministic: the front at 0.08 s is 1.7 / 0.9 / 0.3 / 0.2 mm
behind the explicit one at cfl 0.5 / 0.25 / 0.1 / 0.05 with backward Euler (linear in dt), and
within 0.3 mm at cfl 0.5 with theta = 0.6 or 0.52. Picard iterations on eta did not move it (the
lag is not the error). The first-order error of the theta-method is (2 theta - 1) times backward
Euler's, but a stiff mode (lambda dt >> 1: grains far below yield) is multiplied by
-(1 - theta)/theta each step, -0.67 at 0.6 (decays, alternating), -1 at the trapezoidal rule
theta = 1/2 (never decays: hence theta > 1/2). Over forty runs with shifting at 14.58 mm the front
stopped 13.9 % earlier than the explicit one with backward Euler, 7.8 % with theta = 0.6; at
19.44 mm theta = 0.6 ran 6 points of Lube ahead of it, backward Euler 1.6
(docs/validation/column_collapse.md): neither error was small at every resolution.

tr_bdf2 (the default; Bank et al. 1985, Hosea & Shampine 1996): a trapezoidal stage to
t + GAMMA dt, then BDF2 through v(n), v(n + GAMMA) and v(n+1), GAMMA = 2 - sqrt(2), so that both
stages solve with the same matrix I - (GAMMA/2) dt L. It is second order like the trapezoidal rule
and L-stable like backward Euler (a stiff mode is multiplied by ~ -4.8/(|lambda| dt) -> 0), for two
solves a step of a better-conditioned matrix (5.2 BiCGSTAB iterations a step together on the coarse
a = 2.75 collapse, against 7.4 for theta = 0.6's one). The explicit kick f dt = v* - v(n), held over
the step, drops out of both right-hand sides, and v(n+1) = v* + dt (L y1/(2 - GAMMA) + GAMMA/2 L y2)
is again a sum of pair terms. Measured against the explicit scheme: docs/validation/column_collapse.md,
"TR-BDF2".

The solve is matrix-free over the neighbour lists: BiCGSTAB (van der Vorst 1992) with right
block-Jacobi preconditioning by the d x d diagonal blocks of the solve's I - c dt L_[M27] (c = theta,
or GAMMA/2 for both TR-BDF2 stages; exact for the pair form, an approximation for the stress form). Why BiCGSTAB and not the conjugate gradient of
Weiler et al. (2018): the stress form's L, built from the corrected (non-symmetric) SPH
gradient, is negative definite but not symmetric (tests/test_implicit_viscosity.py measures
both), and CG needs symmetry. The start is v* plus the previous step's viscous change (in a
steady flow the viscous force balances gravity from step to step). Dot products are summed
in fixed blocks, so a run is bitwise reproducible on the CPU.

The solve stops when |residual| <= ``numerics.viscous_tolerance`` |v*| (Euclidean over all
components); the velocities then become v* + dt L x of the solution x, one more operator
application, so that the viscous update exchanges momentum in pairs only and the total is
conserved to round-off as with the explicit term (the residual alone would drift it). One that has not got there after ``numerics.viscous_max_iterations`` raises
ViscousSolveError with the residual and the iteration count, and the run stops (exit 3).
"""
import taichi as ti

from .. import runtime
from ..launch import launcher
from ..state import FieldSpec
from .stage import Stage

DOT_BLOCK = 256  # particles per partial sum of a dot product

# TR-BDF2 (Bank et al. 1985; Hosea & Shampine 1996): a trapezoidal stage to t + GAMMA dt, then
# BDF2 through t(n), t + GAMMA dt, t + dt. GAMMA = 2 - sqrt(2) makes both stages' matrices
# I - (GAMMA/2) dt L, and the method L-stable and second order.
GAMMA = 2.0 - 2.0 ** 0.5
BDF2_STAGE = 1.0 / (2.0 - GAMMA)  # weight of L y1 (the trapezoidal stage's image) in v(n+1) - v*, per dt
BDF2_NEW = 0.5 * GAMMA  # weight of L v(n+1) in it, (1 - GAMMA)/(2 - GAMMA), which is GAMMA/2 for this GAMMA


class ViscousSolveError(RuntimeError):
    """The implicit viscous solve did not converge (the message gives residual and iterations)."""


@ti.data_oriented
class ImplicitViscosity(Stage):
    name = "implicit_viscosity"
    category = "forces"
    equation = "(I - theta dt L) y = theta v* + (1 - theta) v(n), v = v* + dt L y, BiCGSTAB"
    fields = (FieldSpec("viscous_acceleration", "vector",
                        "dv/dt of the implicit viscous update in the last step (its warm start)", "m/s^2",
                        "material"),)

    def __init__(self, ctx, momentum, refresh=()):
        super().__init__(ctx)
        self.momentum = momentum
        self.refresh = list(refresh)  # the rate stages that take a velocity to a viscosity (Picard)
        self.picard_iterations = ctx.numerics.viscous_picard_iterations
        self.time_step = ctx.time_step
        numerics = ctx.numerics
        self.tolerance = numerics.viscous_tolerance
        self.max_iterations = numerics.viscous_max_iterations
        dim, n = ctx.state.dim, ctx.state.n_material
        self.dim = dim
        self.theta = ctx.numerics.viscous_theta
        self.tr_bdf2 = ctx.numerics.viscous_scheme == "tr_bdf2"
        if self.tr_bdf2:
            self.equation = ("TR-BDF2: two solves of (I - (GAMMA/2) dt L) y = target, "
                             "v = v* + dt (L y1/(2 - GAMMA) + GAMMA/2 L y2), BiCGSTAB")
        # v_star: v* of the step; target: the solve's right-hand side (theta: theta v* + (1 - theta) v(n))
        self.v_star, self.target, self.residual, self.shadow, self.direction, self.v, self.t = (
            ti.Vector.field(dim, float, n) for _ in range(7))
        # TR-BDF2: L y1 of the trapezoidal stage, which the BDF2 stage and the update weigh in
        self.stage_image = ti.Vector.field(dim, float, n) if self.tr_bdf2 else None
        self.kept = ti.Vector.field(dim, float, n) if self.picard_iterations > 1 else None  # last solution
        self.preconditioner = ti.Matrix.field(dim, dim, float, n)
        self.n_blocks = max(1, -(-n // DOT_BLOCK))
        self.partial = ti.field(float, self.n_blocks)
        self.total = ti.field(float, ())
        self.iterations = 0  # summed over solves since the last ``take_statistics``
        self.solves = 0
        self.run_iterations = 0  # over the whole run (``run --profile``)
        self.run_solves = 0
        self.picard_change = 0.0  # summed over steps since the last ``take_statistics``
        self.run_picard_change = 0.0  # the largest of the run
        self.last_changes = []  # the Picard re-solves' changes of the velocities in the last step, per |v*|
        self.steps = 0  # since the last ``take_statistics``
        self.run_steps = 0

    # ---- vector kernels ---------------------------------------------------------------------

    @ti.kernel
    def _dot(self, a: ti.template(), b: ti.template()) -> float:
        n = self.state.n_material
        ti.loop_config(serialize=runtime.serial_loops)
        for blk in range(self.n_blocks):  # each block summed in order: the same bits every run
            acc = 0.0
            for i in range(blk * DOT_BLOCK, ti.min((blk + 1) * DOT_BLOCK, n)):
                acc += a[i].dot(b[i])
            self.partial[blk] = acc
        ti.loop_config(serialize=True)
        for _ in range(1):
            acc = 0.0
            for blk in range(self.n_blocks):
                acc += self.partial[blk]
            self.total[None] = acc
        return self.total[None]

    @ti.kernel
    def _take_star(self):
        """v_star = v*, the velocities after the explicit kick."""
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            self.v_star[i] = self.state.velocity[i]

    @ti.kernel
    def _prepare_preconditioner(self, dt: float):
        """The block-Jacobi preconditioner, the inverse of the d x d diagonal blocks of I - dt L (``dt``
        here is the solve's, c dt: one matrix for both stages of TR-BDF2, so one preparation a step)."""
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            self.preconditioner[i] = (ti.Matrix.identity(float, self.dim) - dt * self.momentum.diagonal[i]).inverse()

    @ti.kernel
    def _begin(self, dt: float, start_weight: float, stage_weight: float):
        """target = (1 - start_weight) v* + start_weight v(n) [+ stage_weight L y1 (TR-BDF2)];
        x = target + dt a_viscous(previous step) (``dt`` here is the solve's, c dt); operand = x."""
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            target = (1.0 - start_weight) * self.v_star[i] + start_weight * self.state.velocity_start[i]
            if ti.static(self.tr_bdf2):
                target += stage_weight * self.stage_image[i]
            self.target[i] = target
            x = target + dt * self.state.viscous_acceleration[i]
            self.state.velocity[i] = x
            self.momentum.operand[i] = x

    @ti.kernel
    def _first_residual(self, dt: float):
        """r = target - (I - dt L) x (dt: the solve's c dt); the shadow residual r^ = r; p = v = 0."""
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            r = self.target[i] - (self.state.velocity[i] - dt * self.momentum.image[i])
            self.residual[i] = r
            self.shadow[i] = r
            self.direction[i] = ti.Vector.zero(float, self.dim)
            self.v[i] = ti.Vector.zero(float, self.dim)

    @ti.kernel
    def _new_direction(self, beta: float, omega: float):
        """p = r + beta (p - omega v); operand = K^-1 p."""
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            p = self.residual[i] + beta * (self.direction[i] - omega * self.v[i])
            self.direction[i] = p
            self.momentum.operand[i] = self.preconditioner[i] @ p

    @ti.kernel
    def _system_image(self, dt: float, out: ti.template()):
        """out = (I - dt L) operand (dt: the solve's c dt), with image = L operand."""
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            out[i] = self.momentum.operand[i] - dt * self.momentum.image[i]

    @ti.kernel
    def _update(self, weight: float, image: ti.template()):
        """x += weight operand; r -= weight image."""
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            self.state.velocity[i] += weight * self.momentum.operand[i]
            self.residual[i] -= weight * image[i]

    @ti.kernel
    def _precondition_residual(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            self.momentum.operand[i] = self.preconditioner[i] @ self.residual[i]

    @ti.kernel
    def _end(self, dt: float, image_weight: float, stage_weight: float):
        """v = v* + dt (image_weight L y [+ stage_weight L y1]) (the whole dt): the pair sums themselves
        move the velocities, so that momentum is exchanged only in pairs (conserved to round-off,
        like the explicit term) whatever the residual of y."""
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            a = image_weight * self.momentum.image[i]
            if ti.static(self.tr_bdf2):
                a += stage_weight * self.stage_image[i]
            self.state.viscous_acceleration[i] = a
            self.state.velocity[i] = self.v_star[i] + dt * a

    @ti.kernel
    def _keep_stage_image(self):
        """L y1 of the trapezoidal stage (TR-BDF2)."""
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            self.stage_image[i] = self.momentum.image[i]

    # ---- the solve ---------------------------------------------------------------------------

    def _apply(self, dt: float, out) -> None:
        self.momentum.apply_viscous()
        launcher(self, "_system_image", out)(dt)

    def run(self) -> None:
        """The viscous update of the step in place of the velocities (v* on entry): theta-method or
        TR-BDF2 (``_update_velocities``); with Picard iterations, re-evaluate the viscosity at the
        mid-step velocity after each update but the last and update again from the same v*,
        starting from the last solution."""
        self.steps += 1
        self.run_steps += 1
        self.last_changes = []
        launcher(self, "_take_star")()
        for iteration in range(self.picard_iterations):
            if iteration > 0:
                launcher(self, "_keep")()
                launcher(self, "_to_midpoint")()
                for stage in self.refresh:
                    stage.run()
                launcher(self, "_to_target")()
            self._update_velocities()
            if iteration > 0:  # how far the re-evaluated viscosity moved the solution, per |v*|
                launcher(self, "_change")()
                kept_norm2 = launcher(self, "_dot", self.kept, self.kept)()
                change = (kept_norm2 / max(launcher(self, "_dot", self.target, self.target)(), 1e-300)) ** 0.5
                self.last_changes.append(change)
                self.picard_change += change
                self.run_picard_change = max(self.run_picard_change, change)

    @ti.kernel
    def _keep(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            self.kept[i] = self.state.velocity[i]

    @ti.kernel
    def _change(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            self.kept[i] = self.state.velocity[i] - self.kept[i]

    @ti.kernel
    def _to_midpoint(self):
        """velocity = (v(n) + v(n+1))/2, the velocity of the half step at which the rates are taken."""
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            self.state.velocity[i] = 0.5 * (self.state.velocity_start[i] + self.state.velocity[i])

    @ti.kernel
    def _to_target(self):
        """velocity = v*, from which the next solve builds its right-hand side (its start is the last
        solution)."""
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            self.state.velocity[i] = self.v_star[i]

    def _update_velocities(self) -> None:
        """theta-method: (I - theta dt L) y = theta v* + (1 - theta) v(n), v(n+1) = v* + dt L y.
        TR-BDF2: the trapezoidal stage (I - GAMMA/2 dt L) y1 = GAMMA/2 v* + (1 - GAMMA/2) v(n)
        (y1 = (v(n) + v(n+GAMMA))/2), then BDF2 (I - GAMMA/2 dt L) y2 = v* + dt L y1 / (2 - GAMMA)
        (y2 = v(n+1)), and v(n+1) = v* + dt (L y1 / (2 - GAMMA) + GAMMA/2 L y2): the explicit kick
        f dt = v* - v(n), held over the step, drops out of both right-hand sides."""
        step = float(self.time_step[None])
        if launcher(self.momentum, "max_implicit_viscosity")() == 0.0:  # every grain within the explicit limit
            launcher(self, "_nothing_to_solve")()
            self.solves += 1
            self.run_solves += 1
            return
        launcher(self.momentum, "compute_diagonal")()
        if self.tr_bdf2:
            solve_dt = BDF2_NEW * step  # GAMMA/2 dt, both stages
            launcher(self, "_prepare_preconditioner")(solve_dt)
            self._solve(solve_dt, 1.0 - 0.5 * GAMMA, 0.0)
            launcher(self, "_keep_stage_image")()
            self._solve(solve_dt, 0.0, BDF2_STAGE * step)
            launcher(self, "_end")(step, BDF2_NEW, BDF2_STAGE)
        else:
            launcher(self, "_prepare_preconditioner")(self.theta * step)
            self._solve(self.theta * step, 1.0 - self.theta, 0.0)
            launcher(self, "_end")(step, 1.0, 0.0)

    def _solve(self, dt: float, start_weight: float, stage_weight: float) -> None:
        """Solve (I - dt L) y = (1 - start_weight) v* + start_weight v(n) + stage_weight L y1 by
        BiCGSTAB; on return velocity = y and the momentum stage's image = L y."""
        launcher(self, "_begin")(dt, start_weight, stage_weight)
        target_norm = launcher(self, "_dot", self.target, self.target)() ** 0.5
        self.momentum.apply_viscous()
        launcher(self, "_first_residual")(dt)
        goal = self.tolerance * target_norm
        residual = launcher(self, "_dot", self.residual, self.residual)() ** 0.5
        rho = alpha = omega = 1.0
        iterations = 0
        while residual > goal:
            if iterations >= self.max_iterations:
                raise ViscousSolveError(
                    f"implicit viscous solve did not converge: residual {residual / max(target_norm, 1e-300):.3g} "
                    f"of |v*| after {iterations} iterations (numerics.viscous_max_iterations = "
                    f"{self.max_iterations}, numerics.viscous_tolerance = {self.tolerance:g}; a smaller "
                    f"numerics.cfl shortens the step)")
            iterations += 1
            rho_new = launcher(self, "_dot", self.shadow, self.residual)()
            if rho_new == 0.0 or omega == 0.0:  # breakdown: restart from the current iterate
                self._restart(dt)
                rho, alpha, omega = 1.0, 1.0, 1.0
                continue
            beta = (rho_new / rho) * (alpha / omega)
            launcher(self, "_new_direction")(beta, omega)
            self._apply(dt, self.v)
            alpha = rho_new / launcher(self, "_dot", self.shadow, self.v)()
            launcher(self, "_update", self.v)(alpha)  # x += alpha y, s = r - alpha v (s kept in r)
            residual = launcher(self, "_dot", self.residual, self.residual)() ** 0.5
            if residual <= goal:
                break
            launcher(self, "_precondition_residual")()
            self._apply(dt, self.t)
            omega = launcher(self, "_dot", self.t, self.residual)() / launcher(self, "_dot", self.t, self.t)()
            launcher(self, "_update", self.t)(omega)  # x += omega z, r = s - omega t
            residual = launcher(self, "_dot", self.residual, self.residual)() ** 0.5
            rho = rho_new
        launcher(self, "_copy_velocity_to_operand")()
        self.momentum.apply_viscous()
        self.iterations += iterations
        self.solves += 1
        self.run_iterations += iterations
        self.run_solves += 1

    @ti.kernel
    def _nothing_to_solve(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            self.state.viscous_acceleration[i] = ti.Vector.zero(float, self.dim)

    @ti.kernel
    def _copy_velocity_to_operand(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            self.momentum.operand[i] = self.state.velocity[i]

    def _restart(self, dt: float) -> None:
        """Residual and shadow afresh from the current iterate (a BiCGSTAB breakdown)."""
        launcher(self, "_copy_velocity_to_operand")()
        self.momentum.apply_viscous()
        launcher(self, "_first_residual")(dt)

    def summary(self) -> str:
        """One line for ``run --profile``."""
        mean = self.run_iterations / self.run_steps if self.run_steps else 0.0
        line = f"implicit viscous solve: {self.run_solves} solves, {mean:.2f} BiCGSTAB iterations per step"
        if self.picard_iterations > 1:
            line += (f" ({self.picard_iterations} Picard solves a step; the largest change of a re-solve "
                     f"{self.run_picard_change:.2g} of |v*|)")
        return line

    def take_statistics(self) -> dict:
        """Mean BiCGSTAB iterations per step since the last call (a diagnostics.csv column) and, with
        Picard iterations, the mean change of the velocities by the re-solves per |v*|; then reset."""
        stats = {"viscous_iterations": self.iterations / self.steps if self.steps else 0.0}
        if self.picard_iterations > 1:
            stats["viscous_picard_change"] = self.picard_change / self.steps if self.steps else 0.0
        self.iterations = self.solves = self.steps = 0
        self.picard_change = 0.0
        return stats
