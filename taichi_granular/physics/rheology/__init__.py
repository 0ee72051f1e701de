"""The constitutive models, one package each, by the name ``material.model`` takes.

A model package holds ``parameters.py`` (its keys: a :class:`base.MaterialParameters` dataclass
exported as ``PARAMETERS``; numpy-free, so that loading a scene does not start Taichi) and
``model.py`` (the model, a :class:`base.Model`, exported as ``MODEL``, and its stages). Adding a
model is a new package and its name in :data:`MODELS` (docs/design.md shows it with the toy
Newtonian fluid).
"""
import importlib

MODELS = ("mu_i", "hypoplastic", "elastoplastic", "newtonian")  # the one registry


def parameter_class(name: str) -> type:
    """The parameter class of model ``name`` (its ``material:`` keys)."""
    return importlib.import_module(f"{__name__}.{name}.parameters").PARAMETERS


def model_class(name: str) -> type:
    """The model class of model ``name`` (imports Taichi)."""
    return importlib.import_module(f"{__name__}.{name}.model").MODEL
