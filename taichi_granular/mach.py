"""The Mach number of a weakly compressible flow: what to expect, and what to do when it is high.

All three models are weakly compressible: a flow must stay well below the model's sound speed
c, or its density field (and so its pressure) carries the spurious compression of a flow near
Mach 1. Measured on a mu(I) incline at 28 deg with [M]'s grain compressibility: once max |v|/c
passed ~1 the flow cycled (accelerated, density error 1 % -> 7-10 %, time step 5x smaller,
kinetic energy halved) instead of reaching its steady state.

The Mach number is max |v| / c_0, c_0 the model's reference sound speed: the speed of the waves
of compression (mu(I): (K_t phi_max rho_s0)^(-1/2) [M41]; elastoplastic: sqrt(K/rho_0) [A5];
hypoplastic: material.wave_speed [P]).

``speed_scale`` estimates a scene's flow speed before it runs (``describe``); ``advice`` turns a
Mach number into the value of the model's compressibility key that brings it to
MACH_TARGET x the warning threshold, the speed taken as the larger of the one measured and the
scene's speed scale (a flow that is still accelerating has not reached its speed yet).

Two numerical terms scale with the sound speed, so stiffer grains alone would also change them:
particle shifting moves particles at zeta h c |grad C| (physics/shifting.py) and the density
diffusion exchanges density at delta h c_0 (physics/continuity.py). The advice therefore divides
numerics.particle_shifting.coefficient and numerics.density_diffusion by the same factor, so
that the change of compressibility changes nothing else. Measured on the Table 2 plane with K_t
20x stiffer (c 4.5x faster): with zeta left at 0.2 the layer never settled (37.6 % above [M56]
at 55-60 s, still accelerating); with zeta / 4.5 but delta left at 0.02 it swelled by 8 % within
10 s and kept accelerating through [M56] (velocity error 1.4 % at 15-20 s, 4.8 % at 25-30 s);
with delta / 4.5 as well it swells as slowly as with Table 2's K_t and meets [M56] (docs,
inclined plane).
"""
from __future__ import annotations

import math
from typing import Optional, Tuple

from .config import Scene

MACH_TARGET = 0.8  # the advice aims at this fraction of run.mach_warning (margin for gusts)


def speed_scale(scene: Scene) -> Optional[Tuple[float, str]]:
    """(expected flow speed [m/s], where it comes from), or None where no scale is known:

    - the speed the material's model predicts for the scene (``speed_scale``: a mu(I) layer
      periodic along a slope in the steady range, the [M56] surface speed);
    - otherwise the fastest of free fall from the top of the material to the bottom of the
      domain sqrt(2 g H), the blocks' initial velocities and a drum's rim speed |omega| R.
    """
    predicted = scene.material.speed_scale(scene)
    if predicted is not None:
        return predicted
    dim = scene.dimension
    g = scene.gravity.magnitude
    candidates = []
    if g > 0.0:
        top = max(max(c[dim - 1] for c in b.corners()) for b in scene.particles)
        drop = top - scene.domain.lower[dim - 1]
        candidates.append((math.sqrt(2.0 * g * drop), f"free fall over {drop:.3g} m"))
    for block in scene.particles:
        if block.velocity is not None:
            candidates.append((math.hypot(*block.velocity), f"initial velocity of block '{block.name}'"))
    for obstacle in scene.obstacles:
        if obstacle.shape == "drum":
            candidates.append((abs(obstacle.angular_velocity) * obstacle.radius, f"rim speed of '{obstacle.name}'"))
    return max(candidates) if candidates else None


def advice(scene: Scene, model, mach: float, speed: float, measured: bool = True) -> str:
    """What to set so that a flow of max Mach ``mach`` at max speed ``speed`` [m/s] (or at the
    scene's speed scale, if faster) stays below MACH_TARGET x run.mach_warning."""
    threshold = scene.run.mach_warning
    scale = speed_scale(scene)
    factor = mach / (MACH_TARGET * threshold)  # how much faster the sound must be
    basis = f"the {speed:.3g} m/s {'reached' if measured else 'expected'}"
    if scale is not None and speed > 0.0 and scale[0] > speed:
        factor *= scale[0] / speed
        basis = f"{scale[0]:.3g} m/s, the {scale[1]}"
    remedy = list(model.faster_sound(factor))
    shifting = scene.numerics.particle_shifting
    if shifting.enabled:  # keep the shift's rate zeta c (module docstring)
        remedy.append(("numerics.particle_shifting.coefficient", shifting.coefficient / factor))
    if scene.numerics.density_diffusion > 0.0:  # and the density diffusion's delta c_0
        remedy.append(("numerics.density_diffusion", scene.numerics.density_diffusion / factor))
    settings = ", ".join(f"{key}: {value:.3g}" for key, value in remedy)
    return f"set {settings} (sound {factor:.3g}x faster: Mach {MACH_TARGET * threshold:.2g} at {basis})"


def describe_lines(scene: Scene, model) -> list:
    """``describe``'s lines on the Mach number the scene should expect."""
    c = model.reference_sound_speed()
    scale = speed_scale(scene)
    if scale is None:
        return [f"sound speed: {c:.3g} m/s; no speed scale known for this scene"]
    speed, source = scale
    mach = speed / c
    lines = [f"sound speed: {c:.3g} m/s; expected speed {speed:.3g} m/s ({source}): Mach {mach:.2f}"]
    if mach > scene.run.mach_warning:
        lines.append(f"  warning: above run.mach_warning = {scene.run.mach_warning:g}; "
                     + advice(scene, model, mach, speed, measured=False))
    return lines
