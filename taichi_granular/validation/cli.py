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
    """mu(I) ([M56], both errors < 5 %) or hypoplastic + Bagnold (MODEL.md section 2: velocity
    within 10 % of the Bagnold-type profile, and no steady flow outside the bounding slopes)."""
    from ..validation import inclined_plane

    path = Path(args.config) if args.config else config_path("mu_i/inclined_plane.yaml")
    scene = load_scene(path, args.set)
    out = Path(args.out) if args.out else Path("output/validate") / scene.name
    prepare = inclined_plane.impose_analytic_velocity if args.start == "analytic" else None
    times, frames = _frames(scene, out, args.reuse, args.quiet, prepare)
    result = inclined_plane.evaluate(scene, times, frames, window=args.window)
    print(result.report())
    inclined_plane.write_profile_csv(result, out / "profile.csv")
    if scene.material.model != "hypoplastic":
        ok = result.velocity_error < 0.05 and result.pressure_error < 0.05
        print(f"  acceptance (both errors < 5 %): {'PASS' if ok else 'FAIL'}; profile -> {out / 'profile.csv'}")
        return 0 if ok else 1
    reference = inclined_plane.reference_for(scene)
    low, high = reference.bounding_angles_deg
    n = int(sum(frames[0]["is_wall"] == 0))
    window = [(t, f) for t, f in zip(times, frames) if t >= max(times) - args.window - 1e-9]
    steady = inclined_plane.layer_acceleration([t for t, _ in window], [f for _, f in window], n)
    print(f"  mu_h = {reference.friction:.4f} (I_e {reference.density_factor:.4f}): steady flow between "
          f"{low:.2f} and {high:.2f} deg; at {scene.gravity.tilt_deg:.2f} deg the layer's mean acceleration over "
          f"the window is {steady:+.3f} m/s2")
    bounds = inclined_plane.bounding_slopes(scene)
    for b in bounds:
        print(b.row())
    ok = result.velocity_error < 0.10 and all(b.passed for b in bounds)
    print(f"  acceptance (velocity within 10 %, no steady flow outside the bounds): {'PASS' if ok else 'FAIL'}; "
          f"profile -> {out / 'profile.csv'}")
    return 0 if ok else 1


def _case_paths(folder: str, pattern: str, args):
    """The scene files of a validation family: ``pattern`` (or a list of them) names the coarse CPU variants;
    ``--resolution paper`` picks the paper-resolution files instead; ``--cases`` filters by
    stem, or by its end without the ``_coarse`` suffix (``a2_75``, ``case1``, ``cylinder``)."""
    patterns = [pattern] if isinstance(pattern, str) else list(pattern)
    if getattr(args, "resolution", "coarse") == "paper":
        patterns = [p.replace("_coarse", "") for p in patterns]
    known = sorted(p for pat in patterns for p in config_path(folder).glob(pat)
                   if "_coarse" in pat or "_coarse" not in p.stem)
    if not args.cases:
        return known
    wanted = set(args.cases)

    def matches(stem: str, name: str) -> bool:
        base = stem.replace("_coarse", "")
        return name in (stem, base) or base.endswith("_" + name)

    paths = [p for p in known if any(matches(p.stem, w) for w in wanted)]
    if not paths:
        raise FileNotFoundError(f"no case among {sorted(args.cases)}; known: {', '.join(p.stem for p in known)}")
    return paths


def _each_case(paths, base: Path, args):
    """(scene, its output folder under ``base``, frame times, frames) of each scene file, run
    first unless ``--reuse``."""
    for path in paths:
        scene = load_scene(path, args.set)
        out = base / scene.name
        times, frames = _frames(scene, out, args.reuse, args.quiet)
        yield scene, out, times, frames


# (configs folder, scene files, acceptance bound on the run-out error, read the run-out at rest)
COLLAPSE_FAMILIES = {
    "column-collapse": ("mu_i", "collapse_a*.yaml", 0.15, False),  # 2D mu(I), Table 3 of [M]
    "column-collapse-3d": ("elastoplastic", "collapse3d_a*_coarse.yaml", 0.20, True),  # 3D [A], CPU variants
    "pile-collapse": ("hypoplastic", "collapse_a*.yaml", 0.20, True),  # 2D [P], set 2, on [M]'s geometry
}


def validate_column_collapse(args) -> int:
    import io

    import numpy as np

    from ..output import atomic_write_text, read_diagnostics
    from ..render.frames import write_png
    from ..render.plot import plot_points_and_curve
    from . import column_collapse as cc

    folder, pattern, bound, at_rest = COLLAPSE_FAMILIES[args.case]
    paths = _case_paths(folder, pattern, args)
    base = Path(args.out) if args.out else Path("output/validate") / args.case.replace("-", "_")
    results = []
    print(cc.HEADER)
    for scene, out, times, frames in _each_case(paths, base, args):
        result = cc.evaluate(scene, times, frames, read_diagnostics(out), read_at_end=at_rest)
        cc.write_fronts_csv(result, out / "fronts.csv")
        results.append(result)
        print(result.row(), flush=True)
    buf = io.StringIO()
    def opt(t):
        return "" if t is None else f"{t:.4f}"

    buf.write("case,aspect_ratio,runout,runout_lube,error,deposit_height,front_stop_time,creep_speed,"
              "runout_end,bulk_runout_end,end_time,time_to_rest,final_energy_fraction,escaped\n")
    for r in results:
        buf.write(f"{r.name},{r.aspect_ratio:.4f},{r.runout:.4f},{r.runout_reference:.4f},{r.error:.4f},"
                  f"{r.deposit_height:.5f},{opt(r.front_stop_time)},{r.creep_speed:.3e},{r.runout_end:.4f},{r.bulk_runout_end:.4f},"
                  f"{r.end_time:.4f},{opt(r.time_to_rest)},{r.final_energy_fraction:.3e},{r.escaped}\n")
    atomic_write_text(base / "runout.csv", buf.getvalue())
    a = np.linspace(0.01, max(3.2, max(r.aspect_ratio for r in results) * 1.05), 200)
    image = plot_points_and_curve([(r.aspect_ratio, r.runout) for r in results],
                                  (a, np.array([cc.lube_runout(x) for x in a])),
                                  "aspect ratio a", "(r_inf - r0)/r0", "line: lube et al. 2004, squares: sph")
    write_png(base / "runout.png", image)
    ok = all((abs(r.error) < bound or r.aspect_ratio > 3.0) and r.time_to_rest is not None and r.escaped == 0
             for r in results)
    if at_rest:
        print("run-out read at the end of the run (the deposit at rest)")
    else:
        print("run-out read when the front stops (from then on it never runs ahead faster than "
              f"{100 * cc.FRONT_STOP_FRACTION:.0f} % of its peak speed); afterwards the regularised viscosity lets the "
              "deposit creep at the speed shown (docs, column collapse)")
    print(f"acceptance (run-out within {100 * bound:.0f} % of Lube for a <= 3, at rest, none escaped): "
          f"{'PASS' if ok else 'FAIL'}; {base / 'runout.csv'}, {base / 'runout.png'}")
    return 0 if ok else 1


def validate_stake_rows(args) -> int:
    """Stake rows cases 1-3 of [A]: efficiency factor against Yellin et al. (2013)."""
    from ..output import atomic_write_text
    from . import obstacles as ob

    paths = _case_paths("elastoplastic", "stake_rows_case*_coarse.yaml", args)
    base = Path(args.out) if args.out else Path("output/validate/stake_rows")
    results = []
    print(ob.HEADER)
    for scene, out, times, frames in _each_case(paths, base, args):
        result = ob.evaluate_stake_rows(scene, times, frames)
        results.append(result)
        atomic_write_text(out / "leading_edge.csv", "t,leading_edge_m\n" + "".join(
            f"{t:.4f},{e:.5f}\n" for t, e in zip(result.times, result.leading_edge)))
        print(result.row(), flush=True)
    print(f"areas: 1 = lower panel above the first row, 2 = first row to {ob.LEE} m past the last; efficiency = "
          "(1 + 2)/total; reference: Yellin et al. (2013) experiment, [A] = Abdelrazek et al. SPH")
    close = all(abs(r.error_points) <= ob.ACCEPTANCE_POINTS and r.crossed == 0 for r in results)
    by_case = {r.case: r.efficiency for r in results}
    lowest = set(by_case) != set(ob.EXPERIMENT) or min(by_case, key=by_case.get) == "case2"
    ok = close and lowest
    print(f"acceptance (within {100 * ob.ACCEPTANCE_POINTS:.0f} points, case 2 lowest, none crossed): "
          f"{'PASS' if ok else 'FAIL'}; leading edge over time -> {base}/<case>/leading_edge.csv")
    return 0 if ok else 1


def validate_obstacle_flow(args) -> int:
    """Cylinder (Cui & Gray 2013) and wedge (Tai et al. 2001) of [A]: bow shock, depth jump,
    particle-free wake and protected zone."""
    from ..output import atomic_write_text
    from . import obstacle_flow as of

    paths = _case_paths("elastoplastic", ["cylinder_coarse.yaml", "wedge_coarse.yaml"], args)
    base = Path(args.out) if args.out else Path("output/validate/obstacle_flow")
    print(of.HEADER)
    ok = True
    for scene, out, times, frames in _each_case(paths, base, args):
        result = of.evaluate_obstacle_flow(scene, times, frames)
        atomic_write_text(out / "obstacle_flow.csv", "t,upstream_depth_m,depth_jump,standoff_m,wake_length_m,"
                          "wake_area_m2,wake_closed,protected_particles\n" + "".join(
                              f"{f.time:.4f},{f.upstream_depth:.5f},{f.depth_jump:.3f},{f.standoff:.5f},"
                              f"{f.wake_length:.5f},{f.wake_area:.6f},{int(f.wake_closed)},{f.protected_particles}\n"
                              for f in result.frames))
        print(result.row(), flush=True)
        if "wedge" in scene.name:
            ok &= result.shock_persists and result.protected_max == 0
        else:
            ok &= result.shock_persists and result.wake_persists
    print(f"steady state: the last {100 * of.STEADY_FRACTION:.0f} % of the frames; shock: depth jump > "
          f"{of.SHOCK_JUMP}; wedge: 'inside' counts particles within {of.PROTECTED_LENGTH} m behind the building")
    print(f"acceptance (cylinder: shock and closed wake persist; wedge: shock persists, protected zone empty): "
          f"{'PASS' if ok else 'FAIL'}; per frame -> {base}/<case>/obstacle_flow.csv")
    return 0 if ok else 1


def validate_element_tests(args) -> int:
    """Element tests of the hypoplastic law (MODEL.md section 2) on a patch of particles."""
    from .. import runtime
    from ..output import atomic_write_text

    runtime.init("cpu", "f64")  # a few hundred particles: the CPU is the right backend
    from . import element_tests as et

    base = Path(args.out) if args.out else Path("output/validate/element_tests")
    print("stationary states, parameter set 1, isochoric, patch of 8^3 particles under v = L x:")
    print(et.STATIONARY_HEADER)
    stationary = et.stationary_states()
    for r in stationary:
        print(r.row(), flush=True)
    print("annular shear cell, v_x = 2 kappa z, kappa = 10 1/s for 0.5 s (strain 10), its parameter set:")
    annular = [et.annular_shear_cell(c) for c in et.ANNULAR_SOLID_FRACTIONS]
    for r in annular:
        print(r.row(), flush=True)
    dense = annular[-1]
    ref = et.ANNULAR_REFERENCE
    print(f"C = 0.524 against [P]: sigma_xz {dense.sigma_xz:.2f} Pa ({100 * (dense.sigma_xz / ref['sigma_xz'] - 1):+.1f} %), "
          f"sigma_zz {dense.sigma_zz:.2f} Pa ({100 * (dense.sigma_zz / ref['sigma_zz'] - 1):+.1f} %)")
    atomic_write_text(base / "element_tests.csv", "case,value,reference,density_factor,growth\n" + "".join(
        f"{r.name},{r.ratio:.5f},{r.reference_ratio},{r.density_factor:.5f},{r.growth:.5f}\n" for r in stationary) + "".join(
        f"annular_C{r.solid_fraction:.3f},{r.sigma_xz:.4f},{ref['sigma_xz'] if r.residual else 0.0},"
        f"{r.density_factor:.5f},\n" for r in annular))
    ok_annular = all(not r.residual for r in annular[:-1]) and dense.residual
    ok = all(r.passed for r in stationary) and ok_annular
    print(f"acceptance (triaxial ratio within 1 %, shear ratio within 2 %, each at its I_e within 0.0015 and "
          f"stationary; shear cell: no residual stress for C <= 0.504, residual at 0.524): "
          f"{'PASS' if ok else 'FAIL'}; {base / 'element_tests.csv'}")
    return 0 if ok else 1


def validate_drum(args) -> int:
    """Rotating drum of [P] at omega = 0.5, 1, 2 rad/s: inclination, flowing depth, flux, rigid bed."""
    from ..render.frames import write_png
    from ..render.plot import plot_points_and_curve
    from . import drum as dr

    paths = _case_paths("hypoplastic", "drum_omega*.yaml", args)
    base = Path(args.out) if args.out else Path("output/validate/drum")
    results = []
    print(dr.HEADER)
    for scene, out, times, frames in _each_case(paths, base, args):
        result = dr.evaluate_drum(scene, times, frames)
        results.append(result)
        dr.write_profile_csv(result, out / "velocity_profile.csv")
        image = plot_points_and_curve(list(zip(result.depth, result.velocity)), (result.depth, result.rigid_velocity),
                                      "depth below the surface on the middle cross-section (m)",
                                      "downhill velocity (m/s)", f"{scene.name}: squares sph, line rigid rotation")
        write_png(out / "velocity_profile.png", image)
        print(result.row(), flush=True)
    print(f"steady window: the last {100 * dr.STEADY_FRACTION:.0f} % of the frames; [P]: Peng et al. (2016); flux "
          "reference: the kinematic omega (R^2 - (R - H_0)^2)/2")
    ok = True
    for r in results:
        ref = r.reference
        if ref is not None:
            ok &= abs(r.inclination_deg - ref[0]) <= dr.INCLINATION_TOLERANCE_DEG
            ok &= abs(r.flowing_depth / ref[1] - 1.0) <= dr.DEPTH_TOLERANCE
        ok &= r.bed_departure < 0.1
    ordered = sorted((r for r in results if r.reference is not None), key=lambda r: r.omega)
    rising = all(a.inclination_deg < b.inclination_deg and a.flowing_depth < b.flowing_depth
                 for a, b in zip(ordered, ordered[1:]))
    ok &= rising
    print(f"acceptance (inclination within {dr.INCLINATION_TOLERANCE_DEG} deg, depth within "
          f"{100 * dr.DEPTH_TOLERANCE:.0f} %, both rising with omega, bed within 10 % of omega R of rigid rotation): "
          f"{'PASS' if ok else 'FAIL'}; profiles -> {base}/<case>/velocity_profile.csv, .png")
    return 0 if ok else 1
