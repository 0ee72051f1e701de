"""Throughput of the full mu(I) step in 2D at several sizes (``taichi-granular bench throughput``).

The scene is a square of glass beads (Table 1 of [M]) resting on a ghost floor, periodic along
x, at the paper's resolution (dp = 5 mm, h/dp = 1.3); its side sets the particle count. Each
size is compiled and warmed up first, then timed over ``--steps`` steps with the device
synchronised at both ends. The per-category breakdown comes from the stage profiler in a
second, separately timed pass (it synchronises around every stage).
"""
import math
import time

from .. import runtime
from ..config import scene_from_dict

GLASS_BEADS = {
    "model": "mu_i", "grain_density": 800.0, "grain_diameter": 0.5e-3, "static_friction_deg": 20.90,
    "limit_friction_deg": 32.76, "reference_inertial_number": 0.279, "grain_compressibility": 1.5e-5,
    "max_yield_stress": 190.0, "regularisation_time": 1.0,
}


def block_scene(n_particles: int, arch: str, precision: str, dp: float = 0.005, skin=None, reorder_every=None):
    side = math.sqrt(n_particles) * dp
    numerics = {"particle_spacing": dp, "artificial_viscosity": {"alpha": 0.05}}
    if skin is not None:
        numerics["neighbour_skin"] = skin
    if reorder_every is not None:
        numerics["reorder_every"] = reorder_every
    return scene_from_dict({
        "name": f"bench_{n_particles}", "dimension": 2, "arch": arch, "precision": precision,
        "domain": {"lower": [0.0, -0.02], "upper": [side, 1.5 * side], "periodic": ["x"]},
        "material": dict(GLASS_BEADS),
        "particles": [{"lower": [0.0, 0.0], "upper": [side, side]}],
        "walls": [{"type": "ghost", "point": [0.0, 0.0], "normal": [0.0, 1.0]}],
        "numerics": numerics,
        "run": {"end_time": 1.0, "output_interval": 1.0},
    })


def measure(n_particles: int, steps: int, arch: str, precision: str, skin=None, order: str = "lattice") -> dict:
    """``order``: the material as built (``lattice``, the default reordering), shuffled at random
    and left so (``shuffled``, numerics.reorder_every = 0), or shuffled and then sorted by cell once
    (``reordered``; no reordering within the timed steps)."""
    import numpy as np

    from ..simulation import Simulation

    every = {"lattice": None, "shuffled": 0, "reordered": 10**9}[order]
    scene = block_scene(n_particles, arch, precision, skin=skin, reorder_every=every)
    sim = Simulation(scene, progress=False)
    n_material = sim.state.n_material
    # the lattice through an identity permutation: the gather kernels compile before the timing
    sim.scheme.permute(np.random.default_rng(0).permutation(n_material) if order != "lattice"
                       else np.arange(n_material))
    if order == "reordered":
        sim.scheme.reorder()
    sim.run(max_steps=5)  # compile and warm up (and the list's rebuild after the permutation)
    import taichi as ti
    ti.sync()
    start_steps, start_t = sim.step_count, sim.t
    t0 = time.perf_counter()
    sim.run(max_steps=start_steps + steps)
    ti.sync()
    wall = time.perf_counter() - t0
    done = sim.step_count - start_steps
    simulated = sim.t - start_t
    n = sim.state.n_material
    sim.profiler.enabled = True
    sim.profiler.reset()
    sim.run(max_steps=sim.step_count + max(5, steps // 5))
    shares = sim.profiler.by_category()
    grid = sim.scheme.grid
    total = sum(shares.values()) or 1.0
    return {"particles": n, "walls": sim.state.n_wall, "steps": done,
            "particle_steps_per_second": n * done / wall, "ms_per_step": 1e3 * wall / done,
            "seconds_per_simulated_second": wall / simulated if simulated > 0 else float("nan"),
            "memory_mib": sim.scheme.memory_bytes() / 2**20,
            "skin": scene.numerics.neighbour_skin, "order": order, "list_builds": grid.rebuilds / max(grid.builds, 1),
            "shares": {k: v / total for k, v in shares.items() if v > 0}}


def main(args) -> int:
    runtime.init(args.arch, args.precision)
    print(f"mu(I) full step, 2D, {args.arch}/{args.precision}, dp = 5 mm, h/dp = 1.3, {args.steps} timed steps")
    print(f"{'particles':>10} {'walls':>7} {'skin/h':>6} {'order':>9} {'Mparticle-steps/s':>18} {'ms/step':>9} {'s per sim s':>12} "
          f"{'MiB':>7} {'rebuilt':>7}  breakdown")
    for size in args.sizes:
        for skin, order in [(k, o) for k in getattr(args, "skins", None) or [None]
                            for o in getattr(args, "orders", None) or ["lattice"]]:
            r = measure(size, args.steps, args.arch, args.precision, skin, order)
            breakdown = " ".join(f"{k} {100 * v:.0f}%" for k, v in sorted(r["shares"].items(), key=lambda kv: -kv[1]))
            rebuilt = f"{100 * r['list_builds']:.0f}%" if r["skin"] > 0 else "-"
            print(f"{r['particles']:>10} {r['walls']:>7} {r['skin']:>6.2f} {r['order']:>9} "
                  f"{r['particle_steps_per_second'] / 1e6:>18.3f} "
                  f"{r['ms_per_step']:>9.2f} {r['seconds_per_simulated_second']:>12.1f} {r['memory_mib']:>7.1f} "
                  f"{rebuilt:>7}  {breakdown}", flush=True)
    return 0
