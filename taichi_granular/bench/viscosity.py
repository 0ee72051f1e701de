"""Explicit against implicit viscosity on the Table 3 collapses (``taichi-granular bench viscosity``).

For each mu(I) column collapse config (``configs/mu_i/collapse_a*.yaml``, the paper's
resolution) and each ``numerics.viscosity``, the scene is compiled and warmed up over a few
steps, then timed from release over ``--window`` simulated seconds: steps per simulated second,
wall seconds per simulated second, mean BiCGSTAB iterations per step (implicit), and the
implicit update's speed-up. The explicit step is set by the viscous limit of [M39]
(eta_hat_max = eta_0 + tau_0 m_0 in the grains at rest), the implicit one by the acoustic limit.

With ``--cfls``, an ensemble instead: the accuracy study's tall collapse (a = 2.75, or the cases
named) at ``--spacing``, run to rest once per CFL number and viscosity setting. A tall collapse
of a few hundred grains is chaotic at the front: a 10 % change of the step moves its run-out by
several points of Lube, so the two settings are compared in the mean over the ensemble (with
its standard error), not run by run.
"""
import math
import statistics
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
    if getattr(args, "cfls", None):
        return ensemble(args)
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


def ensemble_run(case, spacing: float, cfl: float, viscosity: str) -> dict:
    """One collapse of the ensemble, to rest: run-out (% of Lube) at the front stop, its time, the
    run-out (% of Lube) and bulk run-out at the end, steps and wall seconds."""
    from ..validation import column_collapse
    from .accuracy import run_case

    done = run_case(case, (f"numerics.particle_spacing={spacing}", f"numerics.cfl={cfl}",
                           f"numerics.viscosity={viscosity}"))
    result = column_collapse.evaluate(done.scene, done.times, done.frames, done.diagnostics)
    return {"cfl": cfl, "viscosity": viscosity, "runout": 100.0 * result.error, "stop": result.front_stop_time,
            "end": 100.0 * (result.runout_end / result.runout_reference - 1.0), "bulk": result.bulk_runout_end, "steps": done.sim.step_count, "wall": done.wall_seconds}


def _mean_se(values):
    values = [v for v in values if v is not None]
    if len(values) < 2:
        return (values[0] if values else math.nan), math.nan
    return statistics.mean(values), statistics.stdev(values) / math.sqrt(len(values))


def ensemble(args) -> int:
    from .accuracy import FULL

    names = args.cases or ["a2_75"]
    cases = [c for c in FULL if c.measure == "collapse" and any(k in c.name for k in names)]
    for case in cases:
        spacing = args.spacing or case.spacings[case.option_level]
        print(f"{case.label()}, dp {1e3 * spacing:g} mm: run-out % of Lube at the front stop / stop s / "
              f"run-out % of Lube / bulk run-out at the end, per CFL number")
        rows = {}
        for viscosity in ("explicit", "implicit"):
            rows[viscosity] = []
            for cfl in args.cfls:
                r = ensemble_run(case, spacing, cfl, viscosity)
                rows[viscosity].append(r)
                stop = "none" if r["stop"] is None else f"{r['stop']:.2f}"
                print(f"  {viscosity:<8} cfl {cfl:<5g} {r['runout']:+6.1f} / {stop} / {r['end']:+6.1f} / {r['bulk']:.3f}   "
                      f"{r['steps']} steps, {r['wall']:.0f} s", flush=True)
        summary = {}
        for viscosity, rr in rows.items():
            runout, stop, end, bulk = (_mean_se([r[k] for r in rr]) for k in ("runout", "stop", "end", "bulk"))
            summary[viscosity] = runout, stop, end
            print(f"  {viscosity:<8} mean run-out {runout[0]:+.2f} % (se {runout[1]:.2f}), front stop "
                  f"{stop[0]:.3f} s (se {stop[1]:.3f}), at the end {end[0]:+.2f} % (se {end[1]:.2f}), "
                  f"bulk {bulk[0]:.3f} (se {bulk[1]:.3f})")
        (re, rse), (se_, sse), (ee, ese) = summary["explicit"]
        (ri, rise), (si, sise), (ei, eise) = summary["implicit"]
        print(f"  implicit - explicit: run-out {ri - re:+.2f} points (se {math.hypot(rse, rise):.2f}), "
              f"front stop {100 * (si / se_ - 1):+.1f} % (se {100 * math.hypot(sse, sise) / se_:.1f} %), "
              f"run-out at the end {ei - ee:+.2f} points (se {math.hypot(ese, eise):.2f})")
    return 0
