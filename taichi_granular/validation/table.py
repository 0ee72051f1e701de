"""The validation table: every case's figures beside the paper's and the reference, with the
resolution and the cost of the run, written by the case's own ``check`` (``table.csv`` in its
output folder) and gathered by ``taichi-granular reference validation`` into
docs/validation/summary.md, so that no figure of the table is typed by hand.

Run folders are scratch (a campaign's hours of output do not belong in git), so the rows are
archived in the repository (``ARCHIVE``: each run's ``table.csv``, a few hundred bytes) and the
table is made from the archive and any folders named besides: it can be regenerated on a fresh
clone, and a row once validated is not lost with the machine that ran it."""
from __future__ import annotations

import csv
import io
import json
from dataclasses import astuple, dataclass, fields
from pathlib import Path
from typing import List

from ..output import atomic_write_text
from ..paths import REPO

RUN_FILE = "run.json"  # beside a run's frames: its steps, wall time and particle count


@dataclass
class Row:
    case: str  # validate case: scene
    measure: str  # what is compared
    ours: str  # our figure
    paper: str  # the paper's own (SPH) figure, '-' where it gives none
    reference: str  # what both are judged against: analytic solution, experiment, scaling law
    resolution: str  # dp and particles
    cost: str  # steps and wall time of the run
    verdict: str  # the case's acceptance: PASS or FAIL


def record_run(out: Path, summary, n_material: int, overrides=(), resumed_at_step=None) -> None:
    """Keep the run's cost, and the ``--set`` overrides it ran with, beside its frames (``--reuse``
    reads them back). A run continued from its checkpoint (``resumed_at_step``) counts all its
    steps and the wall time of all its segments (the checkpoint carries the earlier ones'); a
    checkpoint too old to carry it leaves only the continued part's wall time, and says so."""
    total = getattr(summary, "total_wall_seconds", None)
    run = {"steps": summary.steps, "wall_seconds": round(summary.wall_seconds, 1), "particles": n_material,
           "particle_steps_per_second": summary.particle_steps_per_second, "set": list(overrides)}
    if resumed_at_step is not None:
        run.update(steps=resumed_at_step + summary.steps, resumed_at_step=resumed_at_step,
                   wall_complete=total is not None)
        if total is not None:
            run.update(wall_seconds=round(total, 1))
    atomic_write_text(Path(out) / RUN_FILE, json.dumps(run) + "\n")


# overrides the resolution column already shows (dp, the viscous scheme)
_SHOWN = ("numerics.particle_spacing=", "numerics.viscosity=")


def resolution(scene, frames, out: Path = None) -> str:
    """dp and material particles, the viscous scheme where it is the implicit one (the run-outs
    of the tall collapses depend on it: docs/validation/column_collapse.md), and any other
    ``--set`` the run in ``out`` had (a sensitivity run says what it changed)."""
    n = int((frames[0]["is_wall"] == 0).sum()) if frames else 0
    implicit = ", implicit viscosity" if scene.numerics.implicit_viscosity else ""
    overrides = []
    if out is not None and (Path(out) / RUN_FILE).exists():
        overrides = [o for o in json.loads((Path(out) / RUN_FILE).read_text()).get("set", [])
                     if not o.startswith(_SHOWN)]
    changed = "".join(f", {o}" for o in overrides)
    return f"dp {1e3 * scene.numerics.particle_spacing:g} mm, {n} particles{implicit}{changed}"


def cost(out: Path) -> str:
    """'steps, wall time' of the run in ``out`` ('-' if it was not run by validate)."""
    path = Path(out) / RUN_FILE
    if not path.exists():
        return "-"
    run = json.loads(path.read_text())
    if "resumed_at_step" not in run:
        return f"{run['steps']} steps, {run['wall_seconds']:.0f} s"
    if run.get("wall_complete"):
        return f"{run['steps']} steps, {run['wall_seconds']:.0f} s (resumed at step {run['resumed_at_step']})"
    return (f"{run['steps']} steps, {run['wall_seconds']:.0f} s for the last "
            f"{run['steps'] - run['resumed_at_step']} (resumed at step {run['resumed_at_step']})")


def write_rows(base: Path, rows: List[Row]) -> None:
    buf = io.StringIO()
    writer = csv.writer(buf)
    writer.writerow([f.name for f in fields(Row)])
    writer.writerows(astuple(row) for row in rows)
    atomic_write_text(Path(base) / "table.csv", buf.getvalue())


def gather(*roots: Path) -> List[Row]:
    """Every row of the ``table.csv`` files found under ``roots`` (each validate run writes one in
    its output folder), ordered by the registry's order of cases, then by folder."""
    from . import CASES

    order = {name: k for k, name in enumerate(CASES)}
    found = []
    for root in roots:
        for path in sorted(Path(root).rglob("table.csv")):
            with open(path) as fh:
                for k, row in enumerate(csv.DictReader(fh)):
                    row = Row(**row)
                    found.append((order.get(row.case.split(":")[0], len(order)), str(path), k, row))
    rows = []
    for *_, row in sorted(found, key=lambda item: item[:3]):
        if row not in rows:  # a folder named besides the archive that holds its copy
            rows.append(row)
    return rows


ARCHIVE = REPO / "docs" / "validation" / "runs"  # the archived rows: <run>/.../table.csv


def archive(*roots: Path, into: Path = ARCHIVE) -> List[Path]:
    """Copy every ``table.csv`` under ``roots`` into the archive, at ``<root's name>/<its path under
    the root>`` (a later run of the same folder replaces its rows); returns the copies."""
    copies = []
    for root in roots:
        root = Path(root).resolve()
        for path in sorted(root.rglob("table.csv")):
            if Path(into).resolve() in path.parents:
                continue
            target = Path(into) / root.name / path.relative_to(root)
            target.parent.mkdir(parents=True, exist_ok=True)
            atomic_write_text(target, path.read_text())
            copies.append(target)
    return copies


HEADER = """# Validation summary

Generated by `taichi-granular reference validation` from the `table.csv` that each
`taichi-granular validate CASE` writes beside its runs, as archived in docs/validation/runs/
(`--root DIR --archive` adds a folder's runs; here: {root}); do not edit by hand.
"ours" is this package's figure, "paper" the paper's own SPH figure where it gives one, and
"reference" what both are judged against. Cost is on the machine that ran it (see each case's
page for the machine).

"""
TABLE_HEAD = """| case | measure | ours | paper | reference | resolution | cost | acceptance |
|---|---|---|---|---|---|---|---|
"""
README_BEGIN = "<!-- validation table: generated by `taichi-granular reference validation --readme README.md` -->"
README_END = "<!-- end of the validation table -->"


def spacing(row: Row) -> str:
    """The particle spacing of a row's resolution ("dp 5 mm, 1212 particles, key=value" -> "dp 5
    mm"): its first item, before the particle count and any ``--set`` of the run."""
    return row.resolution.split(",")[0].strip()


def latest_runs(rows: List[Row]) -> List[Row]:
    """Of rows with the same case, measure and particle spacing, only the last in ``gather``'s order
    (the archive's run folders sort by session: the latest run of a case replaces the earlier ones,
    also one that differed by a ``--set`` whose value the configs have since taken)."""
    last = {(row.case, row.measure, spacing(row)): k for k, row in enumerate(rows)}
    return [row for k, row in enumerate(rows) if last[(row.case, row.measure, spacing(row))] == k]


def table(*roots: Path, latest: bool = False) -> str:
    """The Markdown table of every row under ``roots`` (``latest``: of each case, measure and
    particle spacing the latest run only); a registered case without any row is listed as not run, so
    that the table names every case."""
    from . import CASES

    rows = latest_runs(gather(*roots)) if latest else gather(*roots)
    seen = {row.case.split(":")[0] for row in rows}
    missing = [Row(name, case.summary, "-", "-", "-", "-", "-", "NOT RUN") for name, case in CASES.items()
               if name not in seen]
    lines = [TABLE_HEAD.rstrip("\n")]
    for row in rows + missing:
        lines.append("| " + " | ".join(str(v).replace("|", "\\|") for v in astuple(row)) + " |")
    return "\n".join(lines) + "\n"


def markdown(*roots: Path) -> str:
    def shown(root: Path) -> str:  # the archive as the repository's path, not this machine's
        root = Path(root).resolve()
        return str(root.relative_to(REPO)) if REPO in root.parents else str(root)

    return HEADER.format(root=", ".join(shown(r) for r in roots)) + table(*roots)


def update_readme(readme: Path, *roots: Path) -> None:
    """Replace the README's block between README_BEGIN and README_END with the table of the latest
    run of each case and particle spacing (summary.md keeps every run)."""
    text = Path(readme).read_text()
    if README_BEGIN not in text or README_END not in text:
        raise ValueError(f"{readme}: no validation block (the lines {README_BEGIN!r} ... {README_END!r})")
    head, rest = text.split(README_BEGIN, 1)
    _, tail = rest.split(README_END, 1)
    atomic_write_text(Path(readme), head + README_BEGIN + "\n" + table(*roots, latest=True) + README_END + tail)
