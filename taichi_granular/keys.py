"""How a scene key is declared and checked: the one vocabulary of config.py, the sections and
every model's parameter class.

A key is a dataclass field made by :func:`scene_key`: its default (none = required), a one-line
meaning (``doc``), its SI unit and, for numbers, the plausible :class:`Bounds`. The reference
page (``taichi-granular reference keys``) and the loader read the same declaration.
"""
from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass, field
from typing import Any, Optional, Tuple, Union

AXES = ("x", "y", "z")


class ConfigError(ValueError):
    """A scene file error, naming the key path it concerns."""

    def __init__(self, path: str, message: str):
        self.path = path
        super().__init__(f"{path}: {message}" if path else message)


@dataclass(frozen=True)
class Bounds:
    """The plausible range of a numeric key, written as an interval: ``"[0, 90)"``, ``"(0, 1e4]"``.

    Every number of a scene (each component of a vector too) is checked against its key's
    bounds when the scene is loaded, so that a value in the wrong unit (radians for degrees,
    rpm for rad/s, mm for m) or a typo of a few orders of magnitude is stopped before anything
    is allocated. The bounds are deliberately wide: they reject what no granular scene means,
    not what an unusual one might."""

    low: float
    high: float
    low_open: bool
    high_open: bool

    @classmethod
    def parse(cls, text: str) -> "Bounds":
        match = re.fullmatch(r"\s*([\[(])\s*([^,\s]+)\s*,\s*([^\])\s]+)\s*([\])])\s*", text)
        if not match:
            raise ValueError(f"bounds {text!r} must look like '[0, 90)'")
        return cls(float(match[2]), float(match[3]), match[1] == "(", match[4] == ")")

    def __contains__(self, value: float) -> bool:
        above = value > self.low if self.low_open else value >= self.low
        below = value < self.high if self.high_open else value <= self.high
        return above and below

    def __str__(self) -> str:
        return f"{'(' if self.low_open else '['}{self.low:g}, {self.high:g}{')' if self.high_open else ']'}"


def scene_key(doc: str, default: Any = dataclasses.MISSING, unit: str = "", bounds: Optional[str] = None,
         hint: str = "") -> Any:
    """Declare a scene key: its default (none = required), meaning, SI unit and, for numbers,
    the plausible ``bounds`` (:class:`Bounds`; ``hint`` is added to the message of a value
    outside them, e.g. "degrees, not radians")."""
    meta = {"doc": doc, "unit": unit, "bounds": Bounds.parse(bounds) if bounds else None, "hint": hint}
    if isinstance(default, (list, dict)):
        raise TypeError("use tuples for defaults")
    return field(default=default, metadata=meta)


def check_vector(path: str, value: Tuple[float, ...], dim: int) -> None:
    if len(value) != dim:
        raise ConfigError(path, f"needs {dim} components (dimension: {dim}), got {len(value)}")


def join_path(path: str, key: Union[str, int]) -> str:
    if isinstance(key, int):
        return f"{path}[{key}]"
    return f"{path}.{key}" if path else key


def type_name(value: Any) -> str:
    return type(value).__name__


def number(value: Any, path: str) -> float:
    """A finite float from a YAML number, or from text that reads as one (PyYAML reads 1e-5,
    without a dot, as text). NaN and infinity are refused whatever their spelling (.nan, 'nan',
    'inf', 1e999): no key of a scene means them."""
    number = None
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        number = float(value)
    elif isinstance(value, str):
        try:
            number = float(value)
        except ValueError:
            pass
    if number is None:
        raise ConfigError(path, f"expected a number, got {type_name(value)} {value!r}")
    if not math.isfinite(number):
        raise ConfigError(path, f"must be a finite number, got {value!r}")
    return number


def check_numbers(section: Any, path: str = "") -> None:
    """Every number of ``section`` and of the sections below it (vector components included)
    is finite and lies within its key's bounds (:class:`Bounds`), else a ConfigError naming the
    key path. Run by :meth:`Scene.check`, so that a scene made in code (``dataclasses.replace``)
    is held to the same ranges as one read from YAML."""
    for f in dataclasses.fields(section):
        value = getattr(section, f.name)
        sub = join_path(path, f.name)
        items = list(enumerate(value)) if isinstance(value, tuple) else [(None, value)]
        for k, item in items:
            item_path = sub if k is None else join_path(sub, k)
            if dataclasses.is_dataclass(item):
                check_numbers(item, item_path)
            elif isinstance(item, (int, float)) and not isinstance(item, bool):
                if not math.isfinite(item):
                    raise ConfigError(item_path, f"must be a finite number, got {item!r}")
                bounds = f.metadata.get("bounds")
                if bounds is not None and item not in bounds:
                    unit = f" {f.metadata['unit']}" if f.metadata.get("unit", "-") != "-" else ""
                    hint = f" ({f.metadata['hint']})" if f.metadata.get("hint") else ""
                    raise ConfigError(item_path, f"{item:g} is outside the plausible range {bounds}{unit}{hint}")
