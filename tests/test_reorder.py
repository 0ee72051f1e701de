"""Sorting the material by neighbour cell (numerics.reorder_every, state.ParticleOrder): the
physics does not see it (round-off apart), outputs keep the initial order, resume stays bitwise."""
import numpy as np

from scenes import build, layer
from taichi_granular.cli import main
from taichi_granular.output import read_frame, read_series
from taichi_granular.simulation import Simulation


def _sheared(every, steps=None):
    data = layer(height=0.02, length=0.04, tilt_deg=25.0)
    data["numerics"]["reorder_every"] = every
    data["run"] = {"end_time": 0.004, "output_interval": 0.001}
    data["render"] = {"frames": False}
    return data


def _run(data, steps, permute=None):
    sim = Simulation(build(data), progress=False)
    if permute is not None:
        sim.scheme.permute(permute(sim.state.n_material))
    sim.run(end_time=1.0, max_steps=steps)
    return sim


def test_reordering_changes_the_storage_not_the_flow():
    plain = _run(_sheared(0), 60)
    sorted_ = _run(_sheared(7), 60)
    ids = sorted_.state.particle_id.to_numpy()
    assert not np.array_equal(ids, np.arange(len(ids)))  # it did reorder
    assert np.array_equal(np.sort(ids), np.arange(len(ids)))  # a permutation
    a, b = plain.scheme.snapshot(), sorted_.scheme.snapshot()
    assert np.array_equal(b["particle_id"], np.arange(len(ids)))  # outputs in the initial order
    for name in ("position", "velocity", "density", "pressure"):
        scale = np.abs(a[name]).max()
        assert np.abs(a[name] - b[name]).max() <= 1e-11 * scale, name


def test_a_shuffled_order_gives_the_same_flow_and_reordering_undoes_it():
    plain = _run(_sheared(0), 40)
    shuffled = _run(_sheared(0), 40, permute=lambda n: np.random.default_rng(1).permutation(n))
    a, b = plain.scheme.snapshot(), shuffled.scheme.snapshot()
    for name in ("position", "velocity", "pressure"):
        assert np.abs(a[name] - b[name]).max() <= 1e-11 * np.abs(a[name]).max(), name
    sim = _run(_sheared(10**6), 1, permute=lambda n: np.random.default_rng(1).permutation(n))
    sim.scheme.reorder()
    x = sim.state.position.to_numpy()[: sim.state.n_material]
    cell = sim.scheme.grid
    coords = np.floor((x - np.array(cell.lower)) / np.array(cell.cell_size)).astype(int)
    flat = coords[:, 1] * cell.cells[0] + coords[:, 0]  # row-major, x fastest (NeighborGrid.flat_index)
    assert np.all(np.diff(flat) >= 0)  # stored cell by cell


def test_resume_across_reorders_is_bitwise(tmp_path):
    data = _sheared(7)
    straight = Simulation(build(data), out_dir=tmp_path / "straight", progress=False)
    straight.run()
    stopped = Simulation(build(data), out_dir=tmp_path / "stopped", progress=False)
    stopped.run(end_time=0.002)
    assert main(["resume", str(tmp_path / "stopped"), "--quiet"]) == 0
    assert straight.step_count > 3 * 7  # several reorders before and after the checkpoint
    a = read_frame(read_series(tmp_path / "straight")[-1][1])
    b = read_frame(read_series(tmp_path / "stopped")[-1][1])
    for name in ("position", "velocity", "pressure", "density"):
        assert np.array_equal(a[name], b[name]), name
