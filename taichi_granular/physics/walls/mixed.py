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
class GhostAndDynamicWalls(DynamicWalls, GhostWalls):
    """Dynamic walls' density rate, friction and stress index (DynamicWalls, first in the MRO),
    ghost walls' beta, stress extrapolation and impermeability (GhostWalls); the pair rules below
    pick between the two by the particle's kind."""

    name = "ghost+dynamic"
    fields = GhostWalls.fields + DynamicWalls.fields + (
        FieldSpec("wall_dynamic", "scalar", "1 for a dynamic boundary particle, 0 for a ghost", "-", "wall"),)

    @classmethod
    def initial_fields(cls, scene, initial) -> dict:
        """Both kinds' fields (GhostWalls', DynamicWalls') and the flag of each particle's kind."""
        fields = super().initial_fields(scene, initial)
        sources = boundary_sources(scene)
        fields["wall_dynamic"] = np.array([float(scene.is_dynamic(sources[w])) for w in initial.wall_of])
        return fields

    @classmethod
    def position_stage_classes(cls, scene):
        return GhostWalls.position_stage_classes(scene)

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
    def stress(self, i, j, x_ij, sigma_k):
        sigma = sigma_k
        if self.is_ghost(j):
            n, s = self.extrapolation(i, j, x_ij)
            g = ti.Vector(self.gravity)
            sigma += s * (g.outer_product(n) + n.outer_product(g) - g.dot(n) * n.outer_product(n))
        return sigma
