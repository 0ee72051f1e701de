"""The Stage: one kernel launch of one physics step, named for the stage list and profile; pair
stages, and several of them fused into one neighbour pass."""
from dataclasses import dataclass
from typing import Any, Tuple

import taichi as ti

from .. import runtime
from ..launch import launcher
from ..state import FieldSpec

# The categories of the per-stage profile, in the order a step runs them.
CATEGORIES = ("neighbours", "density", "eos", "rheology", "forces", "walls", "integration")

# The slots of a rate evaluation, in the order they run: every stage declares its slot, and the
# scheme runs the stages that the model, the walls and the numerics bring in slot order (each
# contributor's own order kept within a slot). RATE_SLOTS: neighbour lists and kernel
# corrections; the free-surface flag; the boundary particles' own state (extrapolated velocity,
# dynamic walls' density rate); the kinematics (continuity, velocity gradient); the equation of
# state; the rheology (viscosity, stress rates, total stress); stresses carried to the walls;
# the forces (momentum, artificial viscosity and stress); the forces that replace part of those
# at walls (Coulomb friction); the particle shift. MOVE_SLOTS: after each move of the
# particles, material leaving open faces, the walls' motion and impermeability, the model's
# update of its stress.
RATE_SLOTS = ("neighbours", "correction", "free_surface", "wall_state", "kinematics", "eos", "rheology",
              "wall_stress", "forces", "wall_forces", "shifting")
MOVE_SLOTS = ("outflow", "wall_motion", "update")


def in_slot_order(classes: list, slots: tuple) -> list:
    """``classes`` sorted into ``slots`` (stable: the order within a slot is kept)."""
    for cls in classes:
        if cls.slot not in slots:
            raise ValueError(f"stage {cls.__name__} declares slot {cls.slot!r}, not one of {slots}")
    return sorted(classes, key=lambda cls: slots.index(cls.slot))


@dataclass
class Context:
    """What stages are built from: the state, the neighbour grid, the smoothing function, the
    boundary model, the material model, and of the scene only the sections stages read (the
    numerics, gravity, the domain, the plane walls' and obstacles' keys), not the whole Scene."""

    state: Any
    grid: Any
    smoothing: Any
    walls: Any
    model: Any
    numerics: Any  # the scene's numerics section (sections.Numerics)
    gravity: Tuple[float, ...]  # the gravity vector [m/s^2]
    domain: Any  # sections.Domain
    plane_walls: Tuple = ()  # the scene's walls (bodies.Wall)
    obstacles: Tuple = ()  # the scene's obstacles (bodies.*Obstacle)
    gradient: Any = None  # PlainGradient or CorrectedGradient: grad W as pair loops see it
    time_step: Any = None  # 0-d field: the dt of the step being taken [s] (set by Scheme.step)
    time: Any = None  # 0-d field: the time the position stages move the scene to [s] (Scheme.after_move)
    step_fraction: Any = None  # 0-d field: how far into the step that is: 1/2 (predictor, half step) or 1


class Stage:
    """Base class. Subclasses set ``name``, ``category``, ``equation`` and ``fields``
    (the FieldSpecs they need allocated) and define the kernel ``_run`` (one launch), or
    override ``run``. The context's parts are at hand as attributes."""

    name = "stage"
    category = "forces"
    slot = None  # where in a step it runs: one of RATE_SLOTS or MOVE_SLOTS
    equation = ""
    fields: Tuple[FieldSpec, ...] = ()

    def __init__(self, ctx: Context):
        self.state, self.grid, self.walls, self.model = ctx.state, ctx.grid, ctx.walls, ctx.model
        self.smoothing, self.gradient = ctx.smoothing, ctx.gradient

    def run(self) -> None:
        launcher(self, "_run")()  # Taichi's launch without its per-call bookkeeping (launch.py)

    def describe(self) -> str:
        eq = f" {self.equation}" if self.equation else ""
        return f"{self.name} [{self.category}]{eq}"


class PairStage(Stage):
    """A stage that is one sum over each material particle's neighbours:
    ``acc = initial(i)``, ``pair(i, j, x_ij, r, acc)`` for every neighbour, ``store(i, acc)``.

    Consecutive pair stages share one neighbour pass (:class:`FusedPairs`, built by the scheme)
    unless one of them reads, in its pair term, a field that an earlier one stores: ``writes``
    names what ``store`` writes, ``reads`` the fields the pair term takes that some pair stage
    writes (kernel corrections, kernel sums, velocity gradients, ...). The stores run in stage
    order after the shared loop, so a store may build on an earlier one (+= on the acceleration).
    """

    reads: Tuple[str, ...] = ()
    writes: Tuple[str, ...] = ()
    # a stage whose pair term reads per-particle values it can compute once per particle instead
    # of once per pair defines ``prepare(i)``: it runs for every material particle before the pass
    prepares = False

    @ti.kernel
    def _run(self):
        if ti.static(self.prepares):
            ti.loop_config(serialize=runtime.serial_loops)
            for i in range(self.state.n_material):
                self.prepare(i)
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            acc = self.initial(i)
            self.grid.for_each_neighbour(i, self.pair, acc)
            self.store(i, acc)


def fuse_pair_stages(stages: list, ctx) -> list:
    """The stages as run: runs of consecutive pair stages that do not read what an earlier one of
    the run writes become one :class:`FusedPairs` (up to ``FusedPairs.most``); the rest as they are."""
    passes, group = [], []

    def flush():
        if len(group) > 1:
            passes.append(FusedPairs(ctx, list(group)))
        elif group:
            passes.append(group[0])
        group.clear()

    for stage in stages:
        if not isinstance(stage, PairStage):
            flush()
            passes.append(stage)
            continue
        written = {name for member in group for name in member.writes}
        if set(stage.reads) & written or len(group) == FusedPairs.most:
            flush()
        group.append(stage)
    flush()
    return passes


# 'module.Class.pair' of every pair stage compiled into a fused pass so far (profiling.compiled_kernels:
# the kernel itself is FusedPairs._run whatever its members)
FUSED_COMPILED = set()


@ti.data_oriented
class FusedPairs(Stage):
    """Several pair stages in one neighbour pass: each pair term adds to its own accumulator
    (chosen at compile time, no branching on the stage), then each stage stores its own."""

    most = 4

    def __init__(self, ctx, members):
        super().__init__(ctx)
        self.members = tuple(members)
        self.name = " + ".join(m.name for m in members)
        self.category = members[0].category
        self.equation = " ".join(m.equation for m in members if m.equation)
        self.prepares = any(m.prepares for m in members)

    def run(self) -> None:
        FUSED_COMPILED.update(f"{type(m).__module__}.{type(m).__qualname__}.pair" for m in self.members)
        launcher(self, "_run")()

    @ti.func
    def prepare(self, i):
        for k in ti.static(range(len(self.members))):
            if ti.static(self.members[k].prepares):
                self.members[k].prepare(i)

    @ti.func
    def pair(self, i, j, x_ij, r, accs: ti.template()):
        for k in ti.static(range(len(self.members))):
            self.members[k].pair(i, j, x_ij, r, accs[k])

    @ti.kernel
    def _run(self):
        # a Python tuple of Taichi locals cannot be built in a loop: one branch per arity
        m = self.members
        if ti.static(self.prepares):
            ti.loop_config(serialize=runtime.serial_loops)
            for i in range(self.state.n_material):
                self.prepare(i)
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            if ti.static(len(m) == 2):
                a0 = m[0].initial(i)
                a1 = m[1].initial(i)
                self.grid.for_each_neighbour(i, self.pair, ti.static((a0, a1)))
                m[0].store(i, a0)
                m[1].store(i, a1)
            elif ti.static(len(m) == 3):
                a0 = m[0].initial(i)
                a1 = m[1].initial(i)
                a2 = m[2].initial(i)
                self.grid.for_each_neighbour(i, self.pair, ti.static((a0, a1, a2)))
                m[0].store(i, a0)
                m[1].store(i, a1)
                m[2].store(i, a2)
            else:
                a0 = m[0].initial(i)
                a1 = m[1].initial(i)
                a2 = m[2].initial(i)
                a3 = m[3].initial(i)
                self.grid.for_each_neighbour(i, self.pair, ti.static((a0, a1, a2, a3)))
                m[0].store(i, a0)
                m[1].store(i, a1)
                m[2].store(i, a2)
                m[3].store(i, a3)
