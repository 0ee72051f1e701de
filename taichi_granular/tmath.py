"""Small numerical helpers for Taichi functions that the language does not provide."""
import taichi as ti


@ti.func
def expm1(x):
    """exp(x) - 1 without cancellation for small |x| (Taylor series below 1e-2)."""
    result = 0.0
    if ti.abs(x) < 1e-2:
        result = x * (1.0 + x * (0.5 + x * (1.0 / 6.0 + x * (1.0 / 24.0 + x * (1.0 / 120.0 + x / 720.0)))))
    else:
        result = ti.exp(x) - 1.0
    return result
