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


class _Frame:
    """Plot area of a canvas: data -> pixel mapping (linear or log10 per axis), axes, ticks, labels."""

    def __init__(self, canvas, x_range, y_range, log_x=False, log_y=False):
        self.canvas = canvas
        height, width = canvas.shape[:2]
        self.left, self.right = MARGIN_LEFT, width - MARGIN_RIGHT
        self.top, self.bottom = MARGIN_TOP, height - MARGIN_BOTTOM
        self.log_x, self.log_y = log_x, log_y
        self.x_lo, self.x_hi = (np.log10(v) if log_x else v for v in x_range)
        self.y_lo, self.y_hi = (np.log10(v) if log_y else v for v in y_range)

    def to_px(self, x, y):
        """(row, column) pixel coordinates of data points."""
        x = np.log10(x) if self.log_x else np.asarray(x, float)
        y = np.log10(y) if self.log_y else np.asarray(y, float)
        return self.bottom - (y - self.y_lo) / (self.y_hi - self.y_lo) * (self.bottom - self.top), \
            self.left + (x - self.x_lo) / (self.x_hi - self.x_lo) * (self.right - self.left)

    @staticmethod
    def _ticks(lower, upper, log):
        """(value, label) ticks over the axis range (log10 of it on a log axis): nice linear
        steps, or the decades."""
        if not log:
            return [(t, f"{t:g}") for t in _nice_ticks(lower, upper)]
        decades = np.arange(np.ceil(lower - 1e-9), np.floor(upper + 1e-9) + 1)
        return [(10.0**d, f"{10.0**d:g}") for d in decades]

    def axes(self, x_label: str, y_label: str, title: str) -> None:
        canvas, black = self.canvas, (0.0, 0.0, 0.0)
        left, right, top, bottom = self.left, self.right, self.top, self.bottom
        _line(canvas, bottom, left, bottom, right, black, 1)
        _line(canvas, bottom, left, top, left, black, 1)
        x_origin = 10.0**self.x_lo if self.log_x else self.x_lo
        y_origin = 10.0**self.y_lo if self.log_y else self.y_lo
        for t, label in self._ticks(self.x_lo, self.x_hi, self.log_x):
            _, c = self.to_px(t, y_origin)
            _line(canvas, bottom, c, bottom + 5, c, black, 1)
            draw_text(canvas, label, int(c - text_width(label, 2) / 2), bottom + 9, 2)
        for t, label in self._ticks(self.y_lo, self.y_hi, self.log_y):
            r, _ = self.to_px(x_origin, t)
            _line(canvas, r, left - 5, r, left, black, 1)
            draw_text(canvas, label, left - 8 - text_width(label, 2), int(r - GLYPH_HEIGHT), 2)
        height = canvas.shape[0]
        draw_text(canvas, x_label, (left + right - text_width(x_label, 2)) // 2, height - 18, 2)
        draw_text(canvas, y_label, 6, 12, 2)
        draw_text(canvas, title, left + 10, top - 22 + 12, 2)

    def polyline(self, x, y, colour, width=2) -> None:
        rows, cols = self.to_px(x, y)
        for k in range(len(rows) - 1):
            _line(self.canvas, rows[k], cols[k], rows[k + 1], cols[k + 1], colour, width)

    def square(self, x, y, colour, half=4, hollow=False) -> None:
        r, c = (int(v) for v in self.to_px(x, y))
        self.canvas[r - half:r + half + 1, c - half:c + half + 1] = colour
        if hollow:
            self.canvas[r - half + 2:r + half - 1, c - half + 2:c + half - 1] = 1.0


def _to_image(canvas) -> np.ndarray:
    return (np.clip(canvas, 0, 1) * 255 + 0.5).astype(np.uint8)


def plot_points_and_curve(points: Sequence[Tuple[float, float]], curve: Tuple[np.ndarray, np.ndarray],
                          x_label: str, y_label: str, title: str, size=(640, 480)) -> np.ndarray:
    """(H, W, 3) uint8: ``curve`` (x, y arrays) as a line, ``points`` as squares."""
    width, height = size
    canvas = np.ones((height, width, 3))
    xs = np.concatenate([curve[0], [p[0] for p in points]])
    ys = np.concatenate([curve[1], [p[1] for p in points], [0.0]])
    frame = _Frame(canvas, (min(0.0, float(xs.min()) * 1.05), float(xs.max()) * 1.05),
                   (min(0.0, float(ys.min()) * 1.1), float(ys.max()) * 1.1))
    frame.axes(x_label, y_label, title)
    frame.polyline(*curve, VIRIDIS[3], 2)
    for x, y in points:
        frame.square(x, y, VIRIDIS[8] * 0.8)
    return _to_image(canvas)


def plot_pareto(series: Sequence[Tuple[str, Sequence[Tuple[float, float]], Sequence[int]]],
                x_label: str, y_label: str, title: str, size=(800, 560)) -> np.ndarray:
    """(H, W, 3) uint8 log-log scatter: per series (label, points (x, y), indices of its Pareto
    front), the points as hollow squares, the front's points filled and joined by a line, and a
    legend of the series' colours."""
    width, height = size
    canvas = np.ones((height, width, 3))
    xs = np.array([p[0] for _, pts, _ in series for p in pts], float)
    ys = np.array([p[1] for _, pts, _ in series for p in pts], float)
    frame = _Frame(canvas, (10 ** np.floor(np.log10(xs.min())), 10 ** np.ceil(np.log10(xs.max()))),
                   (10 ** np.floor(np.log10(ys.min())), 10 ** np.ceil(np.log10(ys.max()))), True, True)
    frame.axes(x_label, y_label, title)
    colours = VIRIDIS[np.linspace(0, len(VIRIDIS) - 2, max(1, len(series))).round().astype(int)] * 0.85
    for k, (label, points, front) in enumerate(series):
        colour = colours[k]
        for x, y in points:
            frame.square(x, y, colour, hollow=True)
        ordered = sorted(front, key=lambda i: points[i][0])
        frame.polyline([points[i][0] for i in ordered], [points[i][1] for i in ordered], colour, 2)
        for i in ordered:
            frame.square(*points[i], colour)
        row = frame.top + 8 + 16 * k
        key = frame.right - 24 - max(text_width(name, 2) for name, _, _ in series)  # the legend fits the frame
        canvas[row:row + 9, key:key + 9] = colour
        draw_text(canvas, label, key + 14, row, 2)
    return _to_image(canvas)
