"""Sweeps (taichi_granular/sweep): the sweep file, the points, and a sweep on a Dask LocalCluster
that loses a worker mid-way and has a run that fails, then --resume."""
import os
import threading
import time

import numpy as np
import pytest
import yaml

from taichi_granular.keys import ConfigError
from taichi_granular.sweep import run_sweep
from taichi_granular.sweep.point import finished
from taichi_granular.sweep.results import read_csv
from taichi_granular.sweep.spec import latin_hypercube, sweep_from_dict

# a collapse of ~40 grains for 0.05 s: seconds a run, most of it compiling
TINY = {"scene": "mu_i/collapse_a0_90.yaml",
        "set": ["numerics.particle_spacing=0.02", "run.end_time=0.05", "run.output_interval=0.025",
                "domain.lower.1=-0.08", "numerics.viscosity=implicit", "run.write_vtu=true"],
        "measures": ["runout", "max:max_speed"]}


def _sweep(tmp_path, **changes):
    data = {**TINY, "out": str(tmp_path / "sweep"), **changes}
    return sweep_from_dict(data, tmp_path / "tiny.yaml")


def test_grid_points_are_the_product_of_the_axes_in_order(tmp_path):
    sweep = _sweep(tmp_path, axes={"material.static_friction_deg": [28.0, 33.0],
                                   "numerics.cfl": {"from": 0.3, "to": 0.5, "num": 3}})
    points = sweep.points()
    assert [p.id for p in points] == [f"p{k:04d}" for k in range(6)]
    assert points[1].values == (("material.static_friction_deg", 28.0), ("numerics.cfl", 0.4))
    assert points[5].overrides() == ["material.static_friction_deg=33.0", "numerics.cfl=0.5"]
    assert sweep.parameters == ["material.static_friction_deg", "numerics.cfl"]


def test_bundled_sweep_files_load():
    from taichi_granular.config import load_scene
    from taichi_granular.paths import config_path
    from taichi_granular.sweep import load_sweep

    files = sorted(config_path("sweeps").glob("*.yaml"))
    assert files
    for path in files:
        sweep = load_sweep(path)
        assert sweep.points()
        for point in sweep.points():
            load_scene(sweep.scene, [*sweep.fixed, *point.overrides()])


def test_latin_hypercube_puts_one_point_in_every_stratum_of_every_range():
    values = latin_hypercube([(25.0, 35.0), (0.0, 1.0)], 10, seed=3)
    assert values.shape == (10, 2)
    for j, (low, high) in enumerate([(25.0, 35.0), (0.0, 1.0)]):
        strata = np.floor((values[:, j] - low) / (high - low) * 10).astype(int)
        assert sorted(strata) == list(range(10))
    np.testing.assert_array_equal(values, latin_hypercube([(25.0, 35.0), (0.0, 1.0)], 10, seed=3))
    assert not np.array_equal(values, latin_hypercube([(25.0, 35.0), (0.0, 1.0)], 10, seed=4))


@pytest.mark.parametrize("changes, path", [
    ({"axes": {"numerics.cfl": [0.3]}, "sweeps": 1}, "sweeps"),
    ({}, "axes"),  # neither axes nor sample
    ({"axes": {"numerics.cfl": [0.3]}, "sample": {"points": 2, "ranges": {"numerics.cfl": [0.2, 0.4]}}}, "axes"),
    ({"axes": {"numerics.cfl": []}}, "axes.numerics.cfl"),
    ({"axes": {"numerics.cfl": {"from": 0.3, "to": 0.5}}}, "axes.numerics.cfl"),
    ({"sample": {"points": 0, "ranges": {"numerics.cfl": [0.2, 0.4]}}}, "sample.points"),
    ({"sample": {"points": 4, "ranges": {"numerics.cfl": [0.4, 0.2]}}}, "sample.ranges.numerics.cfl"),
    ({"sample": {"points": 4, "ranges": {"numerics.cfl": [0.2, float("nan")]}}}, "sample.ranges.numerics.cfl"),
    ({"axes": {"numerics.cfl": [0.3]}, "measures": ["run_out"]}, "measures.0"),
])
def test_a_bad_sweep_file_names_its_key(tmp_path, changes, path):
    with pytest.raises(ConfigError) as err:
        _sweep(tmp_path, **changes)
    assert err.value.path == path, str(err.value)


def test_sweep_on_a_local_cluster_survives_a_lost_worker_and_a_failed_run_then_resumes(tmp_path):
    """Two workers, four points, one of which the scene loader refuses (a negative friction
    angle): a worker is killed while it runs a point, Dask reruns that point elsewhere, and
    results.csv has every point, the failure with its error; --resume then runs only what is
    not finished (here: a finished run removed, and the failed one)."""
    from dask.distributed import Client, LocalCluster

    sweep = _sweep(tmp_path, axes={"material.static_friction_deg": [28.0, 30.5, 33.0, -5.0]})
    runs = tmp_path / "sweep" / "runs"
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster, \
            Client(cluster) as client:
        killed, stop = [], threading.Event()

        def kill_a_busy_worker():  # once a run has finished, kill a worker that is running another
            while not stop.is_set() and not killed:
                busy = [w for w, keys in client.processing().items() if keys]
                done = runs.exists() and any(finished(p) for p in runs.iterdir() if p.is_dir())
                if busy and done:
                    killed.append(busy[0])
                    try:
                        client.run(os._exit, 1, workers=busy[:1])
                    except Exception:  # noqa: BLE001 - the worker's connection closes as it dies
                        pass
                time.sleep(0.1)

        killer = threading.Thread(target=kill_a_busy_worker, daemon=True)
        killer.start()
        try:
            results = run_sweep(sweep, scheduler=cluster.scheduler_address, threads=1, quiet=True)
        finally:
            stop.set()
            killer.join(timeout=5)
        assert killed, "no worker was busy to be killed"
        table = read_csv(tmp_path / "sweep" / "results.csv")
        assert [r["id"] for r in table] == ["p0000", "p0001", "p0002", "p0003"]
        assert [r["status"] for r in table] == ["ok", "ok", "ok", "failed"], table
        assert "material.static_friction_deg" in table[3]["error"]
        assert all(float(r["runout"]) > 0 and float(r["max:max_speed"]) > 0 for r in table[:3])
        assert results["p0003"]["status"] == "failed"
        assert sorted(p.name for p in runs.iterdir()) == ["p0000", "p0001", "p0002", "p0003.failed"]
        assert (runs / "p0003.failed" / "error.txt").exists()
        assert (tmp_path / "sweep" / "plots" / "runout_vs_material_static_friction_deg.png").exists()

        # resume: the finished runs stay as they are; the removed one and the failed one run again
        kept = {p: (runs / p / "result.json").stat().st_mtime_ns for p in ("p0000", "p0002")}
        import shutil
        shutil.rmtree(runs / "p0001")
        with pytest.raises(FileExistsError):
            run_sweep(sweep, scheduler=cluster.scheduler_address, threads=1, quiet=True)
        run_sweep(sweep, scheduler=cluster.scheduler_address, threads=1, resume=True, quiet=True)
        assert {p: (runs / p / "result.json").stat().st_mtime_ns for p in kept} == kept
        table = read_csv(tmp_path / "sweep" / "results.csv")
        assert [r["status"] for r in table] == ["ok", "ok", "ok", "failed"]
        assert finished(runs / "p0001") is not None


def test_sampled_sweep_runs_without_dask_one_point_after_another(tmp_path):
    """A Latin-hypercube sample of two points through the command, --workers 0 (no Dask): both
    runs finish, the CSV has the sampled values, and the plots include the scatter matrix."""
    from taichi_granular.cli import main

    path = tmp_path / "sweep.yaml"
    sample = {"points": 2, "seed": 7, "ranges": {"numerics.cfl": [0.3, 0.5]}}
    path.write_text(yaml.safe_dump({**TINY, "sample": sample, "out": str(tmp_path / "out")}))
    assert main(["sweep", str(path), "--workers", "0", "--quiet"]) == 0
    table = read_csv(tmp_path / "out" / "results.csv")
    assert [r["status"] for r in table] == ["ok", "ok"] and all(float(r["steps"]) > 0 for r in table)
    cfl = sorted(float(r["numerics.cfl"]) for r in table)
    assert 0.3 <= cfl[0] < 0.4 <= cfl[1] <= 0.5  # one point in each half of the range
    assert (tmp_path / "out" / "plots" / "scatter_matrix.png").exists()
    path.write_text(yaml.safe_dump({**TINY, "axes": {"numerics.cfl": [0.4]}, "measures": ["speed"]}))
    assert main(["sweep", str(path), "--workers", "0"]) == 2  # the bad measure named, exit 2
