"""What a constitutive model declares and offers: the one interface the scheme reads.

A model class names its fields (``fields``: FieldSpecs the state allocates), the fields it only
derives for output (``derived_fields``, from ``derived_output``), the tensors the integrator
advances like the density (``history``: (field, rate, start) names) and whether it needs the
free-surface flag (``needs_free_surface``); it builds itself from a scene (``from_scene``), lists the stages of a
rate evaluation (``stage_classes``) and those after each update (``update_stage_classes``),
and offers, inside kernels, ``stable_time_step(i)`` [s] and ``density_error(i)`` [-]. The
defaults below are what a model without that feature declares. What a scene may combine with
the model (wall types, obstacles, model-specific numerics keys) its parameter class in config.py
declares, so that a scene is checked before anything is built.
"""
from typing import Tuple


class Model:
    fields: Tuple = ()
    derived_fields: Tuple = ()
    history: Tuple = ()
    needs_free_surface = False

    def initial_fields(self, initial) -> dict:
        """Model fields to load at t = 0 beyond the common ones (name -> array)."""
        return {}

    def derived_output(self, arrays: dict) -> dict:
        """Quantities derived from the stored fields for the VTU files (``derived_fields``)."""
        return {}

    def update_stage_classes(self):
        """Stages run after each integrator update: none by default."""
        return []
