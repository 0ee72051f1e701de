"""The Stage: one kernel launch of one physics step, named for the stage list and profile."""
from dataclasses import dataclass
from typing import Any, Tuple

from ..state import FieldSpec

# The categories of the per-stage profile, in the order a step runs them.
CATEGORIES = ("neighbours", "density", "eos", "rheology", "forces", "walls", "integration")


@dataclass
class Context:
    """What stages are built from: the state, the neighbour grid, the smoothing function,
    the boundary model, the material model and the scene."""

    state: Any
    grid: Any
    smoothing: Any
    walls: Any
    model: Any
    scene: Any
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
    equation = ""
    fields: Tuple[FieldSpec, ...] = ()

    def __init__(self, ctx: Context):
        self.state, self.grid, self.walls, self.model = ctx.state, ctx.grid, ctx.walls, ctx.model
        self.smoothing, self.gradient = ctx.smoothing, ctx.gradient

    def run(self) -> None:
        self._run()

    def describe(self) -> str:
        eq = f" {self.equation}" if self.equation else ""
        return f"{self.name} [{self.category}]{eq}"
