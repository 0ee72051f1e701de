"""Flows of the hypoplastic + Bagnold model (MODEL.md section 2): the inclined plane's analytic
reference, and a reduced inclined plane held on it only with the numerical bulk viscosity."""
import math

import numpy as np
import pytest

from scenes import HYPOPLASTIC_SAND, build, layer
from taichi_granular.validation import inclined_plane as ip



def plane(bulk_viscosity, height=0.012, tilt_deg=28.0, end_time=0.1):
    """The inclined plane of configs/hypoplastic/ reduced to 6 rows x 10 columns (dp 2 mm)."""
    data = layer(height=height, length=0.02, dp=0.002, tilt_deg=tilt_deg, material=HYPOPLASTIC_SAND,
                 end_time=end_time, smoothing="wendland_c6", integrator="predictor_corrector")
    data["walls"][0]["type"] = "extrapolated"
    data["numerics"].update(cfl=0.3, gradient_correction="matrix", bulk_viscosity=bulk_viscosity)
    return build(data)


@pytest.fixture(scope="module")
def reference():
    return ip.reference_for(plane(0.5))


def test_bagnold_reference_bounds_and_scale(reference):
    """mu_h of set 2 is 0.494 (MODEL.md; measured 0.4942), so steady flow lies between 26.3 and
    33 deg; A^2 follows MODEL.md's formula at the initial bulk density."""
    low, high = reference.bounding_angles_deg
    assert reference.friction == pytest.approx(0.494, abs=0.001)
    assert low == pytest.approx(math.degrees(math.atan(0.494)), abs=0.05) and high == 33.0
    rho, theta, alpha = 2650.0 / 1.897, math.radians(28.0), math.radians(33.0)
    mu = reference.friction
    A2 = rho * 9.81 * (math.sin(theta) - mu * math.cos(theta)) / (
        0.1 * 2650.0 * 2e-3**2 * (math.sin(alpha) - mu * math.cos(alpha)))
    assert reference.shear_rate_scale() == pytest.approx(math.sqrt(A2), rel=1e-12)
    with pytest.raises(ValueError, match="outside the steady range"):
        reference.shear_rate_scale(math.radians(25.0))
    with pytest.raises(ValueError, match="outside the steady range"):
        reference.shear_rate_scale(math.radians(34.0))


def synthetic_frames(reference, scale_velocity=1.0, scale_stress=1.0, rows=10, cols=10, dp=0.002):
    height = rows * dp
    z = (np.arange(rows) + 0.5) * dp
    x = (np.arange(cols) + 0.5) * dp
    X, Z = np.meshgrid(x, z)
    pos = np.stack([X.ravel(), Z.ravel()], axis=1)
    n = len(pos)
    vel = np.zeros((n, 2))
    vel[:, 0] = scale_velocity * reference.velocity(pos[:, 1], height)
    s_yy = 40.0  # Pa: the normal stress read is p - s_yy
    deviatoric = np.zeros((n, 4))
    deviatoric[:, 3] = s_yy
    frame = {"position": pos, "velocity": vel, "mass": np.full(n, reference.density * dp * dp),
             "density": np.full(n, reference.density), "is_wall": np.zeros(n, int),
             "pressure": scale_stress * reference.normal_stress(pos[:, 1], height) + s_yy,
             "deviatoric_stress": deviatoric}
    return [0.0, 0.05, 0.1], [frame] * 3


def test_bagnold_frames_score_zero_and_perturbed_frames_their_error(reference):
    scene = plane(0.5)
    times, frames = synthetic_frames(reference)
    exact = ip.evaluate(scene, times, frames, window=0.1)
    assert exact.velocity_error < 1e-3 and exact.pressure_error < 1e-3 and exact.reference == reference.name
    times, frames = synthetic_frames(reference, scale_velocity=1.1, scale_stress=0.9)
    off = ip.evaluate(scene, times, frames, window=0.1)
    assert off.velocity_error == pytest.approx(0.10, abs=0.005)
    assert off.pressure_error == pytest.approx(0.10, abs=0.01)
    faster = dict(frames[0], velocity=frames[0]["velocity"] + np.array([0.05, 0.0]))
    n = len(frames[0]["mass"])
    assert ip.layer_acceleration([0.0, 0.1, 0.2], [frames[0], faster, frames[0]], n) == pytest.approx(0.0, abs=1e-9)
    assert ip.layer_acceleration([0.0, 0.1], [frames[0], faster], n) == pytest.approx(0.5, rel=1e-9)


def _flow(bulk_viscosity):
    scene = plane(bulk_viscosity)
    times, frames, _ = ip.run_in_memory(scene, 0.1, 0.01, ip.impose_analytic_velocity)
    n = int(np.sum(frames[0]["is_wall"] == 0))
    density_factor = np.array([f["density_factor"][:n].mean() for f in frames[1:]])
    return ip.evaluate(scene, times, frames, window=0.05), density_factor


def test_reduced_plane_holds_the_bagnold_profile_and_the_bulk_viscosity_holds_its_void_ratio(reference):
    """From the analytic profile (28 deg, 12 mm, d 2 mm, surface speed 1.55 m/s), 0.1 s: with
    alpha_b = 0.5 the layer's mean I_e stays at the stationary 0.913 (measured 0.9116-0.9132)
    and the velocity profile within 5 % of the Bagnold-type solution (measured 1.0 %); without
    it the void ratio and T_s oscillate (measured: mean I_e 0.907-0.938, T_s swinging twenty-fold;
    before the residual damping of physics/momentum.py and the direction-keeping tension guard
    this layer blew up)."""
    damped, factor = _flow(0.5)
    assert np.abs(factor - reference.density_factor).max() < 0.005, factor
    assert damped.velocity_error < 0.05, damped.report()
    assert damped.drift < 0.02, damped.report()
    assert abs(damped.height / damped.mass_height - 1.0) < 0.02, damped.report()
    _, factor = _flow(0.0)
    assert np.abs(factor - reference.density_factor).max() > 0.015, factor


def test_bulk_viscosity_is_for_the_hypoplastic_model_only():
    from taichi_granular.config import ConfigError
    data = layer(end_time=0.1)
    data["numerics"]["bulk_viscosity"] = 0.5
    with pytest.raises(ConfigError) as err:
        build(data)
    assert err.value.path == "numerics.bulk_viscosity"
    data = layer(material=HYPOPLASTIC_SAND, end_time=0.1)
    data["walls"][0]["type"] = "extrapolated"
    data["numerics"]["bulk_viscosity"] = -0.1
    with pytest.raises(ConfigError) as err:
        build(data)
    assert err.value.path == "numerics.bulk_viscosity"


def test_coarse_pile_collapses_to_rest_with_no_grain_thrown_out():
    """The pile collapse of configs/hypoplastic/ at dp 8.8 mm (22 x 6 grains), 0.8 s: it spreads
    (measured: front 0.097 -> 0.193 m), comes to rest (0.75 s) and loses no grain; its run-out is
    +47 % of Lube's (not asserted: the full-size scene's +92 % is an open problem). Before the
    Bagnold stress was left out on the free surface, grains of the flanks were shot out at
    4.5-5.5 m/s (the full-size scene: at 0.23-0.38 s)."""
    from scenes import run_frames
    from taichi_granular.config import load_scene
    from taichi_granular.paths import config_path
    from taichi_granular.validation import column_collapse as cc

    scene = load_scene(config_path("hypoplastic/collapse_a0_55.yaml"),
                       ["numerics.particle_spacing=0.0088", "run.end_time=0.8", "run.output_interval=0.05"])
    times, frames, diagnostics = run_frames(scene, 0.05)
    result = cc.evaluate(scene, times, frames, diagnostics, read_at_end=True)
    assert result.escaped == 0, result.row()
    assert result.fronts[-1].front_mean > 1.3 * result.fronts[0].front_mean, result.row()  # it spread
    assert result.time_to_rest is not None, result.row()
    peak = max(d["kinetic_energy"] for d in diagnostics)
    assert diagnostics[-1]["kinetic_energy"] < 1e-2 * peak, result.row()
    assert max(d["max_speed"] for d in diagnostics) < 1.5, result.row()  # free fall from H0 is 1.0 m/s


def test_hypoplastic_pile_stops_at_box_obstacles():
    """Obstacles other than the drum are extrapolated wall particles too (docs/models/hypoplastic.md):
    the a = 0.55 pile collapses against two boxes 1.8 cm beyond its feet. Measured to 0.5 s with
    boxes at +-0.14 m: the fronts stop 1.3 mm (0.3 dp) inside the boxes' nominal faces, outside
    their first row of wall particles (dp/2 in), and stay. Here, closer boxes, to 0.15 s: the front
    reaches them and no grain gets more than dp/2 into a box or past it."""
    import numpy as np

    from taichi_granular.config import load_scene
    from taichi_granular.paths import config_path
    from taichi_granular.simulation import Simulation

    face, dp = 0.115, 0.0044
    scene = load_scene(config_path("hypoplastic/collapse_a0_55.yaml"), [
        f"obstacles=[{{shape: box, lower: [{face}, 0.0], upper: [{face + 0.03}, 0.05]}}, "
        f"{{shape: box, lower: [{-face - 0.03}, 0.0], upper: [{-face}, 0.05]}}]", "run.end_time=0.15"])
    sim = Simulation(scene)
    sim.run(end_time=0.0)
    front = 0.0
    while sim.t < scene.run.end_time - 1e-12:
        sim.run(end_time=min(scene.run.end_time, sim.t + 0.01))
        reach = np.abs(sim.state.material("position")[:, 0]).max()
        assert reach < face + 0.5 * dp, f"a grain {reach - face:.4f} m into a box at t = {sim.t:.2f} s"
        front = max(front, reach)
    assert front > face - dp, f"the front stopped at {front:.3f} m, short of the boxes"
