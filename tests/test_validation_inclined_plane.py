"""The inclined-plane metric itself: exact frames score zero, perturbed frames score their error."""
import math

import numpy as np
import pytest

from scenes import build, layer
from taichi_granular.validation import inclined_plane as ip


def synthetic_frames(scene, scale_velocity=1.0, scale_pressure=1.0, n_frames=5):
    material = scene.material
    slope = math.radians(scene.gravity.tilt_deg)
    dp = scene.numerics.particle_spacing
    phi_u = ip.steady_solid_fraction(material, slope)
    length = scene.domain.size[0]
    rows, cols = 20, int(round(length / dp))
    mass = phi_u * material.grain_density * dp * dp
    height = ip.steady_height(mass * rows * cols / length, material, slope, 9.81)
    z = (np.arange(rows) + 0.5) * height / rows
    x = (np.arange(cols) + 0.5) * dp
    X, Z = np.meshgrid(x, z)
    pos = np.stack([X.ravel(), Z.ravel()], axis=1)
    n = len(pos)
    vel = np.zeros((n, 2))
    vel[:, 0] = scale_velocity * ip.analytic_velocity(pos[:, 1], height, material, slope, 9.81)
    frame = {"position": pos, "velocity": vel, "mass": np.full(n, mass), "is_wall": np.zeros(n, int),
             "pressure": scale_pressure * ip.analytic_pressure(pos[:, 1], height, material, slope, 9.81),
             "solid_fraction": np.full(n, phi_u)}
    return [0.1 * k for k in range(n_frames)], [frame] * n_frames


@pytest.fixture(scope="module")
def scene():
    return build(layer(height=0.1, length=0.2, tilt_deg=25.0))


def test_analytic_frames_score_zero(scene):
    times, frames = synthetic_frames(scene)
    result = ip.evaluate(scene, times, frames, window=1.0)
    assert result.velocity_error < 1e-3 and result.pressure_error < 1e-3
    assert result.surface_velocity_reference == pytest.approx(12.8, abs=0.3)  # MODEL.md: about 12.8 m/s
    assert result.drift < 1e-12


def test_perturbed_frames_score_their_error(scene):
    times, frames = synthetic_frames(scene, scale_velocity=1.1, scale_pressure=0.95)
    result = ip.evaluate(scene, times, frames, window=1.0)
    assert result.velocity_error == pytest.approx(0.10, abs=0.005)
    assert result.pressure_error == pytest.approx(0.05, abs=0.003)


def test_steady_inertial_number_and_range(scene):
    material = scene.material
    assert ip.steady_inertial_number(material, math.radians(25.0)) == pytest.approx(0.1330, abs=2e-4)
    with pytest.raises(ValueError, match="outside the steady range"):
        ip.steady_inertial_number(material, math.radians(35.0))
