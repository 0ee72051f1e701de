"""Ghost plane walls and dynamic boundary particles in one scene: a model's own ghost walls
([M34]-[M36]) with obstacles (and any plane walls of type dynamic) laid as dynamic boundary
particles (walls/dynamic.py).

Each boundary particle keeps the rule of its kind: a flag per particle (``wall_dynamic``) picks,
in every pair term, the ghost's (it carries the facing grain's state, the velocity beta v_i and
the extrapolated stress) or the dynamic particle's (its own density and pressure, zero velocity,
the facing grain's deviatoric stress or none with a Coulomb angle). The branch is on the
particle's kind, data like ``j >= n_material``, not on the scene's configuration; a scene with
one kind only keeps its single-kind model (scheme.boundary_class).
"""
import numpy as np
import taichi as ti

from ...state import FieldSpec
from .dynamic import DynamicWalls
from .ghost import GhostWalls, boundary_sources


@ti.data_oriented
class GhostAndDynamicWalls(GhostWalls):
    name = "ghost+dynamic"
    fields = GhostWalls.fields + DynamicWalls.fields + (
        FieldSpec("wall_dynamic", "scalar", "1 for a dynamic boundary particle, 0 for a ghost", "-", "wall"),)

    def __init__(self, state, gravity=None):
        super().__init__(state, gravity)
        self.coulomb = state.has("wall_friction")

    @classmethod
    def initial_fields(cls, scene, initial) -> dict:
        """The ghosts' fields (obstacles have no ghost rule: beta_max 1, mirror stress, both unused)
        and the dynamic particles' Coulomb coefficient, with the flag of each particle's kind."""
        fields = DynamicWalls.initial_fields(scene, initial)
        sources = boundary_sources(scene)
        dynamic = np.array([scene.is_dynamic(sources[w]) for w in initial.wall_of], bool)
        ghost = [sources[w] if not d else None for w, d in zip(initial.wall_of, dynamic)]
        fields["wall_beta_max"] = np.array([1.0 if g is None else g.max_velocity_factor for g in ghost], float)
        fields["wall_extrapolation"] = np.array([float(g is not None and g.ghost_stress == "extrapolated")
                                                 for g in ghost])
        fields["wall_dynamic"] = dynamic.astype(float)
        return fields

    @classmethod
    def stage_classes(cls, scene):
        return DynamicWalls.stage_classes(scene)

    @ti.func
    def is_ghost(self, j):
        n = self.state.n_material
        ghost = False
        if j >= n:
            ghost = self.state.wall_dynamic[j - n] == 0.0
        return ghost

    @ti.func
    def state_index(self, i, j):
        k = j
        if self.is_ghost(j):
            k = i
        return k

    @ti.func
    def relative(self, velocity: ti.template(), i, j, x_ij):
        v_ij = velocity[i] - velocity[j]
        if self.is_ghost(j):
            v_ij = self.beta(i, j, x_ij) * velocity[i]
        return v_ij

    @ti.func
    def self_factor(self, i, j, x_ij):
        factor = 1.0
        if self.is_ghost(j):
            factor = self.beta(i, j, x_ij)
        return factor

    @ti.func
    def pressure(self, i, j, x_ij):
        p = self.state.pressure[j]
        if self.is_ghost(j):
            n, s = self.extrapolation(i, j, x_ij)
            p = self.state.pressure[i] - s * ti.Vector(self.gravity).dot(n)
        return p

    @ti.func
    def stress_index(self, i, j):
        """A ghost: i's; a dynamic particle: i's (rough), or none of its own with a Coulomb angle
        (walls/dynamic.py)."""
        k = j
        n = self.state.n_material
        if j >= n:
            k = i
            if ti.static(self.coulomb):
                if self.state.wall_friction[j - n] >= 0.0:
                    k = j
        return k

    @ti.func
    def stress(self, i, j, x_ij, sigma_k):
        sigma = sigma_k
        if self.is_ghost(j):
            n, s = self.extrapolation(i, j, x_ij)
            g = ti.Vector(self.gravity)
            sigma += s * (g.outer_product(n) + n.outer_product(g) - g.dot(n) * n.outer_product(n))
        return sigma
