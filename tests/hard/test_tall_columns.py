"""Tall columns (a = 3 and 6, outside the dense regime of the collapse validations) of every
model run to rest with no NaN and no grain through the floor or out of the domain (the run-time
guard stops a run at the first NaN or escaped grain; the test checks the state as well). The
hypoplastic a = 6 column does not yet: it is marked as a known failure (strict, so its fixing
shows up)."""
import numpy as np
import pytest

from cases import MODELS, tall_column_data
from scenes import build
from taichi_granular.simulation import Simulation, SimulationError


EJECTS = pytest.mark.xfail(
    strict=True, raises=SimulationError,
    reason="known defect: the hypoplastic a = 6 column throws a grain out of its top at 5.4 m/s at 0.11 s "
           "(with the pile collapse's numerics; with none of them the a = 3 column does so at 0.07 s)")
CASES = [(m, a) for m in MODELS for a in (3.0, 6.0) if (m, a) != ("hypoplastic", 6.0)] + \
    [pytest.param("hypoplastic", 6.0, marks=EJECTS)]


@pytest.mark.parametrize("model, aspect_ratio", CASES)
def test_tall_column_runs_to_rest_without_nan_or_escape(model, aspect_ratio):
    """Measured (half-width 2 cm, dp 5 mm, 96 / 192 grains; time to rest, spread): mu(I) a = 3
    0.26 s, 0.18 m; a = 6 0.34 s, 0.29 m; hypoplastic a = 3 0.58 s, 0.47 m; elastoplastic a = 3
    0.38 s, 0.21 m; a = 6 0.52 s, 0.42 m."""
    sim = Simulation(build(tall_column_data(model, aspect_ratio)))
    n = sim.state.n_material
    sim.run()
    x = sim.state.position.to_numpy()[:n]
    assert np.all(np.isfinite(x)) and np.all(np.isfinite(sim.state.velocity.to_numpy()[:n]))
    assert x[:, 1].min() > 0.0
    assert sim.at_rest(), (sim.t, sim.last_diagnostics)
    assert np.ptp(x[:, 0]) > 2 * 0.04  # it collapsed and spread beyond its own width
