"""Explicit against implicit viscosity on the Table 3 collapses (``taichi-granular bench viscosity``).

For each mu(I) column collapse config (``configs/mu_i/collapse_a*.yaml``, the paper's
resolution) and each ``numerics.viscosity``, the scene is compiled and warmed up over a few
steps, then timed from release over ``--window`` simulated seconds: steps per simulated second,
wall seconds per simulated second, mean BiCGSTAB iterations per step (implicit), and the
implicit update's speed-up. The explicit step is set by the viscous limit of [M39]
(eta_hat_max = eta_0 + tau_0 m_0 in the grains at rest), the implicit one by the acoustic limit.
"""
import time

from .. import runtime

CASES = ("a0_19", "a0_55", "a0_90", "a1_60", "a2_75", "a3_00")


def measure(case: str, viscosity: str, window: float, arch: str) -> dict:
    import taichi as ti

    from ..config import load_scene
    from ..paths import config_path
    from ..simulation import Simulation

    scene = load_scene(config_path(f"mu_i/collapse_{case}.yaml"),
                       [f"numerics.viscosity={viscosity}", f"arch={arch}"])
    sim = Simulation(scene, progress=False)
    sim.run(end_time=window, max_steps=3)  # compile and warm up
    ti.sync()
    steps0, t0 = sim.step_count, sim.t
    solve = sim.scheme.viscous_solve
    iterations0 = solve.run_iterations if solve is not None else 0
    start = time.perf_counter()
    sim.run(end_time=window)
    ti.sync()
    wall = time.perf_counter() - start
    steps, simulated = sim.step_count - steps0, sim.t - t0
    return {"case": case, "viscosity": viscosity, "particles": sim.state.n_material, "steps": steps,
            "steps_per_simulated_second": steps / simulated, "wall_per_simulated_second": wall / simulated,
            "iterations": (solve.run_iterations - iterations0) / steps if solve is not None else 0.0}


def main(args) -> int:
    runtime.init(args.arch, "f64")
    cases = [c for c in CASES if not args.cases or any(k in c for k in args.cases)]
    print(f"mu(I) collapses of Table 3 at the paper's resolution, {args.arch}, timed over the first "
          f"{args.window:g} s after release")
    print(f"{'case':<7} {'particles':>9} {'viscosity':<9} {'steps/sim s':>12} {'wall s/sim s':>13} "
          f"{'BiCGSTAB it/step':>17} {'speed-up':>9}")
    for case in cases:
        rows = [measure(case, viscosity, args.window, args.arch) for viscosity in ("explicit", "implicit")]
        speedup = rows[0]["wall_per_simulated_second"] / rows[1]["wall_per_simulated_second"]
        for r in rows:
            tail = f"{speedup:>9.1f}" if r["viscosity"] == "implicit" else ""
            print(f"{case:<7} {r['particles']:>9} {r['viscosity']:<9} {r['steps_per_simulated_second']:>12.4g} "
                  f"{r['wall_per_simulated_second']:>13.4g} {r['iterations']:>17.1f} {tail}", flush=True)
    return 0
