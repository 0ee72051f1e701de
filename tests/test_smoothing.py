"""Every smoothing function, 2D and 3D: unit integral, antisymmetric gradient consistent with
the value, zero mean gradient, and the first-moment identity sum V x (x) grad W = -I."""
import itertools

import numpy as np
import pytest
import taichi as ti

from taichi_granular.smoothing import SMOOTHING_FUNCTIONS

H = 0.01


def lattice(dim, spacing, offset):
    n = int(np.ceil(2.2 * H / spacing))
    axis = (np.arange(-n, n + 1) + offset) * spacing
    grids = np.meshgrid(*([axis] * dim), indexing="ij")
    return np.stack([g.ravel() for g in grids], axis=1)


def evaluate(sf, points):
    n = len(points)
    x = ti.Vector.field(sf.dim, float, n)
    w = ti.field(float, n)
    gw = ti.Vector.field(sf.dim, float, n)
    x.from_numpy(points)

    @ti.kernel
    def run():
        for i in range(n):
            r = x[i].norm()
            w[i] = sf.value(r)
            gw[i] = sf.gradient(x[i], r)

    run()
    return w.to_numpy(), gw.to_numpy()


def second_derivatives(sf, radii):
    r_field = ti.field(float, len(radii))
    w2 = ti.field(float, len(radii))
    r_field.from_numpy(np.asarray(radii, float))

    @ti.kernel
    def run():
        for i in range(r_field.shape[0]):
            w2[i] = sf.second_derivative(r_field[i])

    run()
    return w2.to_numpy()


@pytest.mark.parametrize("name,dim", list(itertools.product(SMOOTHING_FUNCTIONS, (2, 3))))
def test_smoothing_function(name, dim):
    sf = SMOOTHING_FUNCTIONS[name](H, dim)
    spacing = H / (16 if dim == 2 else 8)
    pts = lattice(dim, spacing, offset=0.37)  # off-centre lattice: no symmetry help
    vol = spacing**dim
    w, gw = evaluate(sf, pts)
    assert np.sum(w) * vol == pytest.approx(1.0, abs=2e-3)
    assert np.all(w >= 0) and np.all(w[np.linalg.norm(pts, axis=1) >= 2 * H] == 0)
    # first moment: sum_j V_j x_ij (x) grad_i W_ij = -I; with x_ij = -p both factors flip sign
    moment = (pts[:, :, None] * gw[:, None, :]).sum(axis=0) * vol
    np.testing.assert_allclose(moment, -np.eye(dim), atol=5e-3)
    # antisymmetry: grad W(-x) = -grad W(x), exactly
    _, gw_neg = evaluate(sf, -pts)
    np.testing.assert_array_equal(gw_neg, -gw)
    # gradient agrees with the derivative of the value (central differences along x)
    sample = pts[(np.linalg.norm(pts, axis=1) > 0.1 * H) & (np.linalg.norm(pts, axis=1) < 1.9 * H)][:200]
    step = 1e-7
    shift = np.zeros(dim)
    shift[0] = step
    w_plus, _ = evaluate(sf, sample + shift)
    w_minus, _ = evaluate(sf, sample - shift)
    _, g_sample = evaluate(sf, sample)
    scale = np.max(np.abs(g_sample[:, 0]))
    np.testing.assert_allclose((w_plus - w_minus) / (2 * step), g_sample[:, 0], atol=1e-6 * scale)


def test_coincident_particles_have_finite_gradient():
    for name in SMOOTHING_FUNCTIONS:
        sf = SMOOTHING_FUNCTIONS[name](H, 2)
        w, gw = evaluate(sf, np.zeros((1, 2)))
        assert np.isfinite(w).all() and np.all(gw == 0)


@pytest.mark.parametrize("name", list(SMOOTHING_FUNCTIONS))
def test_second_derivative_is_the_derivative_of_the_gradient(name):
    """d^2W/dr^2 against central differences of the radial gradient, over the whole support
    (both branches of the cubic spline), zero beyond it."""
    sf = SMOOTHING_FUNCTIONS[name](H, 2)
    radii = np.linspace(0.01, 1.99, 150) * H
    step = 1e-7
    along = lambda r: evaluate(sf, np.c_[r, np.zeros_like(r)])[1][:, 0]  # dW/dr on the x axis
    numeric = (along(radii + step) - along(radii - step)) / (2 * step)
    exact = second_derivatives(sf, radii)
    np.testing.assert_allclose(exact, numeric, atol=1e-5 * np.max(np.abs(numeric)))
    assert exact[0] < 0.0  # the peak at r = 0
    assert np.all(second_derivatives(sf, [2.0 * H, 2.5 * H]) == 0.0)
