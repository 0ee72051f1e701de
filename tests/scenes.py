"""Small scenes for tests, built as plain dicts (what a YAML file would hold)."""
import copy

from taichi_granular.config import scene_from_dict

GLASS_BEADS = {  # Table 1/2 of [M]
    "model": "mu_i", "grain_density": 800.0, "grain_diameter": 0.5e-3, "static_friction_deg": 20.90,
    "limit_friction_deg": 32.76, "reference_inertial_number": 0.279, "solid_fraction_max": 0.6,
    "solid_fraction_min": 0.5, "grain_compressibility": 1.5e-5, "max_yield_stress": 190.0,
    "regularisation_time": 1.0,
}
SAND = {"model": "elastoplastic", "density": 2600.0, "youngs_modulus": 5.0e6, "poisson_ratio": 0.3,
        "friction_angle_deg": 30.0}  # the elastoplastic tests' sand ([A]'s, E lowered for the CPU)
HYPOPLASTIC_SAND = {"model": "hypoplastic", "parameter_set": "set2", "grain_density": 2650.0,
                    "grain_diameter": 2e-3, "initial_void_ratio": 0.897}  # [P] set 2, at its stationary I_e


def elastoplastic_numerics(dp, **extra):
    """The numerics of [A] for small elastoplastic scenes, with ``extra`` keys changed."""
    data = {"particle_spacing": dp, "smoothing_length_ratio": 1.2, "smoothing_function": "cubic_spline",
            "integrator": "predictor_corrector", "gradient_correction": "none", "cfl": 0.3,
            "artificial_viscosity": {"alpha": 1.0, "beta": 1.0}, "density_diffusion": 0.1,
            "stress_diffusion": 0.1, "particle_shifting": {"coefficient": 0.0}}
    data.update(extra)
    return data


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
        x = sim.state.material("position")
        lowest, rightmost = min(lowest, x[:, 1].min()), max(rightmost, x[:, 0].max())
    return float(lowest), float(rightmost)
