"""Analytic checks on small scenes: kinematics, rest, conservation."""
import numpy as np
import pytest

from scenes import build, layer
from taichi_granular.simulation import Simulation


@pytest.mark.parametrize("h_over_dp,tolerance", [(1.3, 0.03), (2.0, 0.002)])
def test_strain_rate_of_a_linear_field(h_over_dp, tolerance):
    """[M31] on a lattice: gamma_dot = sqrt(2 eps:eps) of a linear field v = A x, away from edges,
    up to the lattice's first-moment error of the uncorrected gradient (2.6 % at h/dp = 1.3,
    shrinking with h/dp; the kernel gradient correction makes it exact)."""
    data = layer(height=0.1, length=0.1)
    data["numerics"]["smoothing_length_ratio"] = h_over_dp
    data["domain"] = {"lower": [-0.1, -0.1], "upper": [0.2, 0.2], "periodic": []}
    data["walls"] = []
    data["gravity"]["magnitude"] = 0.0
    sim = Simulation(build(data))
    A = np.array([[0.3, 1.7], [-0.4, -0.2]])  # 1/s
    x = sim.state.position.to_numpy()
    sim.state.velocity.from_numpy(x @ A.T)
    sim.scheme.evaluate_rates()
    eps = 0.5 * (A + A.T)
    expected = np.sqrt(2 * np.sum(eps * eps))
    n = sim.state.n_material
    interior = np.all((x[:n] > 0.025) & (x[:n] < 0.075), axis=1)
    assert interior.sum() > 50
    gamma_dot = sim.state.strain_rate.to_numpy()[interior]
    np.testing.assert_allclose(gamma_dot, gamma_dot[0], rtol=1e-12)  # uniform inside
    assert abs(gamma_dot[0] / expected - 1) < tolerance


@pytest.mark.parametrize("viscosity,steps", [("explicit", 10_000), ("implicit", 2_000)])
def test_momentum_is_conserved_to_round_off_in_a_periodic_box(viscosity, steps):
    """No gravity, no walls, periodic in x and y, default numerics but
    ``particle_shifting.conserve_momentum``: pairwise forces (pressure, viscous, artificial
    viscosity) and the particle shift (its Taylor velocity correction less its mean) change total
    momentum only by round-off over 10^4 Verlet steps: 6e-16 of |p| measured, against 4.3e-3 with
    the plain Taylor term, the default (docs: it keeps sheared layers right). The implicit viscous update too
    (its velocities are v* + dt L x, pair sums; with v = x, the solution to its tolerance, the
    residual drifted p by 6e-5 of sum m|v| in 10^4 steps, measured)."""
    data = layer(height=0.06, length=0.06, alpha=0.05)
    data["numerics"]["viscosity"] = viscosity
    data["numerics"]["particle_shifting"] = {"conserve_momentum": True}
    data["domain"] = {"lower": [0.0, 0.0], "upper": [0.06, 0.06], "periodic": ["x", "y"]}
    data["particles"][0].update(lower=[0.0, 0.0], upper=[0.06, 0.06], initial_stress="zero")
    data["walls"] = []
    data["gravity"]["magnitude"] = 0.0
    sim = Simulation(build(data))
    rng = np.random.default_rng(3)
    n = sim.state.n_material
    x = sim.state.position.to_numpy()
    sim.state.position.from_numpy(x + rng.normal(0, 2e-4, x.shape))
    v0 = rng.normal(0, 0.2, x.shape)
    sim.state.velocity.from_numpy(v0)
    rho = sim.state.density.to_numpy()
    sim.state.density.from_numpy(rho * (1 + 0.01 * rng.random(n)))  # packed: p > 0
    mass = sim.state.mass.to_numpy()[:, None]
    p0 = (mass * sim.state.velocity.to_numpy()).sum(axis=0)
    scale = (mass * np.abs(sim.state.velocity.to_numpy())).sum()
    assert sim.scene.numerics.particle_shifting.enabled
    sim.run(end_time=100.0, max_steps=steps)
    assert sim.step_count == steps
    v = sim.state.velocity.to_numpy()
    assert np.abs(v[:n] - v0[:n]).max() > 0.1  # forces did act: the random velocities have mixed
    p1 = (mass * v).sum(axis=0)
    assert np.abs(p1 - p0).max() < 1e-13 * scale
    assert np.abs(p1 - p0).max() < 1e-10 * np.abs(p0).max()


@pytest.mark.parametrize("momentum,correction,h_over_dp,tolerance", [
    ("stress_divergence", "scalar", 1.3, 0.015),
    ("stress_divergence", "matrix", 1.3, 0.02),
    ("viscous_pair", "none", 1.3, 0.04),
    ("viscous_pair", "none", 1.5, 0.025),
])
def test_layer_at_rest_keeps_hydrostatic_pressure(momentum, correction, h_over_dp, tolerance):
    """A 5 cm layer of glass beads on the ghost wall stays at rest over 3000 steps: speeds
    below 1e-3 sqrt(g H), no drift of the centre of mass, and the pressure of every row of
    particles within ``tolerance`` x rho g H of rho g (H - z). Without gradient correction at
    the paper's h/dp = 1.3 the SPH gradient on a lattice is 2.6 % short (see the strain-rate
    test), so the pressure gradient settles that much steeper; at h/dp = 1.5 the error is
    0.3 %; with either correction the bulk is exact and only the free-surface rows deviate."""
    data = layer(height=0.05, length=0.1, end_time=5.0)
    data["numerics"].update(smoothing_length_ratio=h_over_dp, gradient_correction=correction,
                            momentum=momentum)
    scene = build(data)
    sim = Simulation(scene)
    n = sim.state.n_material
    y0 = sim.state.material("position")[:, 1]
    sim.run(max_steps=3000)
    assert sim.step_count == 3000
    x = sim.state.material("position")
    v = sim.state.material("velocity")
    p = sim.state.material("pressure")
    g, H = 9.81, 0.05
    assert np.abs(v).max() < 1e-3 * np.sqrt(g * H)
    rho = sim.state.material("density")
    # The lattice starts at uniform spacing although its density grows with depth; particle
    # shifting lets it settle towards the spacing that compression implies. The full settlement
    # of the centre of mass would be ~ K_t (rho g H / 2) H / 2; allow a quarter of it.
    settlement = 1.5e-5 * rho.mean() * g * H / 2 * H / 2
    assert abs(x[:, 1].mean() - y0.mean()) < 0.25 * settlement
    column_weight = rho.mean() * g * H
    for level in np.unique(np.round(y0, 6)):
        mask = np.isclose(y0, level)
        expected = rho.mean() * g * (H - level)
        assert abs(p[mask].mean() - expected) < tolerance * column_weight, level


def test_first_time_step_is_the_same_with_either_integrator():
    """The first step's dt comes from rates evaluated at t = 0 with both integrators: mu(I)'s sound
    speed needs the grain density the EOS stage derives (with the predictor-corrector it was
    unset and the first dt was 1e27 s). Beads at rest: the viscous bound of [M39], 3.2e-5 s."""
    steps = []
    for integrator in ("symplectic_verlet", "predictor_corrector"):
        data = layer(height=0.02, length=0.04, integrator=integrator)
        data["numerics"]["viscosity"] = "explicit"  # the viscous bound (implicit drops it)
        sim = Simulation(build(data))
        sim.run(max_steps=1)
        steps.append(sim.dt)
    assert steps[1] == pytest.approx(steps[0], rel=1e-3)
    assert 1e-6 < steps[0] < 1e-3
