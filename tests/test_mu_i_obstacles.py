"""mu(I) with obstacles (issue 28: every model with every geometry): a chute and solid boxes laid
as dynamic boundary particles, whose pressure is the grain EOS at rest (physics/rheology/mu_i),
alone or beside [M]'s ghost walls (physics/walls/mixed.py)."""
import copy

import numpy as np
import pytest

from scenes import GLASS_BEADS, build

DP = 0.005
BLOCK = (0.15, 0.18, 0.10)  # the obstacle box: x from, x to, height  [m]


def chute_with_box(end_time=0.2, floor="chute", **numerics):
    """A 6 cm column of glass beads on a horizontal bed under gravity tilted 30 deg towards +x,
    a back wall at x = 0 and a box 10 cm high standing on the bed 9 cm downstream. The bed is a
    chute obstacle (dynamic boundary particles) or, ``floor="ghost"``, a ghost wall of [M]."""
    bed = {"name": "bed", "shape": "chute", "origin": [0.0, 0.0], "segments": [{"length": 0.3, "slope_deg": 0.0}]}
    ghost = {"name": "floor", "type": "ghost", "point": [0.0, 0.0], "normal": [0.0, 1.0]}
    return build({
        "name": "mu_i_chute_box", "dimension": 2,
        "domain": {"lower": [-0.04, -0.03], "upper": [0.34, 0.16]},
        "gravity": {"magnitude": 9.81, "tilt_deg": 30.0},
        "material": copy.deepcopy(GLASS_BEADS),
        "particles": [{"name": "column", "lower": [0.0, 0.0], "upper": [0.06, 0.06]}],
        "walls": [ghost] if floor == "ghost" else [],
        "obstacles": ([bed] if floor == "chute" else []) + [
            {"name": "back", "shape": "box", "lower": [-0.03, -0.02], "upper": [0.0, 0.12]},
            {"name": "block", "shape": "box", "lower": [BLOCK[0], 0.0], "upper": [BLOCK[1], BLOCK[2]]},
        ],
        "numerics": {"particle_spacing": DP, **numerics},
        "run": {"end_time": end_time, "output_interval": end_time},
    })


@pytest.mark.parametrize("floor", ["chute", "ghost"])
def test_mu_i_flow_on_a_chute_stops_at_a_box_obstacle(floor):
    """The column collapses along the bed and hits the box (measured at dp = 4 mm, Coulomb boundaries
    at their default delta = arctan(mu_s): on the chute the front arrives at 0.145 s and runs
    5.4 cm up its face, on the ghost floor at 0.15 s and 5.8 cm; both at rest by 0.4 s): no grain
    ever enters the box or passes it, none sinks through the bed (below the first boundary row,
    dp/2 under it), and the front did reach the box (so the check is not vacuous)."""
    from taichi_granular.physics.walls import DynamicWalls, GhostAndDynamicWalls
    from taichi_granular.simulation import Simulation

    scene = chute_with_box(floor=floor)
    sim = Simulation(scene)
    assert type(sim.scheme.walls) is {"chute": DynamicWalls, "ghost": GhostAndDynamicWalls}[floor]
    sim.run(end_time=0.0)
    front, lowest, run_up = -np.inf, np.inf, 0.0
    while sim.t < scene.run.end_time - 1e-12:
        sim.run(end_time=min(scene.run.end_time, sim.t + 0.01))
        x = sim.state.material("position")
        assert not np.any(x[:, 0] > BLOCK[0]), f"grains in or past the box at t = {sim.t:.3f} s"
        front, lowest = max(front, x[:, 0].max()), min(lowest, x[:, 1].min())
        run_up = max(run_up, x[x[:, 0] > BLOCK[0] - 2 * DP, 1].max(initial=0.0))
    assert front > BLOCK[0] - DP, f"the front stopped at {front:.3f} m, short of the box"
    assert run_up > 0.03, f"no run-up on the box face: {run_up:.3f} m"
    assert lowest > -0.5 * DP, f"a grain sank through the bed to y = {lowest:.4f} m"


@pytest.mark.parametrize("numerics, key", [({"viscosity": "implicit"}, "numerics.viscosity"),
                                           ({"momentum": "viscous_pair"}, "numerics.momentum")])
def test_mu_i_obstacles_refuse_what_their_boundary_particles_cannot_carry(numerics, key):
    from taichi_granular.config import ConfigError

    with pytest.raises(ConfigError, match=key):
        chute_with_box(**numerics)
