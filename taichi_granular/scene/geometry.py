"""Obstacles -> dynamic boundary particles, in numpy only (MODEL.md section 3, [A] Sec 4.3).

Every obstacle is laid in its own frame (bodies.py ``_Obstacle``, local_frame.py): ``origin`` and a tilt about the
y axis, so that local x runs down a slope and local z is the slope normal. In that frame:

- chute planes are slabs of ``layers`` rows below the bed, staggered by dp/2 along the plane
  on odd rows (Dalrymple & Knio's staggered rows: no gap of one row lines up with a gap of the
  next), as the plane walls of scene/__init__.py; side walls the same, standing on the bed;
- solids (box, post rows, cylinder, wedge, any closed triangle mesh) are the lattice points
  (spacing dp, cell-centred from the solid's lower corner) inside the solid and within
  ``layers`` lattice steps of its surface, found by eroding the inside mask ``layers`` times
  with the 6-neighbourhood. Faces along the frame axes are exact rows; oblique and curved faces
  are staircases of step dp, which a rough wall of particles of size dp does not notice.

``layers`` is ceil(2h/dp), enough that a material particle at the surface sees a full kernel
support of boundary particles.
"""
from __future__ import annotations

import math
from typing import Callable, List, Tuple

import numpy as np

from ..bodies import (BoxObstacle, ChuteObstacle, CylinderObstacle, DrumObstacle, MeshObstacle, PostRowsObstacle,
                      WedgeObstacle)
from ..local_frame import local_axes, to_global, to_local
from ..sections import max_particles


class GeometryError(ValueError):
    """A solid that cannot be laid as particles (too many for this machine, an unreadable mesh);
    scene/__init__.py names the scene key it came from."""


def lattice_counts(extent, spacing: float) -> List[int]:
    """Lattice points per axis of spacing ``spacing`` over ``extent`` [(lo, hi), ...]  [m]; raises
    :class:`GeometryError` before numpy allocates more points than :func:`sections.max_particles`."""
    counts = [max(int(math.floor((hi - lo) / spacing + 1e-9)), 0) for lo, hi in extent]
    total = math.prod(counts)
    if total > max_particles():
        raise GeometryError(f"would lay {total:.3g} particles at dp = {spacing:g} m, more than this machine's "
                            f"memory holds ({max_particles():.3g}); shrink it or coarsen numerics.particle_spacing")
    return counts


# ---- slabs (planes) ------------------------------------------------------------------------


def slab(extent: List[Tuple[float, float]], spacing: float, layers: int, staggered: bool = True) -> np.ndarray:
    """Rows below a plane, local frame: the plane is the last coordinate = 0, its extent the
    ranges of the others; row l sits at depth (l + 1/2) dp, its points at lo + (k + 1/2) dp
    along the plane, shifted by dp/2 on odd rows when ``staggered`` (Dalrymple & Knio's
    staggered rows: every gap of one row is covered by a particle of the next)."""
    if math.prod(lattice_counts(extent, spacing)) * layers > max_particles():
        lattice_counts(extent + [(0.0, layers * spacing)], spacing)  # raises, naming the count
    axes = [np.arange(n) for n in lattice_counts(extent, spacing)]
    rows = []
    for layer in range(layers):
        shift = 0.5 * (layer % 2) if staggered else 0.0
        grids = np.meshgrid(*[lo + (a + 0.5 + shift) * spacing for a, (lo, hi) in zip(axes, extent)],
                            indexing="ij")
        pts = np.stack([g.ravel() for g in grids] + [np.full(grids[0].size, -(layer + 0.5) * spacing)], axis=1)
        upper = np.array([hi for lo, hi in extent])
        rows.append(pts[np.all(pts[:, :-1] <= upper + 1e-9 * spacing, axis=1)])
    return np.concatenate(rows)


def chute_particles(chute: ChuteObstacle, dim: int, spacing: float, layers: int) -> np.ndarray:
    """The planes of ``chute`` and its side walls, global coordinates. Where a steeper plane
    follows a gentler one (a convex break) the slabs overlap below the bed: the points of the
    lower slab that fall inside the upper one are dropped."""
    origin = np.zeros(dim) if chute.origin is None else np.asarray(chute.origin, float)
    out, previous = [], None
    half = 0.5 * chute.width
    for seg in chute.segments:
        extent = [(0.0, seg.length)] + ([(-half, half)] if dim == 3 else [])
        local = slab(extent, spacing, layers)
        if dim == 3 and chute.side_wall_height > 0:
            for side in (-1.0, 1.0):
                # a vertical plane y' = side * half, material on the inside; rows outwards
                wall = slab([(0.0, seg.length), (-layers * spacing, chute.side_wall_height)], spacing, layers)
                out.append(to_global(np.stack([wall[:, 0], side * (half - wall[:, 2]), wall[:, 1]], axis=1),
                                     origin, seg.slope_deg))
        pts = to_global(local, origin, seg.slope_deg)
        if previous is not None:
            prev_origin, prev_slope, prev_length = previous
            inside_prev = to_local(pts, prev_origin, prev_slope)
            overlap = (inside_prev[:, 0] < prev_length) & (inside_prev[:, -1] > -layers * spacing) & \
                (inside_prev[:, -1] < 0.0)
            pts = pts[~overlap]
        out.append(pts)
        previous = (origin, seg.slope_deg, seg.length)
        origin = origin + seg.length * local_axes(seg.slope_deg, dim)[:, 0]
    return np.concatenate(out)


def chute_surface(chute: ChuteObstacle, dim: int, s: np.ndarray) -> np.ndarray:
    """Points on the chute's centre line at distances ``s`` along the bed from its origin  [m]."""
    origin = np.zeros(dim) if chute.origin is None else np.asarray(chute.origin, float)
    s = np.atleast_1d(np.asarray(s, float))
    out = np.zeros((len(s), dim))
    start = 0.0
    for k, seg in enumerate(chute.segments):
        axis = local_axes(seg.slope_deg, dim)[:, 0]
        last = k == len(chute.segments) - 1
        on = (s >= start) & ((s < start + seg.length) | last)
        out[on] = origin + np.outer(s[on] - start, axis)
        origin = origin + seg.length * axis
        start += seg.length
    return out


# ---- solids ---------------------------------------------------------------------------------


def solid_shell(inside: Callable[[np.ndarray], np.ndarray], lower, upper, spacing: float,
                layers: int) -> np.ndarray:
    """Lattice points of the box [lower, upper] (local frame) that are ``inside`` the solid and
    within ``layers`` lattice steps of its surface (erosion with the 6-neighbourhood)."""
    lower = np.asarray(lower, float)
    upper = np.asarray(upper, float)
    counts = [max(n, 1) for n in lattice_counts(list(zip(lower, upper)), spacing)]
    axes = [lo + (np.arange(n) + 0.5) * spacing for lo, n in zip(lower, counts)]
    grids = np.meshgrid(*axes, indexing="ij")
    points = np.stack([g.ravel() for g in grids], axis=1)
    mask = inside(points).reshape(grids[0].shape)
    core = mask.copy()
    for _ in range(layers):
        padded = np.pad(core, 1, constant_values=False)
        eroded = padded[tuple(slice(1, -1) for _ in counts)].copy()
        for a in range(len(counts)):
            for step in (-1, 1):
                index = [slice(1, -1)] * len(counts)
                index[a] = slice(1 + step, padded.shape[a] - 1 + step)
                eroded &= padded[tuple(index)]
        core = eroded
    return points[(mask & ~core).ravel()]


def winding_number(points: np.ndarray, triangles: np.ndarray, chunk: int = 20000) -> np.ndarray:
    """Generalised winding number of a closed triangle mesh at ``points`` (1 inside, 0 outside):
    the sum of the solid angles of its triangles (Van Oosterom & Strackee 1983) over 4 pi."""
    out = np.empty(len(points))
    for start in range(0, len(points), chunk):
        p = points[start:start + chunk, None, :]
        a, b, c = (triangles[None, :, k, :] - p for k in range(3))
        la, lb, lc = (np.linalg.norm(v, axis=2) for v in (a, b, c))
        det = np.einsum("ntk,ntk->nt", a, np.cross(b, c))
        den = la * lb * lc + np.einsum("ntk,ntk->nt", a, b) * lc + np.einsum("ntk,ntk->nt", a, c) * lb \
            + np.einsum("ntk,ntk->nt", b, c) * la
        out[start:start + chunk] = np.sum(2.0 * np.arctan2(det, den), axis=1) / (4.0 * math.pi)
    return out


def mesh_inside(triangles: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    return lambda points: np.abs(winding_number(points, triangles)) > 0.5


def wedge_triangles(wedge: WedgeObstacle) -> np.ndarray:
    """The four faces of the tetrahedral wedge, local frame, (4, 3, 3)  [m]."""
    tip = (0.0, 0.0, 0.0)
    left, right = (wedge.length, -0.5 * wedge.width, 0.0), (wedge.length, 0.5 * wedge.width, 0.0)
    top = (wedge.length, 0.0, wedge.height)
    return np.array([[tip, right, left], [tip, left, top], [tip, top, right], [left, right, top]])


def read_mesh_triangles(path: str, scale: float) -> np.ndarray:
    """Triangles (n, 3, 3) of every triangle and quad cell that meshio reads from ``path``  [m]."""
    import meshio

    try:
        mesh = meshio.read(path)
    except Exception as err:  # meshio raises its own ReadError, OSError, ValueError, ... by format
        raise GeometryError(f"cannot read the mesh {path}: {err}") from None
    pts = np.asarray(mesh.points, float)[:, :3] * scale
    tris = []
    for block in mesh.cells:
        if block.type == "triangle":
            tris.append(block.data)
        elif block.type == "quad":
            tris += [block.data[:, [0, 1, 2]], block.data[:, [0, 2, 3]]]
    if not tris:
        raise GeometryError(f"the mesh {path} has no triangle or quad cells")
    return pts[np.concatenate(tris)]


def post_boxes(posts: PostRowsObstacle) -> List[Tuple[np.ndarray, np.ndarray]]:
    """(lower, upper) local corners of every post."""
    period = posts.post_size + posts.gap
    boxes = []
    for row in range(posts.rows):
        x0 = row * posts.row_spacing
        offset = 0.5 * period if posts.staggered and row % 2 else 0.0
        n = int(math.floor((posts.width + posts.gap) / period + 1e-9))
        first = -0.5 * (n * period - posts.gap) + offset
        for k in range(n):
            y0 = first + k * period
            if y0 + posts.post_size > 0.5 * posts.width + 1e-12:
                continue
            boxes.append((np.array([x0, y0, 0.0]), np.array([x0 + posts.post_size, y0 + posts.post_size,
                                                              posts.height])))
    return boxes


def box_inside(lower, upper):
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    return lambda p: np.all((p >= lower) & (p <= upper), axis=1)


def drum_particles(radius: float, spacing: float, layers: int) -> np.ndarray:
    """Rings at radii R + (k + 1/2) dp, k < layers, each spaced about dp along its arc and turned
    by half a spacing from the ring inside it (no radial gap lines up), centred at 0  [m]."""
    lattice_counts([(0.0, 2.0 * math.pi * (radius + layers * spacing))] * 1 + [(0.0, layers * spacing)], spacing)
    rings = []
    for k in range(layers):
        r = radius + (k + 0.5) * spacing
        n = max(3, int(round(2.0 * math.pi * r / spacing)))
        phi = (np.arange(n) + 0.5 * (k % 2)) * 2.0 * math.pi / n
        rings.append(np.c_[r * np.cos(phi), r * np.sin(phi)])
    return np.concatenate(rings)


def obstacle_particles(obstacle, dim: int, spacing: float, layers: int) -> np.ndarray:
    """Boundary particles of one obstacle, global coordinates  [m]."""
    if isinstance(obstacle, DrumObstacle):
        return drum_particles(obstacle.radius, spacing, layers) + np.asarray(obstacle.origin or (0.0, 0.0), float)
    if isinstance(obstacle, ChuteObstacle):
        return chute_particles(obstacle, dim, spacing, layers)
    if isinstance(obstacle, BoxObstacle):
        local = solid_shell(box_inside(obstacle.lower, obstacle.upper), obstacle.lower, obstacle.upper, spacing,
                            layers)
    elif isinstance(obstacle, PostRowsObstacle):
        local = np.concatenate([solid_shell(box_inside(lo, hi), lo, hi, spacing, layers)
                                for lo, hi in post_boxes(obstacle)])
    elif isinstance(obstacle, CylinderObstacle):
        r, hgt = obstacle.radius, obstacle.height
        lower, upper = np.array([-r, -r, 0.0]), np.array([r, r, hgt])
        # a lattice whose rows are centred on the axis
        n = int(math.floor(2 * r / spacing + 1e-9))
        lower[:2] = -0.5 * n * spacing
        upper[:2] = 0.5 * n * spacing
        local = solid_shell(lambda p: (p[:, 0] ** 2 + p[:, 1] ** 2 <= r * r) & (p[:, 2] <= hgt), lower, upper,
                            spacing, layers)
    elif isinstance(obstacle, WedgeObstacle):
        tris = wedge_triangles(obstacle)
        local = solid_shell(mesh_inside(tris), tris.reshape(-1, 3).min(axis=0), tris.reshape(-1, 3).max(axis=0),
                            spacing, layers)
    elif isinstance(obstacle, MeshObstacle):
        tris = read_mesh_triangles(obstacle.file, obstacle.scale)
        local = solid_shell(mesh_inside(tris), tris.reshape(-1, 3).min(axis=0), tris.reshape(-1, 3).max(axis=0),
                            spacing, layers)
    else:
        raise TypeError(f"unknown obstacle {type(obstacle).__name__}")
    return to_global(local, obstacle.origin, obstacle.tilt_deg)
