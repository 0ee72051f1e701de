"""Cell-linked-list neighbour search with periodic images, and the one neighbour loop.

Particles are binned into cells of edge >= the kernel support 2h by a counting sort:
count per cell -> exclusive prefix sum (blocked, so it runs on every Taichi arch; Taichi 1.7's
built-in parallel scan does not run on the CPU backend) -> scatter -> each cell's list sorted
by particle id. The last step makes the order of every pair sum, and hence every result,
independent of thread scheduling: runs are bitwise reproducible on the CPU. The material is
rebinned at every build; boundary particles are binned once into a second cell list, or, where
they move (a drum's wall), at every rebuild of the list (see :class:`NeighbourGrid`).

Every pair loop in the package goes through :meth:`NeighbourGrid.for_each_neighbour`, which
hands ``task(i, j, x_ij, r, acc)`` the minimum-image displacement x_ij = x_i - x_j.

With a skin (``numerics.neighbour_skin`` > 0, a Verlet list), the cells are at least
support + skin wide and every build writes each particle's neighbours within support + skin into
a row of its own, in ascending id order; the pair loops then read the row (and keep the pairs
within the support) instead of scanning 3^d cells of which only ~35 % (2D) or ~15 % (3D) of the
candidates are neighbours. The rows are rebuilt only when some material particle has moved more
than half the skin since the last build (two particles closing on each other by the whole skin
is then the most that can have happened), so between rebuilds no pair within the support is
missed and the sums are those of the cell scan (round-off apart: ascending ids, not cell by cell;
tested), whenever the list was built, so a resumed run is bitwise the uninterrupted one. A boundary particle's row holds its material neighbours only: the one pair loop over
boundary particles, :meth:`for_each_material_neighbour`, needs no more, and a wall particle with
no material in reach then does no pair work at all.
"""

import math
from typing import Sequence

import taichi as ti

from . import runtime
from .launch import launcher

SUB_CELLS = 4  # per axis, the within-cell order of a reordering (cell_order)
SCAN_BLOCK = 256  # cells per block of the blocked prefix scan


class NeighbourListOverflow(RuntimeError):
    """A particle has more neighbours within support + skin than its list row holds."""


def list_capacity(dim: int, reach: float, spacing: float) -> int:
    """Row length of the Verlet list: twice the lattice count of a ball of radius ``reach`` at the
    initial ``spacing`` (room for the material to compact to twice its packing), plus 8."""
    ball = math.pi * reach**2 if dim == 2 else 4.0 / 3.0 * math.pi * reach**3
    return int(2.0 * ball / spacing**dim) + 8


@ti.data_oriented
class NeighbourGrid:
    """Cells over the domain box; ``build()`` bins the current positions.

    Parameters: ``position`` field (all particles, walls included), domain ``lower`` and
    ``upper`` corners [m], ``periodic`` flag per axis, the kernel ``support`` radius [m], and
    ``n_moving``: particles ``[0, n_moving)`` (the material) are rebinned at every build;
    particles ``[n_moving, N)`` (boundary particles, which never move) are binned once, into a
    cell list of their own, at the first build. In obstacle scenes boundary particles outnumber
    the material 3-40 to 1, so binning them every step would cost more than the material's
    physics. Within a cell the material list precedes the fixed list and both are sorted by id,
    so every pair sum visits its neighbours in ascending id order, exactly as a single list.
    A scene whose walls move (a rotating drum) must call :meth:`fixed_moved` after moving them; built
    with ``fixed_move``, its Verlet list then treats them as it treats the material (rebuilt, and
    they rebinned, only once some particle has moved half the skin) instead of rebuilding at every
    evaluation (41 % of a drum step, measured).
    """

    def __init__(self, position, lower: Sequence[float], upper: Sequence[float],
                 periodic: Sequence[bool], support: float, n_moving: int = None, skin: float = 0.0,
                 capacity: int = 0, fixed_move: bool = False):
        self.position = position
        self.dim = len(lower)
        self.n_particles = position.shape[0]
        self.n_moving = self.n_particles if n_moving is None else int(n_moving)
        self.n_fixed = self.n_particles - self.n_moving
        self.fixed_move = bool(fixed_move) and self.n_fixed > 0  # the boundary particles move (drum walls)
        # particles whose displacement since the list's build decides its rebuild
        self.n_tracked = self.n_particles if self.fixed_move else self.n_moving
        self.lower = tuple(float(v) for v in lower)
        self.box = tuple(float(hi - lo) for lo, hi in zip(lower, upper))
        self.periodic = tuple(bool(p) for p in periodic)
        self.support = float(support)
        self.skin = float(skin)  # [m]; 0: no Verlet list, every pair loop scans the cells
        # a periodic axis needs 3 cells (the scan must not see an image twice): a narrow periodic box
        # gets the skin that fits, or none
        for L, per in zip(self.box, self.periodic):
            if per and self.support + self.skin > L / 3.0:
                self.skin = max(0.0, L / 3.0 * (1.0 - 1e-9) - self.support)
        self.reach = self.support + self.skin  # what a cell scan finds [m]
        self.cells = tuple(max(1, int(math.floor(L / self.reach))) for L in self.box)
        for a in range(self.dim):
            if self.periodic[a] and self.cells[a] < 3:
                raise ValueError(f"periodic axis {a} needs at least 3 cells of size {self.reach} m")
        self.cell_size = tuple(L / n for L, n in zip(self.box, self.cells))
        self.n_cells = int(math.prod(self.cells))
        self.n_blocks = (self.n_cells + SCAN_BLOCK - 1) // SCAN_BLOCK
        self.particle_cell = ti.field(ti.i32, self.n_particles)
        self.sorted_ids = ti.field(ti.i32, max(1, self.n_moving))
        self.cell_start = ti.field(ti.i32, self.n_cells + 1)
        self.cell_count = ti.field(ti.i32, self.n_cells)
        self.cursor = ti.field(ti.i32, self.n_cells)
        self.block_sum = ti.field(ti.i32, self.n_blocks)
        self.fixed_sorted_ids = ti.field(ti.i32, self.n_fixed) if self.n_fixed else None
        self.fixed_cell_start = ti.field(ti.i32, self.n_cells + 1) if self.n_fixed else None
        self.lists = ((self.sorted_ids, self.cell_start),)
        if self.n_fixed:
            self.lists += ((self.fixed_sorted_ids, self.fixed_cell_start),)
        self.material_lists = self.lists[:1]
        self._fixed_binned = False
        self._stale = False  # the material was permuted since the last build (cell_order)
        self.verlet = self.skin > 0.0
        self.capacity = int(capacity)
        self.rebuilds = 0  # Verlet list builds (bench throughput)
        self.builds = 0  # calls of build()
        if self.verlet:
            if self.capacity < 1:
                raise ValueError("a Verlet list (skin > 0) needs its row capacity")
            self.neighbour_count = ti.field(ti.i32, self.n_particles)
            self.neighbour_ids = ti.field(ti.i32, (self.n_particles, self.capacity))
            self.reference = ti.Vector.field(self.dim, float, max(1, self.n_tracked))  # positions at the build
            self.longest = ti.field(ti.i32, ())  # the longest row the last build wanted
            self.longest_particle = ti.field(ti.i32, ())

    def memory_bytes(self) -> int:
        fixed = (self.n_fixed + self.n_cells + 1) if self.n_fixed else 0
        lists = self.n_particles * (self.capacity + 1) + 2 * self.dim * self.n_tracked if self.verlet else 0
        return 4 * (self.n_particles + self.n_moving + 3 * self.n_cells + 1 + self.n_blocks + fixed + lists)

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

    @ti.func
    def in_reach(self, x):
        """False for a position more than one support outside the box along a non-periodic
        axis: such a particle (one parked beyond an open face, physics/outflow.py) is binned
        nowhere and has no neighbours. Clamping it into the edge cells instead would pile every
        parked particle into a few cells, each scanning all the others at every step."""
        ok = True
        for a in ti.static(range(self.dim)):
            if ti.static(not self.periodic[a]):
                if x[a] < self.lower[a] - self.support or x[a] > self.lower[a] + self.box[a] + self.support:
                    ok = False
        return ok

    # ---- build --------------------------------------------------------------------------------

    def build(self) -> None:
        """Bin the material at its current positions (and the fixed particles, once, or at every
        rebuild if they move); with a Verlet list, only when some particle has moved more than
        half the skin since the list was built (or boundary particles moved behind its back), and
        then rebuild the list."""
        self.builds += 1
        if self.verlet and self.rebuilds and self._fixed_binned and not self._stale \
                and 2.0 * launcher(self, "_largest_move")() <= self.skin:
            return
        self._stale = False
        if self.n_fixed and (not self._fixed_binned or self.fixed_move):
            self._bin(self.n_moving, self.n_particles, self.fixed_sorted_ids, self.fixed_cell_start)
            self._fixed_binned = True
        self._bin(0, self.n_moving, self.sorted_ids, self.cell_start)
        if self.verlet:
            self._fill_lists()
            self.rebuilds += 1
            if self.longest[None] > self.capacity:
                raise NeighbourListOverflow(
                    f"particle {self.longest_particle[None]} has {self.longest[None]} particles within "
                    f"support + skin ({self.reach:.4g} m), more than the {self.capacity} its neighbour list holds "
                    f"(twice the initial packing: the material has compacted far beyond it, or particles "
                    f"have clumped; numerics.neighbour_skin = 0 scans the cells instead)")

    # ---- checkpoint ---------------------------------------------------------------------------

    REFERENCE_KEY = "neighbour_list_reference"  # the checkpoint's array of the list's build positions

    def checkpoint_arrays(self) -> dict:
        """What a checkpoint needs to rebuild the Verlet list as it stands: the positions it was
        built at (none when the next build rebuilds anyway). Why: the pair sums see the rows'
        entries beyond the support too (the compiled loop's round-off depends on the row, measured
        on the drum: 1e-16 after one step), so a resumed run that built its list at the
        checkpoint's positions would drift from the uninterrupted run by round-off."""
        if not self.verlet or not self.rebuilds or self._stale or not self._fixed_binned:
            return {}
        return {self.REFERENCE_KEY: self.reference.to_numpy()[: self.n_tracked]}

    def restore(self, arrays: dict) -> None:
        """Rebuild the list at the build positions a checkpoint kept (:meth:`checkpoint_arrays`),
        so that the resumed run holds the rows the uninterrupted run held, then put the particles
        back where they are. Without them (an older checkpoint) the next build rebuilds."""
        reference = arrays.get(self.REFERENCE_KEY)
        if reference is None or not self.verlet:
            return
        current = self.position.to_numpy()
        built_at = current.copy()
        built_at[: self.n_tracked] = reference
        self.position.from_numpy(built_at)
        self._fixed_binned, self._stale = False, True  # rebin everything, rebuild the rows
        self.build()
        self.position.from_numpy(current)

    def cell_order(self, order) -> None:
        """Fill ``order`` (n_moving slots) with the material ids sorted by cell at the current
        positions (within a cell row-major on a finer grid, then by id; particles out of reach
        last, ascending); the next :meth:`build` rebins and rebuilds the list (the caller is
        about to permute them)."""
        self._bin(0, self.n_moving, self.sorted_ids, self.cell_start)
        self._fill_order(order)
        self.material_moved()

    def material_moved(self) -> None:
        """The material was permuted (or moved) behind the grid's back: rebin and rebuild the
        list at the next :meth:`build`."""
        self._stale = True

    @ti.func
    def _sub_cell(self, x):
        """Row-major index of x's place on a grid SUB_CELLS times finer than the cells, inside its
        cell: the order within a cell (ids alone leave a shuffled cell shuffled: 13 % slower at
        160k particles than row-major within the cell, measured)."""
        key = 0
        for a in ti.static(range(self.dim - 1, -1, -1)):
            u = (x[a] - self.lower[a]) / self.cell_size[a]
            k = ti.cast(ti.floor((u - ti.floor(u)) * SUB_CELLS), ti.i32)
            key = key * SUB_CELLS + ti.min(ti.max(k, 0), SUB_CELLS - 1)
        return key

    @ti.kernel
    def _fill_order(self, order: ti.template()):
        total = self.cell_start[self.n_cells]
        ti.loop_config(serialize=runtime.serial_loops)
        for k in range(total):
            order[k] = self.sorted_ids[k]
        # insertion sort inside each cell by sub-cell, then id (stable: ids are ascending)
        ti.loop_config(serialize=runtime.serial_loops)
        for c in range(self.n_cells):
            first, last = self.cell_start[c], self.cell_start[c + 1]
            for k in range(first + 1, last):
                moving = order[k]
                key = self._sub_cell(self.position[moving])
                m = k - 1
                while m >= first:  # (Taichi's `and` does not short-circuit: no order[first - 1])
                    if self._sub_cell(self.position[order[m]]) <= key:
                        break
                    order[m + 1] = order[m]
                    m -= 1
                order[m + 1] = moving
        slot = total
        ti.loop_config(serialize=True)
        for i in range(self.n_moving):
            if self.particle_cell[i] < 0:
                order[slot] = i
                slot += 1

    def fixed_moved(self) -> None:
        """The boundary particles have moved. Built with ``fixed_move``, a Verlet list counts their
        displacement with the material's (two particles close on each other by at most the two
        largest moves, bounded by twice the largest) and rebins them when it rebuilds; otherwise
        they are rebinned, and the list rebuilt, at the next build."""
        if not (self.verlet and self.fixed_move):
            self._fixed_binned = False

    @ti.kernel
    def _largest_move(self) -> float:
        """The farthest any material particle (and moving boundary particle) has moved since the
        list was built [m]."""
        largest = 0.0
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.n_tracked):
            ti.atomic_max(largest, self.displacement(self.position[i], self.reference[i]).norm())
        return largest

    @ti.func
    def _append(self, i, j, x_ij, r, count: ti.template()):
        if count < self.capacity:
            self.neighbour_ids[i, count] = j
        count += 1

    @ti.kernel
    def _fill_lists(self):
        """Each particle's neighbours within support + skin, in the order of the cell scan (a
        boundary particle's: the material ones only); the reference positions."""
        self.longest[None] = 0
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.n_particles):
            count = 0
            if i < self.n_moving:
                self._scan(i, self._append, count, self.lists, self.reach)
            else:
                self._scan(i, self._append, count, self.material_lists, self.reach)
            stored = ti.min(count, self.capacity)
            self.neighbour_count[i] = stored
            ti.atomic_max(self.longest[None], count)
            # ascending ids: the sums then do not depend on when the list was built (a resumed run,
            # whose list is built at the checkpoint, stays bitwise the uninterrupted one)
            for k in range(1, stored):
                key = self.neighbour_ids[i, k]
                m = k - 1
                while m >= 0:  # (Taichi's `and` does not short-circuit: no [i, -1])
                    if self.neighbour_ids[i, m] <= key:
                        break
                    self.neighbour_ids[i, m + 1] = self.neighbour_ids[i, m]
                    m -= 1
                self.neighbour_ids[i, m + 1] = key
            if count > self.capacity:
                self.longest_particle[None] = i  # one that overflowed (any: the message names one)
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.n_tracked):
            self.reference[i] = self.position[i]

    @ti.kernel
    def _bin(self, begin: ti.i32, end: ti.i32, sorted_ids: ti.template(), cell_start: ti.template()):
        """Counting sort of particles [begin, end) by cell into ``sorted_ids`` (slot k holds a
        particle id; the ids of cell c are slots cell_start[c] .. cell_start[c+1]-1)."""
        ti.loop_config(serialize=runtime.serial_loops)
        for c in range(self.n_cells):
            self.cell_count[c] = 0
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(begin, end):
            c = -1
            if self.in_reach(self.position[i]):
                c = self.flat_index(self.cell_coord(self.position[i]))
                ti.atomic_add(self.cell_count[c], 1)
            self.particle_cell[i] = c
        # exclusive scan: per block in parallel, then the block totals serially, then offsets
        ti.loop_config(serialize=runtime.serial_loops)
        for b in range(self.n_blocks):
            running = 0
            for k in range(SCAN_BLOCK):
                c = b * SCAN_BLOCK + k
                if c < self.n_cells:
                    cell_start[c] = running
                    running += self.cell_count[c]
            self.block_sum[b] = running
        total = 0
        ti.loop_config(serialize=True)
        for b in range(self.n_blocks):
            block_total = self.block_sum[b]
            self.block_sum[b] = total
            total += block_total
        cell_start[self.n_cells] = total
        ti.loop_config(serialize=runtime.serial_loops)
        for c in range(self.n_cells):
            cell_start[c] += self.block_sum[c // SCAN_BLOCK]
            self.cursor[c] = cell_start[c]
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(begin, end):
            c = self.particle_cell[i]
            if c >= 0:
                slot = ti.atomic_add(self.cursor[c], 1)
                sorted_ids[slot] = i
        # insertion sort inside each cell (a handful of particles) -> deterministic order
        ti.loop_config(serialize=runtime.serial_loops)
        for c in range(self.n_cells):
            first = cell_start[c]
            last = cell_start[c + 1]
            for k in range(first + 1, last):
                key = sorted_ids[k]
                m = k - 1
                while m >= first:  # (Taichi's `and` does not short-circuit)
                    if sorted_ids[m] <= key:
                        break
                    sorted_ids[m + 1] = sorted_ids[m]
                    m -= 1
                sorted_ids[m + 1] = key

    # ---- the neighbour loop -------------------------------------------------------------------

    @ti.func
    def for_each_neighbour(self, i, task: ti.template(), acc: ti.template()):
        """Call ``task(i, j, x_ij, r, acc)`` for every j != i with r = |x_ij| < support (i a
        material particle: with a Verlet list a boundary particle's row holds material only)."""
        if ti.static(self.verlet):
            self._visit_list(i, task, acc, False)
        else:
            self._scan(i, task, acc, self.lists, self.support)

    @ti.func
    def for_each_material_neighbour(self, i, task: ti.template(), acc: ti.template()):
        """As :meth:`for_each_neighbour`, over the rebinned particles j < n_moving only (a
        boundary particle's continuity sees only the material moving past it [A11])."""
        if ti.static(self.verlet):
            self._visit_list(i, task, acc, True)
        else:
            self._scan(i, task, acc, self.material_lists, self.support)

    @ti.func
    def _visit_list(self, i, task: ti.template(), acc: ti.template(), material_only: ti.template()):
        x_i = self.position[i]
        for k in range(self.neighbour_count[i]):
            j = self.neighbour_ids[i, k]
            if ti.static(material_only):
                if j >= self.n_moving:
                    continue
            x_ij = self.displacement(x_i, self.position[j])
            r2 = x_ij.norm_sqr()
            if r2 < self.support * self.support:
                task(i, j, x_ij, ti.sqrt(r2), acc)

    @ti.func
    def _scan(self, i, task: ti.template(), acc: ti.template(), lists: ti.template(), radius: ti.template()):
        """The cell scan: every j != i of ``lists`` in the 3^d cells around i within ``radius``."""
        x_i = self.position[i]
        home = self.cell_coord(x_i)
        reach = self.in_reach(x_i)
        for offset in ti.grouped(ti.ndrange(*([(-1, 2)] * self.dim))):
            c = home + offset
            inside = reach
            for a in ti.static(range(self.dim)):
                if ti.static(self.periodic[a]):
                    c[a] = (c[a] + self.cells[a]) % self.cells[a]
                elif c[a] < 0 or c[a] >= self.cells[a]:
                    inside = False
            if inside:
                cell = self.flat_index(c)
                for sorted_ids, cell_start in ti.static(lists):
                    for k in range(cell_start[cell], cell_start[cell + 1]):
                        j = sorted_ids[k]
                        if j != i:
                            x_ij = self.displacement(x_i, self.position[j])
                            r2 = x_ij.norm_sqr()
                            if r2 < radius * radius:
                                task(i, j, x_ij, ti.sqrt(r2), acc)


from .physics.stage import Stage  # noqa: E402  (stage base has no dependency on this module)


class NeighbourSearch(Stage):
    """Rebuild the cell lists at the current positions."""

    name = "neighbour_search"
    slot = "neighbours"
    category = "neighbours"
    equation = "cell-linked list"

    def run(self) -> None:
        self.grid.build()
