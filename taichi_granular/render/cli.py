"""The ``render`` command: re-render a run's saved particle frames with other settings."""
import dataclasses
from pathlib import Path

from ..output import load_run_scene, read_frame, read_series


def render_output(args) -> int:
    from .. import runtime
    from .frames import Renderer, assemble_video, check_colour_field, png_name, write_png

    out_dir = Path(args.output_dir)
    scene = load_run_scene(out_dir)
    settings = scene.render
    changes = {k: v for k, v in (("colour_by", args.colour_by), ("width", args.width),
                                 ("range", tuple(args.range) if args.range else None)) if v is not None}
    if args.view:
        changes["view_lower"], changes["view_upper"] = tuple(args.view[:2]), tuple(args.view[2:])
    if args.camera:  # 3D: another viewpoint (e.g. a top view, with --up 0 1 0: x to the right)
        from ..sections import Camera
        old = settings.camera
        changes["camera"] = Camera(position=tuple(args.camera[:3]), look_at=tuple(args.camera[3:]),
                                   up=tuple(args.up) if args.up else (0.0, 0.0, 1.0),
                                   field_of_view_deg=args.fov or (old.field_of_view_deg if old else 40.0))
    settings = dataclasses.replace(settings, **changes)
    scene = dataclasses.replace(scene, render=settings)
    scene.check()
    series = read_series(out_dir)
    if not series:
        raise FileNotFoundError(f"no frames listed in {out_dir / 'particles.pvd'}")
    target = Path(args.out) if args.out else out_dir / f"frames_{settings.colour_by}"
    runtime.init(args.arch, scene.precision)
    renderer = Renderer(scene)
    written = []
    for index, (t, path) in enumerate(series):
        if args.times and not any(abs(t - wanted) < 1e-6 for wanted in args.times):
            continue
        arrays = read_frame(path)
        if not written:
            check_colour_field(settings.colour_by, arrays, "--colour-by")
        n_material = int((arrays["is_wall"] == 0).sum())
        written.append(target / png_name(index, t))
        write_png(written[-1], renderer.image(arrays, n_material, t))
    print(f"{len(written)} frames -> {target}")
    if args.video:
        print(f"video -> {assemble_video(written, Path(args.video), args.fps)}")
    return 0
