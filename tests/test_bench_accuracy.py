"""The accuracy-versus-cost study (bench/accuracy.py) on a tiny case: the quick sweep's mu(I)
inclined plane (dp 10, 6.25 and 5 mm, 1 s from the analytic profile; measured velocity errors
3.35, 3.19 and 3.16 %) and one option. Checks that the
CSV, the chart and the tables are written, that the error falls as the resolution rises, and
the analysis helpers on numbers whose answer is known."""
import csv
import math
from dataclasses import replace

import imageio.v3 as iio
import pytest

from taichi_granular.bench import accuracy


def test_pareto_front_and_convergence_order_on_known_numbers():
    points = [(1.0, 0.1), (3.0, 0.05), (10.0, 0.06), (30.0, 0.02), (2.0, 0.2)]
    assert accuracy.pareto_front(points) == [0, 1, 3]
    spacings = [0.01, 0.005, 0.0025]
    assert accuracy.convergence_order(spacings, [3.0 * dp**1.5 for dp in spacings]) == pytest.approx(1.5)
    assert math.isnan(accuracy.convergence_order([0.01], [0.1]))


def test_plan_varies_one_option_at_a_time_from_the_config():
    case = accuracy.QUICK[0]
    runs = accuracy.plan([case])
    assert [r.axis for r in runs[:3]] == ["resolution"] * 3
    options = {(r.axis, r.option) for r in runs[3:]}
    assert ("smoothing", "wendland_c2") not in options  # the config's own choice is the baseline
    assert {("smoothing", "wendland_c6"), ("smoothing", "cubic_spline"), ("precision", "f32"),
            ("gradient_correction", "none"), ("integrator", "predictor_corrector"),
            ("artificial_viscosity", "alpha 0.05"), ("cfl", "0.3")} <= options


def test_recommendation_weighs_error_and_cost_over_a_models_cases():
    """Two mu(I) cases: Wendland C6 halves the error at 1.2 times the cost in both (preferred);
    the cubic spline is better still in the mean but worse in one case (never preferred);
    f32 is cheaper and as accurate in one case but failed in the other (never preferred);
    a CFL of 0.3 costs twice as much for the same error (keep the config's 0.5)."""
    cases = [replace(c, axes=("smoothing", "precision", "cfl")) for c in accuracy.QUICK[1:]]
    runs = accuracy.plan(cases)
    for r in runs:
        error, cost = {"wendland_c6": (0.5, 1.2), "0.3": (1.0, 2.0), "f32": (1.0, 0.7),
                       "cubic_spline": (0.2 if r.case is cases[0] else 1.3, 1.0)}.get(r.option, (1.0, 1.0))
        if r.option == "f32" and r.case is cases[1]:
            r.row = {"error": float("nan"), "note": "failed"}
            continue
        r.row = {"error": 0.2 * error, "wall_seconds": 10.0 * cost}
    lines = accuracy.recommendations(runs, cases, "mu_i")
    assert lines[0].startswith("smoothing: wendland_c6 instead of wendland_c2 (error x0.50, cost x1.20")
    assert lines[1] == "precision: keep f64" and lines[2] == "cfl: keep 0.5"


def test_readme_section_is_replaced_between_its_markers(tmp_path):
    readme = tmp_path / "README.md"
    readme.write_text(f"intro\n{accuracy.README_START}\nold table\n{accuracy.README_END}\noutro\n")
    assert accuracy.update_readme(readme, "new table\n")
    assert readme.read_text() == f"intro\n{accuracy.README_START}\nnew table\n{accuracy.README_END}\noutro\n"


def test_quick_sweep_on_a_tiny_case_writes_csv_chart_table_and_error_falls_with_resolution(tmp_path):
    tiny = replace(accuracy.QUICK[0], axes=("artificial_viscosity",))  # the quick plane, one option
    runs, paths = accuracy.study([tiny], tmp_path, "Tiny study", timeout=600, echo=lambda *a: None)
    assert all(r.ok for r in runs), [r.row.get("note") for r in runs]
    with open(paths["csv"]) as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 4 and {r["axis"] for r in rows} == {"resolution", "artificial_viscosity"}
    for r in rows:
        assert float(r["wall_seconds"]) > 0 and int(r["steps"]) > 0 and float(r["peak_rss_mib"]) > 0
        assert sum(float(r[f"share_{c}"]) for c in accuracy.CATEGORIES) == pytest.approx(1.0)
    errors = [float(r["error"]) for r in rows if r["axis"] == "resolution"]
    assert errors[0] > errors[1] > errors[2], errors
    image = iio.imread(paths["png"])
    assert image.ndim == 3 and image.shape[2] == 3
    table = paths["md"].read_text()
    assert "convergence order" in table and "mu i inclined plane" in table and "Recommended per model" in table
    # an interrupted or partly failed study continues: runs that succeeded are read back, not re-run
    again, _ = accuracy.study([tiny], tmp_path, "Tiny study", timeout=1, echo=lambda *a: None, reuse=True)
    assert [r.row["error"] for r in again] == pytest.approx([float(r["error"]) for r in rows])
