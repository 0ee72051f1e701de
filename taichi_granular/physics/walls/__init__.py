"""Boundary models. Each provides, for a pair (i material, j any):

- ``state_index(i, j)``: the particle whose density, pressure, viscosity... j carries in the
  pair (j itself, or i for ghost particles that mirror the material they face);
- ``relative_velocity(i, j, x_ij)``: the v_ij to use in every pair term [m/s];
- ``stages``: the per-step stages the model needs (none for fixed ghosts).
"""
from .ghost import GhostWalls, NoWalls

BOUNDARIES = {"ghost": GhostWalls}

__all__ = ["BOUNDARIES", "GhostWalls", "NoWalls"]
