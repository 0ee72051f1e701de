"""YAML scene -> validated, frozen dataclasses: the :class:`Scene` and its loader.

Every key of a scene is declared exactly once, with its default, a one-line meaning and its
unit (keys.py): the sections in sections.py, the solids in bodies.py, each material's keys in
its model's package (physics/rheology/<model>/parameters.py, picked by ``material.model``
from the model registry). Loading checks everything before any Taichi field exists: unknown
keys (with a close-match suggestion), missing keys, wrong types, vectors of the wrong length
and physically impossible values all raise :class:`ConfigError` naming the key path, e.g.
``material.solid_fraction_min``.
"""
from __future__ import annotations

import dataclasses
import difflib
import math
import typing
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, Optional, Tuple, Union

import yaml

from .bodies import OBSTACLES, AnyObstacle, ParticleBlock, Wall
from .keys import AXES, ConfigError, check_numbers, join_path, number, scene_key, type_name
from .physics.rheology import MODELS, parameter_class
from .sections import (BYTES_PER_CELL, BYTES_PER_PARTICLE, Domain, Gravity, Numerics, Render, Run,
                       max_particles)

MATERIALS = {name: parameter_class(name) for name in MODELS}  # material.model -> its parameter class

# the boundary types that may meet in one scene (physics/walls BOUNDARIES has a model for each)
WALL_COMBINATIONS = (frozenset({"ghost"}), frozenset({"dynamic"}), frozenset({"extrapolated"}),
                     frozenset({"ghost", "dynamic"}))


class AnyMaterial:
    """Annotation marker: the ``model`` key picks the class from :data:`MATERIALS`."""


# numerics keys that only some models read (their materials' ``numerics_read``): the name, whether
# the scene asks for it, the key a message names, and what it is for
MODEL_NUMERICS = {
    "artificial_stress": (lambda n: n.artificial_stress.enabled, "numerics.artificial_stress.epsilon",
                          "the tensile instability correction needs a stress tensor model; set it to 0"),
    "stress_increment": (lambda n: n.stress_increment > 0.0, "numerics.stress_increment",
                         "it bounds the step by the hypoplastic stress rate"),
    "residual_damping": (lambda n: n.residual_damping != 1.0, "numerics.residual_damping",
                         "it scales the hypoplastic secant viscosity of the residual damping; leave it at 1"),
    "bulk_viscosity": (lambda n: n.bulk_viscosity > 0.0, "numerics.bulk_viscosity",
                       "it resists compaction in a model with no equation of state; set it to 0"),
    "stress_diffusion": (lambda n: n.stress_diffusion > 0.0, "numerics.stress_diffusion",
                         "it smooths an integrated stress (mu(I)'s stress is algebraic); set it to 0"),
    "implicit_viscosity": (lambda n: n.viscosity == "implicit", "numerics.viscosity",
                           "the implicit viscous update is for the regularised viscosity of mu(I); set it to explicit"),
}


@dataclass(frozen=True, kw_only=True)
class Scene:
    dimension: Literal[2, 3] = scene_key("2 or 3")
    domain: Domain = scene_key("bounding box and periodic axes")
    material: AnyMaterial = scene_key("constitutive model and its parameters")
    particles: Tuple[ParticleBlock, ...] = scene_key("blocks of material particles")
    numerics: Numerics = scene_key("discretisation")
    run: Run = scene_key("run length and output cadence")
    name: str = scene_key("scene name (default: file name)", "scene")
    arch: Literal["cpu", "cuda", "vulkan", "metal", "gpu"] = scene_key(
        "Taichi backend; gpu: the first of CUDA, Vulkan (Metal on macOS) found; without a device the run "
        "goes on the CPU and says so", "cpu")
    precision: Literal["f32", "f64"] = scene_key("floating point precision of all fields", "f64")
    gravity: Gravity = scene_key("gravitational acceleration", Gravity())
    walls: Tuple[Wall, ...] = scene_key("walls as boundary particles", ())
    obstacles: Tuple[AnyObstacle, ...] = scene_key(
        "solids laid as boundary particles of the model's obstacle type (dynamic; hypoplastic: extrapolated): chute, "
        "box, post_rows, cylinder, wedge, mesh, drum", ())
    render: Render = scene_key("PNG frames", Render())

    def check(self) -> None:
        dim = self.dimension
        check_numbers(self)
        self.domain.check("domain", dim)
        self.render.check("render", dim, self.domain)
        self.material.check("material")
        dp = self.numerics.particle_spacing
        if dp > min(self.domain.size):
            raise ConfigError("numerics.particle_spacing",
                              f"dp = {dp} m is larger than the domain ({min(self.domain.size)} m)")
        if not self.particles:
            raise ConfigError("particles", "at least one block of material is needed")
        for k, block in enumerate(self.particles):
            block.check(f"particles[{k}]", dim, self.domain, dp)
        material = type(self.material)  # what the model declares it supports
        for k, wall in enumerate(self.walls):
            wall.check(f"walls[{k}]", dim)
            if wall.type not in material.wall_types:
                raise ConfigError(f"walls[{k}].type", material.walls_note)
        for k, obstacle in enumerate(self.obstacles):
            obstacle.check(f"obstacles[{k}]", dim)
            if obstacle.shape not in material.obstacle_shapes:
                supported = ", ".join(material.obstacle_shapes) or "none"
                raise ConfigError(f"obstacles[{k}].shape", f"material.model: {self.material.model} supports the "
                                                           f"obstacles: {supported}")
            obstacle.check_friction(f"obstacles[{k}]", material.obstacle_walls == "dynamic")
        sources = [(f"walls[{k}]", w) for k, w in enumerate(self.walls)] + \
            [(f"obstacles[{k}]", o) for k, o in enumerate(self.obstacles)]
        for path, source in sources:
            if self.is_dynamic(source) and source.friction in (None, "coulomb") and \
                    self.boundary_friction_deg(source) is None:
                raise ConfigError(f"{path}.friction_angle_deg", f"material.model: {self.material.model} has no "
                                                                "friction angle to default to: give one, or friction: rough")
        if self.wall_types and self.wall_types not in WALL_COMBINATIONS:
            obstacles = f"; obstacles are {material.obstacle_walls} boundary particles" if self.obstacles else ""
            raise ConfigError("walls", f"the boundary types {', '.join(sorted(self.wall_types))} do not combine in "
                                       f"one scene{obstacles}")
        for name, (asked, key, why) in MODEL_NUMERICS.items():  # a model-specific key set for a model without it
            if asked(self.numerics) and name not in material.numerics_read:
                raise ConfigError(key, f"{why}; material.model: {self.material.model} does not have it")
        self.material.check_scene(self)
        if self.run.guard == "stage" and self.run.guard_every > 1:
            raise ConfigError("run.guard_every", "run.guard: stage checks after every stage of every step; "
                                                 "set run.guard_every: 1 (or run.guard: step)")
        self._check_size()
        support = 2.0 * self.numerics.smoothing_length
        for a, name in enumerate(AXES[:dim]):
            if name in self.domain.periodic and self.domain.size[a] < 3 * support:
                raise ConfigError("domain.periodic",
                                  f"periodic axis {name} spans {self.domain.size[a]} m, less than three kernel "
                                  f"supports (3 x {support} m)")

    def _check_size(self) -> None:
        """What would not fit in memory fails here, before anything is allocated: the neighbour grid
        (cells of the kernel support 2h, int32-indexed) and the material blocks' particles.
        Walls and obstacles are counted where they are laid (scene/geometry.py lattice_counts)."""
        dp = self.numerics.particle_spacing
        support = 2.0 * self.numerics.smoothing_length
        cells = math.prod(max(1, math.floor(size / support)) for size in self.domain.size)
        if cells > min(2**31 - 2, max_particles() * BYTES_PER_PARTICLE // BYTES_PER_CELL):
            raise ConfigError("domain.upper", f"the neighbour grid would have {cells:.3g} cells (the domain in "
                                              f"cells of 2h = {support:g} m), more than this machine holds; shrink "
                                              "the domain or coarsen numerics.particle_spacing")
        total = 0
        for k, block in enumerate(self.particles):
            count = math.prod(math.floor((hi - lo) / dp + 1e-9) for lo, hi in zip(block.lower, block.upper))
            total += count
            if total > max_particles():
                raise ConfigError(f"particles[{k}]", f"{total:.3g} material particles at dp = {dp:g} m (this block "
                                                     f"{count:.3g}), more than this machine's memory holds "
                                                     f"({max_particles():.3g}); coarsen numerics.particle_spacing")

    def is_dynamic(self, source) -> bool:
        """Whether a wall or obstacle is laid as dynamic boundary particles."""
        return source.type == "dynamic" if isinstance(source, Wall) else type(self.material).obstacle_walls == "dynamic"

    def boundary_friction_deg(self, source) -> Optional[float]:
        """delta of a wall's or obstacle's Coulomb friction with the material [deg]: its own
        friction_angle_deg, else the material's friction angle; None where it has no Coulomb
        friction (rough, pressure_only, or not dynamic boundary particles)."""
        if not self.is_dynamic(source) or source.friction in ("rough", "pressure_only"):
            return None
        return source.friction_angle_deg if source.friction_angle_deg is not None else self.material.wall_friction_deg

    @property
    def wall_types(self) -> frozenset:
        """The boundary types of the scene: its walls', and its obstacles' (the model's)."""
        obstacles = {type(self.material).obstacle_walls} if self.obstacles else set()
        return frozenset({w.type for w in self.walls} | obstacles)

    @property
    def gravity_vector(self) -> Tuple[float, ...]:
        return self.gravity.vector(self.dimension)


# --------------------------------------------------------------------------------------------
# Loading
# --------------------------------------------------------------------------------------------


# The papers' symbols, so that a scene written from the equations gets pointed to the key.
SYMBOLS = {
    "dp": "particle_spacing", "h": "smoothing_length_ratio (h/dp)", "h_over_dp": "smoothing_length_ratio",
    "g": "gravity.magnitude", "theta": "gravity.tilt_deg", "slope_deg": "tilt_deg",
}
for _material in MATERIALS.values():  # each model's own symbols (its parameter class's ``symbols``)
    SYMBOLS.update(_material.symbols)


def _suggest(key: str, allowed) -> str:
    symbol = SYMBOLS.get(key)
    if symbol and symbol.split(" ")[0].split(".")[-1] in allowed:
        return f"did you mean {symbol}?"
    close = difflib.get_close_matches(key, list(allowed), n=1, cutoff=0.6)
    if not close:  # 'cfl_number' for 'cfl', 'density' for 'grain_density'
        close = sorted((a for a in allowed if key.startswith(a) or a.startswith(key) or a.endswith(key)),
                       key=len, reverse=True)
    if close:
        return f"did you mean '{close[0]}'?"
    return "allowed keys: " + ", ".join(sorted(allowed))


def _convert(tp: Any, value: Any, path: str) -> Any:
    origin = typing.get_origin(tp)
    args = typing.get_args(tp)
    if origin is Union:  # Optional[X]
        if value is None and type(None) in args:
            return None
        inner = [a for a in args if a is not type(None)]
        if len(inner) == 1:
            return _convert(inner[0], value, path)
        raise TypeError(f"unsupported union at {path}")
    if origin is Literal:
        if value not in args:
            choices = ", ".join(repr(a) for a in args)
            hint = ""
            if isinstance(value, str):
                close = difflib.get_close_matches(value, [str(a) for a in args], n=1)
                hint = f"; did you mean '{close[0]}'?" if close else ""
            raise ConfigError(path, f"{value!r} is not one of {choices}{hint}")
        return value
    if origin in (tuple, Tuple):
        if not isinstance(value, (list, tuple)):
            raise ConfigError(path, f"expected a list, got {type_name(value)} {value!r}")
        item_tp = args[0]
        return tuple(_convert(item_tp, v, join_path(path, k)) for k, v in enumerate(value))
    if tp in TAGGED:
        return _load_tagged(value, path, *TAGGED[tp])
    if dataclasses.is_dataclass(tp):
        return _load_dataclass(tp, value, path)
    if tp is float:
        return number(value, path)
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(path, f"expected an integer, got {type_name(value)} {value!r}")
        return value
    if tp is bool:
        if not isinstance(value, bool):
            raise ConfigError(path, f"expected true or false, got {value!r}")
        return value
    if tp is str:
        if not isinstance(value, str):
            raise ConfigError(path, f"expected text, got {type_name(value)} {value!r}")
        return value
    raise TypeError(f"unsupported type {tp} at {path}")


def _load_dataclass(cls: type, data: Any, path: str) -> Any:
    if not isinstance(data, dict):
        raise ConfigError(path, f"expected a mapping of keys, got {type_name(data)} {data!r}")
    fields = {f.name: f for f in dataclasses.fields(cls)}
    for key in data:
        if key not in fields:
            raise ConfigError(join_path(path, str(key)), f"unknown key; {_suggest(str(key), fields)}")
    hints = typing.get_type_hints(cls)
    kwargs = {}
    for name, f in fields.items():
        sub = join_path(path, name)
        if name in data:
            kwargs[name] = _convert(hints[name], data[name], sub)
        elif f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            raise ConfigError(sub, f"missing required key ({f.metadata.get('doc', '')})")
    return cls(**kwargs)


def _load_tagged(data: Any, path: str, tag: str, registry: dict) -> Any:
    """A section whose ``tag`` key (material.model, obstacles[k].shape) picks its class."""
    if not isinstance(data, dict):
        raise ConfigError(path, f"expected a mapping of keys, got {type_name(data)}")
    if tag not in data:
        raise ConfigError(join_path(path, tag), f"missing required key; one of {sorted(registry)}")
    value = data[tag]
    if value not in registry:
        raise ConfigError(join_path(path, tag), f"unknown {tag} {value!r}; {_suggest(str(value), registry)}")
    return _load_dataclass(registry[value], data, path)


TAGGED = {AnyMaterial: ("model", MATERIALS), AnyObstacle: ("shape", OBSTACLES)}


def _check_duplicate_keys(node: yaml.Node, path: str, source: str) -> None:
    """Raise on a key given twice in one mapping (PyYAML would keep the last silently)."""
    if isinstance(node, yaml.MappingNode):
        seen = {}
        for key_node, value_node in node.value:
            key = key_node.value if isinstance(key_node, yaml.ScalarNode) else None
            if key is not None:
                line = key_node.start_mark.line + 1
                if key in seen:
                    raise ConfigError(join_path(path, key), f"given twice in {source}, on lines {seen[key]} and {line}; "
                                      "keep one")
                seen[key] = line
            _check_duplicate_keys(value_node, join_path(path, key) if key is not None else path, source)
    elif isinstance(node, yaml.SequenceNode):
        for index, item in enumerate(node.value):
            _check_duplicate_keys(item, join_path(path, index), source)


def parse_yaml(text: str, path: str = "", source: str = "the scene file") -> Any:
    """Parse YAML text strictly: syntax errors and duplicated keys are :class:`ConfigError` at ``path``."""
    try:
        node = yaml.compose(text, Loader=yaml.SafeLoader)
        if node is not None:
            _check_duplicate_keys(node, path, source)
        return yaml.safe_load(text)
    except yaml.YAMLError as err:
        raise ConfigError(path, f"{source} is not valid YAML: {err}") from None


def apply_overrides(data: dict, overrides: typing.Iterable[str]) -> dict:
    """Apply ``dotted.key=value`` overrides (values parsed as YAML) to a raw scene mapping; an
    integer key picks an entry of a list (``walls.0.friction_angle_deg=30``)."""
    for item in overrides:
        if "=" not in item:
            raise ConfigError(item, "override must look like section.key=value")
        dotted, raw = item.split("=", 1)
        keys = dotted.strip().split(".")
        node = data
        for depth, key in enumerate(keys):
            path = ".".join(keys[:depth + 1])
            last = depth == len(keys) - 1
            if isinstance(node, list):
                if not key.isdigit() or int(key) >= len(node):
                    raise ConfigError(path, f"'{key}' is not an index of this list of {len(node)} entries")
                key = int(key)
            elif not isinstance(node, dict):
                raise ConfigError(path, f"'{keys[depth - 1]}' is not a section")
            if last:
                node[key] = parse_yaml(raw, path, source=f"the value of --set {path}")
            else:
                node = node.setdefault(key, {}) if isinstance(node, dict) else node[key]
    return data


def scene_from_dict(data: Any, name: str = "scene") -> Scene:
    """Validate a raw mapping and return the frozen :class:`Scene`."""
    if not isinstance(data, dict):
        raise ConfigError("", f"a scene file must be a mapping of keys, got {type_name(data)}")
    data = dict(data)
    data.setdefault("name", name)
    scene = _load_dataclass(Scene, data, "")
    scene.check()
    return scene


def load_scene(path: Union[str, Path], overrides: typing.Iterable[str] = ()) -> Scene:
    """Read and validate a YAML scene file; ``overrides`` are ``dotted.key=value`` strings. A path
    that does not exist but names a bundled scene (``mu_i/inclined_plane.yaml``, paths.py) reads that."""
    from .paths import bundled

    path = Path(path)
    if not path.exists():
        path = bundled(path) or path
    try:
        text = path.read_text()
    except (OSError, UnicodeDecodeError) as err:
        raise ConfigError("", f"cannot read the scene file {path}: {err}") from None
    data = parse_yaml(text, source=str(path))
    if overrides and isinstance(data, dict):
        data = apply_overrides(data, overrides)
    if isinstance(data, dict) and isinstance(data.get("obstacles"), list):  # mesh files: from the scene's folder
        for item in data["obstacles"]:
            if isinstance(item, dict) and isinstance(item.get("file"), str) and not Path(item["file"]).is_absolute():
                item["file"] = str(path.parent / item["file"])
    return scene_from_dict(data, name=path.stem)


def scene_to_dict(scene: Any) -> Any:
    """Plain data (every default made explicit), for the resolved config written with outputs."""
    if dataclasses.is_dataclass(scene):
        return {f.name: scene_to_dict(getattr(scene, f.name)) for f in dataclasses.fields(scene)}
    if isinstance(scene, tuple):
        return [scene_to_dict(v) for v in scene]
    return scene


def dump_scene(scene: Scene) -> str:
    return yaml.safe_dump(scene_to_dict(scene), sort_keys=False)
