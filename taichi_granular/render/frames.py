"""Frames: particle arrays -> coloured, annotated PNG images (``Renderer``), and videos.

The Renderer turns one frame's arrays (a run's snapshot or a saved VTU frame) into an image:
particles coloured by a field through the colour map, walls in neutral grey, the simulated
time stamped at the top left and a colour bar with its range on the right.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Dict, Sequence, Tuple

import numpy as np

from ..config import Scene
from ..sections import COLOUR_BAR_MARGIN
from ..output import left_domain
from .colormap import BACKGROUND, NEUTRAL_GREY, colour_map
from .font import GLYPH_HEIGHT, draw_text, text_width

UNITS = {"speed": "m/s", "velocity": "m/s", "pressure": "pa", "density": "kg/m3", "grain_density": "kg/m3",
         "strain_rate": "1/s", "viscosity": "pa s", "solid_fraction": "-", "inertial_number": "-",
         "acceleration": "m/s2", "grain_diameter": "m"}


def field_values(arrays: Dict[str, np.ndarray], name: str) -> np.ndarray:
    """Per-particle scalar for colouring: ``speed`` is |velocity|, vectors give their magnitude,
    tensors their Frobenius norm."""
    if name == "speed":
        name = "velocity"
    if name not in arrays:
        raise KeyError(name)
    values = np.asarray(arrays[name], float)
    if values.ndim > 1:
        values = np.sqrt(np.sum(values.reshape(values.shape[0], -1) ** 2, axis=1))
    return values


def colourable_fields(arrays: Dict[str, np.ndarray]) -> list:
    return ["speed"] + sorted(k for k in arrays if k not in ("position", "is_wall") and not k.endswith("_start"))


def check_colour_field(name: str, arrays: Dict[str, np.ndarray], path: str = "render.colour_by") -> None:
    """A ConfigError naming ``path`` unless ``name`` can colour these frames."""
    import difflib
    from ..config import ConfigError

    fields = colourable_fields(arrays)
    if name not in fields:
        close = difflib.get_close_matches(name, fields, n=1)
        hint = f"did you mean '{close[0]}'? " if close else ""
        raise ConfigError(path, f"no particle field '{name}'; {hint}this scene has: {', '.join(fields)}")


def png_name(index: int, t: float) -> str:
    """``frame_000012_t0.12s.png``: the frame number keeps the files in order, the simulated time
    [s] says which moment it shows."""
    return f"frame_{index:06d}_t{t:.6g}s.png"


class Renderer:
    """Renders frames of one scene with its ``render`` settings (any backend, headless)."""

    def __init__(self, scene: Scene):
        self.scene = scene
        self.settings = scene.render
        self.dim = scene.dimension
        s = self.settings
        self.width, self.height, self.view_width = s.frame_size(scene.domain, self.dim)
        if self.dim == 2:
            lower, upper = s.view_box(scene.domain)
            self.pixel = float((upper[0] - lower[0]) / self.view_width)  # metres per pixel
            self.left, self.top = float(lower[0]), float(upper[1])
        self._raster = None

    # ---- camera (3D) ----------------------------------------------------------------------------
    def camera(self):
        """(eye, right, up, forward, focal length in pixels)."""
        cam = self.settings.camera
        lo, hi = np.array(self.scene.domain.lower, float), np.array(self.scene.domain.upper, float)
        if cam is None:  # default: from the front-left, above, looking at the domain centre
            centre = 0.5 * (lo + hi)
            eye = centre + np.array([-0.9, -1.6, 1.0]) * np.linalg.norm(hi - lo)
            look_at, up_hint, fov = centre, np.array([0.0, 0.0, 1.0]), 40.0
        else:
            eye, look_at = np.array(cam.position, float), np.array(cam.look_at, float)
            up_hint, fov = np.array(cam.up, float), cam.field_of_view_deg
        forward = look_at - eye
        forward /= np.linalg.norm(forward)
        right = np.cross(forward, up_hint)
        right /= np.linalg.norm(right)
        up = np.cross(right, forward)
        focal = 0.5 * self.height / math.tan(math.radians(fov) / 2.0)
        return eye, right, up, forward, focal

    # ---- one image ------------------------------------------------------------------------------
    def colours(self, arrays: Dict[str, np.ndarray], n_material: int) -> Tuple[np.ndarray, float, float]:
        values = field_values(arrays, self.settings.colour_by)[:n_material]
        if self.settings.range is not None:
            lower, upper = self.settings.range
        elif n_material:
            lower, upper = float(values.min()), float(values.max())
        else:
            lower, upper = 0.0, 1.0
        if not upper > lower:
            upper = lower + (abs(lower) if lower else 1.0)
        n = len(arrays["position"])
        colour = np.empty((n, 3))
        colour[:n_material] = colour_map(values, lower, upper)
        colour[n_material:] = NEUTRAL_GREY
        return colour, lower, upper

    def radii(self, arrays: Dict[str, np.ndarray], n_material: int) -> np.ndarray:
        """True particle size: disc of area m/rho (2D), sphere of volume m/rho (3D); wall
        particles get the initial spacing dp as their area/volume; particles that left by an open
        face get none."""
        n = len(arrays["position"])
        volume = np.full(n, self.scene.numerics.particle_spacing ** self.dim)
        volume[:n_material] = arrays["mass"][:n_material] / arrays["density"][:n_material]
        volume[:n_material][left_domain(arrays, n_material)] = 0.0  # out of the flow: not drawn
        if self.dim == 2:
            return np.sqrt(volume / math.pi)
        return np.cbrt(3.0 * volume / (4.0 * math.pi))

    def image(self, arrays: Dict[str, np.ndarray], n_material: int, time: float) -> np.ndarray:
        """(H, W, 3) uint8 image of one frame."""
        import taichi as ti
        from .raster import Rasteriser

        n = len(arrays["position"])
        if self._raster is None or self._raster.capacity < n:
            self._raster = Rasteriser(self.width if self.dim == 3 else self.view_width, self.height, n)
        raster = self._raster
        colour, lower, upper = self.colours(arrays, n_material)
        raster.load(np.asarray(arrays["position"], float), self.radii(arrays, n_material), colour)
        raster.clear(ti.Vector(list(BACKGROUND)))
        if self.dim == 2:
            raster.project_plane(n, self.left, self.top, self.pixel)
        else:
            eye, right, up, forward, focal = self.camera()
            vec = lambda a: ti.Vector([float(c) for c in a])  # noqa: E731
            raster.project_camera(n, vec(eye), vec(right), vec(up), vec(forward), focal)
        view = raster.draw(n, lit=self.dim == 3)
        canvas = np.ones((self.height, raster.width + (COLOUR_BAR_MARGIN if self.dim == 2 else 0), 3))
        canvas[:, :raster.width] = view
        if self.dim == 3:  # the colour bar goes over the right edge of the picture
            canvas[:, -COLOUR_BAR_MARGIN:] = 0.5 * canvas[:, -COLOUR_BAR_MARGIN:] + 0.5
        self.annotate(canvas, time, lower, upper)
        return (np.clip(canvas, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)

    def annotate(self, canvas: np.ndarray, time: float, lower: float, upper: float) -> None:
        scale = 2
        draw_text(canvas, f"t = {time:.3f} s", 8, 8, scale)
        height, width = canvas.shape[:2]
        bar_left = width - COLOUR_BAR_MARGIN + 16
        bar_top, bar_bottom = 40, max(60, int(0.75 * height))
        ramp = colour_map(np.linspace(1.0, 0.0, bar_bottom - bar_top), 0.0, 1.0)
        canvas[bar_top:bar_bottom, bar_left:bar_left + 18] = ramp[:, None, :]
        name = self.settings.colour_by
        label = f"{name} ({UNITS[name]})" if name in UNITS else name
        while text_width(label, scale) > COLOUR_BAR_MARGIN - 4 and scale > 1:
            scale -= 1
        draw_text(canvas, label, width - COLOUR_BAR_MARGIN + 2, bar_top - 8 - GLYPH_HEIGHT * scale, scale)
        for value, row in ((upper, bar_top), (lower, bar_bottom - GLYPH_HEIGHT * 2)):
            draw_text(canvas, f"{value:.3g}", bar_left + 22, row, 2)


def write_png(path: Path, image: np.ndarray) -> None:
    """Atomically (temporary file, then rename) write a PNG."""
    import imageio.v2 as imageio
    from ..output import atomic_write

    atomic_write(Path(path), lambda tmp: imageio.imwrite(tmp, image, format="PNG"))


def assemble_video(frames: Sequence[Path], out: Path, fps: float = 10.0) -> Path:
    """Join PNG frames into a GIF (always available) or an MP4 (needs imageio-ffmpeg:
    ``pip install taichi_granular[video]``)."""
    import imageio.v2 as imageio
    from ..output import atomic_write

    out = Path(out)
    images = [imageio.imread(f) for f in frames]
    if out.suffix.lower() == ".gif":
        atomic_write(out, lambda tmp: imageio.mimsave(tmp, images, format="GIF", duration=1.0 / fps, loop=0))
    elif out.suffix.lower() == ".mp4":
        try:
            import imageio_ffmpeg  # noqa: F401
        except ImportError as err:
            raise RuntimeError("MP4 needs imageio-ffmpeg: pip install 'taichi_granular[video]' "
                               "(or write a .gif)") from err
        atomic_write(out, lambda tmp: imageio.mimsave(tmp, images, format="FFMPEG", fps=fps))
    else:
        raise ValueError(f"video must end in .gif or .mp4, got {out.name}")
    return out
