"""Cell-linked-list neighbour search with periodic images, and the one neighbour loop.

Particles are binned into cells of edge >= the kernel support 2h by a counting sort:
count per cell -> exclusive prefix sum (blocked, so it runs on every Taichi arch; Taichi 1.7's
built-in parallel scan does not run on the CPU backend) -> scatter -> each cell's list sorted
by particle id. The last step makes the order of every pair sum, and hence every result,
independent of thread scheduling: runs are bitwise reproducible on the CPU.

Every pair loop in the package goes through :meth:`NeighborGrid.for_each_neighbor`, which
hands ``task(i, j, x_ij, r, acc)`` the minimum-image displacement x_ij = x_i - x_j.
"""

import math
from typing import Sequence

import taichi as ti

from . import runtime

SCAN_BLOCK = 256  # cells per block of the blocked prefix scan


@ti.data_oriented
class NeighborGrid:
    """Cells over the domain box; ``build()`` bins the current positions.

    Parameters: ``position`` field (all particles, walls included), domain ``lower`` and
    ``upper`` corners [m], ``periodic`` flag per axis, and the kernel ``support`` radius [m].
    """

    def __init__(self, position, lower: Sequence[float], upper: Sequence[float],
                 periodic: Sequence[bool], support: float):
        self.position = position
        self.dim = len(lower)
        self.n_particles = position.shape[0]
        self.lower = tuple(float(v) for v in lower)
        self.box = tuple(float(hi - lo) for lo, hi in zip(lower, upper))
        self.periodic = tuple(bool(p) for p in periodic)
        self.support = float(support)
        self.cells = tuple(max(1, int(math.floor(L / self.support))) for L in self.box)
        for a in range(self.dim):
            if self.periodic[a] and self.cells[a] < 3:
                raise ValueError(f"periodic axis {a} needs at least 3 cells of size {self.support} m")
        self.cell_size = tuple(L / n for L, n in zip(self.box, self.cells))
        self.n_cells = int(math.prod(self.cells))
        self.n_blocks = (self.n_cells + SCAN_BLOCK - 1) // SCAN_BLOCK
        self.particle_cell = ti.field(ti.i32, self.n_particles)
        self.sorted_ids = ti.field(ti.i32, self.n_particles)
        self.cell_count = ti.field(ti.i32, self.n_cells)
        self.cell_start = ti.field(ti.i32, self.n_cells + 1)
        self.cursor = ti.field(ti.i32, self.n_cells)
        self.block_sum = ti.field(ti.i32, self.n_blocks)

    def memory_bytes(self) -> int:
        return 4 * (2 * self.n_particles + 3 * self.n_cells + 1 + self.n_blocks)

    # ---- geometry helpers (ti.func) ----------------------------------------------------------

    @ti.func
    def cell_coord(self, x):
        c = ti.Vector.zero(ti.i32, self.dim)
        for a in ti.static(range(self.dim)):
            k = ti.cast(ti.floor((x[a] - self.lower[a]) / self.cell_size[a]), ti.i32)
            c[a] = ti.min(ti.max(k, 0), self.cells[a] - 1)
        return c

    @ti.func
    def flat_index(self, c):
        idx = c[self.dim - 1]
        for a in ti.static(range(self.dim - 2, -1, -1)):
            idx = idx * self.cells[a] + c[a]
        return idx

    @ti.func
    def displacement(self, x_i, x_j):
        """x_i - x_j, taking the nearest periodic image along periodic axes [m]."""
        d = x_i - x_j
        for a in ti.static(range(self.dim)):
            if ti.static(self.periodic[a]):
                d[a] -= self.box[a] * ti.round(d[a] / self.box[a])
        return d

    @ti.func
    def wrap(self, x):
        """Bring x back into the box along periodic axes [m]."""
        for a in ti.static(range(self.dim)):
            if ti.static(self.periodic[a]):
                x[a] = self.lower[a] + (x[a] - self.lower[a]) - self.box[a] * ti.floor((x[a] - self.lower[a]) / self.box[a])
        return x

    # ---- build --------------------------------------------------------------------------------

    @ti.kernel
    def build(self):
        """Counting sort of all particles by cell (four passes, one launch)."""
        ti.loop_config(serialize=runtime.serial_loops)
        for c in range(self.n_cells):
            self.cell_count[c] = 0
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.n_particles):
            c = self.flat_index(self.cell_coord(self.position[i]))
            self.particle_cell[i] = c
            ti.atomic_add(self.cell_count[c], 1)
        # exclusive scan: per block in parallel, then the block totals serially, then offsets
        ti.loop_config(serialize=runtime.serial_loops)
        for b in range(self.n_blocks):
            running = 0
            for k in range(SCAN_BLOCK):
                c = b * SCAN_BLOCK + k
                if c < self.n_cells:
                    self.cell_start[c] = running
                    running += self.cell_count[c]
            self.block_sum[b] = running
        total = 0
        ti.loop_config(serialize=True)
        for b in range(self.n_blocks):
            block_total = self.block_sum[b]
            self.block_sum[b] = total
            total += block_total
        self.cell_start[self.n_cells] = total
        ti.loop_config(serialize=runtime.serial_loops)
        for c in range(self.n_cells):
            self.cell_start[c] += self.block_sum[c // SCAN_BLOCK]
            self.cursor[c] = self.cell_start[c]
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.n_particles):
            slot = ti.atomic_add(self.cursor[self.particle_cell[i]], 1)
            self.sorted_ids[slot] = i
        # insertion sort inside each cell (a handful of particles) -> deterministic order
        ti.loop_config(serialize=runtime.serial_loops)
        for c in range(self.n_cells):
            begin = self.cell_start[c]
            end = self.cell_start[c + 1]
            for k in range(begin + 1, end):
                key = self.sorted_ids[k]
                m = k - 1
                while m >= begin and self.sorted_ids[m] > key:
                    self.sorted_ids[m + 1] = self.sorted_ids[m]
                    m -= 1
                self.sorted_ids[m + 1] = key

    # ---- the neighbour loop -------------------------------------------------------------------

    @ti.func
    def for_each_neighbor(self, i, task: ti.template(), acc: ti.template()):
        """Call ``task(i, j, x_ij, r, acc)`` for every j != i with r = |x_ij| < support."""
        x_i = self.position[i]
        home = self.cell_coord(x_i)
        for offset in ti.grouped(ti.ndrange(*([(-1, 2)] * self.dim))):
            c = home + offset
            inside = True
            for a in ti.static(range(self.dim)):
                if ti.static(self.periodic[a]):
                    c[a] = (c[a] + self.cells[a]) % self.cells[a]
                elif c[a] < 0 or c[a] >= self.cells[a]:
                    inside = False
            if inside:
                cell = self.flat_index(c)
                for k in range(self.cell_start[cell], self.cell_start[cell + 1]):
                    j = self.sorted_ids[k]
                    if j != i:
                        x_ij = self.displacement(x_i, self.position[j])
                        r2 = x_ij.norm_sqr()
                        if r2 < self.support * self.support:
                            task(i, j, x_ij, ti.sqrt(r2), acc)


from .physics.stage import Stage  # noqa: E402  (stage base has no dependency on this module)


class NeighbourSearch(Stage):
    """Rebuild the cell lists at the current positions."""

    name = "neighbour_search"
    category = "neighbours"
    equation = "cell-linked list"

    def run(self) -> None:
        self.grid.build()
