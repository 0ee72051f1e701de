"""Time a few hundred steps of real scenes and size their full runs (``taichi-granular bench scene``).

Before a long run (a paper-resolution 3D scene, a GPU session with minutes to spend) the first
question is what a step costs there and how many the scene needs. This compiles each scene,
warms it up for ``WARMUP`` steps from release (the first steps compile the kernels and rebuild the
neighbour list), times ``--steps`` steps with the device synchronised at both ends, and
projects the wall time to the scene's ``run.end_time`` at the mean time step of the timed steps.
The step changes as the flow develops, either way (measured against whole runs: the coarse 3D
collapse steps 1.1e-4 s at release and 4.2e-4 s on average, so its projection came out 1.7 times
its run; the coarse drum's step falls from 4.9e-5 s to 1.9e-5 s, 0.3 times): read the projection
as the order of magnitude that decides where a run goes (this machine, a GPU, not at all). No
output is written.
"""
import time

import taichi as ti

from ..config import load_scene

WARMUP = 20  # steps before the timing


def measure_scene(path: str, overrides=(), steps: int = 300) -> dict:
    """One scene, timed over ``steps`` steps after the warm-up."""
    from ..simulation import Simulation

    scene = load_scene(path, overrides)
    t0 = time.perf_counter()
    sim = Simulation(scene, progress=False)
    sim.run(max_steps=WARMUP)
    ti.sync()
    start = time.perf_counter()
    warm = start - t0
    start_steps, start_t = sim.step_count, sim.t
    sim.run(max_steps=start_steps + steps)
    ti.sync()
    wall = time.perf_counter() - start
    done = sim.step_count - start_steps
    dt = (sim.t - start_t) / done
    remaining = max(scene.run.end_time - sim.t, 0.0)
    return {"scene": scene.name, "arch": scene.arch, "precision": scene.precision,
            "material": sim.state.n_material, "boundary": sim.state.n_wall, "steps": done,
            "ms_per_step": 1e3 * wall / done, "time_step": dt,
            "material_steps_per_second": sim.state.n_material * done / wall,
            "seconds_per_simulated_second": wall / (sim.t - start_t),
            "end_time": scene.run.end_time, "projected_seconds": warm + wall + remaining / dt * wall / done,
            "memory_mib": sim.scheme.memory_bytes() / 2**20, "compile_and_warmup_seconds": warm}


def main(args) -> int:
    overrides = list(getattr(args, "set", None) or [])
    print(f"{'scene':<28} {'arch':>6} {'material':>9} {'boundary':>9} {'ms/step':>9} {'dt s':>9} {'Mmat/s':>7} "
          f"{'s/sim s':>9} {'end s':>6} {'projected':>10} {'MiB':>7} {'warm-up s':>9}")
    for path in args.scenes:
        r = measure_scene(path, overrides, args.steps)
        hours = r["projected_seconds"] / 3600.0
        projected = f"{hours:.2f} h" if hours >= 1.0 else f"{r['projected_seconds'] / 60.0:.1f} min"
        print(f"{r['scene']:<28} {r['arch']:>6} {r['material']:>9} {r['boundary']:>9} {r['ms_per_step']:>9.2f} "
              f"{r['time_step']:>9.2e} {r['material_steps_per_second'] / 1e6:>7.3f} "
              f"{r['seconds_per_simulated_second']:>9.1f} {r['end_time']:>6.2f} {projected:>10} "
              f"{r['memory_mib']:>7.1f} {r['compile_and_warmup_seconds']:>9.1f}", flush=True)
    return 0
