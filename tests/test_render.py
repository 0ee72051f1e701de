"""Headless rasteriser (render/): coverage, colours, depth order, walls, the render command."""
import math

import numpy as np
import pytest

from scenes import GLASS_BEADS, build, layer
from taichi_granular import runtime
from taichi_granular.config import ConfigError
from taichi_granular.render.colormap import NEUTRAL_GREY, colour_map
from taichi_granular.render.frames import Renderer, check_colour_field

WHITE = np.array([255, 255, 255])


@pytest.fixture(autouse=True)
def taichi_cpu():
    runtime.init("cpu", "f64")


def scene_2d(**render):
    data = layer(height=0.05, length=0.1)
    data["render"] = {"width": 220, "range": [0.0, 1.0], "view_lower": [0.0, 0.0], "view_upper": [0.1, 0.1],
                      **render}
    return build(data)


def frame(positions, speeds, n_material=None, dp=0.005):
    n = len(positions)
    velocity = np.zeros((n, len(positions[0])))
    velocity[:, 0] = speeds
    return {"position": np.array(positions, float), "velocity": velocity,
            "mass": np.full(n, 600.0 * dp ** velocity.shape[1]), "density": np.full(n, 600.0),
            "pressure": np.linspace(0.0, 1.0, n)}, (n if n_material is None else n_material)


def test_a_disc_covers_its_true_area_in_its_colour():
    scene = scene_2d()
    renderer = Renderer(scene)
    arrays, n = frame([[0.05, 0.05]], [0.3])
    image = renderer.image(arrays, n, 0.0)[:, :renderer.view_width]
    covered = np.any(image != WHITE, axis=2)
    covered[:40, :] = False  # the time stamp
    radius_px = math.sqrt(0.005**2 / math.pi) / renderer.pixel
    assert covered.sum() == pytest.approx(math.pi * radius_px**2, rel=0.08)
    row, col = int((0.1 - 0.05) / renderer.pixel), int(0.05 / renderer.pixel)
    expected = np.round(255 * colour_map(np.array([0.3]), 0.0, 1.0)[0])
    assert np.abs(image[row, col].astype(int) - expected).max() <= 1


def test_walls_are_grey_and_material_is_drawn_over_them():
    scene = scene_2d()
    renderer = Renderer(scene)
    arrays, _ = frame([[0.05, 0.05], [0.0515, 0.05]], [1.0, 0.0])
    image = renderer.image(arrays, 1, 0.0)
    row = int((0.1 - 0.05) / renderer.pixel)
    wall_side = image[row, int(0.0537 / renderer.pixel)]
    assert np.abs(wall_side.astype(int) - np.round(255 * np.array(NEUTRAL_GREY))).max() <= 1
    overlap = image[row, int(0.0508 / renderer.pixel)]  # both cover it: the material particle wins
    assert np.abs(overlap.astype(int) - np.round(255 * colour_map(np.array([1.0]), 0, 1)[0])).max() <= 1


@pytest.mark.parametrize("padded", [False, True])
def test_particles_out_of_the_flow_are_not_drawn(padded):
    """A particle taken out at an open face gets no size, whether its ``outflow`` flag spans the
    material (a run's snapshot) or every particle (a saved VTU frame, walls padded with 0)."""
    renderer = Renderer(scene_2d())
    arrays, _ = frame([[0.02, 0.05], [0.06, 0.05], [0.08, 0.05]], [0.5, 0.5, 0.0])
    arrays["outflow"] = np.array([0.0, 1.0, 0.0] if padded else [0.0, 1.0])
    radii = renderer.radii(arrays, 2)
    assert radii[0] > 0 and radii[1] == 0 and radii[2] > 0


def test_unknown_colour_field_names_the_key():
    arrays, _ = frame([[0.05, 0.05]], [0.3])
    with pytest.raises(ConfigError, match=r"render.colour_by: no particle field 'presure'; did you mean 'pressure'"):
        check_colour_field("presure", arrays)


def scene_3d():
    material = dict(GLASS_BEADS)
    data = {"name": "splat", "dimension": 3, "domain": {"lower": [-1, -1, -1], "upper": [1, 1, 1]},
            "material": material, "particles": [{"name": "b", "lower": [0, 0, 0], "upper": [0.2, 0.2, 0.2]}],
            "numerics": {"particle_spacing": 0.1}, "run": {"end_time": 1.0, "output_interval": 1.0},
            "render": {"width": 400, "height": 300, "range": [0.0, 1.0],
                       "camera": {"position": [0.0, -3.0, 0.0], "look_at": [0.0, 0.0, 0.0], "up": [0, 0, 1],
                                  "field_of_view_deg": 30.0}}}
    return build(data)


@pytest.mark.parametrize("near_first", [True, False])
def test_the_nearer_sphere_hides_the_farther_one(near_first):
    renderer = Renderer(scene_3d())
    near, far = [0.0, -0.5, 0.0], [0.0, 0.5, 0.0]
    positions = [near, far] if near_first else [far, near]
    speeds = [0.0, 1.0] if near_first else [1.0, 0.0]  # the near sphere is dark blue (speed 0)
    arrays, n = frame(positions, speeds, dp=0.3)
    image = renderer.image(arrays, n, 0.0).astype(int)
    centre = image[150, 200]
    assert centre[2] > centre[0] and centre[2] > centre[1]  # viridis(0) is blue-violet, viridis(1) yellow
    # Lambert shading: the lit side of the sphere is brighter than the side away from the light
    offset = int(0.5 * 0.5 * 300 / math.tan(math.radians(15)) * np.cbrt(3 * 0.3**3 / (4 * math.pi)) / 2.5)
    lit, unlit = image[150 - offset, 200 - offset], image[150 + offset, 200 + offset]
    assert lit.sum() > unlit.sum()


def test_render_command_rerenders_a_run(tmp_path):
    from taichi_granular.cli import main
    from taichi_granular.simulation import Simulation

    data = layer(height=0.02, length=0.04)
    data["run"] = {"end_time": 0.002, "output_interval": 0.001}
    out = tmp_path / "run"
    Simulation(build(data), out_dir=out).run()
    names = sorted(p.name for p in (out / "frames").glob("frame_*.png"))
    assert names == ["frame_000000_t0s.png", "frame_000001_t0.001s.png", "frame_000002_t0.002s.png"]
    gif = tmp_path / "p.gif"
    assert main(["render", str(out), "--colour-by", "pressure", "--width", "200", "--video", str(gif)]) == 0
    assert len(list((out / "frames_pressure").glob("frame_*.png"))) == 3
    assert gif.stat().st_size > 0
    assert main(["render", str(out), "--colour-by", "nonsense"]) == 2


def test_a_top_view_camera_shows_x_to_the_right(tmp_path):
    """The render command's --camera/--up: looking straight down with up = +y, a particle at
    +x appears right of the image centre and one at -x left of it (the default up = +z would be
    parallel to the view)."""
    import dataclasses

    from taichi_granular.sections import Camera

    scene = scene_3d()
    top = Camera(position=(0.0, 0.0, 3.0), look_at=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0), field_of_view_deg=30.0)
    renderer = Renderer(dataclasses.replace(scene, render=dataclasses.replace(scene.render, camera=top)))
    arrays, n = frame([[0.4, 0.0, 0.0], [-0.4, 0.0, 0.0]], [1.0, 0.0], dp=0.3)
    image = renderer.image(arrays, n, 0.0).astype(int)
    row = image[150]
    yellow = np.nonzero((row[:, 0] > 150) & (row[:, 1] > 150) & (row[:, 2] < 120))[0]  # viridis(1), speed 1
    assert len(yellow) and yellow.mean() > 200, yellow


def test_charts_are_drawn_headless():
    """render/plot.py draws with matplotlib's Agg backend (no display): an image of the asked size
    with the reference line and the measured points in it."""
    from taichi_granular.render.plot import plot_pareto, plot_points_and_curve

    x = np.linspace(0.0, 1.0, 20)
    image = plot_points_and_curve([(0.5, 0.3)], (x, x**2), "x [m]", "y [m]", "check", size=(320, 240))
    assert image.shape == (240, 320, 3) and image.dtype == np.uint8
    assert (image < 128).any() and (image > 250).mean() > 0.5  # ink on a mostly white page
    pareto = plot_pareto([("a", [(1.0, 0.1), (10.0, 0.01)], [0, 1])], "wall [s]", "error", "front", size=(400, 300))
    assert pareto.shape == (300, 400, 3)
