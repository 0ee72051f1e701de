"""Builds, for one scene, the ordered stage list of a time step and the fields it needs.

Only what the scene asks for is instantiated: the material model's stages, the boundary
model's stages, artificial viscosity if its coefficients are non-zero, and the chosen
integrator. ParticleState allocates the union of the fields these declare; Taichi compiles a
kernel only when it first runs, so stages that are not in the list are never compiled.
"""
from typing import List

import numpy as np
import taichi as ti

from . import runtime
from .neighbours import NeighbourGrid, NeighbourSearch, list_capacity
from .integrators import INTEGRATORS, StableTimeStep
from .launch import launcher
from .physics.artificial_stress import ArtificialStress
from .physics.artificial_viscosity import ArtificialViscosity
from .physics.gradient_correction import GRADIENTS
from .physics.implicit_viscosity import ImplicitViscosity
from .physics.momentum import MOMENTUM
from .physics.outflow import Outflow
from .physics.rheology import model_class
from .physics.shifting import FreeSurface, ParticleShifting, SurfaceLayer
from .physics.stage import MOVE_SLOTS, RATE_SLOTS, Context, fuse_pair_stages, in_slot_order
from .physics.walls import BOUNDARIES, NoWalls
from .profiling import StageProfiler
from .scene import InitialParticles, build_initial
from .smoothing import make_smoothing
from .state import ParticleOrder, ParticleState, merge_specs
from .config import ConfigError, Scene


def boundary_class(scene: Scene):
    """The boundary model of the scene's walls and obstacles (physics/walls BOUNDARIES)."""
    types = frozenset(scene.wall_types)
    if not types:
        return NoWalls
    if types not in BOUNDARIES:
        raise ConfigError("walls", f"these boundary types do not combine in one scene: {sorted(types)}")
    return BOUNDARIES[types]


def rate_stage_classes(scene: Scene, model) -> List[type]:
    """Stages of one rate evaluation: what the numerics, the walls and the model bring, in the
    order of their slots (physics/stage.py RATE_SLOTS)."""
    numerics = scene.numerics
    classes = [NeighbourSearch] + GRADIENTS[numerics.gradient_correction].stage_classes()
    if numerics.particle_shifting.enabled or model.needs_free_surface:
        classes.append(FreeSurface)
    classes += boundary_class(scene).stage_classes(scene) + model.stage_classes(scene)
    if numerics.artificial_viscosity.enabled:
        classes.append(ArtificialViscosity)
    if numerics.artificial_stress.enabled:
        classes.append(ArtificialStress)
    if numerics.particle_shifting.enabled:
        classes += [SurfaceLayer, ParticleShifting]
    return in_slot_order(classes, RATE_SLOTS)


def move_stage_classes(scene: Scene, model) -> List[type]:
    """Stages after every move of the particles, in the order of their slots (MOVE_SLOTS)."""
    classes = ([Outflow] if scene.domain.outflow else []) + boundary_class(scene).position_stage_classes(scene) \
        + model.update_stage_classes()
    return in_slot_order(classes, MOVE_SLOTS)


def _describe_call(stage, fn) -> str:
    """'integrator: kick [integration]' for a kernel of a stage launched by name (launch.py)."""
    kernel = getattr(getattr(fn, "kernel", None), "func", fn)
    return f"{stage.name}: {getattr(kernel, '__name__', 'call').strip('_').replace('_', ' ')} [{stage.category}]"


@ti.data_oriented
class Clock:
    """The 0-d fields that kernels read the step's timing from: ``dt`` of the step being taken
    [s], the ``time`` the position stages move the scene to [s] and the ``step_fraction`` of the
    step that is [-]. Set by one launch each (launch.py), not by field writes from Python, each
    of which costs as much as two such launches."""

    def __init__(self):
        self.dt = ti.field(float, shape=())
        self.time = ti.field(float, shape=())
        self.step_fraction = ti.field(float, shape=())

    @ti.kernel
    def _begin_step(self, dt: float):
        self.dt[None] = dt

    @ti.kernel
    def _move_to(self, time: float, fraction: float):
        self.time[None] = time
        self.step_fraction[None] = fraction

    def begin_step(self, dt: float) -> None:
        launcher(self, "_begin_step")(dt)

    def move_to(self, time: float, fraction: float) -> None:
        launcher(self, "_move_to")(time, fraction)


class Scheme:
    """State, neighbour grid, smoothing function, boundary and material models, and stages."""

    def __init__(self, scene: Scene, profiler: StageProfiler = None, initial: InitialParticles = None,
                 fuse: bool = True):
        self.scene = scene
        self.profiler = profiler or StageProfiler(False)
        model = model_class(scene.material.model).from_scene(scene)
        self.initial = initial if initial is not None else build_initial(scene, model)
        walls_cls = boundary_class(scene)
        rate_classes = rate_stage_classes(scene, model)
        integrator_cls = INTEGRATORS[scene.numerics.integrator]
        gradient_cls = GRADIENTS[scene.numerics.gradient_correction]
        move_classes = move_stage_classes(scene, model)
        specs = merge_specs([model.fields, walls_cls.fields, integrator_cls.fields, gradient_cls.fields]
                            + [cls.fields for cls in rate_classes + move_classes]
                            + ([ImplicitViscosity.fields] if scene.numerics.implicit_viscosity else []))
        ini = self.initial
        runtime.choose_loops(ini.n_total)
        self.state = ParticleState(scene.dimension, ini.n_material, ini.n_wall, specs)
        wall_fields = {k: v for k, v in walls_cls.initial_fields(scene, ini).items() if self.state.has(k)}
        model_fields = model.initial_fields(ini)
        self.state.load({"position": ini.position, "velocity": ini.velocity, "mass": ini.mass,
                         "density": ini.density, "pressure": ini.pressure, **wall_fields, **model_fields,
                         "particle_id": np.arange(ini.n_material, dtype=np.int32)})
        model.state = self.state
        self.model = model
        self.smoothing = make_smoothing(scene.numerics.smoothing_function, scene.numerics.smoothing_length, scene.dimension)
        skin = scene.numerics.neighbour_skin * self.smoothing.h
        capacity = list_capacity(scene.dimension, self.smoothing.support + skin, scene.numerics.particle_spacing)
        self.grid = NeighbourGrid(self.state.position, scene.domain.lower, scene.domain.upper,
                                 scene.domain.periodic_mask, self.smoothing.support, n_moving=ini.n_material,
                                 skin=skin, capacity=capacity if skin > 0.0 else 0,
                                 fixed_move=any(getattr(cls, "moves_boundary", False) for cls in move_classes))
        self.walls = walls_cls(self.state, scene.gravity_vector)
        self.clock = Clock()
        self.dt, self.time, self.step_fraction = self.clock.dt, self.clock.time, self.clock.step_fraction
        self._step = (0.0, 0.0)  # (t, dt) of the step being taken
        self._recording = None  # the stage descriptions a step's calls leave, while stage_list records
        ctx = Context(state=self.state, grid=self.grid, smoothing=self.smoothing, walls=self.walls,
                      model=model, numerics=scene.numerics, gravity=scene.gravity_vector, domain=scene.domain,
                      plane_walls=scene.walls, obstacles=scene.obstacles, time_step=self.dt, time=self.time,
                      step_fraction=self.step_fraction)
        ctx.gradient = self.gradient = gradient_cls(ctx)
        self.rate_stages = [cls(ctx) for cls in rate_classes]
        # as run: consecutive pair stages share one neighbour pass (physics/stage.py FusedPairs)
        self.rate_passes = fuse_pair_stages(self.rate_stages, ctx) if fuse else list(self.rate_stages)
        self.integrator = integrator_cls(ctx)
        self.viscous_solve = None  # physics/implicit_viscosity.py, between the kick and the drift
        if scene.numerics.implicit_viscosity:
            momentum = next(stage for stage in self.rate_stages if isinstance(stage, tuple(MOMENTUM.values())))
            # a Picard iteration re-evaluates the viscosity: the stages from the strain rate to it,
            # less those of the neighbour category (the surface layer), which read positions only
            names = [stage.name for stage in self.rate_stages]
            span = self.rate_stages[names.index("strain_rate"):names.index("regularised_viscosity") + 1]
            refresh = [stage for stage in span if stage.category != "neighbours"]
            self.viscous_solve = ImplicitViscosity(ctx, momentum, refresh)
        # after every update: walls act on the new positions, the model on the new state
        self.position_stages = [cls(ctx) for cls in move_classes]
        self.time_step = StableTimeStep(ctx)
        self.reorder_every = scene.numerics.reorder_every
        self.particle_order = ParticleOrder(self.state) if self.reorder_every > 0 else None

    # ---- stepping -----------------------------------------------------------------------------

    def run(self, stage, fn=None, *args) -> None:
        """Run one stage (``fn(*args)``, by default ``stage.run()``) through the profiler, or, while
        :meth:`stage_list` records a step, note it and run nothing: every launch of a step passes
        here, so the stage list is the step's own sequence."""
        if self._recording is not None:
            self._recording.append(stage.describe() if fn is None else _describe_call(stage, fn))
        else:
            self.profiler(stage, fn, *args)

    def evaluate_rates(self) -> None:
        for stage in self.rate_passes:
            self.run(stage)

    def solve_viscosity(self) -> None:
        """The implicit viscous update of the velocities after the kick, where the scene asks for it."""
        if self.viscous_solve is not None:
            self.run(self.viscous_solve)

    def solver_statistics(self) -> dict:
        """Columns for diagnostics.csv from the solves since the last call (none without one)."""
        return self.viscous_solve.take_statistics() if self.viscous_solve is not None else {}

    def prepare(self) -> None:
        """Anything the integrator needs before its first step (initial rates)."""
        self.integrator.prepare(self.evaluate_rates)

    def after_move(self, fraction: float = 1.0) -> None:
        """Stages that act on positions right after the integrator moves particles to
        t + fraction dt of the step being taken (moving walls go there too)."""
        t, dt = self._step
        if self._recording is None:
            self.clock.move_to(t + fraction * dt, fraction)
        for stage in self.position_stages:
            self.run(stage)

    def place(self, t: float) -> None:
        """Position stages at time t without a step (a resumed run's loaded state)."""
        self._step = (t, 0.0)
        self.after_move()

    def reorder_if_due(self, step: int) -> None:
        """Before step ``step + 1``: every numerics.reorder_every steps, sort the material by cell.
        Why: a pair loop reads its neighbours' fields, and mixing flows scatter neighbours over
        memory (a shuffled order cost 2.1-3.4x a step, measured). Keyed to the step count, so a
        resumed run reorders at the same steps as the uninterrupted one."""
        if self.particle_order is not None and step > 0 and step % self.reorder_every == 0:
            self.run(self.particle_order, self.reorder)

    def reorder(self) -> None:
        """Sort the material by neighbour cell now (needs numerics.reorder_every > 0)."""
        self.grid.cell_order(self.particle_order.order)
        self.particle_order.apply()

    def permute(self, order: np.ndarray) -> None:
        """Store the material in ``order`` (slot k gets particle order[k]): benchmarks and tests of
        a scattered order; the physics does not change (round-off apart)."""
        permutation = self.particle_order or ParticleOrder(self.state)
        permutation.order.from_numpy(np.asarray(order, dtype=np.int32))
        permutation.apply()
        self.grid.material_moved()

    def step(self, dt: float, t: float = 0.0) -> None:
        """Advance from time t by dt."""
        if self._recording is None:
            self.clock.begin_step(dt)  # stages that act over one step (wall friction) read it
        self._step = (t, dt)
        self.integrator.step(dt, self)

    def stable_time_step(self) -> float:
        self.run(self.time_step)
        return self.time_step.value()

    # ---- description --------------------------------------------------------------------------

    def stage_list(self) -> List[str]:
        """The stages of one time step, in order: recorded from the calls the integrator's step
        makes (:meth:`run`), running nothing; the run loop's reordering before the step and the
        time step after it around them."""
        self._recording = []
        try:
            self.step(0.0, self._step[0])
        finally:
            steps, self._recording = self._recording, None
        reorder = ([f"reorder_by_cell: counting sort of the material by neighbour cell, every "
                    f"{self.reorder_every} steps [neighbours]"] if self.particle_order is not None else [])
        return reorder + steps + [self.time_step.describe()]

    def memory_bytes(self) -> int:
        itemsize = 8 if self.scene.precision == "f64" else 4
        return sum(row[3] for row in self.state.memory_table(itemsize)) + self.grid.memory_bytes()

    def snapshot(self) -> dict:
        """Numpy copy of every field in the scene's initial particle order, plus the model's
        derived quantities for output."""
        arrays = self.state.in_initial_order(self.state.to_numpy())
        arrays.update(self.model.derived_output(arrays))
        return arrays
