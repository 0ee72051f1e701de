"""A scene builds, compiles and runs only the effects it asks for (issue: effects).

Checked through what the engine allocates (the state's field specs), what Taichi compiled (in a
fresh process, so that no other test's kernels count) and the stage list and per-stage profile
of a step; never through timings.
"""
import json
import subprocess
import sys
import textwrap

import pytest

from scenes import HYPOPLASTIC_SAND, build, layer
from taichi_granular.config import ConfigError
from taichi_granular.scheme import Scheme
from taichi_granular.simulation import Simulation



def field_names(data):
    return set(Scheme(build(data)).state.specs)


def test_mu_i_scene_allocates_no_stress_tensor_and_no_void_ratio():
    mu_i = field_names(layer(height=0.02, length=0.04))
    assert not {name for name in mu_i if "stress" in name or "void" in name or "density_factor" in name}
    # the same layer under the hypoplastic model does carry them: the check can fail
    data = layer(height=0.02, length=0.04, material=HYPOPLASTIC_SAND)
    data["walls"][0]["type"] = "extrapolated"
    hypo = field_names(data)
    assert {"frictional_stress", "density_factor", "deviatoric_stress"} <= hypo


COMPILED = textwrap.dedent("""
    import json, sys
    sys.path.insert(0, {tests!r})
    from scenes import HYPOPLASTIC_SAND, build, layer
    from taichi_granular import runtime
    from taichi_granular.profiling import compiled_kernels
    from taichi_granular.simulation import Simulation
    runtime.init("cpu", "f64")
    seen = []
    for alpha in (0.0, 0.05):
        Simulation(build(layer(height=0.02, length=0.04, alpha=alpha, end_time=1e-3))).run(max_steps=3)
        seen.append(compiled_kernels())
    print(json.dumps(seen))
""")


def test_a_mu_i_step_compiles_no_other_model_and_no_switched_off_effect(tmp_path):
    """A fresh process runs three steps of a mu(I) layer without artificial viscosity, then of
    one with it (alpha = 0.05): the kernels compiled after each."""
    from pathlib import Path
    script = COMPILED.format(tests=str(Path(__file__).parent))
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300,
                         cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    without, with_av = json.loads(out.stdout.strip().splitlines()[-1])
    assert any(".mu_i." in k for k in without)
    for other in (".hypoplastic.", ".elastoplastic.", ".artificial_viscosity.", ".artificial_stress."):
        assert not any(other in k for k in without), (other, without)
    assert any(".artificial_viscosity." in k for k in with_av)
    assert not any(".hypoplastic." in k or ".elastoplastic." in k for k in with_av)


@pytest.mark.parametrize("alpha", [0.0, 0.05])
def test_artificial_viscosity_is_in_the_step_and_profile_only_when_on(alpha):
    sim = Simulation(build(layer(height=0.02, length=0.04, alpha=alpha, end_time=1e-3)), profile=True)
    sim.run(max_steps=3)
    # a pass may carry several pair stages ("momentum_stress + artificial_viscosity + ...")
    in_list = any("artificial_viscosity" in line.split(" [")[0] for line in sim.scheme.stage_list())
    in_profile = any("artificial_viscosity" in name for name in sim.profiler.seconds)
    assert in_list == in_profile == (alpha > 0.0)
    assert sum(calls for name, calls in sim.profiler.calls.items() if "momentum_stress" in name) > 0


@pytest.mark.parametrize("key, value, words", [
    ("artifical_viscosity", {"alpha": 0.1}, ["numerics.artifical_viscosity", "did you mean 'artificial_viscosity'"]),
    ("gradient_correction", "kernel", ["numerics.gradient_correction", "'matrix'"]),
    ("smoothing_function", "wendland_c4", ["numerics.smoothing_function", "wendland_c6"]),
])
def test_an_unknown_effect_is_a_clear_error(key, value, words):
    data = layer(height=0.02, length=0.04)
    data["numerics"][key] = value
    with pytest.raises(ConfigError) as err:
        build(data)
    for w in words:
        assert w in str(err.value)


@pytest.mark.parametrize("config, stages, absent", [
    ("mu_i/inclined_plane.yaml", ["grain_density_pressure", "regularised_viscosity"], ["artificial_viscosity",
                                                                                       "total_stress"]),
    ("hypoplastic/drum_omega1.yaml", ["wall_rotation", "hypoplastic_stress_update", "predictor_corrector"],
     ["grain_density_pressure", "artificial_stress"]),
    ("elastoplastic/collapse3d_a0_90_coarse.yaml", ["artificial_viscosity"], ["hypoplastic_stress_update",
                                                                               "wall_rotation"]),
])
def test_describe_shows_each_model_its_own_stages(config, stages, absent, capsys):
    """One config per model here (all 26 in configs/ describe without error; checked by hand)."""
    from pathlib import Path
    from taichi_granular.cli import main
    assert main(["describe", str(Path(__file__).parents[1] / "configs" / config)]) == 0
    text = capsys.readouterr().out
    steps = text.split("one time step:")[1].split("fields:")[0]
    for stage in stages:
        assert stage in steps
    for stage in absent:
        assert stage not in steps
    assert "estimated time step" in text
