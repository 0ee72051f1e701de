"""Small scenes for tests, built as plain dicts (what a YAML file would hold)."""
import copy

from taichi_granular.config import scene_from_dict

GLASS_BEADS = {  # Table 1/2 of [M]
    "model": "mu_i", "grain_density": 800.0, "grain_diameter": 0.5e-3, "static_friction_deg": 20.90,
    "limit_friction_deg": 32.76, "reference_inertial_number": 0.279, "solid_fraction_max": 0.6,
    "solid_fraction_min": 0.5, "grain_compressibility": 1.5e-5, "max_yield_stress": 190.0,
    "regularisation_time": 1.0,
}


def layer(height=0.05, length=0.1, dp=0.005, tilt_deg=0.0, material=None, alpha=0.0, end_time=1.0,
          smoothing="wendland_c2", integrator="symplectic_verlet", name="layer"):
    """A layer of ``height`` on a no-slip ghost wall at y = 0, periodic along x."""
    data = {
        "name": name, "dimension": 2, "precision": "f64",
        "domain": {"lower": [0.0, -0.02], "upper": [length, 3 * height], "periodic": ["x"]},
        "gravity": {"magnitude": 9.81, "tilt_deg": tilt_deg},
        "material": copy.deepcopy(material or GLASS_BEADS),
        "particles": [{"name": "layer", "lower": [0.0, 0.0], "upper": [length, height]}],
        "walls": [{"name": "base", "type": "ghost", "point": [0.0, 0.0], "normal": [0.0, 1.0]}],
        "numerics": {"particle_spacing": dp, "smoothing_function": smoothing, "integrator": integrator,
                     "artificial_viscosity": {"alpha": alpha, "beta": 0.0}},
        "run": {"end_time": end_time, "output_interval": end_time},
    }
    return data


def build(data):
    return scene_from_dict(data, name=data.get("name", "test"))


def run_frames(scene, interval):
    """Run ``scene`` to its end time; return (times, frames, diagnostics) as the validation
    measures read them from a run's output (validation.inclined_plane.run_in_memory)."""
    from taichi_granular.validation.inclined_plane import run_in_memory

    return run_in_memory(scene, scene.run.end_time, interval)


def lowest_and_rightmost(sim, end_time, interval=0.001):
    """Run ``sim`` to ``end_time``; the lowest y and the largest x any material particle
    reached, checked every ``interval`` seconds (walls below y = 0 and beyond some x must
    keep them above and left)  [m]."""
    import numpy as np

    n = sim.state.n_material
    lowest, rightmost = np.inf, -np.inf
    sim.run(end_time=0.0)
    while sim.t < end_time - 1e-12:
        sim.run(end_time=min(end_time, sim.t + interval))
        x = sim.state.position.to_numpy()[:n]
        lowest, rightmost = min(lowest, x[:, 1].min()), max(rightmost, x[:, 0].max())
    return float(lowest), float(rightmost)
