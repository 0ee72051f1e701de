"""The command line end to end on a tiny scene: outputs, errors, description."""
import csv

import meshio
import numpy as np
import pytest
import yaml

from scenes import layer
from taichi_granular.cli import main
from taichi_granular.output import read_series


def write_scene(tmp_path, **changes):
    data = layer(height=0.02, length=0.04, end_time=0.004)
    data["run"].update(output_interval=0.002)
    data.update(changes)
    path = tmp_path / "tiny.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_run_writes_series_diagnostics_and_resolved_config(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", str(write_scene(tmp_path)), "--out", str(out), "--quiet"]) == 0
    series = read_series(out)
    assert [round(t, 6) for t, _ in series] == [0.0, 0.002, 0.004]
    mesh = meshio.read(series[-1][1])
    for name in ("velocity", "pressure", "density", "grain_density", "inertial_number", "is_wall"):
        assert name in mesh.point_data
    n_wall = int(mesh.point_data["is_wall"].sum())
    assert n_wall > 0 and len(mesh.points) > n_wall
    rows = list(csv.DictReader(open(out / "diagnostics.csv")))
    assert [float(r["t"]) for r in rows] == [0.0, 0.002, 0.004]
    assert all(np.isfinite(float(r["kinetic_energy"])) for r in rows)
    resolved = yaml.safe_load((out / "scene.resolved.yaml").read_text())
    assert resolved["numerics"]["cfl"] == 0.5  # defaults made explicit
    assert not list(out.glob(".*tmp"))  # no half-written files left behind
    assert "particle-steps/s" in capsys.readouterr().out


def test_bad_scene_exits_with_the_key_path(tmp_path, capsys):
    data = layer()
    data["material"]["grain_densty"] = 800.0
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(data))
    assert main(["run", str(path), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "material.grain_densty" in err and "did you mean 'grain_density'" in err
    assert not (tmp_path / "o").exists()  # nothing written before validation


def test_describe_lists_stages_fields_and_time_step(tmp_path, capsys):
    assert main(["describe", str(write_scene(tmp_path))]) == 0
    text = capsys.readouterr().out
    for stage in ("neighbour_search", "continuity", "grain_density_pressure", "regularised_viscosity",
                  "momentum_stress", "wall_impermeability", "time_step"):
        assert stage in text
    assert "artificial_viscosity" not in text  # alpha = beta = 0: not in the step
    assert "estimated time step" in text


def test_resume_continues_exactly_where_the_run_stopped(tmp_path):
    """A run stopped after its second frame and resumed from the checkpoint ends in the same
    state, bit for bit, as one that ran straight through, with one series and one diagnostics
    table (frames written after the checkpoint are replaced)."""
    import numpy as np

    from scenes import build, layer
    from taichi_granular.output import read_frame, read_series
    from taichi_granular.simulation import Simulation

    data = layer(height=0.02, length=0.04, tilt_deg=25.0)
    data["run"] = {"end_time": 0.004, "output_interval": 0.001}
    data["render"] = {"frames": False}
    straight = Simulation(build(data), out_dir=tmp_path / "straight")
    straight.run()
    stopped = Simulation(build(data), out_dir=tmp_path / "stopped")
    stopped.run(end_time=0.002)
    assert main(["resume", str(tmp_path / "stopped"), "--quiet"]) == 0
    a = read_frame(read_series(tmp_path / "straight")[-1][1])
    b = read_frame(read_series(tmp_path / "stopped")[-1][1])
    for name in ("position", "velocity", "pressure", "density"):
        assert np.array_equal(a[name], b[name]), name
    assert [t for t, _ in read_series(tmp_path / "stopped")] == [t for t, _ in read_series(tmp_path / "straight")]
    rows = (tmp_path / "stopped" / "diagnostics.csv").read_text().splitlines()
    assert rows == (tmp_path / "straight" / "diagnostics.csv").read_text().splitlines()


def test_resume_without_checkpoint_is_a_clear_error(tmp_path, capsys):
    assert main(["resume", str(tmp_path)]) == 2
    assert "holds no run" in capsys.readouterr().err


def test_validation_cases_are_picked_by_their_short_names():
    from types import SimpleNamespace
    from taichi_granular.validation.cli import _case_paths

    def stems(folder, pattern, cases, resolution="coarse"):
        args = SimpleNamespace(cases=cases, resolution=resolution)
        return [p.stem for p in _case_paths(folder, pattern, args)]

    assert stems("elastoplastic", "collapse3d_*_coarse.yaml", ["a2_75"]) == ["collapse3d_a2_75_coarse"]
    assert stems("elastoplastic", "collapse3d_*_coarse.yaml", ["a2_75"], "paper") == ["collapse3d_a2_75"]
    assert stems("elastoplastic", "stake_rows_case*_coarse.yaml", ["case1", "case3"]) == \
        ["stake_rows_case1_coarse", "stake_rows_case3_coarse"]
    assert stems("mu_i", "collapse_a*.yaml", ["a0_90"]) == ["collapse_a0_90"]
    with pytest.raises(FileNotFoundError, match="known: collapse3d_a0_90_coarse"):
        stems("elastoplastic", "collapse3d_*_coarse.yaml", ["a9_99"])


def test_progress_eta_follows_the_recent_rate_not_the_compile():
    from taichi_granular.simulation import Progress

    progress = Progress(end_time=10.0, enabled=False)
    assert progress.eta(10.0, 0.01) != progress.eta(10.0, 0.01)  # NaN: nothing to extrapolate yet
    # after 10 s of compilation, 0.01 simulated seconds per wall second
    for k in range(1, 60):
        eta = progress.eta(10.0 + k, 0.01 + 0.01 * k)
    assert abs(eta - (10.0 - 0.6) / 0.01) < 1e-6  # the recent rate, not the one since the start (compile included)
    for k in range(60, 101):  # the flow speeds up: twice the simulated time per wall second
        t = 0.6 + 0.02 * (k - 59)
        eta = progress.eta(10.0 + k, t)
    assert abs(eta - (10.0 - t) / 0.02) < 1e-6  # the window holds the new rate only


def test_every_command_and_option_has_help():
    import argparse

    from taichi_granular.cli import build_parser

    parser = build_parser()
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    helped = {choice.dest for choice in commands._choices_actions if choice.help}
    assert helped == set(commands.choices)  # every command listed with a line in the top-level help
    for name, sub in commands.choices.items():
        for action in sub._actions:
            if isinstance(action, argparse._HelpAction):
                continue
            assert action.help and action.help != argparse.SUPPRESS, (name, action.dest)


def test_every_validation_case_has_its_scenes_and_its_check():
    """The registry (validation/__init__.py) is what `validate` offers: each case's module has a
    check, and its patterns name bundled scenes at both resolutions."""
    from types import SimpleNamespace
    from taichi_granular.validation import CASES
    from taichi_granular.validation.cli import _case_paths

    assert set(CASES) >= {"inclined-plane", "column-collapse", "stake-rows", "drum", "element-tests"}
    for case in CASES.values():
        assert callable(case.module().check), case.name
        for resolution in ("coarse", "paper"):
            args = SimpleNamespace(cases=None, resolution=resolution)
            assert bool(case.patterns) == bool(_case_paths(case.folder, case.patterns, args) if case.patterns
                                               else []), (case.name, resolution)


def test_validation_table_is_gathered_from_the_cases_tables(tmp_path):
    """Each validate check writes table.csv beside its runs; `reference validation` gathers them in
    the registry's order into one Markdown table (docs/validation/summary.md)."""
    from taichi_granular.validation import CASES
    from taichi_granular.validation.table import (README_BEGIN, README_END, Row, gather, markdown,
                                                  update_readme, write_rows)

    write_rows(tmp_path / "drum", [Row("drum: drum_omega1", "mean inclination; flowing depth", "30.8 deg; 46 mm",
                                       "22.43 deg; 54 mm", "[P]'s table", "dp 5 mm, 1212 particles", "-", "FAIL")])
    write_rows(tmp_path / "inclined_plane", [Row("inclined-plane: inclined_plane", "velocity profile, relative L2",
                                                 "2.36 %", "-", "[M56] profile", "dp 5 mm, 920 particles",
                                                 "111177 steps, 238 s", "PASS")])
    rows = gather(tmp_path)
    assert [r.case.split(":")[0] for r in rows] == ["inclined-plane", "drum"]
    text = markdown(tmp_path)
    assert "| inclined-plane: inclined_plane | velocity profile, relative L2 | 2.36 % |" in text
    assert text.count("\n| ") == 3 + len(CASES) - 2  # the header row, two cases, the others not run
    assert "| element-tests | " in text and "NOT RUN |" in text
    # a run kept elsewhere (a campaign's folder) joins the table, in the registry's order
    write_rows(tmp_path / "campaign" / "t3", [Row("column-collapse: collapse_a0_90", "run-out", "1.106 (-1.6 %)",
                                                  "-", "Lube et al. (2004): 1.124", "dp 3.02 mm", "-", "PASS")])
    assert [r.case.split(":")[0] for r in gather(tmp_path)] == ["inclined-plane", "column-collapse", "drum"]
    # the README's block between its markers is replaced by the table, the rest kept
    readme = tmp_path / "README.md"
    readme.write_text(f"# title\n\n{README_BEGIN}\nold table\n{README_END}\n\nafter\n")
    update_readme(readme, tmp_path)
    written = readme.read_text()
    assert "old table" not in written and written.startswith("# title") and written.endswith("\nafter\n")
    assert written.count("\n| ") == 4 + len(CASES) - 3 and "| column-collapse: collapse_a0_90 | run-out |" in written
    # a sensitivity run's row says what it changed beyond dp and the viscous scheme
    from types import SimpleNamespace
    from taichi_granular.config import load_scene
    from taichi_granular.paths import config_path
    from taichi_granular.validation.table import cost, record_run, resolution
    scene = load_scene(config_path("mu_i/collapse_a0_19.yaml"), ["material.regularisation_time=3.6"])
    record_run(tmp_path, SimpleNamespace(steps=10, wall_seconds=1.0, particle_steps_per_second=1.0), 5,
               ["numerics.particle_spacing=0.0006", "material.regularisation_time=3.6"])
    frames = [{"is_wall": np.zeros(5)}]
    assert resolution(scene, frames, tmp_path) == "dp 1.2 mm, 5 particles, material.regularisation_time=3.6"
    # a run resumed from a checkpoint older than its wall-time counter: only the last part is timed, and said so
    record_run(tmp_path, SimpleNamespace(steps=10, wall_seconds=1.0, particle_steps_per_second=1.0,
                                         total_wall_seconds=None), 5, resumed_at_step=30)
    assert cost(tmp_path) == "40 steps, 1 s for the last 10 (resumed at step 30)"
    # a later run of the same case and resolution replaces the earlier one in the README, not in summary.md
    write_rows(tmp_path / "s99_rerun" / "drum", [Row("drum: drum_omega1", "mean inclination; flowing depth",
                                                     "27.0 deg; 40 mm", "22.43 deg; 54 mm", "[P]'s table",
                                                     "dp 5 mm, 1212 particles", "-", "FAIL")])
    readme.write_text(f"{README_BEGIN}\n{README_END}\n")
    update_readme(readme, tmp_path)
    written = readme.read_text()
    assert "27.0 deg; 40 mm" in written and "30.8 deg; 46 mm" not in written
    assert "27.0 deg; 40 mm" in markdown(tmp_path) and "30.8 deg; 46 mm" in markdown(tmp_path)
    # ... also one at the same dp that differed by a --set; one at another dp stands beside it
    write_rows(tmp_path / "s99_set" / "drum", [Row("drum: drum_omega1", "mean inclination; flowing depth",
                                                   "29.5 deg; 34 mm", "22.43 deg; 54 mm", "[P]'s table",
                                                   "dp 5 mm, 1212 particles, numerics.smoothing_length_ratio=1.6",
                                                   "-", "FAIL")])
    write_rows(tmp_path / "s99_set" / "drum_coarse", [Row("drum: drum_omega1", "mean inclination; flowing depth",
                                                          "31.2 deg; 48 mm", "22.43 deg; 54 mm", "[P]'s table",
                                                          "dp 10 mm, 289 particles", "-", "FAIL")])
    update_readme(readme, tmp_path)
    written = readme.read_text()
    assert "29.5 deg; 34 mm" in written and "31.2 deg; 48 mm" in written and "27.0 deg; 40 mm" not in written
    readme.write_text("# no block\n")
    with pytest.raises(ValueError, match="no validation block"):
        update_readme(readme, tmp_path)


def test_validation_rows_are_archived_so_the_table_outlives_the_run_folders(tmp_path):
    """`reference validation --root DIR --archive` copies the runs' rows into the archive, from which
    the table is regenerated once the run folders are gone; a folder named besides its own archived
    copy adds no row twice; the repository's archive holds every validated case's rows."""
    from taichi_granular.validation.table import ARCHIVE, Row, archive, gather, write_rows

    run = tmp_path / "scratch" / "s30_wedge"
    row = Row("obstacle-flow: wedge_coarse", "protected zone", "0 particles", "-", "[A]", "dp 10 mm", "-", "PASS")
    write_rows(run / "wedge_coarse", [row])
    kept = tmp_path / "archive"
    copies = archive(run, into=kept)
    assert copies == [kept / "s30_wedge" / "wedge_coarse" / "table.csv"]
    assert gather(run, kept) == [row]  # the run folder and its copy: one row
    for path in sorted(run.rglob("*"), reverse=True):
        path.unlink() if path.is_file() else path.rmdir()
    assert gather(run, kept) == [row]  # the scratch folder is gone, the row stays
    archived = {r.case.split(":")[0] for r in gather(ARCHIVE)}
    assert {"inclined-plane", "column-collapse", "stake-rows", "element-tests", "drum"} <= archived


def test_validate_resume_continues_an_interrupted_case_from_its_checkpoint(tmp_path):
    """A case whose run stopped half-way (a checkpoint, no run.json) continues with `validate
    --resume` and takes the same steps as the uninterrupted run (bit-exact resume); its cost
    counts the wall time of both segments (the checkpoint carries the first's) and says it was
    resumed; a finished case is reused, not rerun."""
    import json

    from taichi_granular.config import load_scene
    from taichi_granular.output import read_checkpoint
    from taichi_granular.paths import config_path
    from taichi_granular.simulation import Simulation

    sets = ["numerics.particle_spacing=0.009", "numerics.viscosity=implicit", "run.end_time=0.1",
            "run.output_interval=0.025"]
    common = ["validate", "column-collapse", "--cases", "a0_90", "--quiet"] + [a for s in sets for a in ("--set", s)]
    main(common + ["--out", str(tmp_path / "whole")])
    whole = json.loads((tmp_path / "whole" / "collapse_a0_90" / "run.json").read_text())

    scene = load_scene(config_path("mu_i/collapse_a0_90.yaml"), sets)
    first = Simulation(scene, out_dir=tmp_path / "cut" / "collapse_a0_90", progress=False).run(end_time=0.05)
    _, counters = read_checkpoint(tmp_path / "cut" / "collapse_a0_90")
    assert 0.0 < counters["wall_seconds"] <= first.wall_seconds == first.total_wall_seconds
    main(common + ["--out", str(tmp_path / "cut"), "--resume"])
    cut = json.loads((tmp_path / "cut" / "collapse_a0_90" / "run.json").read_text())
    assert cut["steps"] == whole["steps"] and 0 < cut["resumed_at_step"] < cut["steps"]
    assert cut["wall_complete"] and cut["wall_seconds"] >= round(counters["wall_seconds"], 1)
    table = (tmp_path / "cut" / "table.csv").read_text()
    assert f"{cut['steps']} steps, {cut['wall_seconds']:.0f} s (resumed at step {cut['resumed_at_step']})" in table
    fronts = [(tmp_path / d / "collapse_a0_90" / "fronts.csv").read_text() for d in ("whole", "cut")]
    assert fronts[0] == fronts[1]
    stamp = (tmp_path / "cut" / "collapse_a0_90" / "run.json").stat().st_mtime_ns
    main(common + ["--out", str(tmp_path / "cut"), "--resume"])  # finished: reused
    assert (tmp_path / "cut" / "collapse_a0_90" / "run.json").stat().st_mtime_ns == stamp
