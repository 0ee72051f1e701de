"""Where the bundled scenes live: ``taichi_granular/configs`` in an installed wheel (pyproject.toml
ships the repository's ``configs/`` there), the repository's ``configs/`` in a source checkout."""
from pathlib import Path
from typing import Optional

PACKAGE = Path(__file__).resolve().parent
REPO = PACKAGE.parent  # a source checkout's root (README.md, renders/); not there in a wheel install
SOURCE_CHECKOUT = (REPO / "pyproject.toml").is_file() and (REPO / "configs").is_dir()
CONFIGS = PACKAGE / "configs" if (PACKAGE / "configs").is_dir() else REPO / "configs"


def config_path(relative: str) -> Path:
    """The bundled scene (or folder of scenes) ``relative`` to the configs folder, e.g.
    ``mu_i/collapse_a0_90.yaml``."""
    path = CONFIGS / relative
    if not path.exists():
        raise FileNotFoundError(f"{relative} is not a bundled scene (looked in {CONFIGS}); "
                                f"pass a scene file's path")
    return path


def bundled(path: Path) -> Optional[Path]:
    """The bundled scene a path that does not exist names, if any: ``mu_i/inclined_plane.yaml``
    or ``configs/mu_i/inclined_plane.yaml`` from any folder, so that the README's commands work
    after a plain ``pip install`` too."""
    parts = Path(path).parts
    if parts and parts[0] == "configs":
        parts = parts[1:]
    if not parts or Path(*parts).is_absolute():
        return None
    candidate = CONFIGS.joinpath(*parts)
    return candidate if candidate.is_file() else None
