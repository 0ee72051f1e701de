"""Hard cases of every model at small size: grains at zero pressure and zero strain rate keep
finite fields; a fast stream (5 m/s) thrown at a floor and a side wall loses no grain through
either (the elastoplastic impact on dynamic boundaries is tests/test_elastoplastic.py)."""
import numpy as np
import pytest

from cases import MODELS, settled_layer_data
from scenes import build, lowest_and_rightmost
from taichi_granular.simulation import Simulation


@pytest.mark.parametrize("model", MODELS)
def test_grains_at_zero_pressure_and_zero_strain_rate_keep_finite_fields(model):
    """No gravity, no initial stress, at rest: every grain is where the constitutive laws divide
    by pressure or strain rate (mu(I)'s viscosity and inertial number, the hypoplastic law's
    tr T_s, the Mohr-Coulomb yield scaling). 50 steps: every field stays finite and nothing
    starts to move (measured: at most 5e-5 m/s, the free surface of the lattice settling)."""
    data = settled_layer_data(model, height=0.03, length=0.04)
    data["gravity"] = {"magnitude": 0.0}
    data["particles"][0]["initial_stress"] = "zero"
    data["run"]["end_time"] = 100.0
    sim = Simulation(build(data))
    sim.run(max_steps=50)
    arrays = sim.scheme.snapshot()
    n = sim.state.n_material
    for name, value in arrays.items():
        if np.issubdtype(value.dtype, np.floating):
            assert np.all(np.isfinite(value)), name
    for name in {"viscosity", "inertial_number", "frictional_stress", "deviatoric_stress"} & set(arrays):
        assert np.all(np.isfinite(arrays[name])), name
    assert np.abs(arrays["velocity"][:n]).max() < 1e-3


@pytest.mark.parametrize("model", ["mu_i", "hypoplastic"])
def test_a_fast_stream_loses_no_grain_through_floor_or_side_wall(model):
    """A 2 x 2 cm block thrown at 5 m/s down and 2.5 m/s sideways onto the floor and a side wall
    2 cm ahead of it, 0.03 s: no grain below the floor or beyond the side wall at any output,
    everything finite, the walls turned the block back (mean downward speed below 1 m/s)."""
    data = settled_layer_data(model, height=0.02, length=0.02)
    data["domain"] = {"lower": [-0.1, -0.02], "upper": [0.07, 0.08]}  # room for the splash back
    data["particles"][0].update(lower=[0.0, 0.01], upper=[0.02, 0.03], velocity=[2.5, -5.0], initial_stress="zero")
    side = {**data["walls"][0], "name": "side", "point": [0.04, 0.0], "normal": [-1.0, 0.0],
            "lower": [0.0, -0.02], "upper": [0.07, 0.08]}
    data["walls"][0].update(lower=[-0.1, -0.02], upper=[0.07, 0.08])
    data["walls"].append(side)
    data["run"] = {"end_time": 0.03, "output_interval": 0.001}
    sim = Simulation(build(data))
    lowest, rightmost = lowest_and_rightmost(sim, 0.03)
    v = sim.state.velocity.to_numpy()[:sim.state.n_material]
    assert lowest > 0.0 and rightmost < 0.04, (lowest, rightmost)
    assert np.all(np.isfinite(v)) and v[:, 1].mean() > -1.0, v[:, 1].mean()
