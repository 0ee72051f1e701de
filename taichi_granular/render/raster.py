"""Taichi rasteriser: particles into an image field, headless (any backend, no display).

2D: filled discs of the particle's true size (area m/rho). 3D: sphere splats (volume m/rho)
seen through a pinhole camera, depth-tested per pixel, Lambert-shaded so that relief reads.
Every pass is deterministic whatever the thread order: a pixel takes the nearest surface
(atomic min of depth), ties going to the lowest particle index (atomic min of the index),
so material particles, which come first, are drawn over the wall particles behind them.
"""
import numpy as np
import taichi as ti

NO_PARTICLE = 2**31 - 1
AMBIENT = 0.3  # share of the colour kept on the side of a sphere away from the light
LIGHT = (-0.45, 0.6, -0.66)  # towards the light, camera frame (x right, y up, z forward)


@ti.data_oriented
class Rasteriser:
    """Owns the image, depth and owner buffers and the per-particle draw list."""

    def __init__(self, width: int, height: int, capacity: int):
        self.width, self.height, self.capacity = int(width), int(height), int(capacity)
        self.image = ti.Vector.field(3, float, shape=(self.height, self.width))
        self.depth = ti.field(float, shape=(self.height, self.width))
        self.owner = ti.field(ti.i32, shape=(self.height, self.width))
        self.centre = ti.Vector.field(3, float, shape=self.capacity)  # world position [m]
        self.radius = ti.field(float, shape=self.capacity)  # [m]
        self.colour = ti.Vector.field(3, float, shape=self.capacity)
        self.screen = ti.Vector.field(4, float, shape=self.capacity)  # column, row, radius [px], depth [m]

    def load(self, centre: np.ndarray, radius: np.ndarray, colour: np.ndarray) -> int:
        n = len(radius)
        if n > self.capacity:
            raise ValueError(f"{n} particles for a rasteriser made for {self.capacity}")
        pad = self.capacity - n
        c3 = np.zeros((n, 3), np.float64)
        c3[:, :centre.shape[1]] = centre
        self.centre.from_numpy(np.concatenate([c3, np.zeros((pad, 3), np.float64)]))
        self.radius.from_numpy(np.concatenate([radius, np.zeros(pad)]).astype(np.float64))
        self.colour.from_numpy(np.concatenate([colour, np.zeros((pad, 3))]).astype(np.float64))
        return n

    @ti.kernel
    def clear(self, background: ti.types.vector(3, float)):
        for r, c in self.image:
            self.image[r, c] = background
            self.depth[r, c] = 3.0e38
            self.owner[r, c] = NO_PARTICLE

    @ti.kernel
    def project_plane(self, n: ti.i32, left: float, top: float, pixel: float):
        """2D view: column = (x - left)/pixel, row = (top - y)/pixel; all at depth 0."""
        for p in range(n):
            x = self.centre[p]
            self.screen[p] = ti.Vector([(x[0] - left) / pixel, (top - x[1]) / pixel, self.radius[p] / pixel, 0.0])

    @ti.kernel
    def project_camera(self, n: ti.i32, eye: ti.types.vector(3, float), right: ti.types.vector(3, float),
                       up: ti.types.vector(3, float), forward: ti.types.vector(3, float), focal: float):
        """Pinhole camera: focal length in pixels; particles behind the eye get radius 0."""
        for p in range(n):
            d = self.centre[p] - eye
            z = d.dot(forward)
            s = ti.Vector([0.0, 0.0, 0.0, z], float)
            if z > self.radius[p]:
                s[0] = 0.5 * self.width + focal * d.dot(right) / z
                s[1] = 0.5 * self.height - focal * d.dot(up) / z
                s[2] = focal * self.radius[p] / z
            self.screen[p] = s

    @ti.func
    def footprint(self, p, r, c):
        """(inside, dx, dy, depth) of pixel (r, c) in the disc of particle p; dx, dy in radii."""
        s = self.screen[p]
        dx = (c + 0.5 - s[0]) / s[2]
        dy = (r + 0.5 - s[1]) / s[2]
        q = dx * dx + dy * dy
        depth = s[3] - self.radius[p] * ti.sqrt(ti.max(1.0 - q, 0.0))
        return q < 1.0, dx, dy, depth

    @ti.func
    def pixel_box(self, p):
        s = self.screen[p]
        c0 = ti.max(ti.cast(ti.floor(s[0] - s[2]), ti.i32), 0)
        c1 = ti.min(ti.cast(ti.ceil(s[0] + s[2]), ti.i32), self.width)
        r0 = ti.max(ti.cast(ti.floor(s[1] - s[2]), ti.i32), 0)
        r1 = ti.min(ti.cast(ti.ceil(s[1] + s[2]), ti.i32), self.height)
        return r0, r1, c0, c1

    @ti.kernel
    def cover(self, n: ti.i32, owner_pass: ti.template()):
        """Every pixel of every particle's disc: first pass keeps the nearest depth, second
        pass (owner_pass) gives the pixel to the lowest index at that depth."""
        for p in range(n):
            if self.screen[p][2] > 0.0:
                r0, r1, c0, c1 = self.pixel_box(p)
                for r, c in ti.ndrange((r0, r1), (c0, c1)):
                    inside, dx, dy, depth = self.footprint(p, r, c)
                    if inside:
                        if ti.static(owner_pass):
                            if depth <= self.depth[r, c]:
                                ti.atomic_min(self.owner[r, c], p)
                        else:
                            ti.atomic_min(self.depth[r, c], depth)

    @ti.kernel
    def shade(self, lit: ti.i32):
        light = ti.Vector(LIGHT, float).normalized()
        for r, c in self.image:
            p = self.owner[r, c]
            if p != NO_PARTICLE:
                colour = self.colour[p]
                if lit:
                    inside, dx, dy, depth = self.footprint(p, r, c)
                    normal = ti.Vector([dx, -dy, -ti.sqrt(ti.max(1.0 - dx * dx - dy * dy, 0.0))], float)
                    colour *= AMBIENT + (1.0 - AMBIENT) * ti.max(normal.dot(light), 0.0)
                self.image[r, c] = colour

    def draw(self, n: int, lit: bool) -> np.ndarray:
        """Depth, owner and shading passes over the projected particles; returns (H, W, 3) floats."""
        self.cover(n, False)
        self.cover(n, True)
        self.shade(int(lit))
        return self.image.to_numpy()
