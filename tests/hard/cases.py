"""Small hard cases of the stability suite, one builder per case, every model (issue: stability)."""
import numpy as np

from scenes import HYPOPLASTIC_SAND, SAND, build, elastoplastic_numerics, layer

G = 9.81
HYPOPLASTIC = {**HYPOPLASTIC_SAND, "grain_diameter": 1e-3, "initial_void_ratio": 0.75}  # dense: I_e ~ 0.77 at rest
MODELS = ("mu_i", "hypoplastic", "elastoplastic")


def settled_layer_data(model: str, height=0.05, length=0.04, dp=0.005):
    """A layer of ``height`` at rest on a wall of the model's own kind, periodic along x: the
    mu(I) layer of tests/scenes.py on ghost walls, the hypoplastic one of [P] (set 2, Wendland
    C6, matrix correction, predictor-corrector, extrapolated wall), the elastoplastic one of [A]
    (dynamic boundary particles and the numerics of tests/test_elastoplastic.py, plus the scalar
    gradient correction: without it the cubic spline's gradient deficit at h/dp = 1.2 leaves the
    bottom row's vertical stress 4.3 % of the column weight above the overburden, measured)."""
    if model == "mu_i":
        return layer(height=height, length=length, dp=dp)
    if model == "hypoplastic":
        data = layer(height=height, length=length, dp=dp, material=HYPOPLASTIC, smoothing="wendland_c6",
                     integrator="predictor_corrector")
        data["walls"][0]["type"] = "extrapolated"
        data["numerics"].update(cfl=0.3, gradient_correction="matrix")
        return data
    data = layer(height=height, length=length, dp=dp, material=SAND)
    data["walls"][0].update(type="dynamic", initial_pressure="overburden")  # at rest from t = 0
    data["numerics"] = elastoplastic_numerics(dp, gradient_correction="scalar")
    return data


def vertical_stress(sim) -> np.ndarray:
    """-sigma_yy of every material particle, compression positive  [Pa]."""
    s = sim.state
    if s.has("frictional_stress"):  # hypoplastic, tension positive
        return -s.material("frictional_stress")[:, 1, 1]
    p = s.material("pressure")
    if s.has("deviatoric_stress"):
        return p - s.material("deviatoric_stress")[:, 1, 1]
    return p  # mu(I): no stress tensor; at rest its deviatoric stress vanishes


def nearest_distance(x: np.ndarray, period: float) -> float:
    """Smallest distance between two particles, periodic along x  [m]."""
    d = x[:, None, :] - x[None, :, :]
    d[..., 0] -= period * np.round(d[..., 0] / period)
    r = np.sqrt((d**2).sum(-1))
    np.fill_diagonal(r, np.inf)
    return float(r.min())


def tall_column_data(model: str, aspect_ratio: float, half_width=0.02, dp=0.005, end_time=1.0):
    """A 2D column of half-width ``half_width`` and height ``aspect_ratio`` x ``half_width``
    released in the middle of a floor of the model's wall kind (no side walls, the domain wide
    enough for any run-out), run until at rest (kinetic energy below 1e-3 of its peak) or
    ``end_time``."""
    height = aspect_ratio * half_width
    data = settled_layer_data(model, height=height, length=2 * half_width, dp=dp)
    reach = 0.4 + height
    data["domain"] = {"lower": [-reach, -0.03], "upper": [reach, height + 0.05]}
    data["particles"][0].update(lower=[-half_width, 0.0], upper=[half_width, height])
    data["walls"][0].update(lower=[-reach, -0.03], upper=[reach, height + 0.05])
    data["run"] = {"end_time": end_time, "output_interval": 0.02, "stop_at_rest": 1e-3}
    if model == "hypoplastic":  # the numerics of the pile collapse (configs/hypoplastic/collapse_a0_55.yaml)
        data["material"]["initial_void_ratio"] = 0.897
        data["numerics"].update(artificial_viscosity={"alpha": 0.1, "beta": 0.0}, bulk_viscosity=0.5,
                                stress_increment=1.0)
    return data
