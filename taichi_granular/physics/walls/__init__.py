"""Boundary models. Each provides, for a pair (i material, j any):

- ``state_index(i, j)``: the particle whose density, pressure, viscosity... j carries in the
  pair (j itself, or i for ghost particles that mirror the material they face);
- ``relative_velocity(i, j, x_ij)``: the v_ij to use in every pair term [m/s], and
  ``relative(velocity, i, j, x_ij)`` the same for any velocity-like field (ghost and no walls,
  the ones the implicit viscous solve of mu(I) meets);
- ``stress_index(i, j)``: the particle whose deviatoric stress j carries (the state index, or i
  for dynamic boundary particles: a rough wall), and ``stress(i, j, x_ij, sigma)`` the total
  stress j carries given that deviatoric stress and the pressure of the state index [Pa];
- ``stages``: the per-step stages the model needs (none for fixed ghosts).
"""
from .dynamic import DynamicWalls
from .extrapolated import ExtrapolatedWalls
from .ghost import GhostWalls, NoWalls
from .mixed import GhostAndDynamicWalls

# the boundary model of a scene, by the set of its walls' and obstacles' types
BOUNDARIES = {frozenset({"ghost"}): GhostWalls, frozenset({"dynamic"}): DynamicWalls,
              frozenset({"extrapolated"}): ExtrapolatedWalls, frozenset({"ghost", "dynamic"}): GhostAndDynamicWalls}

__all__ = ["BOUNDARIES", "DynamicWalls", "ExtrapolatedWalls", "GhostAndDynamicWalls", "GhostWalls", "NoWalls"]
