"""The rigid local frame of blocks and obstacles: an origin and a tilt about the y axis (3D; z in
2D), so that local x runs down a slope of ``tilt_deg`` and the last local axis is the slope
normal. numpy only."""
import math

import numpy as np


def local_axes(tilt_deg: float, dim: int) -> np.ndarray:
    """(dim, dim) matrix whose columns are the local axes in global coordinates: x' down a
    slope of ``tilt_deg`` below the horizontal, (y' = y in 3D), and the slope normal last."""
    t = math.radians(tilt_deg)
    if dim == 2:
        return np.array([[math.cos(t), math.sin(t)], [-math.sin(t), math.cos(t)]])
    return np.array([[math.cos(t), 0.0, math.sin(t)], [0.0, 1.0, 0.0], [-math.sin(t), 0.0, math.cos(t)]])


def to_global(points: np.ndarray, origin, tilt_deg: float) -> np.ndarray:
    """Local-frame points -> global coordinates  [m]."""
    points = np.asarray(points, float)
    dim = points.shape[1]
    origin = np.zeros(dim) if origin is None else np.asarray(origin, float)
    return origin + points @ local_axes(tilt_deg, dim).T


def to_local(points: np.ndarray, origin, tilt_deg: float) -> np.ndarray:
    """Global points -> local-frame coordinates  [m]."""
    points = np.asarray(points, float)
    dim = points.shape[1]
    origin = np.zeros(dim) if origin is None else np.asarray(origin, float)
    return (points - origin) @ local_axes(tilt_deg, dim)
