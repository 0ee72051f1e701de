"""Scene geometry -> initial particles, in numpy only.

Material particles fill each block on a lattice of spacing dp (cell-centred: the first
particle sits dp/2 inside the box). Wall particles sit on the same lattice behind each wall
plane, as many layers as the kernel support 2h needs. The result is a plain
:class:`InitialParticles` that the scheme copies into Taichi fields once.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Dict, List

import numpy as np

from ..config import ConfigError, Scene
from ..local_frame import local_axes, to_global
from .geometry import GeometryError, lattice_counts, obstacle_particles, slab


@dataclass
class InitialParticles:
    """Material particles first, then wall particles; arrays are (n_total, ...)."""

    position: np.ndarray
    velocity: np.ndarray
    mass: np.ndarray
    density: np.ndarray
    pressure: np.ndarray
    n_material: int
    # per boundary particle, where it was laid: 'wall_distance' behind its plane [m] and the plane's
    # 'wall_normal' (zero for obstacles); the boundary model derives its own fields from these and
    # from its source's keys (physics/walls initial_fields)
    wall_layout: Dict[str, np.ndarray] = field(default_factory=dict)  # (n_wall, ...)
    block_of: np.ndarray = None  # block index of each material particle
    wall_of: np.ndarray = None  # source of each wall particle: walls[k], then obstacles[k - len(walls)]

    @property
    def n_total(self) -> int:
        return self.position.shape[0]

    @property
    def n_wall(self) -> int:
        return self.n_total - self.n_material


def lattice_box(lower, upper, spacing: float) -> np.ndarray:
    """Cell-centred lattice points of spacing ``spacing`` filling the box [lower, upper]."""
    counts = lattice_counts(list(zip(lower, upper)), spacing)
    axes = [lo + (np.arange(n) + 0.5) * spacing for lo, n in zip(lower, counts)]
    grids = np.meshgrid(*axes, indexing="ij")
    return np.stack([g.ravel() for g in grids], axis=1)


def tangent_basis(normal: np.ndarray) -> List[np.ndarray]:
    """Unit tangents completing ``normal`` to an orthonormal basis (2D: one, 3D: two)."""
    n = np.asarray(normal, dtype=float)
    if n.size == 2:
        return [np.array([n[1], -n[0]])]
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    t1 = np.cross(n, helper)
    t1 /= np.linalg.norm(t1)
    return [t1, np.cross(n, t1)]


def face_tolerance(lower, upper) -> float:
    """Distance [m] by which a lattice point laid on a face of the box [lower, upper] may miss
    it through rounding and still count as inside."""
    return 1e-9 * max(1.0, float(np.max(np.abs(np.asarray(upper, float) - np.asarray(lower, float)))))


def wall_lattice(point, normal, lower, upper, spacing: float, layers: int, staggered: bool = False):
    """The rows of :func:`geometry.slab` behind the plane (``point``, ``normal``), laid along
    its tangents from ``point`` and kept inside the box [lower, upper].

    Returns (positions, distance behind the plane): points at
    point + (i + 1/2 + s_l) dp t (+ (k + 1/2 + s_l) dp t2) - (l + 1/2) dp n, l < layers, with
    s_l = 1/2 on odd rows when ``staggered``.
    """
    point = np.asarray(point, float)
    normal = np.asarray(normal, float)
    lower = np.asarray(lower, float)
    upper = np.asarray(upper, float)
    tangents = tangent_basis(normal)
    corners = np.array(np.meshgrid(*[[lo, hi] for lo, hi in zip(lower, upper)], indexing="ij")).reshape(len(lower), -1).T
    extent = []
    for t in tangents:
        proj = (corners - point) @ t / spacing
        extent.append(((math.floor(proj.min()) - 1) * spacing, (math.ceil(proj.max()) + 1) * spacing))
    local = slab(extent, spacing, layers, staggered)
    pos = point + local[:, :-1] @ np.array(tangents) + local[:, -1:] * normal
    depth = -local[:, -1]
    tol = face_tolerance(lower, upper)
    inside = np.all((pos >= lower - tol) & (pos <= upper + tol), axis=1)
    return pos[inside], depth[inside]


def hydrostatic_pressure(depth: np.ndarray, gravity_normal: float,
                         density_of_pressure: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
    """p(depth) solving dp/d(depth) = rho(p) g_n with p(0) = 0 (RK4 on a fine grid)  [Pa].

    ``gravity_normal`` is the component of gravity along the bed normal [m/s^2].
    """
    depth = np.asarray(depth, float)
    if depth.size == 0 or gravity_normal <= 0:
        return np.zeros_like(depth)
    d_max = float(depth.max())
    n = max(200, int(d_max / 1e-4))
    grid = np.linspace(0.0, d_max, n + 1)
    step = grid[1] - grid[0]
    p = np.zeros(n + 1)

    def rate(value):
        return gravity_normal * density_of_pressure(np.array([value]))[0]

    for k in range(n):
        k1 = rate(p[k])
        k2 = rate(p[k] + 0.5 * step * k1)
        k3 = rate(p[k] + 0.5 * step * k2)
        k4 = rate(p[k] + step * k3)
        p[k + 1] = p[k] + step * (k1 + 2 * k2 + 2 * k3 + k4) / 6.0
    return np.interp(np.clip(depth, 0.0, None), grid, p)


def build_initial(scene: Scene, model) -> InitialParticles:
    """Material blocks and wall particles of ``scene``; ``model`` supplies
    ``initial_density(pressure)`` and ``reference_density()``."""
    dim = scene.dimension
    dp = scene.numerics.particle_spacing
    g = np.array(scene.gravity_vector)
    g_normal = -g[dim - 1]  # gravity along -(vertical axis): bed-normal component
    rho_ref = model.reference_density()
    volume = dp**dim

    positions, velocities, pressures, block_of = [], [], [], []
    for k, block in enumerate(scene.particles):
        try:
            pts = lattice_box(block.lower, block.upper, dp)
        except GeometryError as err:
            raise ConfigError(f"particles[{k}]", f"the block {err}") from None
        block_g_normal, top = g_normal, block.upper[dim - 1]
        if block.framed:  # lattice and overburden in the block's own frame
            block_g_normal = -float(g @ local_axes(block.tilt_deg, dim)[:, -1])
        if block.shape == "cylinder":  # the vertical cylinder inscribed in the box
            centre = 0.5 * (np.array(block.lower[:2]) + np.array(block.upper[:2]))
            radius = 0.5 * (block.upper[0] - block.lower[0])
            pts = pts[np.sum((pts[:, :2] - centre) ** 2, axis=1) <= radius**2]
        if block.clip_circle is not None:  # a drum's fill: dp/2 clear of its wall
            cx, cy, radius = block.clip_circle
            pts = pts[np.hypot(pts[:, 0] - cx, pts[:, 1] - cy) <= radius - 0.5 * dp]
        if len(pts) == 0:
            raise ConfigError(f"particles[{k}]", "box holds no particle at this spacing")
        vel = np.zeros_like(pts) if block.velocity is None else np.tile(np.array(block.velocity, float), (len(pts), 1))
        velocities.append(vel)
        if block.initial_stress == "hydrostatic":
            depth = top - pts[:, dim - 1]
            pressures.append(hydrostatic_pressure(depth, block_g_normal, model.initial_density))
        else:
            pressures.append(np.zeros(len(pts)))
        if block.framed:
            pts = to_global(pts, block.origin, block.tilt_deg)
        positions.append(pts)
        block_of.append(np.full(len(pts), k))
    x_mat = np.concatenate(positions)
    block_of = np.concatenate(block_of)
    _check_overlaps(x_mat, block_of, dp, scene)
    _check_inside_domain(x_mat, scene, lambda i: f"particles[{block_of[i]}]", "material outside the domain")
    n_mat = len(x_mat)

    wall_pos, wall_depth, wall_normal, wall_of = [], [], [], []
    layers = int(math.ceil(2.0 * scene.numerics.smoothing_length / dp - 1e-9))
    for w, wall in enumerate(scene.walls):
        lower = wall.lower if wall.lower is not None else scene.domain.lower
        upper = wall.upper if wall.upper is not None else scene.domain.upper
        try:
            pts, depth = wall_lattice(wall.point, wall.normal, lower, upper, dp, layers,
                                      staggered=wall.type == "dynamic")
        except GeometryError as err:
            raise ConfigError(f"walls[{w}]", f"wall '{wall.name}': {err}") from None
        behind = (x_mat - np.array(wall.point)) @ np.array(wall.normal) < 0
        inside = np.all((x_mat >= np.array(lower) - 1e-12) & (x_mat <= np.array(upper) + 1e-12), axis=1)
        if np.any(behind & inside):
            i = int(np.argmax(behind & inside))
            raise ConfigError(f"walls[{w}]", f"material particle {i} at {x_mat[i].tolist()} lies behind wall "
                                             f"'{wall.name}'")
        if len(pts) == 0:
            raise ConfigError(f"walls[{w}]", f"wall '{wall.name}' has no particle inside its box")
        wall_pos.append(pts)
        wall_depth.append(depth)
        wall_normal.append(np.tile(np.array(wall.normal, float), (len(pts), 1)))
        wall_of.append(np.full(len(pts), w))
    for k, obstacle in enumerate(scene.obstacles):
        try:
            pts = obstacle_particles(obstacle, dim, dp, layers)
        except GeometryError as err:
            raise ConfigError(f"obstacles[{k}]", f"obstacle '{obstacle.name}': {err}") from None
        if len(pts) == 0:
            raise ConfigError(f"obstacles[{k}]", f"obstacle '{obstacle.name}' holds no particle at this spacing")
        wall_pos.append(pts)
        wall_depth.append(np.zeros(len(pts)))
        wall_normal.append(np.zeros((len(pts), dim)))
        wall_of.append(np.full(len(pts), len(scene.walls) + k))
    if wall_pos:
        x_wall, keep = _unique_points(np.concatenate(wall_pos), dp)
        wall_layout = {"wall_distance": np.concatenate(wall_depth)[keep], "wall_normal": np.concatenate(wall_normal)[keep]}
        wall_of_arr = np.concatenate(wall_of)[keep]
        _check_inside_domain(x_wall, scene, lambda i: _wall_key(scene, wall_of_arr[i]),
                             "wall particles reach outside the domain; enlarge domain")
        _check_clear_of_walls(x_mat, x_wall, wall_of_arr, dp, scene)
    else:
        x_wall = np.zeros((0, dim))
        wall_layout, wall_of_arr = {}, np.zeros(0, int)

    p_mat = np.concatenate(pressures)
    n_wall = len(x_wall)
    position = np.concatenate([x_mat, x_wall]).astype(float)
    velocity = np.concatenate([np.concatenate(velocities), np.zeros((n_wall, dim))])
    p_wall = np.zeros(n_wall)
    preloaded = [k for k, w in enumerate(scene.walls) if w.initial_pressure == "overburden"]
    if preloaded and n_mat:
        mask = np.isin(wall_of_arr, preloaded)
        p_wall[mask] = _overburden(x_wall[mask], x_mat, p_mat, g, rho_ref, 2.0 * scene.numerics.smoothing_length + dp)
    pressure = np.concatenate([p_mat, p_wall])
    density = np.concatenate([model.initial_density(p_mat), model.initial_density(p_wall) if n_wall else []])
    mass = np.full(n_mat + n_wall, rho_ref * volume)
    return InitialParticles(position=position, velocity=velocity, mass=mass, density=density,
                            pressure=pressure, n_material=n_mat, wall_layout=wall_layout,
                            block_of=block_of, wall_of=wall_of_arr)


def _overburden(x_wall, x_mat, p_mat, g, rho, reach):
    """Initial pressure of dynamic boundary particles: the weight of the material over them,
    p = max_j [p_j + rho |g| (h_j - h_w)] >= 0, h the height against gravity and j the material
    particles in the boundary particle's column of width ``reach`` (lateral cells of that size
    and their neighbours); with hydrostatic p_j this is rho |g| (surface - h_w)  [Pa]. A
    boundary particle's pressure follows its density [A5], so one laid at the reference
    density pushes back nothing at t = 0 and the layer falls into the wall: measured, a 5 cm
    elastoplastic layer at rest rang with its vertical stress +-40 % off the overburden, still
    6 % off after 0.57 s (max speed 2e-3 m/s), and with it within 2.1 % (4.7e-5 m/s). Opt-in per
    wall (``walls[].initial_pressure``): [A] lays its boundary particles at the reference
    density, and the validated collapses keep that start (measured: the small 3D a = 0.9
    collapse of tests/test_elastoplastic.py moves from -32.6 % to -42.2 % of Lube's run-out
    with a preloaded floor, the initial sinking into the floor being part of its spreading)."""
    g = np.asarray(g, float)
    g_norm = float(np.linalg.norm(g))
    if g_norm == 0.0:
        return np.zeros(len(x_wall))
    up = -g / g_norm
    dim = len(up)
    # lateral coordinates: an orthonormal basis of the plane normal to gravity
    basis = np.linalg.svd(np.eye(dim) - np.outer(up, up))[0][:, : dim - 1]

    def cells(x):
        return np.floor(x @ basis / reach).astype(np.int64)

    level = p_mat + rho * g_norm * (x_mat @ up)  # p_j + rho |g| h_j: constant down a hydrostatic column
    keys, inverse = np.unique(cells(x_mat), axis=0, return_inverse=True)
    top = np.full(len(keys), -np.inf)
    np.maximum.at(top, inverse.ravel(), level)
    table = {tuple(k): v for k, v in zip(keys, top)}
    wall_cells = cells(x_wall)
    offsets = np.array(np.meshgrid(*[[-1, 0, 1]] * (dim - 1), indexing="ij")).reshape(dim - 1, -1).T
    best = np.full(len(x_wall), -np.inf)
    for w, c in enumerate(wall_cells):
        for o in offsets:
            best[w] = max(best[w], table.get(tuple(c + o), -np.inf))
    return np.maximum(best - rho * g_norm * (x_wall @ up), 0.0)


def _unique_points(points: np.ndarray, spacing: float):
    """Drop wall points that coincide with earlier ones (walls meeting at a corner)."""
    keys = np.round(points / (1e-3 * spacing)).astype(np.int64)
    _, first = np.unique(keys, axis=0, return_index=True)
    keep = np.sort(first)
    return points[keep], keep


def _check_overlaps(points: np.ndarray, block_of: np.ndarray, spacing: float, scene: Scene) -> None:
    keys = np.round(points / (1e-3 * spacing)).astype(np.int64)
    _, first, counts = np.unique(keys, axis=0, return_index=True, return_counts=True)
    if np.any(counts > 1):
        i = int(first[np.argmax(counts > 1)])
        raise ConfigError(f"particles[{block_of[i]}]", f"blocks overlap at {points[i].tolist()}")


def _check_inside_domain(points: np.ndarray, scene: Scene, key_of, message: str) -> None:
    lower = np.array(scene.domain.lower)
    upper = np.array(scene.domain.upper)
    periodic = np.array(scene.domain.periodic_mask)
    tol = face_tolerance(lower, upper)
    outside = np.any(((points < lower - tol) | (points > upper + tol)) & ~periodic, axis=1)
    if np.any(outside):
        i = int(np.argmax(outside))
        raise ConfigError(key_of(i), f"{message}: particle at {points[i].tolist()} is outside "
                                     f"[{scene.domain.lower}, {scene.domain.upper}]")


def _wall_key(scene: Scene, w: int) -> str:
    """The key of the w-th boundary source: walls first, then obstacles."""
    return f"walls[{w}]" if w < len(scene.walls) else f"obstacles[{w - len(scene.walls)}]"


def _check_clear_of_walls(x_mat: np.ndarray, x_wall: np.ndarray, wall_of: np.ndarray, spacing: float,
                          scene: Scene) -> None:
    """No material particle may start closer than dp/2 to a boundary particle (inside an
    obstacle, or a block overlapping a wall): it would be expelled on the first step."""
    if len(x_wall) == 0 or len(x_mat) == 0:
        return
    lo = np.minimum(x_mat.min(axis=0), x_wall.min(axis=0))
    dim = x_mat.shape[1]
    cells_w = np.floor((x_wall - lo) / spacing).astype(np.int64) + 1
    cells_m = np.floor((x_mat - lo) / spacing).astype(np.int64) + 1
    span = np.maximum(cells_w.max(axis=0), cells_m.max(axis=0)) + 2
    weights = np.cumprod(np.r_[1, span[:-1]])
    key_w = cells_w @ weights
    order = np.argsort(key_w, kind="stable")
    sorted_keys = key_w[order]
    nearest = np.full(len(x_mat), np.inf)
    nearest_j = np.zeros(len(x_mat), np.int64)
    for off in np.array(np.meshgrid(*[[-1, 0, 1]] * dim, indexing="ij")).reshape(dim, -1).T:
        key = (cells_m + off) @ weights
        first = np.searchsorted(sorted_keys, key, side="left")
        last = np.searchsorted(sorted_keys, key, side="right")
        for k in range(int((last - first).max(initial=0))):
            has = first + k < last
            j = order[np.minimum(first + k, len(order) - 1)]
            d = np.where(has, np.linalg.norm(x_wall[j] - x_mat, axis=1), np.inf)
            closer = d < nearest
            nearest[closer], nearest_j[closer] = d[closer], j[closer]
    bad = nearest < 0.5 * spacing * (1 - 1e-6)
    if np.any(bad):
        i = int(np.argmax(bad))
        w = int(wall_of[nearest_j[i]])
        raise ConfigError(_wall_key(scene, w), f"material particle {i} at {np.round(x_mat[i], 6).tolist()} lies "
                                               f"within dp/2 of a boundary particle of '{_source_name(scene, w)}'")


def _source_name(scene: Scene, w: int) -> str:
    return scene.walls[w].name if w < len(scene.walls) else scene.obstacles[w - len(scene.walls)].name
