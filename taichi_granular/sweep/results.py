"""A sweep's results: one tidy CSV (a row per run: its parameters, its measures, steps, wall
time, status and error) and matplotlib plots of each measure against each parameter (and, for a
sampled sweep, a scatter matrix of parameters and measures)."""
from __future__ import annotations

import csv
import io
import math
from pathlib import Path
from typing import Dict, List, Sequence

from ..output import atomic_write, atomic_write_text
from .spec import Point, Sweep

CSV_NAME = "results.csv"
RUN_COLUMNS = ("steps", "simulated_time", "wall_seconds", "job_seconds")


def rows(sweep: Sweep, points: Sequence[Point], results: Dict[str, dict]) -> List[dict]:
    """A row per point, in the sweep's order; a point without a result is 'missing'."""
    table = []
    for point in points:
        result = results.get(point.id, {})
        row = {"id": point.id, "status": result.get("status", "missing"), **dict(point.values)}
        for name in (*sweep.measures, *RUN_COLUMNS):
            row[name] = result.get(name, math.nan)
        row["error"] = result.get("error", "")
        table.append(row)
    return table


def write_csv(path: Path, table: List[dict]) -> None:
    if not table:
        return
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=list(table[0]))
    writer.writeheader()
    for row in table:
        writer.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in row.items()})
    atomic_write_text(Path(path), buf.getvalue())


def read_csv(path: Path) -> List[dict]:
    with open(path) as fh:
        return list(csv.DictReader(fh))


def _numeric(values) -> List[float]:
    out = []
    for v in values:
        try:
            out.append(float(v))
        except (TypeError, ValueError):
            out.append(math.nan)
    return out


def plot(sweep: Sweep, table: List[dict], folder: Path) -> List[Path]:
    """PNG plots of every measure against every parameter (runs that failed left out), and a
    scatter matrix for a sampled sweep; the paths written. Needs matplotlib (the sweep extra)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = [r for r in table if r["status"] == "ok"]
    written = []
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)

    def save(fig, name):
        path = folder / name
        atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=100, format="png"))
        plt.close(fig)
        written.append(path)

    for measure in sweep.measures:
        for parameter in sweep.parameters:
            x, y = _numeric(r[parameter] for r in ok), _numeric(r[measure] for r in ok)
            pairs = sorted((a, b) for a, b in zip(x, y) if math.isfinite(a) and math.isfinite(b))
            fig, ax = plt.subplots(figsize=(5, 3.6))
            if pairs:
                ax.plot([p[0] for p in pairs], [p[1] for p in pairs], "o" if sweep.is_sample else "o-")
            ax.set_xlabel(parameter)
            ax.set_ylabel(measure)
            ax.set_title(f"{measure} against {parameter} ({len(pairs)} of {len(table)} runs)", fontsize=9)
            ax.grid(True, alpha=0.3)
            fig.tight_layout()
            save(fig, f"{_file_name(measure)}_vs_{_file_name(parameter)}.png")
    if sweep.is_sample:
        names = [*sweep.parameters, *sweep.measures]
        n = len(names)
        fig, axes = plt.subplots(n, n, figsize=(2.2 * n, 2.2 * n), squeeze=False)
        columns = {name: _numeric(r[name] for r in ok) for name in names}
        for i, row_name in enumerate(names):
            for j, col_name in enumerate(names):
                ax = axes[i][j]
                if i == j:
                    values = [v for v in columns[row_name] if math.isfinite(v)]
                    if values:
                        ax.hist(values, bins=max(3, min(20, len(values) // 2)))
                else:
                    ax.plot(columns[col_name], columns[row_name], ".", markersize=4)
                if i == n - 1:
                    ax.set_xlabel(col_name, fontsize=7)
                if j == 0:
                    ax.set_ylabel(row_name, fontsize=7)
                ax.tick_params(labelsize=6)
        fig.tight_layout()
        save(fig, "scatter_matrix.png")
    return written


def _file_name(key: str) -> str:
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in key)
