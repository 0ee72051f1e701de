"""Accuracy against cost (``taichi-granular bench accuracy [--quick]``).

Sweeps cases that have a reference -- the mu(I) inclined plane (analytic profile [M56]), the
mu(I) column collapse at a = 0.55 and 2.75 (run-out scaling of Lube et al. 2004) and the
hypoplastic inclined plane (the Bagnold-type profile of MODEL.md section 2) -- over

- resolution: a ladder of particle spacings with the config's numerics, from which the observed
  convergence order p is fitted (error ~ dp^p, least squares in log-log);
- one option at a time, at one rung of the ladder (the case's ``option_level``): smoothing
  function (Wendland C2, Wendland C6, cubic spline), kernel gradient correction (matrix /
  none), integrator (symplectic Verlet / predictor-corrector), precision (f64 / f32),
  artificial viscosity (alpha 0 / 0.05) and CFL number.

Every run happens in a fresh process (precision is global in Taichi, and the process's peak
memory is then the run's own) and reports: its error against the reference, the wall time of
its steps (the first step, which compiles the kernels, is timed apart as ``compile_seconds``
and the steps' time extrapolated over it), time steps taken, particle-steps per second,
seconds per simulated second, peak resident memory of the process and memory of its fields,
and the share of each stage category (neighbours, density, eos, rheology, forces, walls,
integration) from the stage profiler (profiling.py, the one behind ``run --profile``), over a
separately profiled stretch of steps after the run (profiling synchronises around every stage).

Outputs (``--out``): ``accuracy.csv`` (every run), ``accuracy.png`` (error against wall time,
log-log, one colour per case, each case's Pareto front filled and joined) and ``accuracy.md``
(the tables docs/accuracy.md includes between its ``accuracy-study`` markers; the full study rewrites
that part of docs/accuracy.md, ``--quick`` never does).
"""
from __future__ import annotations

import csv
import io
import math
import time
from dataclasses import asdict, dataclass, field, replace
from functools import lru_cache
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

from ..physics.stage import CATEGORIES

README_START = "<!-- accuracy-study:start (written by taichi-granular bench accuracy) -->"
README_END = "<!-- accuracy-study:end -->"

# axis -> (option name, overrides) in the order they are tried; the config's own choice is the baseline
AXES: Dict[str, List[Tuple[str, Tuple[str, ...]]]] = {
    "smoothing": [(k, (f"numerics.smoothing_function={k}",)) for k in ("wendland_c2", "wendland_c6", "cubic_spline")],
    "gradient_correction": [(k, (f"numerics.gradient_correction={k}",)) for k in ("matrix", "none")],
    "integrator": [(k, (f"numerics.integrator={k}",)) for k in ("symplectic_verlet", "predictor_corrector")],
    "precision": [(k, (f"precision={k}",)) for k in ("f64", "f32")],
    "artificial_viscosity": [(f"alpha {a:g}", (f"numerics.artificial_viscosity.alpha={a}",)) for a in (0.0, 0.05)],
    "cfl": [(f"{c:g}", (f"numerics.cfl={c}",)) for c in (0.15, 0.3, 0.5)],
    "viscosity": [(k, (f"numerics.viscosity={k}",)) for k in ("explicit", "implicit")],  # mu(I) only
}
MU_I_AXES = tuple(AXES)
OTHER_AXES = tuple(a for a in AXES if a != "viscosity")


@dataclass(frozen=True)
class Case:
    """One reference case: a config, the overrides that make it a study case, a ladder of
    particle spacings and how its error is measured."""
    name: str
    model: str
    config: str  # under configs/
    reference: str
    error_name: str
    measure: str  # "inclined_plane" | "collapse"
    spacings: Tuple[float, ...]  # m, coarse to fine
    end_time: float  # s (a collapse stops earlier once at rest)
    output_interval: float  # s
    overrides: Tuple[str, ...] = ()
    option_level: int = 0  # index in ``spacings`` of the one-option-at-a-time runs
    window: float = 0.0  # inclined plane: the error is averaged over the last ``window`` seconds
    # the option values tried besides the config's own (a case may leave out what it cannot run)
    axes: Tuple[str, ...] = MU_I_AXES

    def label(self) -> str:
        return self.name.replace("_", " ")


def _mu_i_plane(spacings, end_time, window, option_level=0):
    # 0.1 m long instead of 0.2 m (periodic: the uniform flow does not see the length); every
    # spacing divides the 0.1 m layer and the length
    return Case("mu_i_inclined_plane", "mu_i", "mu_i/inclined_plane.yaml", "[M56] analytic profile",
                "velocity relative L2", "inclined_plane", spacings, end_time, 0.05,
                ("domain.upper=[0.1, 0.3]", "particles.0.upper=[0.1, 0.1]"), option_level, window)


def _collapse(aspect, config, spacings, end_time, option_level=0):
    # the floor's ghost rows need 3 h below y = 0 at the coarsest spacing
    depth = -3.0 * 1.3 * max(spacings)
    return Case(f"mu_i_collapse_a{aspect}", "mu_i", config, "Lube et al. (2004) run-out", "run-out relative",
                "collapse", spacings, end_time, 0.01, (f"domain.lower.1={depth:.4f}",), option_level)


def _hypoplastic_plane(spacings, end_time, window, option_level=0):
    return Case("hypoplastic_inclined_plane", "hypoplastic", "hypoplastic/inclined_plane.yaml",
                "Bagnold-type profile (MODEL.md 2)", "velocity relative L2", "inclined_plane", spacings, end_time,
                0.025, (f"domain.lower=[0.0, {-3.0 * 1.3 * max(spacings):.4f}]",), option_level, window,
                OTHER_AXES)


# the full study (what the README quotes) and the quick one (a few minutes on two CPU cores)
FULL = (
    _mu_i_plane((0.01, 0.00625, 0.005, 0.003125), 3.0, 1.0, option_level=2),
    # the steady state: 3 s from the analytic profile do not show a slow drift of the layer
    # (measured: Wendland C6 looked better at 3 s and compacted the layer by 7 % by 25 s)
    replace(_mu_i_plane((0.005,), 30.0, 5.0), name="mu_i_inclined_plane_steady", axes=("smoothing", "viscosity")),
    _collapse("0_55", "mu_i/collapse_a0_55.yaml", (0.0088, 0.0066, 0.0044), 0.4, option_level=1),
    _collapse("2_75", "mu_i/collapse_a2_75.yaml", (0.01944, 0.01458, 0.00972), 0.8, option_level=1),
    _hypoplastic_plane((0.004, 0.0025, 0.002), 0.5, 0.25, option_level=0),
)
QUICK = (  # measured: 11 plane runs ~2 min, the two collapses ~40 s (their options took 7 min more)
    _mu_i_plane((0.01, 0.00625, 0.005), 1.0, 0.5),
    replace(_collapse("0_55", "mu_i/collapse_a0_55.yaml", (0.0088,), 0.4), axes=()),
    replace(_collapse("2_75", "mu_i/collapse_a2_75.yaml", (0.01944,), 0.8), axes=()),
)


# ---- one run (in a child process) ---------------------------------------------------------------

def _error(case: Case, scene, times, frames, diagnostics) -> Tuple[float, str]:
    """(error, a note) of a run against the case's reference."""
    if case.measure == "inclined_plane":
        from ..validation import inclined_plane
        result = inclined_plane.evaluate(scene, times, frames, window=case.window)
        return result.velocity_error, f"normal stress {100 * result.pressure_error:.1f} %"
    from ..validation import column_collapse
    result = column_collapse.evaluate(scene, times, frames, diagnostics)
    note = f"a {result.aspect_ratio:.2f}, run-out {result.runout:.3f} vs {result.runout_reference:.3f}"
    if result.front_stop_time is None:
        note += ", front still moving at the end"
    return abs(result.error), note


@dataclass
class CaseRun:
    """A case run to its end time (a collapse: or to rest), frames at every output time."""
    scene: Any
    sim: Any
    times: List[float]
    frames: List[dict]
    diagnostics: List[dict]
    wall_seconds: float  # stepping only, the first step's share estimated (it compiles)
    compile_seconds: float


def run_case(case: Case, overrides: Sequence[str]) -> CaseRun:
    """Run ``case`` with ``overrides`` in this process (its runtime initialised by the Simulation)."""
    import taichi as ti

    from ..config import load_scene
    from ..paths import config_path
    from ..simulation import Simulation
    from ..validation.inclined_plane import impose_analytic_velocity

    scene = load_scene(config_path(case.config), [*case.overrides, *overrides,
                                                 f"run.end_time={case.end_time}",
                                                 f"run.output_interval={case.output_interval}"])
    sim = Simulation(scene, progress=False)
    if case.measure == "inclined_plane":
        impose_analytic_velocity(sim)  # the steady state is the same from rest, ~15 s further ([M])
    n = sim.state.n_material
    is_wall = np.r_[np.zeros(n, int), np.ones(sim.state.n_wall, int)]
    start = time.perf_counter()
    sim.run(end_time=0.0)
    frames, times, diagnostics = [{**sim.scheme.snapshot(), "is_wall": is_wall}], [0.0], []
    sim.run(max_steps=1)  # compiles the step's kernels
    ti.sync()
    compile_seconds = time.perf_counter() - start
    stepping = 0.0
    while sim.t < case.end_time - 1e-9:
        tick = time.perf_counter()
        sim.run(end_time=min(case.end_time, (round(sim.t / case.output_interval) + 1) * case.output_interval))
        ti.sync()
        stepping += time.perf_counter() - tick
        times.append(sim.t)
        frames.append({**sim.scheme.snapshot(), "is_wall": is_wall})
        diagnostics.append(sim.last_diagnostics)
        if case.measure == "collapse" and sim.at_rest():
            break
    steps = sim.step_count
    wall = stepping * steps / max(1, steps - 1)  # the first step's share, timed with the compilation
    return CaseRun(scene, sim, times, frames, diagnostics, wall, compile_seconds)


def measure(case: Case, overrides: Sequence[str], profile_steps: int = 200) -> dict:
    """Run ``case`` with ``overrides`` in this process; the row of the CSV."""
    import resource

    done = run_case(case, overrides)
    scene, sim, times, frames, diagnostics = done.scene, done.sim, done.times, done.frames, done.diagnostics
    steps, wall, compile_seconds = sim.step_count, done.wall_seconds, done.compile_seconds
    n = sim.state.n_material
    error, note = _error(case, scene, times, frames, diagnostics)
    sim.profiler.enabled = True
    sim.profiler.reset()
    sim.run(end_time=sim.t + 1e3, max_steps=steps + profile_steps)
    shares = sim.profiler.by_category()
    total = sum(shares.values()) or 1.0
    numerics = scene.numerics
    return {
        "case": case.name, "model": case.model, "dp": numerics.particle_spacing, "particles": n,
        "precision": scene.precision, "smoothing": numerics.smoothing_function,
        "gradient_correction": numerics.gradient_correction, "integrator": numerics.integrator,
        "alpha": numerics.artificial_viscosity.alpha, "cfl": numerics.cfl,
        "error": error, "note": note, "simulated_time": times[-1],
        "steps": steps, "wall_seconds": wall, "compile_seconds": compile_seconds,
        "particle_steps_per_second": n * steps / wall if wall > 0 else float("nan"),
        "seconds_per_simulated_second": wall / times[-1] if times[-1] > 0 else float("nan"),
        "peak_rss_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
        "field_mib": sim.scheme.memory_bytes() / 2**20,
        **{f"share_{c}": shares.get(c, 0.0) / total for c in CATEGORIES},
    }


def measure_job(payload: dict) -> dict:
    """One run as a job of sweep/engine.py (in a process of its own): its row of the CSV."""
    case = Case(**{k: tuple(v) if isinstance(v, list) else v for k, v in payload["case"].items()})
    return measure(case, payload["overrides"])


# ---- the sweep -----------------------------------------------------------------------------------

@dataclass
class Run:
    case: Case
    axis: str  # "resolution" or an option axis
    option: str
    dp: float  # particle spacing [m]
    overrides: Tuple[str, ...]
    row: dict = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        return "error" in self.row and math.isfinite(self.row["error"])


@lru_cache(maxsize=None)
def baseline_option(case: Case, axis: str) -> str:
    """The option a case's config itself uses on ``axis``."""
    import yaml

    from ..config import apply_overrides, scene_from_dict
    from ..paths import config_path

    data = apply_overrides(yaml.safe_load(config_path(case.config).read_text()), case.overrides)
    scene = scene_from_dict(data)
    numerics = scene.numerics
    return {"smoothing": numerics.smoothing_function, "gradient_correction": numerics.gradient_correction,
            "integrator": numerics.integrator, "precision": data.get("precision", "f64"),
            "artificial_viscosity": f"alpha {numerics.artificial_viscosity.alpha:g}", "cfl": f"{numerics.cfl:g}",
            "viscosity": "implicit" if scene.numerics.implicit_viscosity else "explicit"}[axis]


def plan(cases: Sequence[Case]) -> List[Run]:
    """The resolution ladder of every case, then each option other than the config's own at the
    case's option level."""
    runs = []
    for case in cases:
        for dp in case.spacings:
            runs.append(Run(case, "resolution", f"dp {1e3 * dp:g} mm", dp, (f"numerics.particle_spacing={dp}",)))
        dp = case.spacings[case.option_level]
        for axis in case.axes:
            base = baseline_option(case, axis)
            for option, overrides in AXES[axis]:
                if option != base:
                    runs.append(Run(case, axis, option, dp, (f"numerics.particle_spacing={dp}", *overrides)))
    return runs


def job(run: Run, index: int):
    from ..sweep.engine import Job
    return Job(f"{index:03d}", "taichi_granular.bench.accuracy:measure_job",
               {"case": asdict(run.case), "overrides": list(run.overrides)})


def row_of(result: dict) -> dict:
    """A job's result as a CSV row: a failed run has error NaN and its message in ``note``."""
    if result.get("status") != "ok":
        return {"error": float("nan"), "note": f"failed: {result.get('error', '')[:300]}"}
    return {k: v for k, v in result.items() if k not in ("status", "job_seconds")}


# ---- analysis ------------------------------------------------------------------------------------

def pareto_front(points: Sequence[Tuple[float, float]]) -> List[int]:
    """Indices of the points no other point beats in both coordinates (cost, error)."""
    front = []
    for i, (c, e) in enumerate(points):
        if not any((c2 <= c and e2 <= e) and (c2 < c or e2 < e) for c2, e2 in points):
            front.append(i)
    return front


def convergence_order(spacings: Sequence[float], errors: Sequence[float]) -> float:
    """p of error ~ dp^p, least squares of log(error) on log(dp); NaN with fewer than 2 points."""
    pairs = [(dp, e) for dp, e in zip(spacings, errors) if e > 0 and math.isfinite(e)]
    if len(pairs) < 2:
        return float("nan")
    x, y = np.log([p[0] for p in pairs]), np.log([p[1] for p in pairs])
    return float(np.polyfit(x, y, 1)[0])


def _runs_of(runs, case):
    return [r for r in runs if r.case is case]


def _option_base(runs, case) -> Optional[Run]:
    """The resolution run at the option level: the baseline the options are compared with."""
    dp = case.spacings[case.option_level]
    return next((r for r in _runs_of(runs, case) if r.axis == "resolution" and r.dp == dp), None)


def option_ratios(runs: Sequence[Run], case: Case) -> Dict[Tuple[str, str], Optional[Tuple[float, float]]]:
    """(axis, option) -> (error ratio, cost ratio) against the case's baseline run at its
    option level; None where the option's run failed."""
    base = _option_base(runs, case)
    ratios = {}
    if base is None or not base.ok:
        return ratios
    for r in _runs_of(runs, case):
        if r.axis != "resolution":
            ratios[(r.axis, r.option)] = (r.row["error"] / base.row["error"],
                                          r.row["wall_seconds"] / base.row["wall_seconds"]) if r.ok else None
    return ratios


def recommendations(runs: Sequence[Run], cases: Sequence[Case], model: str) -> List[str]:
    """Per option axis, for the cases of ``model``: the option to prefer over the configs' own
    choice, or keep it. An option is preferred when, in the geometric mean over the model's
    cases, it lowers the error by more than 10 % for less than 1.5 times the cost, or keeps it
    within 10 % for less than 0.8 times the cost (identical runs differed by up to 16 % in wall
    time beside another job, measured), and it ran in every case and raised no case's error by
    10 % or more: a default must not break a case it was not chosen for."""
    own_cases = [c for c in cases if c.model == model]
    per_case = [option_ratios(runs, c) for c in own_cases]
    lines = []
    for axis in dict.fromkeys(a for c in own_cases for a in c.axes):
        owns = sorted({baseline_option(c, axis) for c in own_cases if axis in c.axes})
        options = dict.fromkeys(o for ratios in per_case for (a, o) in ratios if a == axis)
        best = None
        for option in options:
            values = [ratios.get((axis, option)) for ratios in per_case if (axis, option) in ratios]
            if not values or any(v is None for v in values):
                continue
            e = math.exp(np.mean([math.log(v[0]) for v in values]))
            c = math.exp(np.mean([math.log(v[1]) for v in values]))
            worst = max(v[0] for v in values)
            if ((e < 0.9 and c < 1.5) or (e < 1.1 and c < 0.8)) and worst < 1.1 and (best is None or e * c < best[0]):
                best = (e * c, option, e, c, len(values))
        if best is None:
            lines.append(f"{axis}: keep {'/'.join(owns)}")
        else:
            _, option, e, c, n = best
            lines.append(f"{axis}: {option} instead of {'/'.join(owns)} (error x{e:.2f}, cost x{c:.2f}, "
                         f"geometric mean of {n} case{'s' if n > 1 else ''})")
    return lines


def _pct(x: float) -> str:
    return f"{100 * x:.2f} %" if math.isfinite(x) else "failed"


def markdown(runs: Sequence[Run], cases: Sequence[Case], title: str) -> str:
    out = io.StringIO()
    out.write(f"{title}\n\n")
    out.write("| case | reference | error | convergence order p (error ~ dp^p) | runs on the Pareto front |\n"
              "|---|---|---|---|---|\n")
    for case in cases:
        own = [r for r in _runs_of(runs, case) if r.ok]
        res = [r for r in own if r.axis == "resolution"]
        p = convergence_order([r.row["dp"] for r in res], [r.row["error"] for r in res])
        front = pareto_front([(r.row["wall_seconds"], r.row["error"]) for r in own])
        names = ", ".join(f"{own[i].option}" + ("" if own[i].axis == "resolution" else f" ({own[i].axis})")
                          for i in sorted(front, key=lambda i: own[i].row["wall_seconds"]))
        p_text = f"{p:.2f} ({len(res)} levels)" if math.isfinite(p) else "-"
        out.write(f"| {case.label()} | {case.reference} | {case.error_name} | {p_text} | {names} |\n")
    out.write("\n| case | varied | option | dp mm | particles | error | note | wall s | cost factor | steps | "
              "particle-steps/s | s per sim s | peak MiB | fields MiB | top stages |\n"
              "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n")
    for case in cases:
        base = _option_base(runs, case)
        for r in _runs_of(runs, case):
            row = r.row
            if not r.ok and "wall_seconds" not in row:
                out.write(f"| {case.label()} | {r.axis} | {r.option} | | | failed | {row.get('note', '')} "
                          f"| | | | | | | | |\n")
                continue
            factor = "" if r.axis == "resolution" or base is None or not base.ok else \
                f"x{row['wall_seconds'] / base.row['wall_seconds']:.2f}"
            top = sorted(((row[f"share_{c}"], c) for c in CATEGORIES), reverse=True)[:3]
            stages = ", ".join(f"{c} {100 * s:.0f} %" for s, c in top if s > 0)
            out.write(f"| {case.label()} | {r.axis} | {r.option} | {1e3 * row['dp']:g} | {row['particles']} | "
                      f"{_pct(row['error'])} | {row['note']} | {row['wall_seconds']:.1f} | {factor} | {row['steps']} | "
                      f"{row['particle_steps_per_second']:.3g} | {row['seconds_per_simulated_second']:.3g} | "
                      f"{row['peak_rss_mib']:.0f} | {row['field_mib']:.2f} | {stages} |\n")
    out.write("\nRecommended per model, from the option runs above: an option replaces the configs' choice when, "
              "in the geometric mean over the model's cases, it lowers the error by more than 10 % for less than "
              "1.5 times the cost, or keeps it within 10 % for less than 0.8 times the cost, and it ran in every "
              "case and raised no case's error by 10 % or more:\n\n")
    for model in dict.fromkeys(c.model for c in cases):
        lines = recommendations(runs, cases, model)
        out.write(f"- {model}: " + ("; ".join(lines) if lines else "no option runs") + "\n")
    return out.getvalue()


COLUMNS = ("case", "model", "axis", "option", "dp", "particles", "precision", "smoothing", "gradient_correction",
           "integrator", "alpha", "cfl", "error", "note", "simulated_time", "steps", "wall_seconds",
           "compile_seconds", "particle_steps_per_second", "seconds_per_simulated_second", "peak_rss_mib",
           "field_mib", *(f"share_{c}" for c in CATEGORIES))


def write_outputs(runs: Sequence[Run], cases: Sequence[Case], out: Path, title: str) -> Dict[str, Path]:
    from ..output import atomic_write_text
    from ..render.frames import write_png
    from ..render.plot import plot_pareto

    buf = io.StringIO()
    writer = csv.DictWriter(buf, COLUMNS, extrasaction="ignore")
    writer.writeheader()
    for r in runs:
        writer.writerow({"case": r.case.name, "model": r.case.model, "axis": r.axis, "option": r.option, **r.row})
    paths = {"csv": out / "accuracy.csv", "png": out / "accuracy.png", "md": out / "accuracy.md"}
    atomic_write_text(paths["csv"], buf.getvalue())
    series = []
    for case in cases:
        own = [r for r in _runs_of(runs, case) if r.ok and r.row["error"] > 0]
        points = [(r.row["wall_seconds"], r.row["error"]) for r in own]
        if points:
            series.append((case.label(), points, pareto_front(points)))
    if series:
        write_png(paths["png"], plot_pareto(series, "wall time s", "error", "error against wall time"))
    atomic_write_text(paths["md"], markdown(runs, cases, title))
    return paths


def update_readme(readme: Path, table: str) -> bool:
    """Replace the text between the README's accuracy-study markers by ``table``."""
    from ..output import atomic_write_text

    text = readme.read_text()
    if README_START not in text or README_END not in text:
        return False
    head, rest = text.split(README_START, 1)
    _, tail = rest.split(README_END, 1)
    atomic_write_text(readme, f"{head}{README_START}\n{table}{README_END}{tail}")
    return True


def read_rows(path: Path) -> Dict[Tuple[str, str, str], dict]:
    """Rows of an earlier ``accuracy.csv`` that ran (error finite), by (case, axis, option), with
    their numbers as numbers."""
    if not path.exists():
        return {}
    rows = {}
    with open(path) as fh:
        for row in csv.DictReader(fh):
            parsed = {}
            for key, value in row.items():
                try:
                    parsed[key] = int(value) if key in ("particles", "steps") else float(value)
                except (TypeError, ValueError):
                    parsed[key] = value
            if isinstance(parsed.get("error"), float) and math.isfinite(parsed["error"]):
                rows[(row["case"], row["axis"], row["option"])] = parsed
    return rows


def sweep(cases: Sequence[Case], out: Path, timeout: float = 3600.0, echo=print, reuse: bool = False,
          workers: int = 0, scheduler: Optional[str] = None) -> List[Run]:
    """Every run of ``plan(cases)``, each a job of sweep/engine.py (its own process): one after
    another here by default, since the study measures wall time (``workers``/``scheduler``: on
    Dask, when the costs are not what is wanted); with ``reuse`` the runs that succeeded in
    ``out``'s CSV are taken from it (an interrupted or partly failed study continues there)."""
    from ..sweep.engine import run_jobs

    runs = plan(cases)
    earlier = read_rows(out / "accuracy.csv") if reuse else {}
    todo = {}
    for k, run in enumerate(runs):
        key = (run.case.name, run.axis, run.option)
        if key in earlier:
            run.row = earlier[key]
        else:
            todo[job(run, k).id] = run
    echo(f"{len(runs)} runs, one process each, {len(runs) - len(todo)} kept from {out / 'accuracy.csv'} -> {out}")

    def report(done_job, result):
        run = todo[done_job.id]
        run.row = row_of(result)
        echo(f"[{done_job.id}] {run.case.name:<28} {run.axis:<20} {run.option:<20} "
             f"error {_pct(run.row.get('error', float('nan'))):>9}  wall {run.row.get('wall_seconds', float('nan')):8.1f} s"
             f"  ({result.get('job_seconds', float('nan')):.0f} s total)  {run.row.get('note', '')}")

    run_jobs([job(run, int(i)) for i, run in todo.items()], workers=workers, scheduler=scheduler, timeout=timeout,
             on_result=report, quiet=True)
    return runs


def study(cases: Sequence[Case], out: Path, title: str, timeout: float = 3600.0, readme: Optional[Path] = None,
          echo=print, reuse: bool = False, workers: int = 0,
          scheduler: Optional[str] = None) -> Tuple[List[Run], Dict[str, Path]]:
    """Run the sweep of ``cases`` (``reuse``: keep the successful runs of ``out``'s CSV), write
    the CSV, chart and tables into ``out``, and rewrite the study section of ``readme`` if given."""
    runs = sweep(cases, out, timeout, echo, reuse, workers, scheduler)
    title += f" ({len(runs)} runs, {sum(r.row.get('wall_seconds', 0.0) for r in runs):.0f} s of stepping)"
    paths = write_outputs(runs, cases, out, title)
    if readme is not None and readme.exists() and update_readme(readme, paths["md"].read_text()):
        echo(f"README section rewritten: {readme}")
    return runs, paths


def main(args) -> int:
    from ..paths import REPO, SOURCE_CHECKOUT

    cases = QUICK if args.quick else FULL
    if args.cases:
        cases = tuple(c for c in cases if any(key in c.name for key in args.cases))
    # the repository's renders/ and README only in a source checkout (never inside an installed package)
    default = (Path("output/bench/accuracy_quick") if args.quick else
               REPO / "renders" / "accuracy" if SOURCE_CHECKOUT else Path("output/bench/accuracy"))
    out = Path(args.out) if args.out else default
    whole = SOURCE_CHECKOUT and not args.quick and not args.cases and not args.no_readme
    runs, paths = study(cases, out, "Quick study" if args.quick else "Full study", args.timeout,
                        REPO / "docs" / "accuracy.md" if whole else None, reuse=args.reuse,
                        workers=args.workers or 0, scheduler=args.scheduler)
    print(paths["md"].read_text())
    print("outputs: " + ", ".join(str(p) for p in paths.values() if p.exists()))
    return 0 if all(r.ok for r in runs) else 1
