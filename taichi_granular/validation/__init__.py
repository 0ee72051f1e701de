"""Validation cases: each runs its scene (or reads its output) and returns errors as numbers."""
from typing import Dict

import numpy as np


def left_domain(frame: Dict[str, np.ndarray], n: int) -> np.ndarray:
    """Mask of the n material particles taken out of the flow at an open face
    (``domain.outflow``; physics/outflow.py parks them outside the box)."""
    if "outflow" not in frame:
        return np.zeros(n, bool)
    return np.asarray(frame["outflow"][:n]) > 0
