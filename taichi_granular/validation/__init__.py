"""Validation cases: each runs its scene (or reads its output) and returns errors as numbers."""
