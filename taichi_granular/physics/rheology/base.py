"""What a constitutive model declares and offers: the one interface the scene check and the
scheme read. A model is one package here (``<name>/parameters.py`` and ``<name>/model.py``)
named in the registry of ``__init__.py``.

:class:`MaterialParameters` is the base of a model's parameter class (its keys, under
``material:``): besides the keys it declares, as class variables, what a scene may combine with
the model (wall types, obstacle shapes and the boundary model they are laid as, the
model-specific numerics keys it reads), so that a scene is checked before anything is built.

:class:`Model` is the base of the model itself. It names its fields (``fields``: FieldSpecs the
state allocates), the fields it only derives for output (``derived_fields``, from
``derived_output``), the tensors the integrator advances like the density (``history``:
(field, rate, start) names) and whether it needs the free-surface flag
(``needs_free_surface``); it builds itself from a scene (``from_scene``), lists the stages of a
rate evaluation (``stage_classes``) and those after each update (``update_stage_classes``),
and offers, inside kernels, ``stable_time_step(i)`` [s] and ``density_error(i)`` [-]. The
defaults below are what a model without that feature declares.
"""
from dataclasses import dataclass
from typing import ClassVar, Dict, FrozenSet, Tuple


@dataclass(frozen=True, kw_only=True)
class MaterialParameters:
    wall_types: ClassVar[Tuple[str, ...]] = ()  # Wall.type values the model's physics supports
    walls_note: ClassVar[str] = ""  # why other wall types are refused (the error message)
    obstacle_shapes: ClassVar[Tuple[str, ...]] = ()  # obstacle shapes a scene of this model may hold
    obstacle_walls: ClassVar[str] = "dynamic"  # the boundary model obstacles are laid as
    numerics_read: ClassVar[FrozenSet[str]] = frozenset()  # model-specific numerics keys (config.MODEL_NUMERICS)
    symbols: ClassVar[Dict[str, str]] = {}  # the paper's symbol -> the key (an unknown key's suggestion)
    # True where a deposit creeps below yield and never comes to rest (mu(I)'s regularised viscosity,
    # [M48]): its run-out is read when the front stops, not at the end (validation/column_collapse.py)
    deposit_creeps: ClassVar[bool] = False

    def check(self, path: str) -> None:
        """Relations between keys (each key's own range is checked by keys.check_numbers)."""

    def check_scene(self, scene) -> None:
        """What the model needs from the rest of a scene beyond the declarations above (numerics
        it cannot run with): a ConfigError naming the key."""

    @property
    def wall_friction_deg(self):
        """The Coulomb friction angle a dynamic boundary takes unless its scene gives one [deg]: the
        material's own friction angle; None for a model without one."""
        return None

    def speed_scale(self, scene):
        """The flow speed the model predicts for this scene (m/s, and where it comes from), or
        None (mach.py then takes free fall and the scene's own speeds)."""
        return None

    @property
    def reference_density(self) -> float:
        """Bulk density of the material at rest and unstressed  [kg/m^3]."""
        raise NotImplementedError


class Model:
    fields: Tuple = ()
    derived_fields: Tuple = ()
    history: Tuple = ()
    needs_free_surface = False

    def __init__(self, material, dim: int, smoothing_length: float, state=None):
        """``material``: the parameter class instance; ``smoothing_length`` h [m]; ``state``: the
        ParticleState, set by the scheme once it is allocated."""
        self.material = material
        self.dim = dim
        self.state = state
        self.h = float(smoothing_length)

    def initial_fields(self, initial) -> dict:
        """Model fields to load at t = 0 beyond the common ones (name -> array)."""
        return {}

    def derived_output(self, arrays: dict) -> dict:
        """Quantities derived from the stored fields for the VTU files (``derived_fields``)."""
        return {}

    def update_stage_classes(self):
        """Stages run after each integrator update: none by default."""
        return []
