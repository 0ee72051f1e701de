"""Per-stage wall-clock profile: the one timing mechanism (``run --profile`` and benchmarks).

Every stage call goes through :class:`StageProfiler`. Disabled, it just calls the stage.
Enabled, it synchronises the device around the call (so asynchronous GPU launches are
charged to the right stage) and accumulates seconds per stage and per category.
"""
import time
from collections import defaultdict
from typing import List

import taichi as ti

from .physics.stage import CATEGORIES


class StageProfiler:
    def __init__(self, enabled: bool = False):
        self.enabled = enabled
        self.seconds = defaultdict(float)
        self.calls = defaultdict(int)
        self.category_of = {}
        self.after = None  # called with the stage after each call (the per-stage run-time guard)

    def __call__(self, stage, fn=None, *args) -> None:
        fn = stage.run if fn is None else fn
        if not self.enabled:
            fn(*args)
            if self.after is not None:
                self.after(stage)
            return
        ti.sync()
        start = time.perf_counter()
        fn(*args)
        ti.sync()
        self.seconds[stage.name] += time.perf_counter() - start
        self.calls[stage.name] += 1
        self.category_of[stage.name] = stage.category
        if self.after is not None:
            self.after(stage)

    def reset(self) -> None:
        self.seconds.clear()
        self.calls.clear()

    def by_category(self) -> dict:
        totals = {c: 0.0 for c in CATEGORIES}
        for name, sec in self.seconds.items():
            totals[self.category_of[name]] += sec
        return totals

    def table(self) -> str:
        total = sum(self.seconds.values()) or 1.0
        lines = [f"{'stage':<28}{'category':<13}{'calls':>8}{'seconds':>10}{'share':>8}"]
        for name, sec in sorted(self.seconds.items(), key=lambda kv: -kv[1]):
            lines.append(f"{name:<28}{self.category_of[name]:<13}{self.calls[name]:>8}{sec:>10.3f}"
                         f"{100 * sec / total:>7.1f}%")
        lines.append(f"{'total':<49}{total:>10.3f}")
        return "\n".join(lines)


def compiled_kernels() -> List[str]:
    """'module.Class.kernel' of every Taichi kernel compiled so far in this process (Taichi
    compiles a kernel at its first launch): what a scene's step actually built, so that a test
    or ``run --profile`` can show that an effect switched off was never compiled."""
    from taichi.lang import impl

    from .physics.stage import FUSED_COMPILED
    return sorted({f"{k.func.__module__}.{k.func.__qualname__}"
                   for k in impl.get_runtime().kernels if k.compiled_kernels and
                   k.func.__module__.startswith("taichi_granular")} | FUSED_COMPILED)
