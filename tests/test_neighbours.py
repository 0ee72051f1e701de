"""The cell-list neighbour search finds exactly the brute-force neighbour sets, with periodic
images, in 2D and 3D, and visits them in a deterministic order; with fixed particles binned
once apart from the moving ones, it finds the same sets in the same (ascending id) order."""
import numpy as np
import pytest
import taichi as ti

from taichi_granular.neighbours import NeighbourGrid


def brute_force(points, lower, upper, periodic, support):
    d = points[:, None, :] - points[None, :, :]
    box = np.asarray(upper) - np.asarray(lower)
    for a, per in enumerate(periodic):
        if per:
            d[..., a] -= box[a] * np.round(d[..., a] / box[a])
    r = np.linalg.norm(d, axis=2)
    return (r < support) & ~np.eye(len(points), dtype=bool)


def grid_neighbours(points, lower, upper, periodic, support, n_moving=None, material_only=False, grid=None,
                    **list_options):
    n, dim = points.shape
    if grid is None:
        x = ti.Vector.field(dim, float, n)
        grid = NeighbourGrid(x, lower, upper, periodic, support, n_moving=n_moving, **list_options)
    grid.position.from_numpy(points)
    count = ti.field(ti.i32, n)
    id_sum = ti.field(ti.i64, n)
    order_hash = ti.field(ti.i64, n)

    @ti.data_oriented
    class Probe:
        @ti.func
        def task(self, i, j, x_ij, r, acc: ti.template()):
            acc[0] += 1
            acc[1] += ti.cast(j, ti.i64) * j
            acc[2] = (acc[2] * 31 + j) % 1000000007

        @ti.kernel
        def run(self):
            for i in range(n):
                acc = ti.Vector([0, 0, 0], ti.i64)
                if ti.static(material_only):
                    grid.for_each_material_neighbour(i, self.task, acc)
                else:
                    grid.for_each_neighbour(i, self.task, acc)
                count[i] = ti.cast(acc[0], ti.i32)
                id_sum[i] = acc[1]
                order_hash[i] = acc[2]

    grid.build()
    Probe().run()
    if list_options or grid.verlet:
        return count.to_numpy(), id_sum.to_numpy(), order_hash.to_numpy(), grid
    return count.to_numpy(), id_sum.to_numpy(), order_hash.to_numpy()


CASES = [
    (2, (False, False)), (2, (True, False)), (2, (True, True)),
    (3, (False, False, False)), (3, (True, False, True)),
]


@pytest.mark.parametrize("dim,periodic", CASES)
def test_equals_brute_force(dim, periodic):
    rng = np.random.default_rng(dim + 2 * sum(periodic))
    lower = np.zeros(dim)
    upper = np.array([0.31, 0.2, 0.17][:dim])
    support = 0.05
    n = 1500 if dim == 2 else 2500
    points = lower + rng.random((n, dim)) * (upper - lower)
    points[:20, 0] = upper[0] - 1e-9  # on the faces: images across the periodic seam
    points[20:40, 0] = lower[0]
    mask = brute_force(points, lower, upper, periodic, support)
    count, id_sum, order = grid_neighbours(points, lower, upper, periodic, support)
    np.testing.assert_array_equal(count, mask.sum(axis=1))
    expected_ids = np.array([np.sum(np.nonzero(row)[0].astype(np.int64) ** 2) for row in mask])
    np.testing.assert_array_equal(id_sum, expected_ids)
    # the visiting order is the same on a second, independent build
    _, _, order_again = grid_neighbours(points, lower, upper, periodic, support)
    np.testing.assert_array_equal(order, order_again)


@pytest.mark.parametrize("dim,periodic", [CASES[1], CASES[4]])
def test_fixed_particles_binned_apart(dim, periodic):
    """Walls (ids >= n_moving) in their own list: same sets, same visiting order as one list;
    moving the material and rebuilding keeps the fixed list; the material-only loop sees
    exactly the neighbours with id < n_moving."""
    rng = np.random.default_rng(7 + dim)
    lower = np.zeros(dim)
    upper = np.array([0.31, 0.2, 0.17][:dim])
    support = 0.05
    n, n_moving = 1200, 500
    points = lower + rng.random((n, dim)) * (upper - lower)
    mask = brute_force(points, lower, upper, periodic, support)
    one_list = grid_neighbours(points, lower, upper, periodic, support)
    split = grid_neighbours(points, lower, upper, periodic, support, n_moving=n_moving)
    for a, b in zip(one_list, split):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(split[0], mask.sum(axis=1))
    count, id_sum, _ = grid_neighbours(points, lower, upper, periodic, support, n_moving=n_moving,
                                       material_only=True)
    np.testing.assert_array_equal(count, mask[:, :n_moving].sum(axis=1))
    expected = np.array([np.sum(np.nonzero(row[:n_moving])[0].astype(np.int64) ** 2) for row in mask])
    np.testing.assert_array_equal(id_sum, expected)


@pytest.mark.parametrize("dim,periodic", [CASES[0], CASES[2], CASES[4]])
def test_verlet_list_finds_the_cell_scan_neighbours(dim, periodic):
    """With a skin: the material's rows give the brute-force sets in a reproducible order,
    the walls' rows their material neighbours; after moves shorter than half the skin the list is
    not rebuilt and still gives the exact sets at the new positions; a longer move rebuilds it."""
    rng = np.random.default_rng(11 + dim)
    lower = np.zeros(dim)
    upper = np.array([0.31, 0.2, 0.17][:dim])
    support, skin = 0.045, 0.01  # 3 cells of support + skin across the 0.17 m axis
    n, n_moving = 1200, 700
    points = lower + rng.random((n, dim)) * (upper - lower)
    options = dict(skin=skin, capacity=600)
    scan = grid_neighbours(points, lower, upper, periodic, support, n_moving=n_moving)
    count, id_sum, order, grid = grid_neighbours(points, lower, upper, periodic, support, n_moving=n_moving,
                                                 **options)
    for a, b in zip(scan[:2], (count, id_sum)):  # material rows: the same sets
        np.testing.assert_array_equal(a[:n_moving], b[:n_moving])
    # in the same order on an independent build (its cells are support + skin wide: its own scan order)
    again = grid_neighbours(points, lower, upper, periodic, support, n_moving=n_moving, **options)
    np.testing.assert_array_equal(order, again[2])
    material = grid_neighbours(points, lower, upper, periodic, support, n_moving=n_moving, material_only=True)
    listed = grid_neighbours(points, lower, upper, periodic, support, material_only=True, grid=grid)
    for a, b in zip(material[:2], listed[:2]):  # every row, material neighbours only
        np.testing.assert_array_equal(a, b)
    assert grid.rebuilds == 1
    moved = points.copy()
    step = rng.normal(size=(n_moving, dim))
    moved[:n_moving] += 0.49 * skin * step / np.linalg.norm(step, axis=1, keepdims=True)
    moved[:n_moving] = np.clip(moved[:n_moving], lower, upper - 1e-9)
    count, id_sum, _, _ = grid_neighbours(moved, lower, upper, periodic, support, grid=grid)
    assert grid.rebuilds == 1  # within half the skin: the old rows still hold every pair
    mask = brute_force(moved, lower, upper, periodic, support)
    np.testing.assert_array_equal(count[:n_moving], mask[:n_moving].sum(axis=1))
    expected = np.array([np.sum(np.nonzero(row)[0].astype(np.int64) ** 2) for row in mask[:n_moving]])
    np.testing.assert_array_equal(id_sum[:n_moving], expected)
    moved[0] = points[0] + 0.51 * skin * np.eye(dim)[1]
    grid_neighbours(moved, lower, upper, periodic, support, grid=grid)
    assert grid.rebuilds == 2


def test_verlet_list_overflow_names_the_particle():
    from taichi_granular.neighbours import NeighbourListOverflow

    points = np.full((30, 2), 0.1) + np.linspace(0.0, 1e-3, 30)[:, None]  # a clump
    with pytest.raises(NeighbourListOverflow, match=r"particle \d+ has 29 particles .* more than the 10"):
        grid_neighbours(points, (0.0, 0.0), (0.3, 0.2), (False, False), 0.05, skin=0.01, capacity=10)


def test_rebuild_moves_only_the_material():
    """A second build after the material moved finds the new material neighbours and the
    walls where they were binned."""
    points = np.array([[0.05, 0.05], [0.25, 0.15], [0.07, 0.05], [0.26, 0.15]])
    x = ti.Vector.field(2, float, 4)
    x.from_numpy(points)
    grid = NeighbourGrid(x, (0.0, 0.0), (0.31, 0.2), (False, False), 0.05, n_moving=2)
    count = ti.field(ti.i32, 4)

    @ti.data_oriented
    class Probe:
        @ti.func
        def task(self, i, j, x_ij, r, acc: ti.template()):
            acc += 1

        @ti.kernel
        def run(self):
            for i in range(4):
                acc = 0
                grid.for_each_neighbour(i, self.task, acc)
                count[i] = acc

    grid.build()
    Probe().run()
    np.testing.assert_array_equal(count.to_numpy(), [1, 1, 1, 1])  # 0-2 and 1-3 pairs
    points[0] = [0.255, 0.155]  # particle 0 moves next to 1 and wall 3
    x.from_numpy(points)
    grid.build()
    Probe().run()
    np.testing.assert_array_equal(count.to_numpy(), [2, 2, 0, 2])


def test_particles_beyond_reach_are_binned_nowhere():
    """A particle parked more than one support outside the box (an open face) has no
    neighbours and is nobody's; one just outside is still clamped into the edge cells."""
    support = 0.05
    points = np.array([[0.30, 0.10], [0.34, 0.10], [0.40, 0.10], [0.41, 0.10], [0.29, 0.10]])
    # 1: 0.03 beyond the face x = 0.31 (within reach); 2 and 3: 0.09 and 0.10 beyond (parked)
    count, _, _ = grid_neighbours(points, np.zeros(2), np.array([0.31, 0.2]), (False, False), support)
    np.testing.assert_array_equal(count, [2, 1, 0, 0, 1])  # 1-4 are exactly one support apart
