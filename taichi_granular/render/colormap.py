"""Perceptually uniform colour map for particle fields.

Viridis (van der Walt & Smith, matplotlib 2.0; released CC0): lightness rises monotonically
and evenly from dark blue through green to yellow, so equal steps in a field read as equal
steps in colour, and the map survives grey-scale printing and the common colour-vision
deficiencies. Stored as 11 samples (at 0, 0.1, ..., 1) of the published 256-entry table and
interpolated linearly in sRGB.
"""
import numpy as np

VIRIDIS = np.array([
    (0.267004, 0.004874, 0.329415), (0.282623, 0.140926, 0.457517), (0.253935, 0.265254, 0.529983),
    (0.206756, 0.371758, 0.553117), (0.163625, 0.471133, 0.558148), (0.127568, 0.566949, 0.550556),
    (0.134692, 0.658636, 0.517649), (0.266941, 0.748751, 0.440573), (0.477504, 0.821444, 0.318195),
    (0.741388, 0.873449, 0.149561), (0.993248, 0.906157, 0.143936),
])

NEUTRAL_GREY = (0.55, 0.55, 0.55)  # walls and obstacles
BACKGROUND = (1.0, 1.0, 1.0)


def colour_map(values: np.ndarray, lower: float, upper: float) -> np.ndarray:
    """RGB in [0, 1], shape (n, 3), of ``values`` on [lower, upper] (clipped)."""
    span = upper - lower if upper > lower else 1.0
    s = np.clip((np.asarray(values, float) - lower) / span, 0.0, 1.0) * (len(VIRIDIS) - 1)
    k = np.minimum(s.astype(int), len(VIRIDIS) - 2)
    f = (s - k)[:, None]
    return (1.0 - f) * VIRIDIS[k] + f * VIRIDIS[k + 1]
