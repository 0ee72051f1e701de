"""The documentation: the generated key reference is current, the site builds with --strict
(every page in the nav, every link resolving), and the README stays short."""
import subprocess
import sys
from pathlib import Path

from taichi_granular.reference import key_reference, output_reference

REPO = Path(__file__).resolve().parent.parent


def test_key_reference_is_current():
    """docs/reference/keys.md is what `taichi-granular reference keys` writes today: regenerate it
    with `taichi-granular reference keys --out docs/reference/keys.md` after changing a key."""
    assert (REPO / "docs" / "reference" / "keys.md").read_text() == key_reference()


def test_output_reference_is_current():
    """docs/reference/outputs.md likewise (`taichi-granular reference outputs --out ...`)."""
    text = output_reference()
    assert (REPO / "docs" / "reference" / "outputs.md").read_text() == text
    for row in ("| `velocity` | vector | m/s | all |", "| `deviatoric_stress` | matrix |", "| `frictional_stress` | tensor3 |", "| `void_ratio` |",
                "| `inertial_number` |", "| `mach` | - |", "| `is_wall` |"):
        assert row in text, row


def test_key_reference_names_every_key_with_its_unit_and_bounds():
    text = key_reference()
    for row in ("| `grain_compressibility` | float | required | 1/Pa |", "| `guard_every` | int | 1 |",
                "## `obstacles[]` with `shape: cylinder`", "## `material` with `model: hypoplastic`",
                "## `numerics.particle_shifting`"):
        assert row in text, row


def test_site_builds_strict(tmp_path):
    built = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
                           cwd=REPO, capture_output=True, text=True, timeout=300)
    assert built.returncode == 0, built.stdout + built.stderr
    assert (tmp_path / "site" / "reference" / "keys" / "index.html").exists()


def test_readme_is_short_and_links_resolve():
    readme = (REPO / "README.md").read_text()
    assert len(readme.splitlines()) <= 150
    for target in [part.split(")")[0] for part in readme.split("](")[1:]]:
        if not target.startswith("http"):
            assert (REPO / target).exists(), target
