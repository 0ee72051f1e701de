"""The ``validate`` command: pick the case from the registry (validation/__init__.py), run (or
reuse) its scenes' output, and let the case's module check it."""
from pathlib import Path

from ..config import load_scene
from ..output import read_frame, read_series
from ..paths import config_path
from . import CASES
from .table import RUN_FILE, record_run


def validate(args) -> int:
    """0 if the case passes its acceptance, 1 if not."""
    case = CASES[args.case]
    module = case.module()
    if args.config:
        paths = [Path(args.config)]
    else:
        paths = _case_paths(case.folder, case.patterns, args) if case.patterns else []
    base = Path(args.out) if args.out else Path("output/validate") / case.name.replace("-", "_")
    prepare = module.prepare(args) if hasattr(module, "prepare") else None
    return 0 if module.check(case, _each_case(paths, base, args, prepare), base, args) else 1


def _frames(scene, out: Path, reuse: bool, quiet: bool, prepare=None, overrides=(), resume: bool = False):
    """Frames of ``scene`` in ``out``: run it first unless ``reuse``; ``prepare(sim)`` may set
    the initial state before the run. With ``resume`` a run that was interrupted (a checkpoint but
    no run.json) continues from its checkpoint, a finished one is reused, and one never started
    runs."""
    started = (Path(out) / "checkpoint.npz").exists()
    if resume and (Path(out) / RUN_FILE).exists():
        reuse = True
    if not reuse:
        from ..simulation import Simulation
        sim = Simulation(scene, out_dir=out, progress=not quiet)
        if resume and started:
            sim.resume()
            print(f"{scene.name}: resumed at t = {sim.t:.6g} s, step {sim.step_count}")
        elif prepare is not None:
            prepare(sim)
        summary = sim.run()
        print(f"ran {scene.name}: {summary.steps} steps, {summary.wall_seconds:.1f} s wall, "
              f"{summary.particle_steps_per_second:.3g} particle-steps/s")
        record_run(out, summary, sim.state.n_material, overrides,
                   resumed_at_step=sim.step_count - summary.steps if resume and started else None)
    series = read_series(out)
    return [t for t, _ in series], [read_frame(p) for _, p in series]


RESOLUTIONS = {"coarse": "_coarse", "cpu": "_cpu", "paper": ""}  # --resolution: the scene files' suffix


def _case_paths(folder: str, pattern: str, args):
    """The scene files of a validation family: ``pattern`` (or a list of them) names the coarse CPU variants
    (``*_coarse.yaml``); ``--resolution cpu`` picks the ``*_cpu.yaml`` variants (CPU-sized scenes
    finer than the coarse ones, or with a deeper stream) and ``paper`` the paper-resolution files instead; ``--cases`` filters by stem,
    or by its end without the suffix (``a2_75``, ``case1``, ``cylinder``)."""
    patterns = [pattern] if isinstance(pattern, str) else list(pattern)
    suffix = RESOLUTIONS[getattr(args, "resolution", "coarse")]
    others = [s for s in RESOLUTIONS.values() if s and s != suffix]
    patterns = [p.replace("_coarse", suffix) for p in patterns]
    known = sorted(p for pat in patterns for p in config_path(folder).glob(pat)
                   if not any(p.stem.endswith(other) for other in others))
    if not known:
        raise FileNotFoundError(f"no {getattr(args, 'resolution', 'coarse')} scenes for this case "
                                f"({', '.join(patterns)} in configs/{folder})")
    if not args.cases:
        return known
    wanted = set(args.cases)

    def matches(stem: str, name: str) -> bool:
        base = stem[: len(stem) - len(suffix)] if suffix and stem.endswith(suffix) else stem
        return name in (stem, base) or base.endswith("_" + name)

    paths = [p for p in known if any(matches(p.stem, w) for w in wanted)]
    if not paths:
        raise FileNotFoundError(f"no case among {sorted(args.cases)}; known: {', '.join(p.stem for p in known)}")
    return paths


def _each_case(paths, base: Path, args, prepare=None):
    """(scene, its output folder under ``base``, frame times, frames) of each scene file, run
    first unless ``--reuse`` (``prepare(sim)`` sets the initial state before the run)."""
    for path in paths:
        scene = load_scene(path, args.set)
        out = base / scene.name
        times, frames = _frames(scene, out, args.reuse, args.quiet, prepare, args.set or (),
                                getattr(args, "resume", False))
        yield scene, out, times, frames
