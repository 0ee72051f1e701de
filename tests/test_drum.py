"""The drum measures (validation/drum.py) on a synthetic frame with a known answer."""
import math

import numpy as np
import pytest

from taichi_granular.config import load_scene
from taichi_granular.paths import config_path
from taichi_granular.validation import drum


def synthetic_frames(theta_deg=22.4, delta=0.054, surface_speed=0.3, omega=1.0, radius=0.1442, dp=0.005):
    """A half-filled drum whose surface through the centre rises at theta to the right (the side a
    counter-clockwise drum lifts); below depth delta the bed turns rigidly, above it the grains flow
    downhill at surface_speed (1 - z/delta)."""
    g = np.arange(-radius, radius, dp) + 0.5 * dp
    x = np.array(np.meshgrid(g, g)).reshape(2, -1).T
    x = x[np.hypot(x[:, 0], x[:, 1]) < radius - 0.5 * dp]
    t = math.radians(theta_deg)
    tangent, normal = np.array([math.cos(t), math.sin(t)]), np.array([-math.sin(t), math.cos(t)])
    depth = -(x @ normal)
    x = x[depth > 0]
    depth = depth[depth > 0]
    v = omega * np.c_[-x[:, 1], x[:, 0]]
    flowing = depth < delta
    v[flowing] = (-tangent)[None] * (surface_speed * (1 - depth[flowing] / delta))[:, None]
    frame = {"position": x, "velocity": v, "is_wall": np.zeros(len(x), int)}
    return [0.0, 1.0], [frame, frame]


def test_drum_measures_recover_a_known_surface_layer_and_rigid_bed():
    scene = load_scene(config_path("hypoplastic/drum_omega1.yaml"))
    times, frames = synthetic_frames()
    r = drum.evaluate_drum(scene, times, frames)
    assert r.inclination_deg == pytest.approx(22.4, abs=0.3)
    assert r.flowing_depth == pytest.approx(0.054, abs=0.005)  # within a depth bin
    assert r.flux == pytest.approx(0.5 * 0.3 * 0.054, rel=0.15)  # the triangle under u(z)
    assert r.bed_departure < 0.02


def test_drum_measures_see_a_bed_that_does_not_turn_rigidly():
    scene = load_scene(config_path("hypoplastic/drum_omega1.yaml"))
    times, frames = synthetic_frames()
    for f in frames:
        f["velocity"] = f["velocity"] * np.where(np.hypot(*f["position"].T) > 0.1, 0.5, 1.0)[:, None]
    assert drum.evaluate_drum(scene, times, frames).bed_departure > 0.1
