"""One run of a sweep, in its job's process (sweep/engine.py): the scene with the point's
overrides, run into a hidden partial folder that becomes ``runs/<id>`` only when the run and
its measures are complete (``result.json`` inside), so a folder of that name is always a
finished run. A run that fails leaves its partial output as ``runs/<id>.failed`` (with
``error.txt``) for inspection."""
from __future__ import annotations

import json
import os
import shutil
import uuid
from pathlib import Path

RESULT_FILE = "result.json"


def finished(folder: Path):
    """The result of a finished run's folder, or None."""
    path = Path(folder) / RESULT_FILE
    if not path.exists():
        return None
    return json.loads(path.read_text())


def run_point(payload: dict) -> dict:
    """payload: scene, overrides, out (the run's folder), measures. Returns the measures, the
    steps, the simulated time and the stepping wall time  [-, s]."""
    from ..config import load_scene
    from ..output import atomic_write_text
    from ..simulation import Simulation
    from .measures import measure

    final = Path(payload["out"])
    final.parent.mkdir(parents=True, exist_ok=True)
    partial = final.parent / f".{final.name}.{uuid.uuid4().hex[:8]}.partial"
    try:
        scene = load_scene(payload["scene"], payload["overrides"])
        sim = Simulation(scene, out_dir=partial, progress=False)
        summary = sim.run()
        result = {"steps": summary.steps, "simulated_time": float(sim.t),
                  "wall_seconds": float(summary.wall_seconds),
                  **measure(payload["measures"], scene, partial)}
        atomic_write_text(partial / RESULT_FILE, json.dumps(result) + "\n")
    except BaseException as err:
        failed = final.parent / f"{final.name}.failed"
        shutil.rmtree(failed, ignore_errors=True)
        partial.mkdir(parents=True, exist_ok=True)
        (partial / "error.txt").write_text(f"{type(err).__name__}: {err}\n")
        os.replace(partial, failed)
        raise
    if finished(final) is not None:  # another attempt of the same point (a rescheduled job) finished first
        shutil.rmtree(partial, ignore_errors=True)
        return finished(final)
    shutil.rmtree(final, ignore_errors=True)
    shutil.rmtree(final.parent / f"{final.name}.failed", ignore_errors=True)
    os.replace(partial, final)
    return result
