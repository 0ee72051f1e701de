"""The toy Newtonian model (physics/rheology/newtonian/): a fourth model added as one package and
one registry line (docs/design.md) runs a scene end to end and matches the analytic solution."""
import numpy as np

from scenes import build, layer

FLUID = {"model": "newtonian", "density": 1000.0, "viscosity": 10.0, "sound_speed": 5.0}


def poiseuille(dp=0.005, height=0.05, end_time=0.25):
    """Plane Poiseuille flow: the fluid between no-slip ghost plates at y = 0 and y = H, driven
    along the periodic x axis by gravity tilted 30 deg (g_x = g/2)."""
    data = layer(height=height, length=0.04, dp=dp, tilt_deg=30.0, material=FLUID, end_time=end_time,
                 name="poiseuille")
    data["gravity"]["magnitude"] = 1.0
    data["domain"]["upper"][1] = height + 0.02
    data["walls"].append({"name": "lid", "type": "ghost", "point": [0.0, height], "normal": [0.0, -1.0]})
    return build(data)


def test_newtonian_poiseuille_profile():
    """u(y) = rho g_x y (H - y)/(2 eta) at steady state: the SPH profile within 3 % of its peak
    (the diffusion time rho H^2/(pi^2 eta) is 0.025 s: 0.25 s is ten of them)."""
    from taichi_granular.simulation import Simulation

    scene = poiseuille()
    sim = Simulation(scene)
    sim.run(end_time=scene.run.end_time)
    x = sim.state.material("position")
    u = sim.state.material("velocity")[:, 0]
    fluid = scene.material
    g_x = scene.gravity_vector[0]
    H = 0.05
    exact = fluid.density * g_x * x[:, 1] * (H - x[:, 1]) / (2.0 * fluid.viscosity)
    error = np.abs(u - exact).max() / exact.max()
    print(f"Poiseuille: max error {error:.2%} of the peak {exact.max():.4g} m/s")
    assert error < 0.03, f"Poiseuille profile off by {error:.1%} of its peak"
    assert np.abs(sim.state.material("velocity")[:, 1]).max() < 0.01 * exact.max()
