"""Throughput of the full step, every model, 2D and 3D, at several sizes
(``taichi-granular bench throughput``).

The scene is a block resting on a floor of the model's own wall kind, periodic along the
horizontal axes, its side setting the particle count. mu(I): glass beads of [M] (Table 1) at the
paper's resolution (dp = 5 mm, h/dp = 1.3) on a ghost floor, with artificial viscosity; the
hypoplastic and elastoplastic blocks take the material and numerics of a bundled scene of the
model (REFERENCE) on its own floor. Each size is compiled and warmed up first, then timed over
``--steps`` steps with the device synchronised at both ends. Separately (never inside the
timing): the per-category breakdown from the stage profiler (it synchronises around every
stage), and the kernel launches and host reads per step, counted with cProfile.
``--compare`` times a bare density sweep over the same neighbour list in the same process: the
ceiling one pair pass can reach, against which a step is a number of such passes.
"""
import cProfile
import pstats
import time

import numpy as np
import taichi as ti

from .. import runtime
from ..config import scene_from_dict

GLASS_BEADS = {
    "model": "mu_i", "grain_density": 800.0, "grain_diameter": 0.5e-3, "static_friction_deg": 20.90,
    "limit_friction_deg": 32.76, "reference_inertial_number": 0.279, "grain_compressibility": 1.5e-5,
    "max_yield_stress": 190.0, "regularisation_time": 1.0,
}
# material, numerics and floor of each model's block (mu(I): GLASS_BEADS, the figures since issue 25)
REFERENCE = {"hypoplastic": "hypoplastic/collapse_a0_55.yaml",
             "elastoplastic": "elastoplastic/collapse3d_a2_75_coarse.yaml"}
MODELS = ("mu_i", "hypoplastic", "elastoplastic")
FIXED_COST_SIZE = 100  # particles: a block this small is nearly all per-step overhead
BATCHES = 5  # timed batches per block; the median is reported


def _reference(model: str):
    """(material, numerics, floor wall) of the model's block."""
    if model == "mu_i":
        return (dict(GLASS_BEADS), {"particle_spacing": 0.005, "artificial_viscosity": {"alpha": 0.05}},
                {"type": "ghost"})
    import yaml

    from ..paths import config_path
    data = yaml.safe_load(config_path(REFERENCE[model]).read_text())
    wall = {k: v for k, v in data["walls"][0].items() if k not in ("name", "point", "normal")}
    return data["material"], data["numerics"], wall


def block_scene(n_particles: int, arch: str, precision: str, model: str = "mu_i", dimension: int = 2,
                skin=None, reorder_every=None):
    material, numerics, wall = _reference(model)
    numerics = dict(numerics)
    dp = numerics["particle_spacing"]
    if skin is not None:
        numerics["neighbour_skin"] = skin
    if reorder_every is not None:
        numerics["reorder_every"] = reorder_every
    d = dimension
    # a cube (square) of the particle count, but at least 10 dp across: three kernel supports,
    # the least a periodic axis takes; a small block is then a layer
    side = max(round(n_particles ** (1.0 / d)), 10) * dp
    height = max(round(n_particles / round(side / dp) ** (d - 1)), 1) * dp
    up = [0.0] * (d - 1) + [1.0]
    return scene_from_dict({
        "name": f"bench_{model}_{d}d_{n_particles}", "dimension": d, "arch": arch, "precision": precision,
        "domain": {"lower": [0.0] * (d - 1) + [-5.0 * dp], "upper": [side] * (d - 1) + [1.5 * height + 5.0 * dp],
                   "periodic": ["x", "y"][: d - 1]},
        "material": material,
        "particles": [{"lower": [0.0] * d, "upper": [side] * (d - 1) + [height], "initial_stress": "hydrostatic"}],
        "walls": [{**wall, "point": [0.0] * d, "normal": up}],
        "numerics": numerics,
        "run": {"end_time": 1.0, "output_interval": 1.0},
    })


def _launches_and_reads(sim, steps: int):
    """Kernel launches and host reads (kernel results and Python-scope field reads) per step over
    ``steps`` steps: Taichi's, counted by cProfile, and launch.py's, by its counters."""
    from ..launch import Launcher

    fast = (Launcher.launches, Launcher.results)
    profile = cProfile.Profile()
    profile.enable()
    sim.run(max_steps=sim.step_count + steps)
    profile.disable()
    fast_launches, fast_results = Launcher.launches - fast[0], Launcher.results - fast[1]
    calls = {}
    for (_, _, name), row in pstats.Stats(profile).stats.items():
        calls[name] = calls.get(name, 0) + row[1]  # primitive calls
    # Taichi's own launches (Kernel.launch_kernel; the C++ binding is named "<built-in ...>") and ours
    launches = calls.get("launch_kernel", 0) + fast_launches
    reads = calls.get("construct_kernel_ret", 0) + fast_results + sum(
        count for name, count in calls.items() if any(k in name for k in ("read_float", "read_int", "read_uint")))
    return launches / steps, reads / steps


@ti.data_oriented
class DensitySweep:
    """The ceiling of a pair pass: rho_i = sum_j m_j W(r_ij) over the scene's own neighbour
    loop and smoothing function, nothing else (bench only)."""

    def __init__(self, scheme):
        self.grid, self.state, self.w = scheme.grid, scheme.state, scheme.smoothing
        self.out = ti.field(float, scheme.state.n_material)

    @ti.func
    def _pair(self, i, j, x_ij, r, acc: ti.template()):
        acc[0] += self.state.mass[j] * self.w.value(r)

    @ti.kernel
    def run(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            acc = ti.Vector([self.state.mass[i] * self.w.value(0.0)])
            self.grid.for_each_neighbour(i, self._pair, acc)
            self.out[i] = acc[0]


def _pair_passes(scheme) -> int:
    """Neighbour passes per step: the pair passes of one rate evaluation times the integrator's."""
    from ..physics.stage import FusedPairs, PairStage
    passes = sum(isinstance(stage, (PairStage, FusedPairs)) for stage in scheme.rate_passes)
    return passes * scheme.integrator.rate_evaluations


def measure(n_particles: int, steps: int, arch: str, precision: str, skin=None, order: str = "lattice",
            model: str = "mu_i", dimension: int = 2, compare: bool = False, counts: bool = True,
            batches: int = BATCHES) -> dict:
    """One block, timed: ``batches`` runs of ``steps`` steps each, the median batch reported (and
    the spread of the batches, (slowest - fastest)/median). ``order``: the material as built
    (``lattice``), shuffled at random and left so (``shuffled``, numerics.reorder_every = 0), or
    shuffled and then sorted by cell once (``reordered``; no reordering within the timed steps)."""
    from ..simulation import Simulation

    every = {"lattice": None, "shuffled": 0, "reordered": 10**9}[order]
    scene = block_scene(n_particles, arch, precision, model, dimension, skin=skin, reorder_every=every)
    sim = Simulation(scene, progress=False)
    scheme, grid = sim.scheme, sim.scheme.grid
    n_material, n_wall = sim.state.n_material, sim.state.n_wall
    # compile the reordering's sort and (the lattice through an identity permutation) its gathers
    # before the timing: the order itself is set by the permutation
    if scheme.particle_order is not None:
        grid.cell_order(scheme.particle_order.order)
    scheme.permute(np.random.default_rng(0).permutation(n_material) if order != "lattice"
                   else np.arange(n_material))
    if order == "reordered":
        scheme.reorder()
    sim.run(max_steps=5)  # compile and warm up (and the list's rebuild after the permutation)
    ti.sync()
    timed = []  # (wall seconds, steps, simulated seconds) of each batch
    for _ in range(max(1, batches)):
        start_steps, start_t = sim.step_count, sim.t
        t0 = time.perf_counter()
        sim.run(max_steps=start_steps + steps)
        ti.sync()
        timed.append((time.perf_counter() - t0, sim.step_count - start_steps, sim.t - start_t))
    per_step = sorted(w / n for w, n, _ in timed)
    # the median batch: the second core's wake-ups make single batches vary by 10-30 % on a 2-core VM
    wall, done, simulated = sorted(timed, key=lambda b: b[0] / b[1])[len(timed) // 2]
    row = {"model": model, "dimension": dimension, "particles": n_material, "walls": n_wall, "steps": done,
           "spread": (per_step[-1] - per_step[0]) / (wall / done),
           "particle_steps_per_second": n_material * done / wall,
           "total_particle_steps_per_second": (n_material + n_wall) * done / wall,
           "ms_per_step": 1e3 * wall / done,
           "seconds_per_simulated_second": wall / simulated if simulated > 0 else float("nan"),
           "memory_mib": scheme.memory_bytes() / 2**20, "skin": scene.numerics.neighbour_skin, "order": order,
           "list_builds": grid.rebuilds / max(grid.builds, 1), "pair_passes": _pair_passes(scheme)}
    if grid.verlet:
        listed = grid.neighbour_count.to_numpy()
        row["neighbours"] = float(listed[:n_material].mean())  # within the support + skin
        row["pair_interactions_per_second"] = row["pair_passes"] * float(listed.sum()) * done / wall
    if counts:
        row["launches"], row["host_reads"] = _launches_and_reads(sim, max(3, min(steps, 20)))
    if compare:
        sweep = DensitySweep(scheme)
        sweep.run()
        ti.sync()
        reps = max(3, steps)
        t0 = time.perf_counter()
        for _ in range(reps):
            sweep.run()
        ti.sync()
        row["sweep_ms"] = 1e3 * (time.perf_counter() - t0) / reps
    sim.profiler.enabled = True
    sim.profiler.reset()
    sim.run(max_steps=sim.step_count + max(5, steps // 5))
    shares = sim.profiler.by_category()
    total = sum(shares.values()) or 1.0
    row["shares"] = {k: v / total for k, v in shares.items() if v > 0}
    return row


DEFAULT_SIZES = {2: [1_000, 10_000, 40_000, 160_000], 3: [10_000, 40_000, 150_000]}


def _print_row(r: dict, compare: bool) -> None:
    breakdown = " ".join(f"{k} {100 * v:.0f}%" for k, v in sorted(r["shares"].items(), key=lambda kv: -kv[1]))
    rebuilt = f"{100 * r['list_builds']:.0f}%" if r["skin"] > 0 else "-"
    nbrs = f"{r['neighbours']:.1f}" if "neighbours" in r else "-"
    pairs = f"{r['pair_interactions_per_second'] / 1e6:.0f}" if "pair_interactions_per_second" in r else "-"
    counted = (f"{r['launches']:.1f}/{r['host_reads']:.1f}" if r.get("launches") is not None else "-")
    ceiling = f" {r['sweep_ms']:>8.3f} {r['ms_per_step'] / r['sweep_ms']:>6.1f}" if compare else ""
    print(f"{r['particles']:>9} {r['walls']:>7} {r['skin']:>5.2f} {r['order']:>9} "
          f"{r['particle_steps_per_second'] / 1e6:>8.3f} {r['total_particle_steps_per_second'] / 1e6:>7.3f} "
          f"{r['ms_per_step']:>9.2f} {100 * r['spread']:>6.0f}% {r['seconds_per_simulated_second']:>10.1f} "
          f"{r['memory_mib']:>7.1f} "
          f"{nbrs:>6} {r['pair_passes']:>6} {pairs:>8} {counted:>11} {rebuilt:>7}{ceiling}  {breakdown}", flush=True)


def main(args) -> int:
    runtime.init(args.arch, args.precision)
    compare = getattr(args, "compare", False)
    for model in getattr(args, "models", None) or ["mu_i"]:
        for dim in getattr(args, "dims", None) or [2]:
            scene = block_scene(FIXED_COST_SIZE, args.arch, args.precision, model, dim)
            print(f"{model}, {dim}D, {args.arch}/{args.precision}, dp = {1e3 * scene.numerics.particle_spacing:g} mm, "
                  f"h/dp = {scene.numerics.smoothing_length_ratio:g}, {scene.numerics.smoothing_function}, "
                  f"{scene.numerics.integrator}, the median of {BATCHES} batches of {args.steps} timed steps")
            print(f"{'material':>9} {'walls':>7} {'skin':>5} {'order':>9} {'Mmat/s':>8} {'Mall/s':>7} {'ms/step':>9} "
                  f"{'spread':>7} {'s/sim s':>10} {'MiB':>7} {'nbrs':>6} {'passes':>6} {'Mpairs/s':>8} {'launch/read':>11} "
                  f"{'rebuilt':>7}" + (f" {'sweep ms':>8} {'ratio':>6}" if compare else "") + "  breakdown")
            rows = []
            for size in args.sizes or DEFAULT_SIZES[dim]:
                for skin, order in [(k, o) for k in getattr(args, "skins", None) or [None]
                                    for o in getattr(args, "orders", None) or ["lattice"]]:
                    rows.append(measure(size, args.steps, args.arch, args.precision, skin, order, model, dim, compare))
                    _print_row(rows[-1], compare)
            tiny = measure(FIXED_COST_SIZE, max(args.steps, 200), args.arch, args.precision, model=model,
                           dimension=dim, counts=False)
            small = measure(1_000, max(args.steps, 200), args.arch, args.precision, model=model, dimension=dim,
                            counts=False)
            # the step as fixed + per-particle cost through the two sizes: the fixed part is what a step
            # costs however few particles it moves (launches, host reads, Python); the small block
            # itself still moves a tenth of the 1k block's particles, so it bounds the fixed cost above
            per_particle = (small["ms_per_step"] - tiny["ms_per_step"]) / (small["particles"] - tiny["particles"])
            fixed = tiny["ms_per_step"] - per_particle * tiny["particles"]
            # (in 3D the small block is mostly walls, and the line through the two can fall below zero)
            intercept = (f"{fixed:.3f} ms = {100 * fixed / small['ms_per_step']:.0f} %" if fixed > 0.0
                         else "below what the two blocks resolve (intercept < 0)")
            print(f"fixed per-step cost: {intercept} of a "
                  f"{small['particles']}-particle step ({small['ms_per_step']:.3f} ms), from a "
                  f"{tiny['particles']}-particle block ({tiny['ms_per_step']:.3f} ms = "
                  f"{100 * tiny['ms_per_step'] / small['ms_per_step']:.0f} %, an upper bound)\n", flush=True)
    return 0
