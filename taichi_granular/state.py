"""ParticleState: the structure-of-arrays Taichi fields a scene needs, and no others.

Material particles occupy indices [0, n_material) and boundary particles [n_material, n_total)
of every per-particle field, so one neighbour grid and one pair loop see both. Stages declare
the fields they use as :class:`FieldSpec`; the state allocates the union of those
declarations, so a model that never asks for a stress tensor never allocates one.
"""
from dataclasses import dataclass
from typing import Dict, Iterable, List

import numpy as np
import taichi as ti

from . import runtime

SCOPES = ("all", "material", "wall")


@dataclass(frozen=True)
class FieldSpec:
    """A per-particle field: name, shape ('scalar' | 'vector' | 'matrix' (dim x dim) |
    'tensor3' (3 x 3 in 2D too: a plane-strain stress keeps its out-of-plane part)), meaning, unit.

    scope 'all' spans every particle, 'material' only material particles, 'wall' only
    boundary particles (indexed j - n_material).
    """

    name: str
    shape: str
    doc: str
    unit: str = "-"
    scope: str = "all"
    dtype: str = "float"

    def components(self, dim: int) -> int:
        return {"scalar": 1, "vector": dim, "matrix": dim * dim, "tensor3": 9}[self.shape]


# Every scheme has these.
CORE_FIELDS = (
    FieldSpec("position", "vector", "particle position", "m"),
    FieldSpec("velocity", "vector", "particle velocity", "m/s"),
    FieldSpec("mass", "scalar", "particle mass", "kg"),
    FieldSpec("density", "scalar", "bulk density rho", "kg/m^3"),
    FieldSpec("pressure", "scalar", "pressure p, positive in compression", "Pa"),
    FieldSpec("acceleration", "vector", "dv/dt from the last rate evaluation", "m/s^2", "material"),
    FieldSpec("density_rate", "scalar", "d rho/dt from the last rate evaluation [M26]", "kg/m^3/s", "material"),
    FieldSpec("particle_id", "scalar", "the particle's index in the scene's initial order: the fields are sorted by "
              "cell now and then (ParticleOrder), outputs are written in this order", "-", "material", "int"),
)


def merge_specs(groups: Iterable[Iterable[FieldSpec]]) -> List[FieldSpec]:
    """Union of field declarations; the same name declared twice must be declared alike."""
    merged: Dict[str, FieldSpec] = {}
    for group in groups:
        for spec in group:
            old = merged.get(spec.name)
            if old is not None and old != spec:
                if (old.shape, old.dtype) != (spec.shape, spec.dtype):
                    raise ValueError(f"field {spec.name!r} declared twice with different shapes")
                if old.scope != spec.scope:  # the wider scope wins
                    merged[spec.name] = spec if spec.scope == "all" else old
                continue
            merged.setdefault(spec.name, spec)
    return list(merged.values())


@ti.data_oriented
class ParticleState:
    """Owns the particle fields; attributes are named after the specs (``state.pressure``)."""

    def __init__(self, dim: int, n_material: int, n_wall: int, specs: Iterable[FieldSpec]):
        if n_material < 1:
            raise ValueError("a state needs at least one material particle")
        self.dim = dim
        self.n_material = int(n_material)
        self.n_wall = int(n_wall)
        self.n_total = self.n_material + self.n_wall
        self.specs: Dict[str, FieldSpec] = {}
        for spec in merge_specs([CORE_FIELDS, specs]):
            n = self.count(spec.scope)
            if n == 0:
                continue
            dtype = float if spec.dtype == "float" else ti.i32
            if spec.shape == "scalar":
                f = ti.field(dtype, n)
            elif spec.shape == "vector":
                f = ti.Vector.field(dim, dtype, n)
            elif spec.shape == "tensor3":
                f = ti.Matrix.field(3, 3, dtype, n)
            else:
                f = ti.Matrix.field(dim, dim, dtype, n)
            setattr(self, spec.name, f)
            self.specs[spec.name] = spec

    def count(self, scope: str) -> int:
        return {"all": self.n_total, "material": self.n_material, "wall": self.n_wall}[scope]

    def has(self, name: str) -> bool:
        return name in self.specs

    def field(self, name: str):
        return getattr(self, name)

    def load(self, arrays: Dict[str, np.ndarray]) -> None:
        """Copy numpy arrays into the fields of the same names (shapes must match)."""
        for name, array in arrays.items():
            if name not in self.specs:
                raise KeyError(f"state has no field {name!r}")
            f = self.field(name)
            dtype = ti.lang.util.to_numpy_type(f.dtype)  # f32 fields take float32 arrays
            f.from_numpy(np.ascontiguousarray(array, dtype=dtype))

    def to_numpy(self, names: Iterable[str] = None) -> Dict[str, np.ndarray]:
        """The fields as they are stored (material possibly sorted by cell: see :meth:`in_initial_order`)."""
        names = list(self.specs) if names is None else names
        return {name: self.field(name).to_numpy() for name in names}

    def in_initial_order(self, arrays: Dict[str, np.ndarray]) -> Dict[str, np.ndarray]:
        """``arrays`` (from :meth:`to_numpy`, material first) with the material rows put back in
        the scene's initial order (row particle_id[k] gets stored row k); boundary rows are never
        reordered."""
        ids = self.particle_id.to_numpy()
        if np.array_equal(ids, np.arange(self.n_material)):
            return arrays
        out = {}
        for name, array in arrays.items():
            if name in self.specs and self.specs[name].scope != "wall" and len(array) >= self.n_material:
                array = array.copy()
                array[ids] = array[: self.n_material].copy()
            out[name] = array
        return out

    def material(self, name: str) -> np.ndarray:
        """The material rows of field ``name`` in the scene's initial order (scripts and tests
        that compare particles across steps: the stored order changes every
        numerics.reorder_every steps)."""
        return self.in_initial_order({name: self.field(name).to_numpy()})[name][: self.n_material]

    def memory_table(self, itemsize: int) -> List[tuple]:
        """(name, scope, shape, bytes) of every allocated field."""
        rows = []
        for name, spec in self.specs.items():
            size = 4 if spec.dtype == "int" else itemsize
            nbytes = self.count(spec.scope) * spec.components(self.dim) * size
            rows.append((name, spec.scope, spec.shape, nbytes))
        return rows


@ti.data_oriented
class ParticleOrder:
    """Permutes the material rows of every material and all-scope field of ``state`` into a
    given order (a gather through one scratch field per field type); boundary rows stay."""

    name, category = "reorder_by_cell", "neighbours"  # as a stage in run --profile

    def __init__(self, state: ParticleState):
        self.state = state
        self.n = state.n_material
        self.order = ti.field(ti.i32, self.n)  # slot k receives particle order[k]
        self._scratch = {}
        for name, spec in state.specs.items():  # allocated now, not between kernel launches
            if spec.scope != "wall":
                self._scratch_for(state.field(name))

    def _scratch_for(self, f):
        """A field of ``f``'s type over the material, one per type."""
        if isinstance(f, ti.lang.matrix.MatrixField):
            key = (f.n, f.m, f.ndim, f.dtype)
            if key not in self._scratch:
                self._scratch[key] = (ti.Matrix.field(f.n, f.m, f.dtype, self.n) if f.ndim == 2
                                      else ti.Vector.field(f.n, f.dtype, self.n))
        else:
            key = (f.dtype,)
            if key not in self._scratch:
                self._scratch[key] = ti.field(f.dtype, self.n)
        return self._scratch[key]

    @ti.kernel
    def _gather(self, f: ti.template(), scratch: ti.template()):
        ti.loop_config(serialize=runtime.serial_loops)
        for k in range(self.n):
            scratch[k] = f[self.order[k]]
        ti.loop_config(serialize=runtime.serial_loops)
        for k in range(self.n):
            f[k] = scratch[k]

    def apply(self) -> None:
        """Put the material into ``self.order`` (filled by the caller) in every field."""
        for name, spec in self.state.specs.items():
            if spec.scope != "wall":
                f = self.state.field(name)
                self._gather(f, self._scratch_for(f))
