"""The run loop: time stepping, output cadence, progress, guards."""
from __future__ import annotations

import collections
import math
import signal
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Optional

import numpy as np

from . import runtime
from .config import Scene
from .diagnostics import Diagnostics, Guard
from .output import RunOutput
from .neighbours import NeighbourListOverflow
from .physics.implicit_viscosity import ViscousSolveError
from .profiling import StageProfiler


class SimulationError(RuntimeError):
    """A run stopped by a guard: names the step, time, particle and offending values."""


class ResumeError(RuntimeError):
    """A checkpoint that does not fit the scene it is resumed with."""


class _Interrupt:
    """Within ``with``: Ctrl-C (SIGINT) sets ``caught`` instead of raising, so that the run
    finishes its step and writes the final frame and checkpoint; a second Ctrl-C raises at once.
    Outside the main thread (no signal handlers there) it does nothing."""

    def __init__(self):
        self.caught = False
        self.previous = None

    def _handle(self, signum, frame):
        if self.caught:
            raise KeyboardInterrupt
        self.caught = True

    def __enter__(self):
        try:
            self.previous = signal.signal(signal.SIGINT, self._handle)
        except ValueError:  # not the main thread
            self.previous = None
        return self

    def __exit__(self, *exc):
        if self.previous is not None:
            signal.signal(signal.SIGINT, self.previous)
        return False


@dataclass
class RunSummary:
    steps: int
    time: float
    wall_seconds: float  # this call's stepping
    frames: int
    particle_steps_per_second: float
    out_dir: Optional[Path]
    total_wall_seconds: Optional[float] = None  # every segment of a resumed run; None: a checkpoint too old to say


class Progress:
    """One status line on stderr: simulated time, steps/s, ETA (only on terminals, or forced).

    The ETA extrapolates the simulated time's rate over the last WINDOW seconds of wall time, not
    since the start: the first steps compile every kernel (a one-minute run's first estimate
    read 12 hours), and a flow's time step changes as it speeds up or settles."""

    WINDOW = 30.0  # s of wall time

    def __init__(self, end_time: float, enabled: bool):
        self.end_time = end_time
        self.enabled = enabled
        self.start = time.perf_counter()
        self.last = 0.0
        self.samples = collections.deque()  # (wall, simulated time) of recent updates

    def eta(self, now: float, t: float) -> float:
        """Wall seconds left at the recent rate (NaN until two updates a while apart)."""
        self.samples.append((now, t))
        while len(self.samples) > 2 and now - self.samples[1][0] >= self.WINDOW:
            self.samples.popleft()
        wall0, t0 = self.samples[0]
        if now - wall0 <= 0.0 or t <= t0:
            return float("nan")
        return (self.end_time - t) * (now - wall0) / (t - t0)

    def update(self, t: float, step: int, force: bool = False) -> None:
        if not self.enabled:
            return
        now = time.perf_counter()
        if not force and now - self.last < 0.5:
            return
        self.last = now
        elapsed = now - self.start
        rate = step / elapsed if elapsed > 0 else 0.0
        frac = min(1.0, t / self.end_time)
        eta = self.eta(now, t)
        bar = "#" * int(30 * frac)
        eta_text = time.strftime("%H:%M:%S", time.gmtime(eta)) if math.isfinite(eta) else "--:--:--"
        sys.stderr.write(f"\r[{bar:<30}] t = {t:.4g}/{self.end_time:.4g} s  step {step}  "
                         f"{rate:.0f} steps/s  ETA {eta_text} ")
        sys.stderr.flush()

    def close(self) -> None:
        if self.enabled:
            sys.stderr.write("\n")


class Simulation:
    """A scene made runnable: ``Simulation(scene).run()``."""

    def __init__(self, scene: Scene, out_dir: Optional[Path] = None, profile: bool = False,
                 progress: Optional[bool] = None):
        runtime.init(scene.arch, scene.precision)
        from .scheme import Scheme  # after runtime.init: building the scheme allocates fields

        self.scene = scene
        self.profiler = StageProfiler(profile)
        self.scheme = Scheme(scene, self.profiler)
        self.state = self.scheme.state
        self.diagnostics = Diagnostics(self.state, self.scheme.model)
        self.guard = Guard(self.state, scene.domain, self.scheme.model.reference_density())
        if scene.run.guard == "stage":  # every stage call goes through the profiler
            self.profiler.after = lambda stage: self._check(f"stage {stage.name} of step {self.step_count + 1}")
        self.output = RunOutput(out_dir, scene.run.write_vtu) if out_dir is not None else None
        self.renderer = None
        if self.output is not None and scene.render.frames:
            from .render.frames import Renderer
            self.renderer = Renderer(scene)
        self.show_progress = sys.stderr.isatty() if progress is None else progress
        self.t = 0.0
        self.step_count = 0
        self.dt = 0.0
        self.frame_index = 0
        self.last_diagnostics: dict = {}
        self.peak_kinetic_energy = 0.0
        self.mach_warned = False
        self.last_guarded = 0  # the last step the guard found sound
        self.wall_before: Optional[float] = 0.0  # s of stepping of the run so far, all segments (kept in checkpoints)
        self._wall_origin = time.perf_counter()  # perf_counter() at which the run's stepping wall time is 0

    # ---- pieces -------------------------------------------------------------------------------

    def _check(self, where: str) -> None:
        """Stop the run if the guard finds a bad particle: the message names the step, the time,
        where in the step (``run.guard: stage`` names the stage), the particle and its values,
        and every other field of that particle that is not finite; the whole state goes to
        ``failure.npz`` and ``failure.vtu`` next to the outputs, the last checkpoint untouched."""
        bad = self.guard.check()
        if bad is None:
            self.last_guarded = self.step_count
            return
        slot, reason, values = bad
        pid = int(self.state.particle_id[slot])  # as the outputs number it
        block = int(self.scheme.initial.block_of[pid])
        name = self.scene.particles[block].name
        arrays = self.scheme.snapshot()
        broken = sorted(k for k, v in arrays.items() if k in self.state.specs and
                        np.issubdtype(v.dtype, np.floating) and pid < len(v) and not np.all(np.isfinite(v[pid])))
        message = (f"{where}, t = {self.t:.6g} s: particle {pid} (block '{name}') "
                   f"{reason}: " + ", ".join(f"{k} = {v}" for k, v in values.items()))
        if broken:
            message += "; non-finite fields of this particle: " + ", ".join(broken)
        every = self.scene.run.guard_every
        if every > 1 and self.step_count > self.last_guarded + 1:
            message += (f" (checked every {every} steps: it arose within steps {self.last_guarded + 1}-"
                        f"{self.step_count}; resume from the last checkpoint with --set run.guard_every=1 "
                        f"--set run.guard=stage to name the step and the stage)")
        elif self.scene.run.guard == "step":
            message += " (resume from the last checkpoint with --set run.guard=stage to name the stage)"
        raise SimulationError(self._write_failure(message))

    def _check_unless_checked(self) -> None:
        """The guard at the current step, unless it has already passed it (run.guard_every > 1)."""
        if self.last_guarded != self.step_count:
            self._check(f"after step {self.step_count}")

    def _write_failure(self, message: str) -> str:
        """The whole state to failure.npz / failure.vtu (the last checkpoint untouched); returns
        ``message`` saying where it went."""
        if self.output is None:
            return message
        self.output.write_failure(self.scheme.snapshot(), self.counters(), self.state.n_material)
        return message + f"; state written to {self.output.dir / 'failure.npz'} and failure.vtu"

    def write_frame(self, final: bool = False) -> None:
        """Diagnostics row, VTU frame and PNG of the current state; a checkpoint every
        ``run.checkpoint_every`` frames and always at the ``final`` frame of a run."""
        diag = self.diagnostics.measure()
        self.peak_kinetic_energy = max(self.peak_kinetic_energy, diag["kinetic_energy"])
        self.last_diagnostics = {"t": self.t, "step": self.step_count, "dt": self.dt, **diag,
                                 **self.scheme.solver_statistics()}
        self._warn_mach(diag)
        if self.output is not None:
            arrays = self.scheme.snapshot()
            self.output.write_frame(self.frame_index, self.t, arrays, self.state.n_material)
            self.output.write_diagnostics(self.last_diagnostics)
            if final or self.frame_index % self.scene.run.checkpoint_every == 0:
                # as stored (particle_id included): the resumed run continues in the same order
                self.output.write_checkpoint({**self.state.to_numpy(), **self.scheme.grid.checkpoint_arrays()},
                                             self.counters())
            if self.renderer is not None:
                from .render.frames import check_colour_field, png_name, write_png
                if self.frame_index == 0:  # the first frame comes before the first step
                    check_colour_field(self.scene.render.colour_by, arrays)
                image = self.renderer.image(arrays, self.state.n_material, self.t)
                write_png(self.output.dir / "frames" / png_name(self.frame_index, self.t), image)
        self.frame_index += 1

    def _warn_mach(self, diag: dict) -> None:
        """Once per run: a frame faster than run.mach_warning, with the remedy (mach.py)."""
        threshold = self.scene.run.mach_warning
        if self.mach_warned or not diag["mach"] > threshold:
            return
        from .mach import advice

        self.mach_warned = True
        sys.stderr.write(f"\nwarning: t = {self.t:.4g} s: Mach number {diag['mach']:.2f} (max speed "
                         f"{diag['max_speed']:.3g} m/s, max density error {diag['max_density_error']:.1%}) is above "
                         f"run.mach_warning = {threshold:g}: a weakly compressible flow this fast compresses "
                         f"spuriously; {advice(self.scene, self.scheme.model, diag['mach'], diag['max_speed'])}\n")

    def counters(self) -> dict:
        counters = {"t": self.t, "step": self.step_count, "dt": self.dt, "frame": self.frame_index,
                    "peak_kinetic_energy": self.peak_kinetic_energy}
        if self.wall_before is not None:  # the run's wall time so far, all segments: a resume adds to it
            counters["wall_seconds"] = time.perf_counter() - self._wall_origin
        return counters

    def resume(self) -> None:
        """Continue from the checkpoint in the output directory: every particle field (the
        integrator's start-of-step and rate fields included) and the counters, so that the
        continued run takes the same steps as one that never stopped."""
        from .output import read_checkpoint

        fields, counters = read_checkpoint(self.output.dir)
        lists = {k: fields.pop(k) for k in [self.scheme.grid.REFERENCE_KEY] if k in fields}
        if "particle_id" not in fields and "position" in fields:  # written before reordering existed
            fields["particle_id"] = np.arange(self.state.n_material, dtype=np.int32)
        missing = set(self.state.specs) - set(fields)
        if missing or any(fields[k].shape[0] != self.state.field(k).shape[0] for k in self.state.specs):
            raise ResumeError(f"the checkpoint in {self.output.dir} does not fit this scene "
                             f"(fields or particle counts differ{': missing ' + ', '.join(sorted(missing)) if missing else ''})")
        self.state.load(fields)
        self.t, self.step_count, self.dt = float(counters["t"]), int(counters["step"]), float(counters["dt"])
        self.frame_index = int(counters["frame"]) + 1  # the checkpoint was taken at that frame
        self.last_guarded = self.step_count  # checkpoints are written after the guard passed
        self.peak_kinetic_energy = float(counters["peak_kinetic_energy"])
        self.wall_before = float(counters["wall_seconds"]) if "wall_seconds" in counters else None
        self.output.reopen(self.t)
        self.scheme.place(self.t)  # moving walls of the loaded state
        self.scheme.grid.restore(lists)  # the neighbour list as the uninterrupted run holds it

    def at_rest(self) -> bool:
        """run.stop_at_rest: kinetic energy below that fraction of its peak so far."""
        fraction = self.scene.run.stop_at_rest
        return fraction is not None and self.peak_kinetic_energy > 0.0 and \
            self.last_diagnostics["kinetic_energy"] < fraction * self.peak_kinetic_energy

    # ---- the loop -----------------------------------------------------------------------------

    def _loop(self, end_time: float, max_steps: Optional[int], next_output: float, progress: Progress,
              start_steps: int, interrupt: "_Interrupt") -> None:
        """Steps until end_time, max_steps, rest or Ctrl-C; frames at every output time."""
        interval = self.scene.run.output_interval
        min_dt = self.scene.numerics.min_time_step
        while self.t < end_time * (1 - 1e-12) and not interrupt.caught:
            if max_steps is not None and self.step_count >= max_steps:
                break
            if not self.dt >= min_dt:
                self._check_unless_checked()  # a NaN time step: name the particle behind it
                raise SimulationError(self._write_failure(
                    f"step {self.step_count}, t = {self.t:.6g} s: stable time step {self.dt:.3g} s fell below "
                    f"numerics.min_time_step = {min_dt:.3g} s"))
            dt = min(self.dt, next_output - self.t, end_time - self.t)
            self.scheme.reorder_if_due(self.step_count)
            try:
                self.scheme.step(dt, self.t)
            except (ViscousSolveError, NeighbourListOverflow) as error:
                raise SimulationError(self._write_failure(
                    f"step {self.step_count + 1}, t = {self.t:.6g} s, dt = {dt:.3g} s: {error}")) from None
            self.step_count += 1
            self.t += dt
            frame_due = self.t >= next_output - 1e-9 * interval
            if frame_due or self.step_count % self.scene.run.guard_every == 0:  # never a bad frame written
                self._check(f"after step {self.step_count}")
            self.dt = self.scheme.stable_time_step()
            if frame_due:
                self.write_frame()
                next_output += interval
                if self.at_rest():
                    break
            progress.update(self.t, self.step_count - start_steps)
        progress.update(self.t, self.step_count - start_steps, force=True)

    def run(self, end_time: Optional[float] = None, max_steps: Optional[int] = None) -> RunSummary:
        scene = self.scene
        end_time = scene.run.end_time if end_time is None else end_time
        max_steps = scene.run.max_steps if max_steps is None else max_steps
        interval = scene.run.output_interval
        if self.output is not None:
            self.output.write_scene(scene)
        start_steps = self.step_count
        wall_start = time.perf_counter()
        self._wall_origin = wall_start - (self.wall_before or 0.0)
        if self.step_count == 0:
            self.scheme.prepare()
            self._check("initial rates (step 0)")
            self.dt = self.scheme.stable_time_step()
            self.write_frame()
        next_output = (math.floor(self.t / interval + 1e-9) + 1) * interval
        progress = Progress(end_time, self.show_progress)
        interrupt = _Interrupt()
        with interrupt:
            try:
                self._loop(end_time, max_steps, next_output, progress, start_steps, interrupt)
            finally:
                progress.close()
            if self.step_count > start_steps and self.last_diagnostics.get("step") != self.step_count:
                # stopped between output times (max_steps, end_time off the output grid, Ctrl-C)
                self._check_unless_checked()
                self.write_frame(final=True)
        if interrupt.caught:
            where = f" (state at t = {self.t:.6g} s written to {self.output.dir})" if self.output else ""
            raise KeyboardInterrupt(f"at step {self.step_count}{where}")
        wall = time.perf_counter() - wall_start
        steps = self.step_count - start_steps
        n = self.state.n_material
        if self.wall_before is not None:  # a later run() of this simulation goes on counting
            self.wall_before += wall
        return RunSummary(steps=steps, time=self.t, wall_seconds=wall, frames=self.frame_index,
                          particle_steps_per_second=n * steps / wall if wall > 0 else 0.0,
                          out_dir=self.output.dir if self.output else None,
                          total_wall_seconds=self.wall_before)
