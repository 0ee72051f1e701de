"""bench throughput (bench/throughput.py) on tiny blocks: what it counts is checked against what
the step is known to do, never its speed (timing is for the benchmark, not for tests)."""
import math

import pytest

from taichi_granular import runtime
from taichi_granular.bench import throughput


@pytest.mark.parametrize("model, dimension, passes", [("mu_i", 2, 3), ("hypoplastic", 2, 6), ("elastoplastic", 3, 2)])
def test_each_model_block_counts_its_passes_neighbours_and_launches(model, dimension, passes):
    """Pair passes per step: mu(I) 3 (Verlet, one rate evaluation); hypoplastic 3 per evaluation
    of the predictor-corrector; elastoplastic 2 (the Verlet of its 3D collapse scenes). Neighbours listed per particle
    within 2h + skin: a full disc (sphere) of the lattice holds pi r^2 (4/3 pi r^3) particles; the
    block's free surface and floor leave fewer, never more."""
    runtime.init("cpu", "f64")
    row = throughput.measure(120, 3, "cpu", "f64", model=model, dimension=dimension, compare=True)
    assert row["particles"] >= 100 and row["walls"] > 0
    assert row["pair_passes"] == passes
    scene = throughput.block_scene(120, "cpu", "f64", model, dimension)
    h = scene.numerics.smoothing_length
    radius = (2.0 + scene.numerics.neighbour_skin) * h / scene.numerics.particle_spacing  # skin in h
    full = math.pi * radius**2 if dimension == 2 else 4.0 / 3.0 * math.pi * radius**3
    assert 0.3 * full < row["neighbours"] < full
    # every stage is a launch: at least the pair passes plus the integrator's updates and the
    # end-of-step time step and guard; dt, the guard and the list check are read back every step
    assert row["launches"] >= passes + 4
    assert 3.0 <= row["host_reads"] < row["launches"]
    # timings are reported, not compared: under load one sweep has timed slower than a whole step
    assert row["sweep_ms"] > 0.0 and row["ms_per_step"] > 0.0
    assert abs(sum(row["shares"].values()) - 1.0) < 1e-9


def test_small_blocks_are_a_layer_wide_enough_for_the_periodic_axes():
    scene = throughput.block_scene(100, "cpu", "f64", "elastoplastic", 3)
    block = scene.particles[0]
    support = 2.0 * scene.numerics.smoothing_length
    assert all(u - l >= 3 * support for l, u in zip(block.lower[:2], block.upper[:2]))
    assert block.upper[2] - block.lower[2] == pytest.approx(scene.numerics.particle_spacing)


def test_bench_scene_times_a_real_scene_and_projects_its_run():
    """bench scene (bench/scene.py): the timed steps are taken after the warm-up, the time step
    and the cost per simulated second are those of the timed steps, and the projection adds the
    remaining simulated time at that cost."""
    from taichi_granular.bench import scene

    row = scene.measure_scene("mu_i/collapse_a0_90.yaml", ["numerics.particle_spacing=0.012"], steps=6)
    assert row["steps"] == 6 and row["arch"] == "cpu"
    assert 50 < row["material"] < 200 and row["boundary"] > 0
    assert 0.0 < row["time_step"] < 1e-3
    assert row["seconds_per_simulated_second"] == pytest.approx(1e-3 * row["ms_per_step"] / row["time_step"])
    rest = (row["end_time"] - (scene.WARMUP + 6) * row["time_step"]) * row["seconds_per_simulated_second"]
    assert row["projected_seconds"] > row["compile_and_warmup_seconds"] + 0.5 * rest
