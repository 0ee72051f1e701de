"""The ``validate`` command: run (or reuse) a case's output, print its errors."""
from pathlib import Path

from ..config import load_scene
from ..output import read_frame, read_series
from ..paths import config_path


def _frames(scene, out: Path, reuse: bool, quiet: bool, prepare=None):
    """Frames of ``scene`` in ``out``: run it first unless ``reuse``; ``prepare(sim)`` may set
    the initial state before the run."""
    if not reuse:
        from ..simulation import Simulation
        sim = Simulation(scene, out_dir=out, progress=not quiet)
        if prepare is not None:
            prepare(sim)
        summary = sim.run()
        print(f"ran {scene.name}: {summary.steps} steps, {summary.wall_seconds:.1f} s wall, "
              f"{summary.particle_steps_per_second:.3g} particle-steps/s")
    series = read_series(out)
    return [t for t, _ in series], [read_frame(p) for _, p in series]


def validate_inclined_plane(args) -> int:
    from ..validation import inclined_plane

    path = Path(args.config) if args.config else config_path("mu_i/inclined_plane.yaml")
    scene = load_scene(path, args.set)
    out = Path(args.out) if args.out else Path("output/validate/inclined_plane")
    prepare = inclined_plane.impose_analytic_velocity if args.start == "analytic" else None
    times, frames = _frames(scene, out, args.reuse, args.quiet, prepare)
    result = inclined_plane.evaluate(scene, times, frames, window=args.window)
    print(result.report())
    inclined_plane.write_profile_csv(result, out / "profile.csv")
    ok = result.velocity_error < 0.05 and result.pressure_error < 0.05
    print(f"  acceptance (both errors < 5 %): {'PASS' if ok else 'FAIL'}; profile -> {out / 'profile.csv'}")
    return 0 if ok else 1
