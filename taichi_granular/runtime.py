"""The one place that initialises Taichi.

Precision is global in Taichi (``default_fp``), so a scene's ``precision`` and ``arch`` pick
the runtime; :func:`init` re-initialises only when they change (which invalidates every
existing field, so do it before building a simulation).
"""
from __future__ import annotations

import os
import sys

import taichi as ti

# What ``arch: gpu`` tries, in order. Not Taichi's own ti.gpu, which also probes OpenGL: on a
# machine without a GPU or display that probe crashed the process (measured 2026-12-07, Taichi
# 1.7.4: ti.init(arch=ti.gpu) and ti.opengl segfault; ti.cuda and ti.vulkan fall back to the CPU).
GPU_ORDER = ("cuda", "vulkan", "metal")
_current: tuple | None = None
_on_cpu = True  # whether the runtime runs on the CPU: a GPU arch falls back to it where no device is
THREADS_ENV = "TAICHI_GRANULAR_CPU_THREADS"  # Taichi's CPU threads, when set (a sweep's runs)

# Every top-level particle loop is written ``ti.loop_config(serialize=runtime.serial_loops)``.
# Taichi reads the flag when it compiles a kernel (at its first launch), so the scheme sets it
# before running anything. On the CPU, handing a loop to the thread pool costs ~20 us more than
# running it serially on this 2-core machine, against ~2 us for a launch (launch.py; measured), which dominates small scenes.
serial_loops = False
# particles, material and boundary; measured crossover on 2 idle CPU cores (see choose_loops):
# mu(I) 2D serial / parallel ms a step at 1 088 / 1 617 / 2 115 particles 1.21 / 1.72 / 2.22
# against 1.54 / 1.70 / 2.10, hypoplastic 2D 2.64 / 3.79 / 5.19 against 3.19 / 3.45 / 4.04;
# the elastoplastic 2D step, with more and lighter loops, crosses over later (2.00 / 2.45 ms at
# 2 136, even at 3 166): a loss of up to a fifth for it between the two sizes. 3D mu(I) blocks:
# 6.9 / 14.1 ms serial against 7.4 / 9.3 parallel at 1 300 / 2 507 particles.
# Measured again on 2026-12-06, an empty loop over 64 or 2 000 items took 75-90 us parallel against
# 15 us serial (Taichi's own launch path), so light per-particle loops were tried
# serially up to 20 000 particles with the pair loops parallel (2026-12-06, medians of 8 batches,
# 4-5 runs each, separate processes): no gain at 2k (1.79-1.82 against 1.55-1.93 ms a step), a
# loss at 5k (3.8-4.1 against 2.9-3.4 ms) and 10k (7.7-8.2 against 5.4-6.8 ms): one crossover.
SERIAL_BELOW = 1_500


def init(arch: str = "cpu", precision: str = "f64", force: bool = False) -> None:
    """Initialise Taichi for ``arch`` with ``precision`` ('f32' or 'f64') if not already so."""
    global _current, _on_cpu
    key = (arch, precision)
    if _current == key and not force:
        return
    fp = ti.f64 if precision == "f64" else ti.f32
    # a sweep's worker runs each job with cores // workers threads (sweep/engine.py)
    threads = os.environ.get(THREADS_ENV)
    extra = {"cpu_max_num_threads": int(threads)} if threads else {}
    tried = [a for a in GPU_ORDER if a != "metal" or sys.platform == "darwin"] if arch == "gpu" else [arch]
    for candidate in tried:
        ti.init(arch=getattr(ti, candidate), default_fp=fp, default_ip=ti.i32,
                random_seed=0, log_level=ti.WARN, **extra)
        _on_cpu = ti.lang.impl.current_cfg().arch in (ti.x64, ti.arm64)
        if not _on_cpu:
            break
    if _on_cpu and arch != "cpu":
        print(f"warning: arch {arch}: no {' or '.join(tried)} device here; running on the CPU", file=sys.stderr)
    _current = key


def choose_loops(n_particles: int) -> None:
    """Serial loops for CPU scenes below SERIAL_BELOW particles, parallel otherwise (measured
    crossover, ``taichi-granular bench throughput``); GPU loops are always parallel."""
    global serial_loops
    serial_loops = _current is not None and _on_cpu and n_particles < SERIAL_BELOW


def current() -> tuple | None:
    return _current


def ensure(precision: str = "f64") -> None:
    """Starts the CPU runtime if nothing has started one (a point evaluation of the law outside a
    run: validate --reuse)."""
    if _current is None:
        init("cpu", precision)
