"""Bad scenes fail before any field exists, with an error that names the key path."""
import copy

import pytest
import yaml

from taichi_granular.config import ConfigError, dump_scene, load_scene, scene_from_dict
from taichi_granular.paths import config_path

BASE = yaml.safe_load(config_path("mu_i/inclined_plane.yaml").read_text())


def load_with(edit):
    data = copy.deepcopy(BASE)
    edit(data)
    return scene_from_dict(data)


def error_of(edit) -> ConfigError:
    with pytest.raises(ConfigError) as info:
        load_with(edit)
    return info.value


def test_bundled_scene_loads_and_round_trips():
    scene = load_scene(config_path("mu_i/inclined_plane.yaml"))
    assert scene.material.mu_s == pytest.approx(0.38186, rel=1e-4)
    again = scene_from_dict(yaml.safe_load(dump_scene(scene)))
    assert again == scene


@pytest.mark.parametrize("edit,path,words", [
    (lambda d: d["material"].update(grain_densty=800.0), "material.grain_densty", "did you mean 'grain_density'"),
    (lambda d: d["material"].update(mu_s=0.38), "material.mu_s", "static_friction_deg"),
    (lambda d: d["numerics"].update(cfl_number=0.5), "numerics.cfl_number", "did you mean 'cfl'"),
    (lambda d: d.update(dimensions=2), "dimensions", "did you mean 'dimension'"),
    (lambda d: d["material"].pop("grain_compressibility"), "material.grain_compressibility", "missing"),
    (lambda d: d.pop("run"), "run", "missing"),
    (lambda d: d["material"].update(solid_fraction_min=0.6), "material.solid_fraction_min", "phi_min"),
    (lambda d: d["material"].update(limit_friction_deg=20.0), "material.limit_friction_deg", "mu_2 must exceed"),
    (lambda d: d["material"].update(grain_density=-800.0), "material.grain_density", "plausible range"),
    (lambda d: d["material"].update(grain_diameter=0.5), "material.grain_diameter", "metres"),
    (lambda d: d["material"].update(static_friction_deg=0.36), "material.static_friction_deg", "degrees"),
    (lambda d: d["material"].update(model="mu-i"), "material.model", "did you mean 'mu_i'"),
    (lambda d: d["numerics"].update(particle_spacing=0.5), "numerics.particle_spacing", "larger than the domain"),
    (lambda d: d["numerics"].update(cfl=2.0), "numerics.cfl", "stable"),
    (lambda d: d["numerics"].update(smoothing_function="wendland"), "numerics.smoothing_function", "not one of"),
    (lambda d: d["numerics"].update(particle_spacing="fine"), "numerics.particle_spacing", "expected a number"),
    (lambda d: d["domain"].update(lower=[0.0]), "domain.lower", "2 components"),
    (lambda d: d["domain"].update(periodic=["q"]), "domain.periodic", "unknown axis"),
    (lambda d: d["particles"][0].update(upper=[0.2, 0.5]), "particles[0]", "leaves the domain"),
    (lambda d: d["walls"][0].update(normal=[0.0, 0.5]), "walls[0].normal", "unit vector"),
    (lambda d: d["run"].update(end_time=-1.0), "run.end_time", "plausible range"),
    (lambda d: d["gravity"].update(tilt_deg=95.0), "gravity.tilt_deg", "(-90, 90)"),
    (lambda d: d.update(arch="tpu"), "arch", "not one of"),
    (lambda d: d["run"].update(stop_at_rest=2.0), "run.stop_at_rest", "(0, 1)"),
    (lambda d: d["run"].update(checkpoint_every=0), "run.checkpoint_every", "plausible range"),
    (lambda d: d["run"].update(guard="always"), "run.guard", "not one of"),
    (lambda d: d["walls"][0].update(initial_pressure="overburden"), "walls[0].initial_pressure", "dynamic"),
    (lambda d: d.update(render={"colour_bi": "speed"}), "render.colour_bi", "did you mean 'colour_by'"),
    (lambda d: d.update(render={"range": [5.0, 1.0]}), "render.range", "min < max"),
    (lambda d: d.update(render={"width": 10}), "render.width", "[32, 8192]"),
    (lambda d: d.update(render={"view_lower": [0.0, 0.0]}), "render.view_lower", "both"),
    (lambda d: d.update(render={"camera": {"position": [0, 0, 1], "look_at": [0, 0, 0]}}), "render.camera",
     "only 3D"),
])
def test_bad_values_name_their_key(edit, path, words):
    err = error_of(edit)
    assert err.path == path
    assert words in str(err)


def test_numbers_written_without_a_dot_are_numbers():
    scene = load_with(lambda d: d["material"].update(grain_compressibility="1e-5"))  # PyYAML reads a str
    assert scene.material.grain_compressibility == 1e-5


def test_material_behind_a_wall_is_an_error():
    from taichi_granular.physics.rheology.mu_i.model import MuIRheology
    from taichi_granular.scene import build_initial

    scene = load_with(lambda d: d["walls"][0].update(point=[0.0, 0.05]))
    with pytest.raises(ConfigError, match="behind wall 'base'") as info:
        build_initial(scene, MuIRheology(scene.material, 2, scene.numerics.smoothing_length))
    assert info.value.path == "walls[0]"


def test_overrides_apply_dotted_keys(tmp_path):
    scene = load_scene(config_path("mu_i/inclined_plane.yaml"), ["numerics.cfl=0.25", "run.end_time=0.5"])
    assert scene.numerics.cfl == 0.25 and scene.run.end_time == 0.5


def test_overrides_index_lists():
    """An integer key picks a list entry (a wall, a block); a bad index names the key path."""
    scene = load_scene(config_path("elastoplastic/collapse3d_a0_90_coarse.yaml"),
                       ["walls.0.friction_angle_deg=30", "particles.0.upper=[0.1, 0.1, 0.09]"])
    assert scene.walls[0].friction_angle_deg == 30
    assert scene.particles[0].upper[2] == 0.09
    with pytest.raises(ConfigError, match="not an index") as info:
        load_scene(config_path("elastoplastic/collapse3d_a0_90_coarse.yaml"), ["walls.3.normal=[0, 0, 1]"])
    assert info.value.path == "walls.3"


@pytest.mark.parametrize("scene, overrides, key, words", [
    ("mu_i/collapse_a0_90.yaml", ["walls.0.type=extrapolated"], "walls[0].type", "ghost particles"),
    ("mu_i/collapse_a0_90.yaml", ["numerics.stress_diffusion=0.1"], "numerics.stress_diffusion", "mu_i does not have it"),
    ("mu_i/collapse_a0_90.yaml", ["numerics.bulk_viscosity=0.1"], "numerics.bulk_viscosity", "mu_i does not have it"),
    ("mu_i/collapse_a0_90.yaml", ["numerics.viscosity=implicit", "numerics.viscous_theta=1"], "numerics.viscous_theta",
     "viscous_scheme: theta"),
    ("elastoplastic/collapse3d_a0_90_coarse.yaml", ["numerics.viscosity=implicit"], "numerics.viscosity",
     "elastoplastic does not have it"),
    ("elastoplastic/collapse3d_a0_90_coarse.yaml", ["numerics.stress_increment=0.01"], "numerics.stress_increment",
     "elastoplastic does not have it"),
    ("hypoplastic/collapse_a0_55.yaml", ["walls.0.type=dynamic"], "walls[0].type", "extrapolated walls"),
])
def test_what_a_model_does_not_support_is_named(scene, overrides, key, words):
    """Scene.check reads each material's declaration (wall types, obstacle shapes, the model-specific
    numerics keys it reads), not the model's name."""
    with pytest.raises(ConfigError) as err:
        load_scene(config_path(scene), overrides)
    assert str(err.value).startswith(key + ":") and words in str(err.value), str(err.value)


def test_obstacles_a_model_does_not_support_are_named():
    """The toy Newtonian fluid has no obstacles; the boundary types a scene combines are those
    the walls registry has a model for (ghost walls beside dynamic obstacles: one)."""
    from taichi_granular.config import WALL_COMBINATIONS
    from taichi_granular.physics.walls import BOUNDARIES

    data = yaml.safe_load(config_path("mu_i/collapse_a0_90.yaml").read_text())
    data["material"] = {"model": "newtonian", "density": 1000.0, "viscosity": 1.0, "sound_speed": 10.0}
    data["obstacles"] = [{"shape": "box", "lower": [0.5, 0.0], "upper": [0.6, 0.05]}]
    with pytest.raises(ConfigError) as err:
        scene_from_dict(data)
    assert str(err.value).startswith("obstacles[0].shape:") and "supports the obstacles: none" in str(err.value)
    assert set(WALL_COMBINATIONS) == set(BOUNDARIES)
    drum = yaml.safe_load(config_path("hypoplastic/drum_omega1.yaml").read_text())
    assert scene_from_dict(drum).obstacles[0].shape == "drum"


def test_dynamic_boundaries_default_to_coulomb_friction_at_the_material_angle():
    """Issue 26: a dynamic floor left at its default is Coulomb with delta = phi (zero-pressure
    sheets no longer slide without bound on a rough floor); `friction: rough` keeps the old rule,
    and a friction rule on a ghost wall is refused."""
    import math

    from taichi_granular.scheme import Scheme

    base = "elastoplastic/collapse3d_a0_90_coarse.yaml"
    default = Scheme(load_scene(config_path(base), ["walls.0.friction_angle_deg=null"]))
    assert default.state.wall_friction.to_numpy() == pytest.approx(math.tan(math.radians(30.0)))
    assert "wall_friction" in [s.name for s in default.rate_stages]
    rough = Scheme(load_scene(config_path(base), ["walls.0.friction_angle_deg=null", "walls.0.friction=rough"]))
    assert "wall_friction" not in [s.name for s in rough.rate_stages]
    with pytest.raises(ConfigError, match="walls\\[0\\].friction: only dynamic"):
        load_scene(config_path("mu_i/inclined_plane.yaml"), ["walls.0.friction=coulomb"])
    with pytest.raises(ConfigError, match="friction: rough takes no Coulomb friction angle"):
        load_scene(config_path(base), ["walls.0.friction=rough"])
    with pytest.raises(ConfigError, match="friction: pressure_only takes no Coulomb friction angle"):
        load_scene(config_path(base), ["walls.0.friction=pressure_only"])
    plain = Scheme(load_scene(config_path(base), ["walls.0.friction_angle_deg=null", "walls.0.friction=pressure_only"]))
    assert "wall_friction" not in [s.name for s in plain.rate_stages]
    assert set(plain.state.wall_friction.to_numpy()) == {-2.0}  # dynamic.NO_RULE: [A]'s wall
