"""Where the bundled scenes live (the repository's ``configs/``)."""
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def config_path(relative: str) -> Path:
    path = REPO / "configs" / relative
    if not path.exists():
        raise FileNotFoundError(f"{path} not found: run from a source checkout (pip install -e .) "
                                f"or pass --config")
    return path
