"""The one place that initialises Taichi.

Precision is global in Taichi (``default_fp``), so a scene's ``precision`` and ``arch`` pick
the runtime; :func:`init` re-initialises only when they change (which invalidates every
existing field, so do it before building a simulation).
"""
from __future__ import annotations

import taichi as ti

ARCHES = {"cpu": "cpu", "cuda": "cuda", "vulkan": "vulkan", "metal": "metal", "gpu": "gpu"}
_current: tuple | None = None


def init(arch: str = "cpu", precision: str = "f64", force: bool = False) -> None:
    """Initialise Taichi for ``arch`` with ``precision`` ('f32' or 'f64') if not already so."""
    global _current
    key = (arch, precision)
    if _current == key and not force:
        return
    fp = ti.f64 if precision == "f64" else ti.f32
    ti.init(arch=getattr(ti, ARCHES[arch]), default_fp=fp, default_ip=ti.i32,
            random_seed=0, log_level=ti.WARN)
    _current = key


def current() -> tuple | None:
    return _current
