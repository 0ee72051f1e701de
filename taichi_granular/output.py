"""Outputs of a run, each written atomically (temporary file + rename): nothing half-written.

``<out>/scene.resolved.yaml``   the scene with every default made explicit
``<out>/particles_NNNNNN.vtu``  one VTU point cloud per frame (meshio)
``<out>/particles.pvd``         the series ParaView opens, with simulated times
``<out>/diagnostics.csv``       t, step, dt, kinetic energy, max speed, max density error per frame
``<out>/checkpoint.npz``        every particle field and the run's counters at the last frame
                                (every ``run.checkpoint_every`` frames; ``taichi-granular resume
                                <out>`` continues from it)
``<out>/failure.npz``, ``.vtu`` the state at which the run-time guard stopped a run, if it did
"""
from __future__ import annotations

import csv
import io
import os
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Dict, Iterable, List

import meshio
import numpy as np

from .config import Scene, dump_scene

# diagnostics.csv, one row per frame: column -> (unit, meaning); the optional ones only where the
# scene has what they measure (docs/reference/outputs.md is generated from these)
DIAGNOSTIC_MEANINGS = {
    "t": ("s", "simulated time of the frame"),
    "step": ("-", "time steps taken"),
    "dt": ("s", "the stable time step after this frame's step"),
    "kinetic_energy": ("J (J/m in 2D)", "kinetic energy of the material"),
    "max_speed": ("m/s", "largest particle speed"),
    "max_density_error": ("-", "largest |rho/rho_ref - 1| of the model (the weakly compressible error)"),
    "mach": ("-", "max_speed over the model's reference sound speed (run.mach_warning)"),
    "outflow": ("-", "particles that left by an open face (domain.outflow)"),
    "viscous_iterations": ("-", "mean BiCGSTAB iterations per step of the implicit viscous solve since the previous "
                                "row (numerics.viscosity: implicit)"),
    "viscous_picard_change": ("-", "with Picard iterations: mean change of the velocities by the re-solves, per |v*|"),
}
DIAGNOSTIC_COLUMNS = ("t", "step", "dt", "kinetic_energy", "max_speed", "max_density_error", "mach")
OPTIONAL_DIAGNOSTIC_COLUMNS = ("outflow", "viscous_iterations", "viscous_picard_change")
INTEGER_DIAGNOSTIC_COLUMNS = ("step", "outflow")


def left_domain(arrays: Dict[str, np.ndarray], n_material: int) -> np.ndarray:
    """Mask of the n_material material particles taken out of the flow at an open face
    (``domain.outflow``, physics/outflow.py), from a snapshot or a saved frame (whose
    ``outflow`` field may span every particle)."""
    if "outflow" not in arrays:
        return np.zeros(n_material, bool)
    return np.asarray(arrays["outflow"])[:n_material] > 0


# Fields written to VTU for every particle (walls included), if the state has them.
VTU_FIELDS = ("velocity", "pressure", "density", "mass")


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def atomic_write(path: Path, write) -> None:
    """Call ``write(tmp_path)`` then rename onto ``path`` (same directory, so atomic)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        write(tmp)
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; outputs get the usual permissions
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def atomic_write_text(path: Path, text: str) -> None:
    def write(tmp):
        with open(tmp, "w") as fh:
            fh.write(text)
    atomic_write(path, write)


def frame_name(index: int) -> str:
    return f"particles_{index:06d}.vtu"


def particle_mesh(arrays: Dict[str, np.ndarray], n_material: int) -> meshio.Mesh:
    """A VTU point cloud of every particle; 2D positions get z = 0; material-only fields are
    padded with 0 on wall particles, and ``is_wall`` marks the walls for ParaView thresholds."""
    pos = arrays["position"]
    n, dim = pos.shape
    points = np.zeros((n, 3))
    points[:, :dim] = pos
    data = {}
    for name, values in arrays.items():
        if name == "position" or name.endswith("_start") or name.startswith("wall_"):
            continue
        values = np.asarray(values)
        if values.ndim > 2:  # tensors: flatten components
            values = values.reshape(values.shape[0], -1)
        full = np.zeros((n,) + values.shape[1:], dtype=float)
        full[: values.shape[0]] = values
        if full.ndim == 2 and full.shape[1] == dim and dim == 2:
            full = np.concatenate([full, np.zeros((n, 1))], axis=1)  # ParaView wants 3-vectors
        data[name] = full
    data["is_wall"] = (np.arange(n) >= n_material).astype(np.int32)
    cells = [("vertex", np.arange(n).reshape(-1, 1))]
    return meshio.Mesh(points, cells, point_data=data)


def read_diagnostics(out_dir: Path) -> List[dict]:
    """The rows of a run's diagnostics.csv, numbers as numbers (``step`` and ``outflow`` as int);
    a column left empty in a row (a run of an older version lacks the later ones) is absent."""
    with open(Path(out_dir) / "diagnostics.csv") as fh:
        return [{k: (int(v) if k in INTEGER_DIAGNOSTIC_COLUMNS else float(v)) for k, v in r.items() if v}
                for r in csv.DictReader(fh)]


CHECKPOINT = "checkpoint.npz"
FAILURE = "failure.npz"


class RunOutput:
    """The output directory of one run."""

    def __init__(self, out_dir: Path, write_vtu: bool = True):
        self.dir = Path(out_dir)
        self.dir.mkdir(parents=True, exist_ok=True)
        self.write_vtu = write_vtu
        self.frames: List[tuple] = []  # (time, file name)
        self.diagnostics: List[dict] = []

    def reopen(self, time: float) -> None:
        """Continue a run from its checkpoint at ``time``: keep the frames and diagnostics rows
        up to it (anything later was written after the checkpoint and is dropped)."""
        if (self.dir / "particles.pvd").exists():
            self.frames = [(t, p.name) for t, p in read_series(self.dir) if t <= time * (1 + 1e-12)]
        if (self.dir / "diagnostics.csv").exists():
            self.diagnostics = [r for r in read_diagnostics(self.dir) if r["t"] <= time * (1 + 1e-12)]

    def write_checkpoint(self, arrays: Dict[str, np.ndarray], counters: Dict[str, float]) -> None:
        self._write_state(CHECKPOINT, arrays, counters)

    def write_failure(self, arrays: Dict[str, np.ndarray], counters: Dict[str, float], n_material: int) -> None:
        """The state at which the run-time guard stopped the run: ``failure.npz`` (every field, as
        a checkpoint) and ``failure.vtu`` (for ParaView); the checkpoint keeps the last good state."""
        self._write_state(FAILURE, arrays, counters)
        self._write_vtu("failure.vtu", arrays, n_material)

    def _write_vtu(self, name: str, arrays: Dict[str, np.ndarray], n_material: int) -> None:
        mesh = particle_mesh(arrays, n_material)
        atomic_write(self.dir / name, lambda tmp: meshio.write(tmp, mesh, file_format="vtu"))

    def _write_state(self, name: str, arrays: Dict[str, np.ndarray], counters: Dict[str, float]) -> None:
        data = {f"field/{k}": v for k, v in arrays.items()}
        data.update({f"counter/{k}": np.array(v) for k, v in counters.items()})
        def write(tmp):
            with open(tmp, "wb") as fh:  # a file object: np.savez would append .npz to a bare name
                np.savez(fh, **data)
        atomic_write(self.dir / name, write)

    def write_scene(self, scene: Scene) -> None:
        atomic_write_text(self.dir / "scene.resolved.yaml", dump_scene(scene))

    def write_frame(self, index: int, time: float, arrays: Dict[str, np.ndarray], n_material: int) -> None:
        if not self.write_vtu:
            return
        name = frame_name(index)
        self._write_vtu(name, arrays, n_material)
        self.frames.append((time, name))
        atomic_write_text(self.dir / "particles.pvd", pvd_text(self.frames))

    def write_diagnostics(self, row: dict) -> None:
        self.diagnostics.append(row)
        buf = io.StringIO()
        columns = DIAGNOSTIC_COLUMNS + tuple(c for c in OPTIONAL_DIAGNOSTIC_COLUMNS if c in row)
        writer = csv.DictWriter(buf, fieldnames=columns, extrasaction="ignore")
        writer.writeheader()
        for r in self.diagnostics:
            writer.writerow({k: (f"{v:.9g}" if isinstance(v, float) else v) for k, v in r.items()})
        atomic_write_text(self.dir / "diagnostics.csv", buf.getvalue())


def pvd_text(frames: Iterable[tuple]) -> str:
    lines = ['<?xml version="1.0"?>',
             '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">', "  <Collection>"]
    for time, name in frames:
        lines.append(f'    <DataSet timestep="{time:.9g}" group="" part="0" file="{name}"/>')
    lines += ["  </Collection>", "</VTKFile>", ""]
    return "\n".join(lines)


def read_series(out_dir: Path) -> List[tuple]:
    """(time, path) of every frame listed in ``particles.pvd``."""
    out_dir = Path(out_dir)
    pvd = out_dir / "particles.pvd"
    if not pvd.exists():
        raise FileNotFoundError(f"no particle series in {out_dir} (missing particles.pvd)")
    root = ET.parse(pvd).getroot()
    return [(float(ds.get("timestep")), out_dir / ds.get("file")) for ds in root.iter("DataSet")]


def read_frame(path: Path) -> Dict[str, np.ndarray]:
    """Point data of one VTU frame, with ``position`` added (z dropped where all zero)."""
    mesh = meshio.read(path)
    arrays = {k: np.asarray(v) for k, v in mesh.point_data.items()}
    pts = np.asarray(mesh.points)
    arrays["position"] = pts[:, :2] if np.all(pts[:, 2] == 0) else pts
    return arrays


def read_checkpoint(out_dir: Path):
    """(fields, counters) of ``<out_dir>/checkpoint.npz``."""
    path = Path(out_dir) / CHECKPOINT
    if not path.exists():
        raise FileNotFoundError(f"no checkpoint in {out_dir} (missing {CHECKPOINT})")
    with np.load(path) as data:
        fields = {k.split("/", 1)[1]: data[k] for k in data.files if k.startswith("field/")}
        counters = {k.split("/", 1)[1]: data[k].item() for k in data.files if k.startswith("counter/")}
    return fields, counters


def load_run_scene(out_dir: Path, overrides=()) -> Scene:
    """The scene a run in ``out_dir`` was made with (its scene.resolved.yaml)."""
    from .config import load_scene

    resolved = Path(out_dir) / "scene.resolved.yaml"
    if not resolved.exists():
        raise FileNotFoundError(f"{out_dir} holds no run (missing scene.resolved.yaml)")
    return load_scene(resolved, overrides)
