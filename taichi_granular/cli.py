"""The ``taichi-granular`` command: parsing and printing only; the work is in the modules it calls."""
from __future__ import annotations

import argparse
import sys
import traceback
from pathlib import Path

from .config import ConfigError, load_scene

DESCRIPTION = """Dense granular flows with SPH in Taichi: run a YAML scene (frames, VTU particle files,
diagnostics), resume it from its checkpoint, describe what it will compute, re-render its frames,
run the validation cases and the benchmarks. A scene is a file path, or the name of a bundled
scene such as mu_i/collapse_a0_90.yaml."""

EPILOG = """exit codes: 0 done; 2 a scene or input error (the message names the key); 3 a run stopped by
a guard (NaN, a particle outside the domain, a failed solve: its failure.npz written); 130
interrupted (the state at that step written); 1 an internal error (a bug: please report it with
--debug's traceback)."""


def _default_out(scene) -> Path:
    return Path(scene.run.output_dir) if scene.run.output_dir else Path("output") / scene.name


def cmd_run(args) -> int:
    from .simulation import Simulation

    scene = load_scene(args.scene, args.set)
    out = Path(args.out) if args.out else _default_out(scene)
    sim = Simulation(scene, out_dir=out, profile=args.profile, progress=not args.quiet)
    print(f"{scene.name}: {sim.state.n_material} material + {sim.state.n_wall} wall particles, "
          f"{scene.dimension}D, {scene.arch}/{scene.precision}; output -> {out}")
    summary = sim.run(end_time=args.end_time)
    print(f"done: t = {summary.time:.4g} s in {summary.steps} steps, {summary.wall_seconds:.1f} s wall, "
          f"{summary.particle_steps_per_second:.3g} particle-steps/s, {summary.frames} frames")
    if args.profile:
        from .profiling import compiled_kernels
        print(sim.profiler.table())
        if sim.scheme.viscous_solve is not None:
            print(sim.scheme.viscous_solve.summary())
        kernels = compiled_kernels()
        print(f"compiled kernels ({len(kernels)}): " + ", ".join(k.removeprefix("taichi_granular.") for k in kernels))
    return 0


def cmd_resume(args) -> int:
    from .output import load_run_scene
    from .simulation import Simulation

    out = Path(args.output_dir)
    scene = load_run_scene(out, args.set)
    sim = Simulation(scene, out_dir=out, progress=not args.quiet)
    sim.resume()
    print(f"{scene.name}: resumed at t = {sim.t:.6g} s, step {sim.step_count}; output -> {out}")
    summary = sim.run(end_time=args.end_time)
    whole = "" if summary.total_wall_seconds is None else f" ({summary.total_wall_seconds:.1f} s over the whole run)"
    print(f"done: t = {summary.time:.4g} s in {summary.steps} more steps, {summary.wall_seconds:.1f} s wall{whole}, "
          f"{summary.particle_steps_per_second:.3g} particle-steps/s, {summary.frames} frames")
    return 0


def cmd_render(args) -> int:
    from .render.cli import render_output
    return render_output(args)


def cmd_describe(args) -> int:
    from . import runtime
    from .mach import describe_lines
    from .scheme import Scheme

    scene = load_scene(args.scene, args.set)
    runtime.init("cpu", scene.precision)  # describing takes no step (one rate evaluation): any arch will do
    scheme = Scheme(scene)
    state = scheme.state
    print(f"scene {scene.name}: {scene.dimension}D, model {scene.material.model}, arch {scene.arch}, "
          f"precision {scene.precision}")
    print(f"particles: {state.n_material} material + {state.n_wall} wall")
    print(f"smoothing: {scheme.smoothing.describe()}; integrator: {scene.numerics.integrator}; "
          f"walls: {scheme.walls.name}; periodic: {list(scene.domain.periodic) or 'none'}")
    print("one time step:")
    for k, line in enumerate(scheme.stage_list(), 1):
        print(f"  {k:2d}. {line}")
    itemsize = 8 if scene.precision == "f64" else 4
    print("fields:")
    for name, scope, shape, nbytes in state.memory_table(itemsize):
        print(f"  {name:<24} {scope:<9} {shape:<7} {nbytes / 1024:10.1f} KiB")
    print(f"  {'neighbour grid':<42} {scheme.grid.memory_bytes() / 1024:10.1f} KiB")
    print(f"total field memory: {scheme.memory_bytes() / 2**20:.2f} MiB")
    scheme.evaluate_rates()  # the one launch of the rate stages: the time step needs the rates at t = 0
    print(f"estimated time step: {scheme.stable_time_step():.3g} s (from the rates at t = 0; no step is taken)")
    for line in describe_lines(scene, scheme.model):
        print(line)
    return 0


def cmd_sweep(args) -> int:
    """0 if every run finished, 1 if some failed (recorded in results.csv)."""
    from .sweep import load_sweep, run_sweep
    from .sweep.engine import dask_available

    sweep = load_sweep(args.sweep)
    if args.out:
        sweep.out = Path(args.out)
    if (args.scheduler or args.workers != 0) and not dask_available():
        raise ConfigError("--workers", "Dask is not installed: pip install -e \".[sweep]\" (or --workers 0 to run "
                                       "the points one after another without it)")
    results = run_sweep(sweep, workers=args.workers, scheduler=args.scheduler, threads=args.threads,
                        resume=args.resume, quiet=args.quiet)
    failed = sorted(k for k, r in results.items() if r.get("status") != "ok")
    print(f"{len(results) - len(failed)} of {len(results)} runs finished"
          + (f"; failed: {', '.join(failed)} (their errors in results.csv)" if failed else "")
          + f"; {Path(sweep.out) / 'results.csv'}, plots in {Path(sweep.out) / 'plots'}")
    return 1 if failed else 0


def cmd_validate(args) -> int:
    from .validation.cli import validate
    return validate(args)


def cmd_reference(args) -> int:
    from .reference import REFERENCES

    if args.page == "validation":
        from .validation.table import ARCHIVE, archive, markdown, update_readme
        roots = [Path(r) for r in args.root] or [r for r in [Path("output/validate")] if r.is_dir()]
        if args.archive:
            from .paths import SOURCE_CHECKOUT
            if not args.root or not SOURCE_CHECKOUT:
                raise ValueError("--archive needs the folders to archive (--root DIR) and a source checkout "
                                 "(the archive is the repository's docs/validation/runs)")
            for copy in archive(*roots):
                print(f"archived {copy}")
            roots = []
        roots.append(ARCHIVE)
        text = markdown(*roots)
        if args.readme:
            update_readme(Path(args.readme), *roots)
            print(f"validation table -> {args.readme}")
    else:
        if args.root or args.readme or args.archive:
            raise ValueError("--root, --archive and --readme belong to the validation page")
        text = REFERENCES[args.page]()
    if args.out:
        from .output import atomic_write_text
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        atomic_write_text(Path(args.out), text)
        print(f"{args.page} reference -> {args.out}")
    else:
        sys.stdout.write(text)
    return 0


def cmd_bench(args) -> int:
    if args.study == "throughput":
        from .bench.throughput import main as throughput
        return throughput(args)
    if args.study == "accuracy":
        from .bench.accuracy import main as accuracy
        return accuracy(args)
    if args.study == "viscosity":
        from .bench.viscosity import main as viscosity
        return viscosity(args)
    if args.study == "scene":
        from .bench.scene import main as scene
        if not args.scenes:
            raise ConfigError("--scenes", "bench scene needs the scenes to time (files or bundled names)")
        return scene(args)
    raise AssertionError(args.study)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="taichi-granular", description=DESCRIPTION, epilog=EPILOG)
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("--debug", action="store_true", help="print the traceback of an error")
    sub = parser.add_subparsers(dest="command", required=True)

    def scene_args(p):
        p.add_argument("scene", help="YAML scene file, or a bundled scene's name (e.g. mu_i/inclined_plane.yaml)")
        p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                       help="override a scene key, e.g. --set numerics.cfl=0.3 (repeatable)")

    p = sub.add_parser("run", parents=[common], help="run a scene: VTU frames, diagnostics.csv, resolved config")
    scene_args(p)
    p.add_argument("--out", help="output directory (default: run.output_dir or output/<name>)")
    p.add_argument("--end-time", type=float, help="override run.end_time [s]")
    p.add_argument("--profile", action="store_true", help="time every stage and print the profile")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_run)

    p = sub.add_parser("resume", parents=[common], help="continue a run from the checkpoint in its output directory")
    p.add_argument("output_dir", help="the run's output directory (holds checkpoint.npz)")
    p.add_argument("--end-time", type=float, help="run to this time instead of run.end_time [s]")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="override a key of the saved scene (run.end_time, run.output_interval, render.*)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_resume)

    p = sub.add_parser("describe", parents=[common], help="stage list, fields and memory, the stable time step and Mach estimate (evaluates the "
                                                          "rates once at t = 0; takes no step, writes nothing)")
    scene_args(p)
    p.set_defaults(func=cmd_describe)

    p = sub.add_parser("render", parents=[common], help="re-render a run's saved frames to PNG (and GIF/MP4)")
    p.add_argument("output_dir", help="a run's output directory (holds particles.pvd)")
    p.add_argument("--colour-by", help="particle field (speed, pressure, inertial_number, ...)")
    p.add_argument("--range", type=float, nargs=2, metavar=("MIN", "MAX"), help="fixed colour range")
    p.add_argument("--camera", type=float, nargs=6, metavar=("X", "Y", "Z", "LX", "LY", "LZ"),
                   help="3D: camera position and the point it looks at [m]")
    p.add_argument("--up", type=float, nargs=3, metavar=("UX", "UY", "UZ"),
                   help="3D, with --camera: the direction shown upwards (default z; 0 1 0 for a top view)")
    p.add_argument("--fov", type=float, help="3D, with --camera: vertical field of view [deg]")
    p.add_argument("--width", type=int, help="image width [px]")
    p.add_argument("--view", type=float, nargs=4, metavar=("X0", "Y0", "X1", "Y1"), help="2D view box [m]")
    p.add_argument("--times", type=float, nargs="+", help="only the frames at these simulated times [s]")
    p.add_argument("--out", help="frame directory (default OUTPUT_DIR/frames_<field>)")
    p.add_argument("--video", help="also join the frames into this .gif or .mp4")
    p.add_argument("--fps", type=float, default=10.0, help="video frames per second")
    p.add_argument("--arch", default="cpu", help="Taichi backend for rasterising")
    p.set_defaults(func=cmd_render)

    from .validation import CASES
    from .validation.cli import RESOLUTIONS
    p = sub.add_parser("validate", parents=[common], help="run a validation case and print its errors",
                       formatter_class=argparse.RawDescriptionHelpFormatter,
                       description="cases:\n" + "\n".join(f"  {c.name:<20}{c.summary}" for c in CASES.values()))
    p.add_argument("case", help="the validation case", choices=list(CASES))
    p.add_argument("--resolution", choices=list(RESOLUTIONS), default="coarse",
                   help="column-collapse-3d, stake-rows, obstacle-flow: the coarse CPU scenes (*_coarse.yaml), "
                        "CPU-sized scenes where one exists (*_cpu.yaml: stake rows at the paper's dp, the cylinder at "
                        "dp 3.5 mm, the wedge with a deeper stream), or the paper's resolution (GPU)")
    p.add_argument("--cases", nargs="+", help="only these (e.g. a0_90 a2_75; case1 case3; omega1)")
    p.add_argument("--config", help="scene file (default: the bundled one)")
    p.add_argument("--out", help="output directory (default: output/validate/<case>)")
    p.add_argument("--reuse", action="store_true", help="evaluate existing output instead of running")
    p.add_argument("--resume", action="store_true",
                   help="continue a case whose run was interrupted from the checkpoint in its output folder (a "
                        "finished one is reused, one never started runs), then evaluate")
    p.add_argument("--start", choices=["analytic", "rest"], default="analytic",
                   help="inclined plane: start from the [M56] profile (reaches the discrete steady state "
                        "in ~20 s) or from rest (~60 s, as [M] did)")
    p.add_argument("--window", type=float, default=5.0, help="average over the last WINDOW seconds [s]")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="override a scene key")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_validate)

    from .sweep.measures import NAMED, REDUCERS
    p = sub.add_parser("sweep", parents=[common], help="a parameter sweep or ensemble of a scene on Dask",
                       formatter_class=argparse.RawDescriptionHelpFormatter,
                       description="Runs every point of SWEEP.yaml (a base scene, axes or a Latin-hypercube sample "
                                   "of --set keys, measures; docs/usage.md, sweeps) in a process of its own on Dask "
                                   "distributed, and writes results.csv and plots.\nmeasures: "
                                   + ", ".join(NAMED) + f", {'|'.join(REDUCERS)}:COLUMN of diagnostics.csv")
    p.add_argument("sweep", help="the sweep file (YAML)")
    p.add_argument("--scheduler", help="address of a running Dask scheduler (tcp://host:8786); default: a "
                                       "LocalCluster on this machine")
    p.add_argument("--workers", type=int, help="LocalCluster worker processes (default: one per core; 0: no "
                                               "Dask, the runs one after another here)")
    p.add_argument("--threads", type=int, help="Taichi CPU threads per run (default: cores // workers on a "
                                               "LocalCluster, all of the worker machine's with --scheduler)")
    p.add_argument("--resume", action="store_true", help="keep the finished runs in the sweep's folder and run "
                                                         "the rest (failed and missing ones)")
    p.add_argument("--out", help="the sweep's folder (default: the sweep file's out)")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=cmd_sweep)

    p = sub.add_parser("reference", parents=[common],
                       help="a generated reference page as Markdown: every scene key (meaning, unit, default, bounds, "
                            "from the declarations the loader checks) or every output field and column")
    p.add_argument("page", choices=["keys", "outputs", "validation"],
                   help="keys: the scene keys; outputs: VTU fields, diagnostics.csv; validation: the summary of the "
                        "validate runs (archived in docs/validation/runs, and under output/validate)")
    p.add_argument("--out", help="write it to this file (docs/reference/PAGE.md) instead of printing it")
    p.add_argument("--root", action="append", default=[],
                   help="validation: a folder whose validate runs (their table.csv, found at any depth) join the "
                        "archived rows of docs/validation/runs in the table (repeatable; default output/validate)")
    p.add_argument("--archive", action="store_true",
                   help="validation: first copy the --root folders' rows into docs/validation/runs/<folder name>/, "
                        "so that the table can be regenerated after the run folders are gone")
    p.add_argument("--readme", help="validation: also write the table into this README's validation block")
    p.set_defaults(func=cmd_reference)

    p = sub.add_parser("bench", parents=[common], help="benchmarks (timing lives here, never in tests)")
    p.add_argument("study", choices=["throughput", "accuracy", "viscosity", "scene"],
                   help="throughput: particle-steps/s by size; accuracy: error against cost over resolution "
                        "and numerics (bench/accuracy.py); viscosity: explicit against implicit viscosity on the "
                        "Table 3 collapses (bench/viscosity.py); scene: a few hundred steps of real scenes and "
                        "the wall time their full runs would take (bench/scene.py)")
    p.add_argument("--scenes", nargs="+", help="scene: scene files or bundled names (e.g. elastoplastic/wedge.yaml)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="scene: override a key of every scene (repeatable), e.g. --set arch=cuda")
    p.add_argument("--sizes", type=int, nargs="+",
                   help="throughput: approximate particle counts (default 1k 10k 40k 160k in 2D, 10k 40k 150k in 3D)")
    p.add_argument("--steps", type=int, default=50, help="throughput: timed steps per size (and batch); scene: "
                   "timed steps per scene")
    p.add_argument("--skins", type=float, nargs="+",
                   help="throughput: numerics.neighbour_skin values measured side by side at each size "
                        "(default: the scene default)")
    p.add_argument("--models", nargs="+", choices=["mu_i", "hypoplastic", "elastoplastic"],
                   help="throughput: the models' blocks measured (default mu_i)")
    p.add_argument("--dims", type=int, nargs="+", choices=[2, 3], help="throughput: dimensions (default 2)")
    p.add_argument("--compare", action="store_true",
                   help="throughput: also time a bare density sweep over the same list (the ceiling of a pair "
                        "pass) and print the step as a multiple of it")
    p.add_argument("--orders", nargs="+", choices=["lattice", "shuffled", "reordered"],
                   help="throughput: particle orders measured side by side (shuffled: a random order left so; "
                        "reordered: the same, sorted by cell once)")
    p.add_argument("--quick", action="store_true", help="accuracy: the few-minute sweep (never rewrites docs/accuracy.md)")
    p.add_argument("--cases", nargs="+", help="accuracy, viscosity: only cases whose name contains one of these")
    p.add_argument("--window", type=float, default=0.01, help="viscosity: simulated seconds timed from release")
    p.add_argument("--cfls", type=float, nargs="+",
                   help="viscosity: an ensemble instead, one run to rest per CFL number and setting, of the "
                        "accuracy study's collapse (a2_75 unless --cases)")
    p.add_argument("--spacing", type=float, help="viscosity --cfls: particle spacing [m] (default: the study's middle one)")
    p.add_argument("--out",
                   help="accuracy: output folder (default renders/accuracy, quick: output/bench/accuracy_quick)")
    p.add_argument("--timeout", type=float, default=3600.0, help="accuracy: seconds allowed per run")
    p.add_argument("--workers", type=int, default=0,
                   help="accuracy: run on a Dask LocalCluster of this many workers (as `sweep` does; default 0: "
                        "one run after another, since the study measures wall time)")
    p.add_argument("--scheduler", help="accuracy: run on the Dask scheduler at this address")
    p.add_argument("--no-readme", action="store_true", help="accuracy: do not rewrite the study section of docs/accuracy.md")
    p.add_argument("--reuse", action="store_true",
                   help="accuracy: keep the runs that succeeded in the output folder's accuracy.csv, run the rest")
    p.add_argument("--arch", default="cpu", help="throughput: Taichi backend (cpu, cuda, vulkan)")
    p.add_argument("--precision", default="f64", choices=["f32", "f64"], help="throughput: floating-point precision")
    p.set_defaults(func=cmd_bench)
    return parser


# exit codes: 0 done, 1 a bug (an exception nobody expected), 2 a scene or input error,
# 3 a run stopped by a guard (its failure snapshot written), 130 interrupted (state written)
EXIT_BUG, EXIT_SCENE, EXIT_GUARD, EXIT_INTERRUPTED = 1, 2, 3, 130


def _exit_code(err: BaseException) -> int:
    from .simulation import ResumeError, SimulationError

    if isinstance(err, SimulationError):
        return EXIT_GUARD
    if isinstance(err, (ConfigError, ResumeError, OSError)):  # OSError: a missing file, an unwritable folder
        return EXIT_SCENE
    return EXIT_BUG


def main(argv=None) -> int:
    """Run one command; every failure ends as one ``error: ...`` line on stderr and an exit code
    (traceback only with ``--debug``)."""
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except KeyboardInterrupt as err:
        print(f"\ninterrupted{': ' + str(err) if str(err) else ''}", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Exception as err:  # noqa: BLE001 - the one place that turns exceptions into messages
        code = _exit_code(err)
        if args.debug:
            traceback.print_exc()
        message = str(err) if code != EXIT_BUG else (
            f"internal error, a bug of taichi-granular ({type(err).__name__}: {err}); please report it with "
            "the output of the same command with --debug")
        print(f"error: {message}", file=sys.stderr)
        return code


if __name__ == "__main__":
    sys.exit(main())
