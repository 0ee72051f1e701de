"""Minimal headless x-y plots (numpy canvas, bitmap font) for validation reports: a reference
curve and measured points, with axes, ticks and labels. No plotting library needed."""
from __future__ import annotations

from typing import Sequence, Tuple

import numpy as np

from .colormap import VIRIDIS
from .font import GLYPH_HEIGHT, draw_text, text_width

MARGIN_LEFT, MARGIN_BOTTOM, MARGIN_TOP, MARGIN_RIGHT = 70, 50, 40, 20


def _nice_ticks(lower: float, upper: float, count: int = 5) -> np.ndarray:
    raw = (upper - lower) / count
    step = 10 ** np.floor(np.log10(raw))
    step *= min((m for m in (1, 2, 5, 10) if m * step >= raw), default=10)
    return np.arange(np.ceil(lower / step) * step, upper + 1e-9 * step, step)


def _line(canvas, r0, c0, r1, c1, colour, width=2):
    n = int(max(abs(r1 - r0), abs(c1 - c0))) + 1
    rows = np.linspace(r0, r1, n).round().astype(int)
    cols = np.linspace(c0, c1, n).round().astype(int)
    for dr in range(-(width // 2), width - width // 2):
        for dc in range(-(width // 2), width - width // 2):
            rr, cc = np.clip(rows + dr, 0, canvas.shape[0] - 1), np.clip(cols + dc, 0, canvas.shape[1] - 1)
            canvas[rr, cc] = colour


def plot_points_and_curve(points: Sequence[Tuple[float, float]], curve: Tuple[np.ndarray, np.ndarray],
                          x_label: str, y_label: str, title: str, size=(640, 480)) -> np.ndarray:
    """(H, W, 3) uint8: ``curve`` (x, y arrays) as a line, ``points`` as squares."""
    width, height = size
    canvas = np.ones((height, width, 3))
    xs = np.concatenate([curve[0], [p[0] for p in points]])
    ys = np.concatenate([curve[1], [p[1] for p in points], [0.0]])
    x_lo, x_hi = min(0.0, float(xs.min()) * 1.05), float(xs.max()) * 1.05
    y_lo, y_hi = min(0.0, float(ys.min()) * 1.1), float(ys.max()) * 1.1
    left, right, top, bottom = MARGIN_LEFT, width - MARGIN_RIGHT, MARGIN_TOP, height - MARGIN_BOTTOM

    def to_px(x, y):
        return bottom - (np.asarray(y) - y_lo) / (y_hi - y_lo) * (bottom - top), \
            left + (np.asarray(x) - x_lo) / (x_hi - x_lo) * (right - left)

    black = (0.0, 0.0, 0.0)
    _line(canvas, bottom, left, bottom, right, black, 1)
    _line(canvas, bottom, left, top, left, black, 1)
    for t in _nice_ticks(x_lo, x_hi):
        _, c = to_px(t, 0)
        _line(canvas, bottom, c, bottom + 5, c, black, 1)
        label = f"{t:g}"
        draw_text(canvas, label, int(c - text_width(label, 2) / 2), bottom + 9, 2)
    for t in _nice_ticks(y_lo, y_hi):
        r, _ = to_px(0, t)
        _line(canvas, r, left - 5, r, left, black, 1)
        label = f"{t:g}"
        draw_text(canvas, label, left - 8 - text_width(label, 2), int(r - GLYPH_HEIGHT), 2)
    rows, cols = to_px(*curve)
    for k in range(len(rows) - 1):
        _line(canvas, rows[k], cols[k], rows[k + 1], cols[k + 1], VIRIDIS[3], 2)
    for x, y in points:
        r, c = to_px(x, y)
        canvas[int(r) - 4:int(r) + 5, int(c) - 4:int(c) + 5] = VIRIDIS[8] * 0.8
    draw_text(canvas, x_label, (left + right - text_width(x_label, 2)) // 2, height - 18, 2)
    draw_text(canvas, y_label, 6, 12, 2)
    draw_text(canvas, title, left + 10, top - 22 + 12, 2)
    return (np.clip(canvas, 0, 1) * 255 + 0.5).astype(np.uint8)
