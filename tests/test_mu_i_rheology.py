"""Point checks of the mu(I) constitutive functions (MODEL.md section 1)."""
import math

import numpy as np
import pytest
import taichi as ti

from taichi_granular.physics.rheology.mu_i.parameters import MuIMaterial
from taichi_granular.physics.rheology.mu_i.model import MuIRheology

GLASS = MuIMaterial(model="mu_i", grain_density=800.0, grain_diameter=0.5e-3, static_friction_deg=20.90,
                    limit_friction_deg=32.76, reference_inertial_number=0.279, grain_compressibility=1.5e-5,
                    max_yield_stress=190.0, regularisation_time=1.0)


def solve(model, rho_star, gamma_dot):
    """t = sqrt(rho_s/rho_s0 - 1) and eta_hat(p(t), gamma_dot) for arrays of states."""
    n = len(rho_star)
    a, g, t, eta = (ti.field(float, n) for _ in range(4))
    a.from_numpy(np.asarray(rho_star, float))
    g.from_numpy(np.asarray(gamma_dot, float))

    @ti.kernel
    def run():
        for i in range(n):
            t[i] = model.grain_compression(a[i], g[i])
            eta[i] = model.regularised_viscosity(model.pressure_of(t[i]), g[i])

    run()
    return t.to_numpy(), eta.to_numpy()


def viscosity(model, pressure, gamma_dot):
    n = len(pressure)
    p, g, eta = (ti.field(float, n) for _ in range(3))
    p.from_numpy(np.asarray(pressure, float))
    g.from_numpy(np.asarray(gamma_dot, float))

    @ti.kernel
    def run():
        for i in range(n):
            eta[i] = model.regularised_viscosity(p[i], g[i])

    run()
    return eta.to_numpy()


def states(n=3000, seed=0):
    rng = np.random.default_rng(seed)
    rho_star = rng.uniform(0.35, 0.75, n)  # loose (< phi_max = 0.6) and packed
    gamma_dot = 10 ** rng.uniform(-8, 3.5, n)
    gamma_dot[:50] = 0.0
    return rho_star, gamma_dot


@pytest.mark.parametrize("dim", [2, 3])
def test_root_brackets_the_monotone_form(dim):
    """f(x) = (phi_max - rho*/x)^2 (x - 1) x^-e - G changes sign across the returned root."""
    model = MuIRheology(GLASS, dim, 0.0065)
    rho_star, gamma_dot = states()
    t, _ = solve(model, rho_star, gamma_dot)
    e = 0.0 if dim == 2 else 1.0 / 3.0
    phi = GLASS.solid_fraction_max
    sqrt_G = math.sqrt(model.shear_factor) * gamma_dot

    def g(tt):  # the form solved, in t (no rounding of x - 1 = t^2)
        x = 1.0 + tt * tt
        return (phi - rho_star / x) * tt * x ** (-e / 2) - sqrt_G

    x_m = np.maximum(1.0, rho_star / phi)
    assert np.all(t >= np.sqrt(x_m - 1.0) * (1 - 1e-14))  # physical branch: p >= 0, phi <= phi_max
    moving = gamma_dot > 0
    assert np.all(g(t * (1 - 1e-9))[moving] <= 0) and np.all(g(t * (1 + 1e-9))[moving] >= 0)
    at_rest = ~moving  # G = 0: the root is x_m itself
    np.testing.assert_allclose(1 + t[at_rest] ** 2, x_m[at_rest], rtol=1e-14)


@pytest.mark.parametrize("dim", [2, 3])
def test_root_from_a_guess_is_the_root_from_the_bracket(dim):
    """The EOS stage starts Newton from last step's root: from any start (the root itself, 1 %
    off either way, far outside the bracket) the safeguarded solve lands on the same root."""
    model = MuIRheology(GLASS, dim, 0.0065)
    rho_star, gamma_dot = states()
    cold, _ = solve(model, rho_star, gamma_dot)
    n = len(rho_star)
    a, g, guess, t = (ti.field(float, n) for _ in range(4))
    a.from_numpy(rho_star)
    g.from_numpy(gamma_dot)

    @ti.kernel
    def warm():
        for i in range(n):
            t[i] = model.grain_compression(a[i], g[i], guess[i])

    for factor in (1.0, 0.99, 1.01, 0.0, 1e6):
        guess.from_numpy(cold * factor)
        warm()
        np.testing.assert_allclose(t.to_numpy(), cold, rtol=1e-12, atol=1e-300)


def test_root_is_largest_root_of_the_printed_cubic():
    """Against numpy.roots of [M44] as printed: the same root, and at least as accurate.

    Where the three roots cluster (rho* near phi_max, small gamma_dot) the cubic is
    ill-conditioned and numpy.roots loses digits; there our root must leave a residual of the
    printed cubic no larger than numpy's own root does."""
    model = MuIRheology(GLASS, 2, 0.0065)
    rho_star, gamma_dot = np.meshgrid(np.linspace(0.4, 0.7, 13), np.logspace(-1, 3.5, 19))
    rho_star, gamma_dot = rho_star.ravel(), gamma_dot.ravel()
    t, _ = solve(model, rho_star, gamma_dot)
    x = 1 + t**2
    phi = GLASS.solid_fraction_max
    d_phi = phi - GLASS.solid_fraction_min
    for a, gd, xi in zip(rho_star, gamma_dot, x):
        shear = gd**2 * GLASS.grain_density * GLASS.grain_compressibility * d_phi**2 * GLASS.grain_diameter**2
        cubic = [1.0, -(1 + 2 * a / phi + shear / phi**2), a * (a + 2 * phi) / phi**2, -(a**2) / phi**2]  # [M44]
        roots = np.roots(cubic)
        real = roots[np.abs(roots.imag) < 1e-9 * np.abs(roots)].real
        x_np = real.max()
        assert xi == pytest.approx(x_np, rel=1e-6)
        assert abs(np.polyval(cubic, xi)) <= abs(np.polyval(cubic, x_np)) + 1e-15
        assert xi >= max(1.0, a / phi)  # rho_s >= rho/phi_max and p >= 0


@pytest.mark.parametrize("dim", [2, 3])
def test_root_rederives_from_the_constitutive_equations(dim):
    """[M44] is [M6] I = gd d/sqrt(p/rho_s), [M8] phi(I), [M9] rho = phi rho_s, [M41] p(rho_s),
    [M43] d(rho_s) combined: the root must satisfy each of them."""
    model = MuIRheology(GLASS, dim, 0.0065)
    rho_star = np.linspace(0.45, 0.7, 11)
    gamma_dot = np.array([0.5, 5.0, 50.0, 500.0])
    rs, gd = np.meshgrid(rho_star, gamma_dot)
    t, _ = solve(model, rs.ravel(), gd.ravel())
    rho_s = GLASS.grain_density * (1 + t**2)
    p = t**2 / GLASS.grain_compressibility  # [M41]
    d = GLASS.grain_diameter * (GLASS.grain_density / rho_s) ** (0.5 if dim == 2 else 1 / 3)  # [M43]
    inertial = gd.ravel() * d / np.sqrt(p / rho_s)  # [M6]
    phi = rs.ravel() * GLASS.grain_density / rho_s  # [M9]
    phi_of_I = GLASS.solid_fraction_max - (GLASS.solid_fraction_max - GLASS.solid_fraction_min) * inertial  # [M8]
    np.testing.assert_allclose(phi, phi_of_I, rtol=1e-10)


def test_viscosity_finite_positive_and_continuous():
    model = MuIRheology(GLASS, 2, 0.0065)
    p = np.concatenate([[0.0, 1e-12, 1e-6], np.logspace(-3, 4, 40)])
    gd = np.concatenate([[0.0, 1e-14, 1e-12, 1e-7], np.logspace(-5, 4, 40)])
    P, G = np.meshgrid(p, gd)
    eta = viscosity(model, P.ravel(), G.ravel()).reshape(P.shape)
    assert np.all(np.isfinite(eta))
    assert np.all(eta[:, 1:] > 0)  # positive wherever there is a yield stress (p > 0)
    assert np.all(eta[:, 0] == 0)  # p = 0: no yield stress, no viscosity
    # continuity at gamma_dot = 0: the formula at tiny rates meets the limit [M53]
    np.testing.assert_allclose(eta[1], eta[0], rtol=1e-6)
    np.testing.assert_allclose(eta[2], eta[0], rtol=1e-6)
    # continuity at p = 0: eta -> 0 as p -> 0
    assert np.all(eta[:, 1] < 1e-5)
    # the gamma_dot -> 0 limit is m_0 tau_y + eta_0(tau_y, 0) tau_y / tau_0 and never above eta_hat_max at tau_0
    tau_y = GLASS.mu_s * p
    eta_0 = (GLASS.mu_2 / GLASS.mu_s - 1) * tau_y / np.maximum(
        GLASS.reference_inertial_number / GLASS.grain_diameter * np.sqrt(tau_y / (GLASS.mu_s * GLASS.grain_density)),
        1e-300)
    np.testing.assert_allclose(eta[0], GLASS.regularisation_time * tau_y + eta_0 * tau_y / GLASS.max_yield_stress,
                               rtol=1e-12, atol=1e-300)
    p_at_tau0 = GLASS.max_yield_stress / GLASS.mu_s
    eta_max = viscosity(model, [p_at_tau0], [0.0])[0]
    assert eta_max == pytest.approx(190.3, abs=0.1)  # Table 2: eta_hat_max = 190.3 Pa s


def test_viscosity_below_and_towards_exact():
    """eta_hat never exceeds the exact mu(I) viscosity and meets it at large strain rate."""
    model = MuIRheology(GLASS, 2, 0.0065)
    p = np.full(30, 200.0)
    gd = np.logspace(-2, 3, 30)
    eta = viscosity(model, p, gd)
    d, rho_s = GLASS.grain_diameter, GLASS.grain_density
    inertial = gd * d / np.sqrt(p / rho_s)
    mu = GLASS.mu_s + (GLASS.mu_2 - GLASS.mu_s) / (1 + GLASS.reference_inertial_number / inertial)  # [M7]
    exact = mu * p / gd  # [M10-11]
    assert np.all(eta <= exact * (1 + 1e-12))
    assert eta[-1] == pytest.approx(exact[-1], rel=1e-6)
