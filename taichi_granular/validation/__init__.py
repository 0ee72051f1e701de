"""Validation cases: each runs its scene (or reads its output) and returns errors as numbers."""
from ..output import left_domain  # noqa: F401  (the mask every validation uses)
