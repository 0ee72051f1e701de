"""The package as a user installs it: a wheel carries the bundled scenes, and the commands that
need them work from any folder after a plain install into a fresh environment."""
import os
import subprocess
import sys
import tomllib
import venv
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def test_pyproject_lists_every_package_of_the_tree():
    listed = set(tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    tree = {".".join(p.parent.relative_to(REPO).parts) for p in (REPO / "taichi_granular").rglob("__init__.py")}
    assert listed == tree | {"taichi_granular.configs"}


def test_a_wheel_in_a_fresh_environment_runs_the_bundled_scenes(tmp_path):
    """Built without network (the test extras bring ``wheel``), installed without its
    dependencies into a venv that sees this machine's (taichi, numpy, ...), run from an empty
    folder: the bundled scenes resolve inside the installed package, not in this checkout."""
    built = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
                            "-w", str(tmp_path / "dist"), str(REPO)], capture_output=True, text=True, timeout=300)
    assert built.returncode == 0, built.stderr
    wheel = next((tmp_path / "dist").glob("taichi_granular-*.whl"))
    env_dir = tmp_path / "venv"
    venv.create(env_dir, system_site_packages=True, with_pip=False)
    python = env_dir / "bin" / "python"
    environment = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    installed = subprocess.run([str(python), "-m", "pip", "install", "--no-deps", "--no-index", "-q", str(wheel)],
                               capture_output=True, text=True, timeout=300, env=environment)
    assert installed.returncode == 0, installed.stderr
    work = tmp_path / "elsewhere"
    work.mkdir()
    where = subprocess.run([str(python), "-c", "import taichi_granular.paths as p; print(p.CONFIGS); "
                            "print(p.config_path('mu_i/collapse_a0_90.yaml'))"],
                           capture_output=True, text=True, cwd=work, env=environment, timeout=120)
    assert where.returncode == 0, where.stderr
    configs, scene = where.stdout.split()
    assert Path(configs).parts[-2:] == ("taichi_granular", "configs") and str(env_dir) in configs
    assert Path(scene).is_file() and not Path(scene).is_relative_to(REPO)
    described = subprocess.run([str(python), "-m", "taichi_granular", "describe", "configs/mu_i/inclined_plane.yaml"],
                               capture_output=True, text=True, cwd=work, env=environment, timeout=300)
    assert described.returncode == 0, described.stderr
    assert "estimated time step" in described.stdout
