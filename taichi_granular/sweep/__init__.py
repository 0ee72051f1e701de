"""Parameter sweeps and ensembles (``taichi-granular sweep SWEEP.yaml``): a base scene, axes or
a Latin-hypercube sample of ``--set`` keys (spec.py), measures per run (measures.py), each run in
its own process on Dask distributed (engine.py), results as one CSV and plots (results.py).

Layout of a sweep's folder (``out``):
    sweep.yaml           the sweep file as read
    points.csv           every point's id and parameter values
    runs/<id>/           a finished run's output and result.json (written whole, point.py)
    runs/<id>.failed/    a failed run's partial output and error.txt
    results.csv          a row per point: parameters, measures, steps, wall time, status, error
    plots/               <measure>_vs_<parameter>.png, scatter_matrix.png for a sample
"""
from __future__ import annotations

from pathlib import Path
from typing import Optional

import yaml

from ..output import atomic_write_text
from .engine import Job, run_jobs
from .point import finished
from .results import CSV_NAME, plot, rows, write_csv
from .spec import Sweep, load_sweep  # noqa: F401 - the package's interface

ENTRY = "taichi_granular.sweep.point:run_point"


def jobs_of(sweep: Sweep, points, runs: Path):
    return [Job(p.id, ENTRY, {"scene": _scene_path(sweep), "overrides": [*sweep.fixed, *p.overrides()],
                               "out": str(runs / p.id), "measures": list(sweep.measures)}) for p in points]


def _scene_path(sweep: Sweep) -> str:
    """The base scene as the jobs' processes find it: relative to the sweep file if it is there,
    else as given (a bundled scene's name, or relative to the working folder)."""
    near = sweep.source.parent / sweep.scene if sweep.source is not None else None
    return str(near.resolve()) if near is not None and near.exists() else sweep.scene


def run_sweep(sweep: Sweep, *, workers: Optional[int] = None, scheduler: Optional[str] = None,
              threads: Optional[int] = None, resume: bool = False, quiet: bool = False) -> dict:
    """Run every point not finished yet (``resume``: the finished ones are kept and skipped),
    writing results.csv after each run and the plots at the end; the results by id."""
    from ..config import load_scene

    out = Path(sweep.out)
    runs = out / "runs"
    points = sweep.points()
    if runs.exists() and any(runs.iterdir()) and not resume:
        raise FileExistsError(f"{out} already holds runs: --resume to finish the sweep there, or choose another out")
    load_scene(_scene_path(sweep), list(sweep.fixed))  # the base scene itself must load: its error is the sweep's
    runs.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out / "sweep.yaml", yaml.safe_dump(sweep.raw, sort_keys=False))
    atomic_write_text(out / "points.csv", "id," + ",".join(sweep.parameters) + "\n" + "".join(
        f"{p.id}," + ",".join(str(v) for _, v in p.values) + "\n" for p in points))
    results = {}
    for p in points:
        done = finished(runs / p.id)
        if done is not None:
            results[p.id] = {"status": "ok", **done}
    todo = [p for p in points if p.id not in results]
    if not quiet:
        print(f"sweep {sweep.source or ''}: {len(points)} runs, {len(points) - len(todo)} already finished, "
              f"{len(todo)} to run -> {out}", flush=True)

    def record(job, result):
        results[job.id] = result
        write_csv(out / CSV_NAME, rows(sweep, points, results))

    run_jobs(jobs_of(sweep, todo, runs), workers=workers, scheduler=scheduler, threads=threads,
             timeout=sweep.timeout, on_result=record, quiet=quiet)
    table = rows(sweep, points, results)
    write_csv(out / CSV_NAME, table)
    try:
        plot(sweep, table, out / "plots")
    except ImportError:
        print("plots skipped: matplotlib is not installed (pip install -e \".[sweep]\")")
    return results
