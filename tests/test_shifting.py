"""Particle shifting (physics/shifting.py): zero on a perfect lattice, against the disorder of a
perturbed one, only along a free surface."""
import numpy as np

from scenes import HYPOPLASTIC_SAND, SAND, build, elastoplastic_numerics, layer
from taichi_granular.simulation import Simulation


def periodic_box(numerics=(), **kwargs):
    data = layer(height=0.05, length=0.05, **kwargs)
    data["numerics"].update(numerics)
    data["domain"] = {"lower": [0.0, 0.0], "upper": [0.05, 0.05], "periodic": ["x", "y"]}
    data["particles"][0].update(lower=[0.0, 0.0], upper=[0.05, 0.05], initial_stress="zero")
    data["walls"] = []
    data["gravity"]["magnitude"] = 0.0
    return Simulation(build(data))


def test_no_shift_on_a_perfect_lattice():
    sim = periodic_box()
    sim.scheme.evaluate_rates()
    shift = sim.state.shift_velocity.to_numpy()
    assert np.abs(shift).max() < 1e-9


def test_shift_moves_particles_back_towards_the_lattice():
    sim = periodic_box()
    n = sim.state.n_material
    rng = np.random.default_rng(7)
    x = sim.state.position.to_numpy()
    offset = rng.normal(0.0, 0.1 * 0.005, x.shape)
    sim.state.position.from_numpy(x + offset)
    sim.scheme.evaluate_rates()
    shift = sim.state.shift_velocity.to_numpy()[:n]
    # the shift opposes each particle's displacement relative to its neighbours' mean
    correlation = np.sum(shift * offset[:n]) / np.sqrt(np.sum(shift**2) * np.sum(offset[:n] ** 2))
    assert correlation < -0.5


def test_particles_at_a_free_surface_shift_only_along_it():
    data = layer(height=0.03, length=0.05)
    sim = Simulation(build(data))
    n = sim.state.n_material
    rng = np.random.default_rng(11)
    x = sim.state.position.to_numpy()
    x[:n, 0] += rng.normal(0.0, 0.05 * 0.005, n)  # along-surface disorder only
    sim.state.position.from_numpy(x)
    sim.scheme.evaluate_rates()
    shift = sim.state.shift_velocity.to_numpy()[:n]
    y = x[:n, 1]
    top = y > 0.03 - 0.005
    second = (y > 0.03 - 0.010) & ~top
    # on the surface the normal is the kernel-sum gradient, below it the direction to the surface
    # neighbours; the along-surface disorder tilts both slightly from the vertical (measured: 6 %
    # and 1 % of the tangential shift)
    for row, tilt in ((top, 0.1), (second, 0.05)):
        assert np.abs(shift[row, 1]).max() < tilt * np.abs(shift[row, 0]).max()
        assert np.abs(shift[row, 0]).max() > 0.0


def test_a_squeezed_grain_is_shifted_without_overshoot():
    """A grain between two neighbours squeezed to 0.62 dp on either side, 0.09 dp off the middle,
    shifted alone at the drum's time step (hypoplastic, Wendland C6, h/dp 1.3, cfl 0.3, zeta
    0.2): it moves to the middle and stays. There the anti-clumping weight makes C so stiff that
    the plain step dt zeta h c grad C overshoots the middle by 4-8x and, capped at 0.1 h, flips the
    grain from side to side by the cap every step (measured before the limit; the grain bursts
    of the 2D drum, physics/shifting.py)."""
    sim = periodic_box(material=HYPOPLASTIC_SAND, smoothing="wendland_c6",
                       numerics={"smoothing_length_ratio": 1.3, "cfl": 0.3, "particle_shifting": {"coefficient": 0.2}})
    n = sim.state.n_material
    x = sim.state.position.to_numpy()
    k = int(np.argmin(np.linalg.norm(x[:n] - 0.025, axis=1)))
    left, right = (int(np.argmin(np.linalg.norm(x[:n] - (x[k] + [side * 0.005, 0.0]), axis=1))) for side in (-1, 1))
    gap = 0.62 * 0.005
    x[left, 0], x[right, 0] = x[k, 0] - gap, x[k, 0] + gap
    x[k, 0] += 0.15 * gap
    sim.state.position.from_numpy(x)
    sim.scheme.evaluate_rates()
    dt = sim.scheme.stable_time_step()
    h = sim.scheme.smoothing.h
    offsets = []
    for _ in range(8):
        sim.scheme.clock.begin_step(dt)
        sim.scheme.evaluate_rates()
        move = dt * sim.state.shift_velocity.to_numpy()[k]
        move *= min(1.0, 0.1 * h / max(np.linalg.norm(move), 1e-300))  # the integrator's cap
        x = sim.state.position.to_numpy()
        x[k] += move
        sim.state.position.from_numpy(x)
        offsets.append((x[k, 0] - 0.5 * (x[left, 0] + x[right, 0])) / gap)
    offsets = np.array(offsets)
    assert np.all(offsets >= -1e-9)  # never across the middle
    assert np.all(np.diff(offsets) <= 1e-12) and offsets[-1] < 1e-3  # settles there


def test_a_pocket_is_not_a_free_surface():
    """Grains round a hole of three missing grains have a kernel sum as low as the surface's, but
    neighbours all round (FreeSurface): neither they nor their neighbours are free surface, so
    their shift is not cut to a (non-existent) surface's tangent and fills the pocket. The top
    row and isolated grains are free surface."""
    data = layer(height=0.05, length=0.05, material=HYPOPLASTIC_SAND, smoothing="wendland_c6")
    data["numerics"]["smoothing_length_ratio"] = 1.3
    data["walls"][0]["type"] = "extrapolated"
    sim = Simulation(build(data))
    n = sim.state.n_material
    x = sim.state.position.to_numpy()
    hole = np.argsort(np.linalg.norm(x[:n] - [0.025, 0.016], axis=1))[:3]
    centre, cells = x[hole].mean(axis=0), x[hole].copy()
    x[hole] = [[0.01 + 0.015 * k, 0.12] for k in range(3)]  # lifted far above the layer: isolated grains
    sim.state.position.from_numpy(x)
    sim.scheme.evaluate_rates()
    kernel_sum = sim.state.kernel_sum.to_numpy()[:n]
    surface = sim.state.free_surface.to_numpy()[:n]
    shift = sim.state.shift_velocity.to_numpy()[:n]
    y = x[:n, 1]
    distance = np.linalg.norm(x[:n, None, :] - cells[None, :, :], axis=2).min(axis=1)  # to the nearest cell
    rim = (distance < 1.1 * 0.005) & (y < 0.06)
    assert rim.sum() >= 7
    assert kernel_sum[rim].min() < 0.9  # the Shepard sum alone would call them surface
    assert surface[rim].max() == 0.0
    assert sim.state.surface_layer.to_numpy()[:n][rim].max() == 0.0  # nor next to the surface
    # the full shift, into the pocket: the grains beside the hole move fastest of the layer (measured
    # 8.7-14.2 against the layer's largest 14.2 m/s; cut to the surface's tangent, 1e-14-4e-4)
    size = np.linalg.norm(shift[rim], axis=1)
    towards_hole = np.sum(shift[rim] * (centre - x[:n][rim]), axis=1)
    assert size.max() > 0.5 * np.linalg.norm(shift, axis=1).max()
    assert np.all(towards_hole[size > 0.1 * size.max()] > 0.0)
    top = (y > 0.05 - 0.005) & (y < 0.06)
    assert np.all(surface[top] == 1.0) and np.all(surface[hole] == 1.0)
    assert np.all(surface[(y < 0.05 - 0.005) & ~rim] == 0.0)


def test_free_surface_and_a_pocket_in_3d():
    """A cube of 10^3 grains (cubic spline, h/dp 1.2, threshold 0.97) with its centre grain
    lifted out: every grain of its faces, edges and corners has an open octant in FreeSurface's
    turned frame (kernel sums 0.49-0.79) and is free surface; no grain one row in or deeper is
    (0.99-1.00); the six grains round the hole have a sum under the threshold (0.93) but
    neighbours in every octant, and are neither free surface nor surface layer (measured)."""
    dp = 0.01
    data = {"name": "block3d", "dimension": 3, "precision": "f64",
            "domain": {"lower": [-0.05, -0.05, -0.05], "upper": [0.3, 0.15, 0.15]},
            "gravity": {"magnitude": 0.0}, "material": dict(SAND),
            "particles": [{"name": "block", "lower": [0.0, 0.0, 0.0], "upper": [0.1, 0.1, 0.1],
                           "initial_stress": "zero"}],
            "numerics": elastoplastic_numerics(dp, particle_shifting={"coefficient": 0.2,
                                                                      "free_surface_threshold": 0.97}),
            "run": {"end_time": 0.01, "output_interval": 0.01}}
    sim = Simulation(build(data))
    n = sim.state.n_material
    x = sim.state.position.to_numpy()
    hole = int(np.argmin(np.linalg.norm(x[:n] - 0.05, axis=1)))
    cell = x[hole].copy()
    x[hole] = [0.25, 0.05, 0.05]  # far from the block: an isolated grain
    sim.state.position.from_numpy(x)
    sim.scheme.evaluate_rates()
    surface = sim.state.free_surface.to_numpy()[:n]
    layer_flag = sim.state.surface_layer.to_numpy()[:n]
    kernel_sum = sim.state.kernel_sum.to_numpy()[:n]
    block = np.arange(n) != hole
    outer = (np.minimum(x[:n], 0.1 - x[:n]).min(axis=1) < dp) & block
    rim = (np.linalg.norm(x[:n] - cell, axis=1) < 1.01 * dp) & block
    assert outer.sum() == 10 ** 3 - 8 ** 3 and rim.sum() == 6
    assert np.all(surface[outer] == 1.0) and surface[hole] == 1.0
    assert np.all(surface[block & ~outer] == 0.0)
    assert kernel_sum[rim].max() < 0.97 and layer_flag[rim].max() == 0.0
