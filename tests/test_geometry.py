"""Obstacle geometry (scene/geometry.py): frames, chutes with slope breaks, solids, meshes."""
import math

import numpy as np
import pytest

from taichi_granular.bodies import AnyObstacle
from taichi_granular.config import ConfigError, _convert
from taichi_granular.scene import geometry as geo

DP = 0.005


def obstacle(**keys):
    return _convert(AnyObstacle, keys, "obstacles[0]")


def nearest_distance(points, cloud):
    """Distance from each of ``points`` to the nearest point of ``cloud``."""
    return np.array([np.min(np.linalg.norm(cloud - p, axis=1)) for p in points])


def test_local_frame_is_orthonormal_and_descends():
    for dim in (2, 3):
        axes = geo.local_axes(30.0, dim)
        assert np.allclose(axes.T @ axes, np.eye(dim))
        assert np.isclose(np.linalg.det(axes), 1.0)  # right-handed: no mirror
        assert axes[-1, 0] == pytest.approx(-0.5)  # local x goes down at 30 deg
        assert axes[-1, -1] == pytest.approx(math.cos(math.radians(30.0)))  # normal points up
    p = np.array([[0.3, -0.1, 0.2]])
    assert np.allclose(geo.to_local(geo.to_global(p, [1.0, 2.0, 3.0], 20.0), [1.0, 2.0, 3.0], 20.0), p)


def test_chute_bed_is_closed_at_every_depth_row_and_across_the_slope_break():
    """Two planes, 45 then 20 deg (a concave break, the stake-row chute): every point of the
    bed within the chute lies within sqrt(3)/2 dp of a boundary particle (the most a point can
    be from a lattice of spacing dp whose first row is dp/2 down; a missing particle makes it
    1.1 dp or more), no boundary particle stands above the bed, and the first row sits
    dp/2 below it."""
    chute = obstacle(shape="chute", segments=[{"length": 0.2, "slope_deg": 45.0}, {"length": 0.2, "slope_deg": 20.0}],
                     width=0.06, side_wall_height=0.03)
    pts = geo.obstacle_particles(chute, 3, DP, 3)
    s = np.linspace(0.01, 0.39, 77)
    bed = geo.chute_surface(chute, 3, s)
    for y in (-0.025, 0.0, 0.025):
        assert nearest_distance(bed + [0.0, y, 0.0], pts).max() < 0.87 * DP
    # heights above the bed, measured along each plane's normal (the bed is the lower envelope)
    above = np.full(len(pts), -np.inf)
    for k, (origin, slope) in enumerate([(np.zeros(3), 45.0), (geo.chute_surface(chute, 3, 0.2)[0], 20.0)]):
        local = geo.to_local(pts, origin, slope)
        on = (local[:, 0] >= 0) & (local[:, 0] <= 0.2) & (np.abs(local[:, 1]) < 0.03)
        above[on] = np.maximum(above[on], local[on, 2])
    assert np.max(above[np.isfinite(above)]) == pytest.approx(-0.5 * DP)
    # side walls stand beside the bed, up to their height
    local = geo.to_local(pts, np.zeros(3), 45.0)
    side = (local[:, 0] < 0.18) & (np.abs(local[:, 1]) > 0.03)  # clear of the 20 deg plane's walls
    assert np.abs(local[side, 1]).min() == pytest.approx(0.03 + 0.5 * DP)
    assert 0.03 - DP < local[side, 2].max() <= 0.03 + 1e-12


def test_chute_rows_are_staggered():
    chute = obstacle(shape="chute", segments=[{"length": 0.1, "slope_deg": 0.0}], width=0.05)
    pts = geo.obstacle_particles(chute, 3, DP, 3)
    first = pts[np.isclose(pts[:, 2], -0.5 * DP)]
    second = pts[np.isclose(pts[:, 2], -1.5 * DP)]
    assert np.allclose(np.sort(np.unique(first[:, 0]))[:2], [0.5 * DP, 1.5 * DP])
    assert np.allclose(np.sort(np.unique(second[:, 0]))[:2], [DP, 2 * DP])


def test_convex_slope_break_has_no_doubled_particles():
    """20 then 45 deg (steeper below): the slabs overlap under the break; no two boundary
    particles may end up closer than 0.3 dp."""
    chute = obstacle(shape="chute", segments=[{"length": 0.1, "slope_deg": 20.0}, {"length": 0.1, "slope_deg": 45.0}],
                     width=0.02)
    pts = geo.obstacle_particles(chute, 3, DP, 3)
    d = np.linalg.norm(pts[:, None, :] - pts[None, :, :], axis=2)
    np.fill_diagonal(d, np.inf)
    assert d.min() > 0.3 * DP


def test_box_shell_counts():
    """A 10 x 8 x 6 dp box with 3 layers: every lattice point but the 4 x 2 x 0 core (none)."""
    box = obstacle(shape="box", lower=[0.0, 0.0, 0.0], upper=[10 * DP, 8 * DP, 6 * DP])
    assert len(geo.obstacle_particles(box, 3, DP, 3)) == 10 * 8 * 6
    big = obstacle(shape="box", lower=[0.0, 0.0, 0.0], upper=[10 * DP, 10 * DP, 10 * DP])
    assert len(geo.obstacle_particles(big, 3, DP, 2)) == 10**3 - 6**3


def test_post_rows_gaps_and_staggering():
    """1 cm posts, 1 cm gaps (stake-row case 1 and 3): neighbouring posts' particles face each
    other across gap + dp; a staggered row is shifted by half a period."""
    aligned = obstacle(shape="post_rows", post_size=0.01, gap=0.01, rows=2, row_spacing=0.05, width=0.1,
                       height=0.02)
    staggered = obstacle(shape="post_rows", post_size=0.01, gap=0.01, rows=2, row_spacing=0.05, width=0.1,
                         height=0.02, staggered=True)
    boxes = geo.post_boxes(aligned)
    assert len(boxes) == 10
    assert [b[0][1] for b in boxes[:5]] == pytest.approx([-0.045, -0.025, -0.005, 0.015, 0.035])
    shifted = geo.post_boxes(staggered)
    assert len(shifted) == 9
    assert shifted[5][0][1] - shifted[0][0][1] == pytest.approx(0.01)
    pts = geo.obstacle_particles(aligned, 3, DP, 3)
    row = pts[pts[:, 0] < 0.02]
    ys = np.unique(np.round(row[:, 1], 9))
    gaps = np.diff(ys)
    assert gaps.max() == pytest.approx(0.01 + DP)  # the clear gap between posts, plus dp
    assert len(pts) == 10 * 2 * 2 * 4  # 5 posts a row, 2 rows; 2 x 2 particles per cross-section, 4 high


def test_cylinder_is_round_and_hollow_deep_inside():
    cyl = obstacle(shape="cylinder", radius=0.015, height=0.01, tilt_deg=36.0, origin=[0.1, 0.0, 0.0])
    pts = geo.to_local(geo.obstacle_particles(cyl, 3, 0.002, 3), [0.1, 0.0, 0.0], 36.0)
    r = np.hypot(pts[:, 0], pts[:, 1])
    assert r.max() <= 0.015
    assert r.max() > 0.015 - 0.002
    # the shell stands on the chute plane of its frame and is symmetric about the axis
    assert pts[:, 2].min() == pytest.approx(0.001)
    assert abs(pts[:, 0].mean()) < 1e-9 and abs(pts[:, 1].mean()) < 1e-9


def test_winding_number_and_wedge():
    wedge = obstacle(shape="wedge", length=0.1, width=0.08, height=0.05)
    tris = geo.wedge_triangles(wedge)
    w = geo.winding_number(np.array([[0.08, 0.0, 0.01], [0.02, 0.0, 0.03], [-0.01, 0.0, 0.0]]), tris)
    assert w == pytest.approx([1.0, 0.0, 0.0], abs=1e-9)
    pts = geo.obstacle_particles(wedge, 3, DP, 3)
    assert np.all(geo.winding_number(pts, tris) > 0.5)
    # it points up the slope: the thin end at x = 0, the full rear face at x = length
    assert pts[:, 0].min() < 0.02 and pts[:, 0].max() > 0.1 - DP
    near_tip = pts[pts[:, 0] < 0.02]
    assert np.abs(near_tip[:, 1]).max() < 0.2 * 0.04 + DP


def test_mesh_file_gives_the_same_particles_as_the_box(tmp_path):
    """A cube written as an STL by meshio, read back as a mesh obstacle: the same boundary
    particles as the box obstacle of the same size."""
    import meshio

    size = 8 * DP
    corners = np.array([[x, y, z] for x in (0, size) for y in (0, size) for z in (0, size)])
    quads = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    tris = [[q[0], q[1], q[2]] for q in quads] + [[q[0], q[2], q[3]] for q in quads]
    path = tmp_path / "cube.stl"
    meshio.write(str(path), meshio.Mesh(corners * 1000.0, [("triangle", np.array(tris))]), binary=True)  # in mm
    mesh = obstacle(shape="mesh", file=str(path), scale=1e-3, origin=[0.0, 0.0, 0.0])
    box = obstacle(shape="box", lower=[0.0, 0.0, 0.0], upper=[size, size, size])
    a = np.round(geo.obstacle_particles(mesh, 3, DP, 2) / DP, 6)
    b = np.round(geo.obstacle_particles(box, 3, DP, 2) / DP, 6)
    assert len(a) == len(b) == 8**3 - 4**3
    assert set(map(tuple, a)) == set(map(tuple, b))


def test_obstacle_keys_are_checked():
    with pytest.raises(ConfigError, match=r"obstacles\[0\].shape.*unknown shape 'cylindre'.*cylinder"):
        obstacle(shape="cylindre", radius=0.1, height=0.1)
    with pytest.raises(ConfigError, match=r"obstacles\[0\].radius.*unknown key"):
        obstacle(shape="box", lower=[0, 0, 0], upper=[1, 1, 1], radius=0.1)
    post = obstacle(shape="post_rows", post_size=0.01, gap=0.01, rows=2, row_spacing=0.005, width=0.1, height=0.02)
    with pytest.raises(ConfigError, match="row_spacing"):
        post.check("obstacles[0]", 3)
    with pytest.raises(ConfigError, match="needs dimension 3"):
        obstacle(shape="cylinder", radius=0.1, height=0.1).check("obstacles[0]", 2)


def stake_scene(case=2, resolution="_coarse"):
    from taichi_granular.config import load_scene
    from taichi_granular.paths import config_path

    return load_scene(config_path(f"elastoplastic/stake_rows_case{case}{resolution}.yaml"))


def test_stake_row_scenes_build_as_described():
    """The configs hold what their comments say: 2.0 kg of sand (paper) in the release box, the
    rows 0.30 m down the 20 deg panel, and no material particle inside a boundary."""
    from taichi_granular.physics.rheology import model_class
    from taichi_granular.scene import build_initial
    from taichi_granular.validation import obstacles as ob

    for case, resolution, mass in ((1, "", 2.025), (2, "_coarse", 1.89), (3, "_coarse", 1.89)):
        scene = stake_scene(case, resolution)
        ini = build_initial(scene, model_class("elastoplastic").from_scene(scene))
        assert ini.mass[:ini.n_material].sum() == pytest.approx(mass)
        offset = 0.25 if resolution else 0.0  # the coarse chutes start 0.25 m down the 45 deg panel
        first, last = ob.post_rows_span(scene)
        assert first == pytest.approx(1.8 + 0.3 - offset, abs=1e-4)
        size = 0.02 if case == 2 else 0.01
        assert last - first == pytest.approx(2 * 4 * size + size)
        s, height = ob.along_chute(ob.obstacle_of(scene, ob.ChuteObstacle), ini.position[:ini.n_material])
        assert height.min() == pytest.approx(0.5 * scene.numerics.particle_spacing)  # resting on the bed
        assert 0.30 - offset < s.min() and s.max() < 0.45 - offset


def test_efficiency_factor_counts_the_areas():
    """Particles placed by hand on the coarse case-2 chute: 2 above the rows on the 20 deg panel
    (area 1), 1 among the rows (area 2), 3 past them, 2 still on the 45 deg panel: 3/8."""
    from taichi_granular.scene.geometry import chute_surface
    from taichi_granular.validation import obstacles as ob

    scene = stake_scene(2)
    chute = ob.obstacle_of(scene, ob.ChuteObstacle)
    first, last = ob.post_rows_span(scene)
    s = np.array([1.65, 1.75, first + 0.05, last + ob.LEE + 0.01, 2.25, 2.35, 0.25, 0.75])  # break at 1.55 m
    pos = chute_surface(chute, 3, s) + np.array([0.0, 0.0, 0.004])  # just above the bed
    n = len(pos)
    frame = {"position": pos, "mass": np.ones(n), "is_wall": np.zeros(n, int)}
    result = ob.evaluate_stake_rows(scene, [0.0, 1.0], [frame, frame])
    assert result.area1 == pytest.approx(2 / 8) and result.area2 == pytest.approx(1 / 8)
    assert result.efficiency == pytest.approx(3 / 8)
    assert result.passed == pytest.approx(3 / 8) and result.upper_panel == pytest.approx(2 / 8)
    assert result.efficiency_bracket == pytest.approx((3 / 8, 4 / 8))  # the grain 0.01 m past area 2 within 0.2 m
    assert result.crossed == 0
    below = dict(frame, position=pos - np.array([0.0, 0.0, 0.01]))
    assert ob.evaluate_stake_rows(scene, [0.0], [below]).crossed > 0
    off = dict(below, position=below["position"] + np.array([0.0, 0.3, 0.0]))  # beside the 0.4 m chute
    assert ob.evaluate_stake_rows(scene, [0.0], [off]).crossed == 0
    assert ob.evaluate_stake_rows(scene, [0.0], [off]).fell_off == n


def test_grains_off_the_chute_are_not_retained():
    """Four grains in area 1 and the same four 0.4 m off the centre line and 0.3 m below the bed
    (fallen over the side of the 0.4 m chute): half the sand is retained, not all of it, although
    the fallen grains' distance along the chute lies in area 1; a grain taken out at an open face
    is not retained either."""
    from taichi_granular.scene.geometry import chute_surface
    from taichi_granular.validation import obstacles as ob

    scene = stake_scene(2)
    chute = ob.obstacle_of(scene, ob.ChuteObstacle)
    s = np.array([1.60, 1.65, 1.70, 1.75])  # area 1: the slope break at 1.55 m, the first row at 1.85 m
    on = chute_surface(chute, 3, s) + np.array([0.0, 0.0, 0.004])
    fallen = on + np.array([0.0, 0.4, -0.3])
    pos = np.vstack([on, fallen])
    frame = {"position": pos, "mass": np.ones(8), "is_wall": np.zeros(8, int)}
    result = ob.evaluate_stake_rows(scene, [0.0], [frame])
    assert result.area1 == pytest.approx(0.5) and result.efficiency == pytest.approx(0.5)
    assert result.lost == pytest.approx(0.5) and result.not_retained == pytest.approx(0.5)
    assert result.fell_off == 4 and result.crossed == 0
    end = chute_surface(chute, 3, np.array([sum(seg.length for seg in chute.segments) - 0.01]))[0]
    fallen_off_end = dict(frame, position=np.vstack([on, end + np.array([0.05, 0.0, -0.1])] * 1 + [on[:3]]))
    result = ob.evaluate_stake_rows(scene, [0.0], [fallen_off_end])
    assert result.crossed == 0 and result.lost == pytest.approx(1 / 8)  # off the end, not through the bed
    departed = dict(frame, position=np.vstack([on, on]), outflow=np.array([0.0] * 4 + [1.0] * 4))
    result = ob.evaluate_stake_rows(scene, [0.0], [departed])
    assert result.efficiency == pytest.approx(0.5) and result.departed == 4 and result.fell_off == 0


def test_stake_rows_are_judged_against_the_papers_sph():
    """The efficiency and area 1 are judged against [A]'s SPH at dp 5 mm: within 10 points of
    both passes, 11 points off either fails."""
    from taichi_granular.validation import obstacles as ob

    def result(efficiency, area1):
        return ob.StakeRowResult(name="stake_rows_case2_cpu", case="case2", efficiency=efficiency, area1=area1,
                                 area2=efficiency - area1, passed=1 - efficiency, upper_panel=0.0, lost=0.0,
                                 crossed=0, fell_off=0, departed=0, front_stop_time=1.0)

    assert result(0.43, 0.0).within and result(0.52, 0.09).within
    assert not result(0.48 + 0.06, 0.0).within  # 11 points above [A]'s 43 %
    assert not result(0.43, 0.11).within  # area 1 11 points above [A]'s 0 %


def test_material_inside_an_obstacle_is_refused():
    from taichi_granular.config import ConfigError
    from taichi_granular.physics.rheology import model_class
    from taichi_granular.scene import build_initial
    import dataclasses

    scene = stake_scene(2)
    block = dataclasses.replace(scene.particles[0], lower=(0.25, -0.06, 0.0))  # into the box's back wall
    scene = dataclasses.replace(scene, particles=(block,))
    with pytest.raises(ConfigError, match=r"obstacles\[1\].*within dp/2.*release box back"):
        build_initial(scene, model_class("elastoplastic").from_scene(scene))
