"""The cell-list neighbour search finds exactly the brute-force neighbour sets, with periodic
images, in 2D and 3D, and visits them in a deterministic order."""
import numpy as np
import pytest
import taichi as ti

from taichi_granular.neighbors import NeighborGrid


def brute_force(points, lower, upper, periodic, support):
    d = points[:, None, :] - points[None, :, :]
    box = np.asarray(upper) - np.asarray(lower)
    for a, per in enumerate(periodic):
        if per:
            d[..., a] -= box[a] * np.round(d[..., a] / box[a])
    r = np.linalg.norm(d, axis=2)
    return (r < support) & ~np.eye(len(points), dtype=bool)


def grid_neighbours(points, lower, upper, periodic, support):
    n, dim = points.shape
    x = ti.Vector.field(dim, float, n)
    x.from_numpy(points)
    grid = NeighborGrid(x, lower, upper, periodic, support)
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
                grid.for_each_neighbor(i, self.task, acc)
                count[i] = ti.cast(acc[0], ti.i32)
                id_sum[i] = acc[1]
                order_hash[i] = acc[2]

    grid.build()
    Probe().run()
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
