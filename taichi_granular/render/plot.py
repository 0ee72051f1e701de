"""Charts of validation and benchmark results, with matplotlib (headless Agg backend), returned as
(H, W, 3) uint8 images that ``render.frames.write_png`` writes atomically like every output.
The Taichi rasteriser (render/frames.py) draws the particle frames only."""
from __future__ import annotations

from typing import Sequence, Tuple

import numpy as np

DPI = 100


def _figure(size):
    from matplotlib.figure import Figure  # the object API: no pyplot state, no display needed
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    figure = Figure(figsize=(size[0] / DPI, size[1] / DPI), dpi=DPI)
    FigureCanvasAgg(figure)
    return figure


def _to_image(figure) -> np.ndarray:
    figure.tight_layout()
    figure.canvas.draw()
    return np.asarray(figure.canvas.buffer_rgba())[..., :3].copy()


def plot_points_and_curve(points: Sequence[Tuple[float, float]], curve: Tuple[np.ndarray, np.ndarray],
                          x_label: str, y_label: str, title: str, size=(640, 480)) -> np.ndarray:
    """(H, W, 3) uint8: ``curve`` (x, y arrays), the reference, as a line; ``points``, the
    measurements, as squares."""
    figure = _figure(size)
    axes = figure.add_subplot()
    axes.plot(curve[0], curve[1], color="#3b528b", linewidth=1.5, label="reference")
    if len(points):
        axes.plot([p[0] for p in points], [p[1] for p in points], "s", color="#5ec962", markeredgecolor="k",
                  label="measured")
    axes.set_xlabel(x_label)
    axes.set_ylabel(y_label)
    axes.set_title(title)
    axes.grid(True, alpha=0.3)
    axes.legend(loc="best")
    return _to_image(figure)


def plot_pareto(series: Sequence[Tuple[str, Sequence[Tuple[float, float]], Sequence[int]]],
                x_label: str, y_label: str, title: str, size=(800, 560)) -> np.ndarray:
    """(H, W, 3) uint8 log-log scatter: per series (label, points (x, y), indices of its Pareto
    front), the points as hollow squares, the front's points filled and joined by a line."""
    from matplotlib import colormaps

    figure = _figure(size)
    axes = figure.add_subplot()
    colours = colormaps["viridis"](np.linspace(0.0, 0.85, max(1, len(series))))
    for colour, (label, points, front) in zip(colours, series):
        axes.plot([p[0] for p in points], [p[1] for p in points], "s", markerfacecolor="none",
                  markeredgecolor=colour)
        ordered = sorted(front, key=lambda i: points[i][0])
        axes.plot([points[i][0] for i in ordered], [points[i][1] for i in ordered], "s-", color=colour, label=label)
    axes.set_xscale("log")
    axes.set_yscale("log")
    axes.set_xlabel(x_label)
    axes.set_ylabel(y_label)
    axes.set_title(title)
    axes.grid(True, which="both", alpha=0.3)
    axes.legend(loc="best", fontsize="small")
    return _to_image(figure)
