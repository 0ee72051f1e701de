"""One neighbour pass for several pair stages (physics/stage.py FusedPairs) and the Verlet list
(neighbours.py): a fixed-step run of a small collapsing column gives the velocities of one pass per
stage and of the plain cell scan, to round-off."""
import numpy as np

from scenes import build, layer
from taichi_granular.scheme import Scheme


def column(**numerics):
    data = layer(height=0.04, length=0.04, dp=0.005, end_time=1.0)
    data["domain"] = {"lower": [-0.1, -0.02], "upper": [0.1, 0.06], "periodic": []}
    data["particles"][0].update(lower=[-0.02, 0.0], upper=[0.02, 0.04], initial_stress="hydrostatic")
    data["numerics"].update(viscosity="implicit", artificial_viscosity={"alpha": 0.05}, **numerics)
    return build(data)


def run(scene, fuse=True, steps=100, dt=2e-4):
    scheme = Scheme(scene, fuse=fuse)
    scheme.prepare()
    t = 0.0
    for _ in range(steps):
        scheme.step(dt, t)
        t += dt
    return scheme, scheme.state.velocity.to_numpy()[:scheme.state.n_material]


def test_fused_passes_and_verlet_list_give_the_same_flow():
    scene = column()
    separate, v_separate = run(scene, fuse=False)
    fused, v_fused = run(scene)
    names = [s.name for s in fused.rate_passes]
    assert "gradient_correction + free_surface" in names and "continuity + strain_rate + surface_layer" in names
    assert "momentum_stress + artificial_viscosity + particle_shifting" in names
    assert len(fused.rate_passes) == len(separate.rate_passes) - 5
    speed = np.abs(v_separate).max()
    assert speed > 0.05  # it flows
    assert np.abs(v_fused - v_separate).max() < 1e-12 * speed
    listed, v_listed = run(column(neighbour_skin=0.3))
    assert listed.grid.rebuilds >= 2  # the list was rebuilt while the column slumped
    assert listed.grid.rebuilds < listed.grid.builds / 5
    assert np.abs(v_listed - v_fused).max() < 1e-12 * speed


def test_the_stage_list_is_the_step_recorded_and_runs_nothing():
    """describe's list is recorded from the calls of the integrator's step (Scheme.run): the
    implicit viscous solve sits between the kick and the drift, the moves after the half step
    and after the drift, and recording it launches no kernel."""
    from scenes import build, layer
    from taichi_granular.launch import Launcher
    from taichi_granular.profiling import StageProfiler
    from taichi_granular.scheme import Scheme

    data = layer(height=0.02, length=0.04, end_time=1e-3)
    data["numerics"]["viscosity"] = "implicit"
    scheme = Scheme(build(data), profiler=StageProfiler(True))
    launches = Launcher.launches
    steps = [line.split(" [")[0] for line in scheme.stage_list()]
    assert Launcher.launches == launches and not scheme.profiler.calls
    kick, solve, drift = (steps.index(name) for name in
                          ("symplectic_verlet: kick", "implicit_viscosity", "symplectic_verlet: drift"))
    assert kick < solve < drift
    assert steps[steps.index("symplectic_verlet: half step") + 1] == "wall_impermeability"
    assert steps[drift + 1] == "wall_impermeability" and steps[-1] == "time_step"
