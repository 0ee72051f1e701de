"""The one place that initialises Taichi.

Precision is global in Taichi (``default_fp``), so a scene's ``precision`` and ``arch`` pick
the runtime; :func:`init` re-initialises only when they change (which invalidates every
existing field, so do it before building a simulation).
"""
from __future__ import annotations

import taichi as ti

ARCHES = {"cpu": "cpu", "cuda": "cuda", "vulkan": "vulkan", "metal": "metal", "gpu": "gpu"}
_current: tuple | None = None

# Every top-level particle loop is written ``ti.loop_config(serialize=runtime.serial_loops)``.
# Taichi reads the flag when it compiles a kernel (at its first launch), so the scheme sets it
# before running anything. On the CPU, handing a loop to the thread pool costs ~0.1 ms a launch
# on this 2-core machine against ~0.02 ms serial (measured), which dominates small scenes.
serial_loops = False
SERIAL_BELOW = 2_500  # particles; measured crossover on 2 idle CPU cores (see choose_loops)


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


def choose_loops(n_particles: int) -> None:
    """Serial loops for CPU scenes below SERIAL_BELOW particles, parallel otherwise (measured
    crossover, ``taichi-granular bench throughput``); GPU loops are always parallel."""
    global serial_loops
    serial_loops = _current is not None and _current[0] == "cpu" and n_particles < SERIAL_BELOW


def current() -> tuple | None:
    return _current
