"""A corpus of broken scenes through the command line: each ends in one ``error:`` line that
names the key path, exit code 2, and never a traceback; a guard stop exits 3."""
import copy
import csv
import re

import numpy as np
import pytest
import yaml

from scenes import layer
from taichi_granular.cli import main
from taichi_granular.output import read_checkpoint
from taichi_granular.paths import config_path

# the scenes (configs/sweeps holds sweep files, checked by tests/test_sweep.py)
CONFIGS = sorted(p.relative_to(config_path("")).as_posix() for p in config_path("").rglob("*.yaml")
                 if p.parent.name != "sweeps")
# values no key accepts: every numeric key has finite plausible bounds (config._key)
BAD_NUMBERS = [float("nan"), "nan", float("inf"), "-inf", 1e30, -1e30, "1e400"]


def _numeric_leaves(node, path=""):
    """(path in the loader's spelling, container, key) of every number in a raw scene."""
    if isinstance(node, dict):
        for key, value in node.items():
            sub = f"{path}.{key}" if path else str(key)
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                yield sub, node, key
            else:
                yield from _numeric_leaves(value, sub)
    elif isinstance(node, list):
        for index, value in enumerate(node):
            sub = f"{path}[{index}]"
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                yield sub, node, index
            else:
                yield from _numeric_leaves(value, sub)


def _sections(node, path=""):
    """(path, mapping) of every mapping in a raw scene."""
    if isinstance(node, dict):
        yield path, node
        for key, value in node.items():
            yield from _sections(value, f"{path}.{key}" if path else str(key))
    elif isinstance(node, list):
        for index, value in enumerate(node):
            yield from _sections(value, f"{path}[{index}]")


def mutated_scenes():
    """(id, YAML text, the key path the error must name) from every bundled config: each number
    replaced by a value no key accepts, an unknown key in each section, a duplicated key."""
    corpus = []
    for name in CONFIGS:
        text = config_path(name).read_text()
        base = yaml.safe_load(text)
        for k, (path, _, _) in enumerate(_numeric_leaves(base)):
            data = copy.deepcopy(base)
            leaf = {p: (c, key) for p, c, key in _numeric_leaves(data)}[path]
            bad = BAD_NUMBERS[k % len(BAD_NUMBERS)]
            leaf[0][leaf[1]] = bad
            corpus.append((f"{name}:{path}={bad}", yaml.safe_dump(data), re.sub(r"\[\d+\]$", "", path)))
        for path, section in list(_sections(base))[:6]:
            data = copy.deepcopy(base)
            target = dict(_sections(data))[path]
            target["colour_bi" if "render" in path else "grain_densty"] = 1.0
            key = "colour_bi" if "render" in path else "grain_densty"
            corpus.append((f"{name}:{path}+{key}", yaml.safe_dump(data), f"{path}.{key}" if path else key))
        lines = text.splitlines()
        for i, line in enumerate(lines):  # the first top-level scalar key, given twice
            match = re.match(r"^(\w+):\s*[^\s#]", line)
            if match:
                twice = "\n".join(lines[:i + 1] + [line] + lines[i + 1:])
                corpus.append((f"{name}:{match.group(1)} twice", twice, match.group(1)))
                break
    return corpus


# hand-written: one or more per key family, as --set overrides of a bundled scene
OVERRIDES = [
    ("mu_i/inclined_plane.yaml", ["render.width=64"], "render.width"),
    ("mu_i/inclined_plane.yaml", ["render.height=100000"], "render.height"),
    ("mu_i/inclined_plane.yaml", ["render.view_lower=[0.0, 0.0]", "render.view_upper=[1e-3, 10.0]"],
     "render.height"),
    ("mu_i/inclined_plane.yaml", ["walls.0.point=[0.0,.nan]"], "walls[0].point"),
    ("mu_i/inclined_plane.yaml", ["walls.0.normal=[.nan, 1.0]"], "walls[0].normal"),
    ("mu_i/inclined_plane.yaml", ["walls.0.normal=[0.0, 0.5]"], "walls[0].normal"),
    ("mu_i/inclined_plane.yaml", ["gravity.magnitude=1e30"], "gravity.magnitude"),
    ("mu_i/inclined_plane.yaml", ["gravity.magnitude=-9.81"], "gravity.magnitude"),
    ("mu_i/inclined_plane.yaml", ["gravity.tilt_deg=95"], "gravity.tilt_deg"),
    ("mu_i/inclined_plane.yaml", ["material.grain_compressibility=1e30"], "material.grain_compressibility"),
    ("mu_i/inclined_plane.yaml", ["material.reference_inertial_number=1e30"], "material.reference_inertial_number"),
    ("mu_i/inclined_plane.yaml", ["material.grain_diameter=0.5"], "material.grain_diameter"),
    ("mu_i/inclined_plane.yaml", ["material.static_friction_deg='nan'"], "material.static_friction_deg"),
    ("mu_i/inclined_plane.yaml", ["material={a: 1, a: 2}"], "material.a"),
    ("mu_i/inclined_plane.yaml", ["material.grain_density=[1"], "material.grain_density"),
    ("mu_i/inclined_plane.yaml", ["numerics.particle_spacing=1e-7"], "numerics.particle_spacing"),
    ("mu_i/inclined_plane.yaml", ["numerics.cfl=0"], "numerics.cfl"),
    ("mu_i/inclined_plane.yaml", ["numerics.artificial_viscosity.alpha=1e30"], "numerics.artificial_viscosity.alpha"),
    ("mu_i/inclined_plane.yaml", ["domain.upper=[1e5, 1e5]"], "domain.upper"),
    ("mu_i/inclined_plane.yaml", ["domain.lower=[0.0]"], "domain.lower"),
    ("mu_i/inclined_plane.yaml", ["particles.0.upper=[0.1, 0.5]"], "particles[0]"),
    ("mu_i/inclined_plane.yaml", ["run.end_time=-1"], "run.end_time"),
    ("mu_i/inclined_plane.yaml", ["run.max_steps=0"], "run.max_steps"),
    ("mu_i/inclined_plane.yaml", ["run.output_interval=inf"], "run.output_interval"),
    ("mu_i/inclined_plane.yaml", ["run.mach_warning=0"], "run.mach_warning"),
    ("mu_i/inclined_plane.yaml", ["arch=tpu"], "arch"),
    ("mu_i/inclined_plane.yaml", ["walls.7.point=[0, 0]"], "walls.7"),
    ("mu_i/inclined_plane.yaml", ["novel_key=1"], "novel_key"),
    ("elastoplastic/cylinder_coarse.yaml", ["obstacles.0.segments.0.length=1e30"], "obstacles[0].segments[0].length"),
    ("elastoplastic/cylinder_coarse.yaml", ["obstacles.0.segments.0.length=9000", "obstacles.0.width=900"],
     "obstacles[0]"),
    ("elastoplastic/cylinder_coarse.yaml", ["obstacles.0.side_wall_height='nan'"], "obstacles[0].side_wall_height"),
    ("elastoplastic/cylinder_coarse.yaml", ["obstacles.1.lower=[0, 0, .nan]"], "obstacles[1]"),
    ("elastoplastic/cylinder_coarse.yaml", ["material.cohesion=1e30"], "material.cohesion"),
    ("elastoplastic/cylinder_coarse.yaml", ["material.youngs_modulus=-1"], "material.youngs_modulus"),
    ("elastoplastic/cylinder_coarse.yaml", ["numerics.artificial_viscosity.beta=1e30"],
     "numerics.artificial_viscosity.beta"),
    ("elastoplastic/cylinder_coarse.yaml", ["render.camera.field_of_view_deg=0"], "render.camera"),
    ("elastoplastic/cylinder_coarse.yaml", ["obstacles.0={shape: mesh, file: missing.stl}"], "obstacles[0]"),
    ("hypoplastic/inclined_plane.yaml", ["material.wave_speed=1e30"], "material.wave_speed"),
    ("hypoplastic/inclined_plane.yaml", ["material.void_ratio=nan"], "material.void_ratio"),
    ("hypoplastic/drum_omega1.yaml", ["obstacles.0.radius=-0.1"], "obstacles[0].radius"),
    ("hypoplastic/drum_omega1.yaml", ["obstacles.0.angular_velocity=1e30"], "obstacles[0].angular_velocity"),
]


def _describe(capsys, path, overrides=()):
    code = main(["describe", str(path)] + [f"--set={item}" for item in overrides])
    return code, capsys.readouterr().err


def _complaints(code, err, key):
    if code != 2:
        return f"exit {code}"
    if "Traceback" in err or "internal error" in err:
        return "traceback"
    lines = [line for line in err.splitlines() if line.startswith("error: ")]
    if len(lines) != 1:
        return f"{len(lines)} error lines"
    if key not in lines[0]:
        return f"does not name {key}"
    return None


def test_corpus_of_broken_scenes_gets_named_errors_and_no_traceback(tmp_path, capsys):
    corpus = mutated_scenes()
    assert len(corpus) >= 200
    failures = []
    for k, (label, text, key) in enumerate(corpus):
        path = tmp_path / f"scene_{k}.yaml"
        path.write_text(text)
        problem = _complaints(*_describe(capsys, path), key)
        if problem:
            failures.append(f"{label}: {problem}")
    assert not failures, f"{len(failures)} of {len(corpus)}:\n" + "\n".join(failures[:40])


def test_hand_written_overrides_get_named_errors_and_no_traceback(capsys):
    failures = []
    for name, overrides, key in OVERRIDES:
        code, err = _describe(capsys, config_path(name), overrides)
        problem = _complaints(code, err, key)
        if problem:
            failures.append(f"{name} {overrides}: {problem}: {err.strip()[-300:]}")
    assert not failures, "\n".join(failures)


def test_missing_scene_file_is_a_scene_error(tmp_path, capsys):
    code, err = _describe(capsys, tmp_path / "nowhere.yaml")
    assert code == 2 and err.startswith("error: ") and "nowhere.yaml" in err and "Traceback" not in err


def _tiny(tmp_path, **run):
    data = layer(height=0.02, length=0.04, end_time=0.004)
    data["run"].update(output_interval=0.002, **run)
    path = tmp_path / "tiny.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_guard_stop_exits_3_with_its_message_and_snapshot(tmp_path, capsys):
    out = tmp_path / "out"
    code = main(["run", str(_tiny(tmp_path)), "--out", str(out), "--quiet", "--set", "numerics.min_time_step=0.1"])
    err = capsys.readouterr().err
    assert code == 3
    assert "Traceback" not in err and err.strip().startswith("error: ")
    assert "numerics.min_time_step" in err and "failure.npz" in err
    assert (out / "failure.npz").exists()


def test_max_steps_stop_writes_final_frame_diagnostics_and_checkpoint(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", str(_tiny(tmp_path, max_steps=3)), "--out", str(out), "--quiet"]) == 0
    rows = list(csv.DictReader(open(out / "diagnostics.csv")))
    assert [int(r["step"]) for r in rows] == [0, 3]
    assert np.isfinite(float(rows[-1]["t"])) and float(rows[-1]["t"]) > 0.0
    assert read_checkpoint(out)[1]["step"] == 3
    assert len(list((out / "frames").glob("frame_000001_t*s.png"))) == 1


@pytest.mark.parametrize("text, key", [
    ("dimension: 2\ndimension: 2\n", "dimension"),
    ("material:\n  model: mu_i\n  grain_density: 2500\n  grain_density: 2600\n", "material.grain_density"),
])
def test_duplicated_keys_name_both_lines(tmp_path, capsys, text, key):
    path = tmp_path / "twice.yaml"
    path.write_text(text)
    code, err = _describe(capsys, path)
    assert code == 2 and key in err and re.search(r"lines \d+ and \d+", err)
