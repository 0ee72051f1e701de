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
    """Run ``scene`` to its end time; return (times, frames, diagnostics): a snapshot of every
    particle field (with ``is_wall``) every ``interval`` seconds, and the diagnostics row of each
    stretch between them -- what the validation measures read from a run's output."""
    import numpy as np

    from taichi_granular.simulation import Simulation

    sim = Simulation(scene)
    end = scene.run.end_time
    is_wall = np.r_[np.zeros(sim.state.n_material, int), np.ones(sim.state.n_wall, int)]
    times, frames, diagnostics = [], [], []
    sim.run(end_time=0.0)  # initial rates and equation of state, no step
    while True:
        times.append(sim.t)
        frames.append({**sim.scheme.snapshot(), "is_wall": is_wall})
        if sim.t >= end - 1e-9:
            break
        sim.run(end_time=min(end, sim.t + interval))
        diagnostics.append(sim.last_diagnostics)
    return times, frames, diagnostics
