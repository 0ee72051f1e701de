"""Constitutive models, by the name used in ``material.model``."""
from .mu_i import MuIRheology

MODELS = {"mu_i": MuIRheology}

__all__ = ["MODELS", "MuIRheology"]
