"""Constitutive models, by the name used in ``material.model``."""
from .elastoplastic import ElastoplasticMohrCoulomb
from .mu_i import MuIRheology

MODELS = {"mu_i": MuIRheology, "elastoplastic": ElastoplasticMohrCoulomb}

__all__ = ["MODELS", "MuIRheology", "ElastoplasticMohrCoulomb"]
