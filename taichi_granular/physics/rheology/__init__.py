"""Constitutive models, by the name used in ``material.model``."""
from .elastoplastic import ElastoplasticMohrCoulomb
from .hypoplastic import HypoplasticBagnold
from .mu_i import MuIRheology

MODELS = {"mu_i": MuIRheology, "elastoplastic": ElastoplasticMohrCoulomb, "hypoplastic": HypoplasticBagnold}

__all__ = ["MODELS", "MuIRheology", "ElastoplasticMohrCoulomb", "HypoplasticBagnold"]
