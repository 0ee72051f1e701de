"""The Mach-number monitor: describe's estimate, the advice that fixes it, the run-time warning."""
import csv
import re

import pytest
import yaml

from scenes import layer
from taichi_granular.cli import main
from taichi_granular.config import load_scene
from taichi_granular.mach import MACH_TARGET, speed_scale
from taichi_granular.paths import config_path
from taichi_granular.physics.rheology.mu_i.steady import analytic_velocity

INCLINE = config_path("mu_i/inclined_plane.yaml")


def _describe_mach(capsys, *overrides):
    assert main(["describe", str(INCLINE)] + [f"--set={o}" for o in overrides]) == 0
    out = capsys.readouterr().out
    return float(re.search(r"Mach (\d+\.\d+)", out).group(1)), out


def test_speed_scale_of_a_periodic_incline_is_the_m56_surface_speed():
    scene = load_scene(INCLINE, ["gravity.tilt_deg=28"])
    speed, source = speed_scale(scene)
    assert "[M56]" in source
    import math
    assert speed == pytest.approx(float(analytic_velocity(0.1, 0.1, scene.material, math.radians(28.0), 9.81)))
    assert 30.0 < speed < 40.0  # ~35 m/s: Mach ~3 at [M]'s K_t


def test_the_suggested_compressibility_brings_the_flow_to_the_target(capsys):
    mach, out = _describe_mach(capsys, "gravity.tilt_deg=28")
    assert mach > 2.5 and "warning" in out
    suggested = re.search(r"material\.grain_compressibility: ([0-9.e+-]+)", out).group(1)
    shift = float(re.search(r"numerics\.particle_shifting\.coefficient: ([0-9.e+-]+)", out).group(1))
    factor = float(re.search(r"sound ([0-9.e+-]+)x faster", out).group(1))
    assert shift == pytest.approx(0.2 / factor, rel=5e-3)  # the shift's rate zeta c stays what it was
    delta = float(re.search(r"numerics\.density_diffusion: ([0-9.e+-]+)", out).group(1))
    assert delta == pytest.approx(0.02 / factor, rel=5e-3)  # and the density diffusion's delta c_0
    mach_after, out_after = _describe_mach(capsys, "gravity.tilt_deg=28", f"material.grain_compressibility={suggested}",
                                           f"numerics.particle_shifting.coefficient={shift}",
                                           f"numerics.density_diffusion={delta}")
    assert mach_after == pytest.approx(MACH_TARGET * 0.3, abs=0.01)
    assert "warning" not in out_after


def test_a_fast_run_warns_once_and_writes_the_mach_number(tmp_path, capsys):
    data = layer(height=0.02, length=0.04, end_time=0.004)
    data["run"].update(output_interval=0.001)
    data["particles"][0]["velocity"] = [20.0, 0.0]  # along the periodic bed: Mach >> 0.3
    path = tmp_path / "fast.yaml"
    path.write_text(yaml.safe_dump(data))
    out = tmp_path / "out"
    assert main(["run", str(path), "--out", str(out), "--quiet"]) == 0
    err = capsys.readouterr().err
    assert err.count("warning:") == 1
    assert "run.mach_warning = 0.3" in err and "material.grain_compressibility:" in err
    rows = list(csv.DictReader(open(out / "diagnostics.csv")))
    assert all(float(r["mach"]) > 0.3 for r in rows)
