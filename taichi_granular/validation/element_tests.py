"""Element tests of the hypoplastic + Bagnold law (MODEL.md section 2) on a patch of particles.

A cube of particles (3D lattice) is given the velocity v = L x of a uniform velocity gradient
L at every step. The package's own stages then do the work: kernel gradient renormalisation
and the SPH velocity gradient [M31] (which the correction makes exact for this linear field),
the predictor-corrector update of T_s [P] by the sub-stepped point ODE, with its tension guard.
Positions stay where they are: the deformation is homogeneous, so the stress does not depend
on where the particles sit, and a patch sheared to a strain of 5 would have no interior left.
Results are read on the interior particles (full kernel support).

Cases, with their references (MODEL.md section 2):
- isochoric triaxial compression, L = rate diag(-1, 1/2, 1/2), set 1: stationary state at
  I_e = 1.000 with sigma_1/sigma_3 = 2.454;
- undrained (isochoric) simple shear, v_x = rate z, set 1: stationary at I_e = 0.912 with
  tau/sigma_n = 0.491;
- the annular shear cell, v_x = 2 kappa z with kappa = 10 1/s for 0.5 s, its own parameter set
  and four solid fractions C (e = 1/C - 1): residual frictional stress zero for C <= 0.504,
  non-zero for C = 0.524 (sigma_xz = 36.5 Pa, sigma_zz = 83.2 Pa in [P]). The ramp of kappa
  to 500 1/s over 20 s (10^4 of strain) is not run: T_s is rate independent (the law is
  homogeneous of degree one in D), so it stays at its stationary value, and the total stress
  along the ramp is reported at a few kappa with the Bagnold part from the same D.

Starting states (our choice): isotropic, 1 kPa for set 1, 100 Pa in the shear cell; initial
void ratios chosen so that the stress climbs to the stationary state from slightly below it
(e_crt falls with pressure, which makes the stationary state an attractor):
triaxial e_0 = 0.968 (e_crt at |tr T| = 15 kPa), simple shear e_0 = 0.886.
"""
import math
from dataclasses import dataclass, field
from typing import List, Optional

import numpy as np
import taichi as ti

from .. import runtime
from ..config import scene_from_dict

ANNULAR_SOLID_FRACTIONS = (0.461, 0.483, 0.504, 0.524)
ANNULAR_BAGNOLD = {0.461: 0.0018, 0.483: 0.0027, 0.504: 0.0041, 0.524: 0.0065}  # k_v per C [P]
ANNULAR_REFERENCE = {"sigma_xz": 36.5, "sigma_zz": 83.2}  # Pa, C = 0.524 [P]
ALONG_SLOPE_STRAINS = (-0.2, -0.1, 0.0, 0.05, 0.1, 0.2)  # c of along_slope_friction, per unit shear
STATIONARY_GROWTH = 0.05  # |d ln|T_s| / d strain| below this: stationary


SIMPLE_SHEAR = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])  # v_x = z: unit simple shear


@ti.data_oriented
class PointIntegrator:
    """The rate law of one material point under a fixed velocity gradient and density factor,
    integrated with tr T = -3 held (the law is homogeneous of degree one in T, so only the
    direction of T evolves). Returns T and its relative growth d ln|T|/d strain at the end:
    zero growth marks the stationary state of MODEL.md section 2."""

    def __init__(self, hypoplastic):
        self.model = hypoplastic
        self.stress = ti.Matrix.field(3, 3, float, shape=())
        self.growth = ti.field(float, shape=())

    @ti.kernel
    def run(self, velocity_gradient: ti.types.matrix(3, 3, float), density_factor: float, steps: ti.i32,
            dt: float):
        T = -ti.Matrix.identity(float, 3)
        ti.loop_config(serialize=True)
        for _ in range(steps):
            k1 = self.model.frictional_rate(T, velocity_gradient, density_factor)
            k2 = self.model.frictional_rate(T + 0.5 * dt * k1, velocity_gradient, density_factor)
            T += dt * k2
            T *= -3.0 / T.trace()
        rate = self.model.frictional_rate(T, velocity_gradient, density_factor)
        self.stress[None] = T
        self.growth[None] = (T * rate).sum() / (T * T).sum()

    def __call__(self, velocity_gradient, density_factor, strain=3.0, dt=1e-4):
        self.run(ti.Matrix(velocity_gradient), density_factor, int(round(strain / dt)), dt)
        return self.stress.to_numpy(), float(self.growth[None])


@ti.data_oriented
class RateProbe:
    """dT_s/dt of the rate law at one material point: T_s, grad v (3 x 3) and I_e in, the rate
    (Jaumann terms included, as the stress update integrates it) out  [Pa/s]."""

    def __init__(self, hypoplastic):
        self.model = hypoplastic
        self.rate = ti.Matrix.field(3, 3, float, shape=())

    @ti.kernel
    def run(self, stress: ti.types.matrix(3, 3, float), velocity_gradient: ti.types.matrix(3, 3, float),
            density_factor: float):
        self.rate[None] = self.model.frictional_rate(stress, velocity_gradient, density_factor)

    def __call__(self, stress, velocity_gradient, density_factor) -> np.ndarray:
        self.run(ti.Matrix(np.asarray(stress, float)), ti.Matrix(np.asarray(velocity_gradient, float)),
                 float(density_factor))
        return self.rate.to_numpy()


def plane_strain_rate_for(probe: RateProbe, stress, spin, density_factor, stress_rate) -> np.ndarray:
    """The in-plane strain rate D (3 x 3, plane strain, D_zz = 0) for which the law gives the
    in-plane stress rate ``stress_rate`` (xx, yy, xy) at ``stress`` under the spin ``spin`` (3 x 3,
    antisymmetric): Newton's method with a finite-difference Jacobian from D = 0 and two starts
    either side (the |D| term makes the law non-smooth at D = 0), the smallest residual kept  [1/s]."""
    scale = max(abs(float(np.trace(stress))), 1e-12)
    omega = abs(float(spin[1, 0])) or 1.0

    def residual(d):
        D = np.array([[d[0], d[2], 0.0], [d[2], d[1], 0.0], [0.0, 0.0, 0.0]])
        r = probe(stress, D + spin, density_factor) - stress_rate
        return np.array([r[0, 0], r[1, 1], r[0, 1]]) / scale

    best, best_norm = None, math.inf
    for start in ([0.0, 0.0, 0.0], [0.05 * omega, -0.05 * omega, 0.05 * omega],
                  [-0.05 * omega, 0.05 * omega, -0.05 * omega]):
        d = np.array(start, float)
        r = residual(d)
        for _ in range(50):
            step = 1e-7 * omega
            J = np.column_stack([(residual(d + step * e) - r) / step for e in np.eye(3)])
            delta = np.linalg.lstsq(J, -r, rcond=None)[0]
            d, r = d + delta, residual(d + delta)
            if np.linalg.norm(delta) < 1e-12 * omega:
                break
        if np.linalg.norm(r) < best_norm:
            best, best_norm = d, np.linalg.norm(r)
    return np.array([[best[0], best[2], 0.0], [best[2], best[1], 0.0], [0.0, 0.0, 0.0]])


def stationary_state(hypoplastic, velocity_gradient, low: float = 0.7, high: float = 1.0,
                     tolerance: float = 1e-5):
    """(I_e, T) of the stationary state of the rate law under a fixed grad v (3 x 3), Jaumann terms
    included: the density factor where the growth of |T_s| changes sign (bisection; it falls with
    I_e), and the stress direction there (tr T = -3)  [-, -]."""
    point = PointIntegrator(hypoplastic)
    if not point(velocity_gradient, low)[1] > 0.0 > point(velocity_gradient, high)[1]:
        raise ValueError(f"no stationary state for I_e in [{low}, {high}]")
    while high - low > tolerance:
        middle = 0.5 * (low + high)
        if point(velocity_gradient, middle)[1] > 0.0:
            low = middle
        else:
            high = middle
    density_factor = 0.5 * (low + high)
    return density_factor, point(velocity_gradient, density_factor)[0]


def stationary_simple_shear(hypoplastic, low: float = 0.7, high: float = 1.0, tolerance: float = 1e-5):
    """(I_e, tau/sigma_n) of the stationary state of simple shear: the friction of the hypoplastic
    part there, mu_h of the inclined plane (MODEL.md section 2; set 1: 0.912 / 0.491, set 2:
    0.913 / 0.494)  [-, -]."""
    density_factor, T = stationary_state(hypoplastic, SIMPLE_SHEAR, low, high, tolerance)
    return density_factor, float(T[0, 2] / -T[2, 2])


def along_slope_friction(hypoplastic, compression: float, tolerance: float = 1e-5):
    """The stationary state of a slope-parallel shear v_x = z with an isochoric along-slope strain,
    dv_x/dx = -compression, dv_z/dz = +compression (compression > 0: the layer shortens downhill,
    as where it decelerates against the bed; < 0: it stretches). Returns (I_e,
    sigma_xx/sigma_zz, tau/sigma_zz): the friction the law carries on the slope-parallel plane
    once the along-slope normal stress differs from the normal one (a drum's flowing layer, whose
    faces carry part of its weight, docs/models/hypoplastic.md)  [-, -, -]."""
    L = SIMPLE_SHEAR + compression * np.diag([-1.0, 0.0, 1.0])
    density_factor, T = stationary_state(hypoplastic, L, tolerance=tolerance)
    return density_factor, float(T[0, 0] / T[2, 2]), float(T[0, 2] / -T[2, 2])


def patch_scene(parameter_set: str, void_ratio: float, bagnold_coefficient: Optional[float] = None,
                particles_per_side: int = 8, spacing: float = 1e-3, smoothing_function: str = "wendland_c6"):
    """A 3D cube of particles of the hypoplastic material, no walls, no gravity."""
    half = 0.5 * particles_per_side * spacing
    material = {"model": "hypoplastic", "parameter_set": parameter_set, "grain_density": 2650.0,
                "grain_diameter": 1e-3, "initial_void_ratio": void_ratio}
    if bagnold_coefficient is not None:
        material["bagnold_coefficient"] = bagnold_coefficient
    return scene_from_dict({
        "name": f"element_test_{parameter_set}", "dimension": 3,
        "domain": {"lower": [-2 * half] * 3, "upper": [2 * half] * 3},
        "gravity": {"magnitude": 0.0},
        "material": material,
        "particles": [{"lower": [-half] * 3, "upper": [half] * 3, "initial_stress": "zero"}],
        "numerics": {"particle_spacing": spacing, "smoothing_function": smoothing_function,
                     "gradient_correction": "matrix", "integrator": "predictor_corrector", "cfl": 0.05},
        "run": {"end_time": 1.0, "output_interval": 1.0},
    })


@ti.data_oriented
class ElementTest:
    """A patch under a prescribed uniform velocity gradient, advanced by the package's stages."""

    def __init__(self, scene, initial_pressure: float):
        from ..physics.gradient_correction import GradientCorrection
        from ..physics.rheology.hypoplastic.model import FrictionalStressUpdate, TotalStress
        from ..physics.strain_rate import StrainRate
        from ..scheme import Scheme

        self.scheme = Scheme(scene)
        by_class = {type(s): s for s in self.scheme.rate_stages + self.scheme.position_stages}
        self.neighbours = self.scheme.rate_stages[0]
        self.correction = by_class[GradientCorrection]
        self.strain_rate, self.stress_update = by_class[StrainRate], by_class[FrictionalStressUpdate]
        self.total = by_class[TotalStress]
        self.state = self.scheme.state
        n = self.state.n_material
        self.state.frictional_stress.from_numpy(np.tile(-initial_pressure * np.eye(3), (n, 1, 1)))
        self.neighbours.run()
        self.correction.run()
        from ..physics.shifting import FreeSurface
        if FreeSurface in by_class:  # the Bagnold stress is left out on the free surface (hypoplastic.py)
            by_class[FreeSurface].run()
        x = self.state.position.to_numpy()[:n]
        reach = 2.0 * scene.numerics.smoothing_length
        lo, hi = x.min(axis=0) + reach - 1e-12, x.max(axis=0) - reach + 1e-12
        self.interior = np.where(np.all((x >= lo) & (x <= hi), axis=1))[0]
        if len(self.interior) == 0:
            raise ValueError("the patch has no particle with full kernel support; give it more particles")
        self.strain = 0.0

    @ti.kernel
    def impose(self, velocity_gradient: ti.types.matrix(3, 3, float)):
        """v = L x on every particle of the patch."""
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            self.state.velocity[i] = velocity_gradient @ self.state.position[i]

    def advance(self, velocity_gradient: np.ndarray, dt: float) -> None:
        """One step of T_s under L: the predictor and corrector updates of a scene's step."""
        self.impose(ti.Matrix(velocity_gradient))
        self.strain_rate.run()
        self.scheme.dt[None] = dt
        for fraction in (0.5, 1.0):
            self.scheme.step_fraction[None] = fraction
            self.stress_update.run()
        D = 0.5 * (velocity_gradient + velocity_gradient.T)
        self.strain += math.sqrt(2.0 / 3.0 * float(np.sum(D * D))) * dt  # equivalent strain

    def readings(self) -> dict:
        """Interior means: frictional stress T_s, total stress T (with Bagnold), I_e, the gradient error."""
        self.total.run()
        idx = self.interior
        T_s = self.state.frictional_stress.to_numpy()[idx].mean(axis=0)
        p = self.state.pressure.to_numpy()[idx].mean()
        s = self.state.deviatoric_stress.to_numpy()[idx].mean(axis=0)
        grad = self.state.velocity_gradient.to_numpy()[idx]
        return {"frictional_stress": T_s, "total_stress": s - p * np.eye(3),
                "density_factor": float(self.state.density_factor.to_numpy()[idx].mean()),
                "velocity_gradient": grad.mean(axis=0)}


def relative_growth(T_before: np.ndarray, T_after: np.ndarray, strain: float) -> float:
    """d ln|T| / d strain over the last ``strain``: zero at a stationary state  [-]."""
    return math.log(float(np.linalg.norm(T_after) / np.linalg.norm(T_before))) / strain


@dataclass
class StationaryResult:
    name: str
    reference_ratio: float
    reference_factor: float
    tolerance: float
    ratio: float = 0.0
    density_factor: float = 0.0
    growth: float = 0.0
    strain: float = 0.0
    gradient_error: float = 0.0

    @property
    def ratio_error(self) -> float:
        return self.ratio / self.reference_ratio - 1.0

    @property
    def stationary(self) -> bool:
        return abs(self.growth) < STATIONARY_GROWTH

    @property
    def passed(self) -> bool:
        return self.stationary and abs(self.ratio_error) < self.tolerance and \
            abs(self.density_factor - self.reference_factor) < 0.0015

    def row(self) -> str:
        return (f"{self.name:14s} {self.ratio:8.4f} {self.reference_ratio:8.3f} {100 * self.ratio_error:+7.2f} % "
                f"{self.density_factor:7.4f} {self.reference_factor:6.3f} {self.growth:+8.4f} {self.strain:6.2f} "
                f"{self.gradient_error:9.2e}  {'PASS' if self.passed else 'FAIL'}")


STATIONARY_HEADER = ("case              ratio  ref      error     I_e    ref    d ln|T|/de strain  grad err  "
                     "(ratio: sigma_1/sigma_3 triaxial, tau/sigma_n shear)")


def _run_stationary(kind: str, strain: float, strain_step: float, particles_per_side: int) -> StationaryResult:
    rate = 1.0  # 1/s; the law is rate independent, only strain counts
    if kind == "triaxial":
        L = rate * np.diag([-1.0, 0.5, 0.5])
        result = StationaryResult("triaxial", 2.454, 1.000, 0.01)
        void_ratio = 0.968
    else:
        L = np.zeros((3, 3))
        L[0, 2] = rate
        result = StationaryResult("simple_shear", 0.491, 0.912, 0.02)
        void_ratio = 0.886
    test = ElementTest(patch_scene("set1", void_ratio, particles_per_side=particles_per_side), 1e3)
    D = 0.5 * (L + L.T)
    eq_rate = math.sqrt(2.0 / 3.0 * float(np.sum(D * D)))
    dt = strain_step / eq_rate
    last = 0.05 * strain  # the growth is read over the last 5 % of the strain
    while test.strain < strain - last - 1e-12:
        test.advance(L, dt)
    T_before = test.readings()["frictional_stress"]
    while test.strain < strain - 1e-12:
        test.advance(L, dt)
    r = test.readings()
    T = r["frictional_stress"]
    if kind == "triaxial":
        result.ratio = T[0, 0] / T[1, 1]
    else:
        result.ratio = T[0, 2] / -T[2, 2]
    result.density_factor = r["density_factor"]
    result.growth = relative_growth(T_before, T, last)
    result.strain = test.strain
    result.gradient_error = float(np.abs(r["velocity_gradient"] - L).max()) / rate
    return result


def stationary_states(strain: float = 4.0, strain_step: float = 2e-4, particles_per_side: int = 8):
    """The triaxial and simple-shear stationary states of set 1 (MODEL.md section 2)."""
    return [_run_stationary(kind, strain, strain_step, particles_per_side) for kind in ("triaxial", "simple_shear")]


@dataclass
class AnnularResult:
    solid_fraction: float
    void_ratio: float
    sigma_xz: float
    sigma_zz: float
    density_factor: float
    ramp: List[tuple] = field(default_factory=list)  # (kappa, total sigma_xz, total sigma_zz)

    @property
    def residual(self) -> bool:
        return abs(self.sigma_xz) > 1.0

    def row(self) -> str:
        ramp = "  ".join(f"k={k:.0f}: {xz:.3g}/{zz:.3g}" for k, xz, zz in self.ramp)
        return (f"C = {self.solid_fraction:.3f}  e = {self.void_ratio:.3f}  frictional sigma_xz {self.sigma_xz:7.2f} Pa  "
                f"sigma_zz {self.sigma_zz:7.2f} Pa  I_e {self.density_factor:.4f}   total xz/zz {ramp}")


def annular_shear_cell(solid_fraction: float, duration: float = 0.5, strain_step: float = 2e-4,
                       particles_per_side: int = 8, ramp_kappas=(10.0, 100.0, 500.0)) -> AnnularResult:
    """v_x = 2 kappa z, kappa = 10 1/s for ``duration``; then T at a few kappa of the ramp."""
    void_ratio = 1.0 / solid_fraction - 1.0
    test = ElementTest(patch_scene("annular", void_ratio, ANNULAR_BAGNOLD[solid_fraction],
                                   particles_per_side=particles_per_side), 100.0)
    kappa = 10.0
    L = np.zeros((3, 3))
    L[0, 2] = 2.0 * kappa
    dt = strain_step / L[0, 2]
    steps = int(round(duration / dt))
    for _ in range(steps):
        test.advance(L, dt)
    r = test.readings()
    T = r["frictional_stress"]
    result = AnnularResult(solid_fraction, void_ratio, T[0, 2], -T[2, 2], r["density_factor"])
    for k in ramp_kappas:  # the total stress at kappa: the same T_s, Bagnold from the new D
        L = np.zeros((3, 3))
        L[0, 2] = 2.0 * k
        test.impose(ti.Matrix(L))
        test.strain_rate.run()
        total = test.readings()["total_stress"]
        result.ramp.append((k, total[0, 2], -total[2, 2]))
    return result


# ---- the validate command's case (validation/__init__.py CASES) -------------------------------


def check(case, runs, base, args) -> bool:
    """Element tests of the hypoplastic law (MODEL.md section 2) on a patch of particles (no
    scene file: ``runs`` is empty); writes element_tests.csv."""
    from ..output import atomic_write_text

    runtime.init("cpu", "f64")  # a few hundred particles: the CPU is the right backend
    print("stationary states, parameter set 1, isochoric, patch of 8^3 particles under v = L x:")
    print(STATIONARY_HEADER)
    stationary = stationary_states()
    for r in stationary:
        print(r.row(), flush=True)
    print("slope-parallel shear v_x = z with an isochoric along-slope strain -c (x) +c (z), set 2 (the drum's):")
    print(f"{'c':>6} {'I_e':>7} {'s_xx/s_zz':>10} {'tau/s_zz':>9} {'deg':>6}")
    from ..physics.rheology.hypoplastic.model import HypoplasticBagnold
    slope_model = HypoplasticBagnold.from_scene(patch_scene("set2", 0.896))
    for compression in ALONG_SLOPE_STRAINS:
        I_e, normal_ratio, friction = along_slope_friction(slope_model, compression)
        print(f"{compression:>+6.2f} {I_e:>7.4f} {normal_ratio:>10.3f} {friction:>9.4f} "
              f"{math.degrees(math.atan(friction)):>6.2f}", flush=True)
    print("annular shear cell, v_x = 2 kappa z, kappa = 10 1/s for 0.5 s (strain 10), its parameter set:")
    annular = [annular_shear_cell(c) for c in ANNULAR_SOLID_FRACTIONS]
    for r in annular:
        print(r.row(), flush=True)
    dense = annular[-1]
    ref = ANNULAR_REFERENCE
    print(f"C = 0.524 against [P]: sigma_xz {dense.sigma_xz:.2f} Pa ({100 * (dense.sigma_xz / ref['sigma_xz'] - 1):+.1f} %), "
          f"sigma_zz {dense.sigma_zz:.2f} Pa ({100 * (dense.sigma_zz / ref['sigma_zz'] - 1):+.1f} %)")
    atomic_write_text(base / "element_tests.csv", "case,value,reference,density_factor,growth\n" + "".join(
        f"{r.name},{r.ratio:.5f},{r.reference_ratio},{r.density_factor:.5f},{r.growth:.5f}\n" for r in stationary) + "".join(
        f"annular_C{r.solid_fraction:.3f},{r.sigma_xz:.4f},{ref['sigma_xz'] if r.residual else 0.0},"
        f"{r.density_factor:.5f},\n" for r in annular))
    ok_annular = all(not r.residual for r in annular[:-1]) and dense.residual
    ok = all(r.passed for r in stationary) and ok_annular
    print(f"acceptance (triaxial ratio within 1 %, shear ratio within 2 %, each at its I_e within 0.0015 and "
          f"stationary; shear cell: no residual stress for C <= 0.504, residual at 0.524): "
          f"{'PASS' if ok else 'FAIL'}; {base / 'element_tests.csv'}")
    from .table import Row, write_rows

    patch, verdict = "patch of 8^3 particles", "PASS" if ok else "FAIL"
    write_rows(base, [Row(f"{case.name}: {r.name}", "stationary stress ratio (at I_e)",
                          f"{r.ratio:.4f} ({r.density_factor:.4f})", "-",
                          f"MODEL.md point integration: {r.reference_ratio} ({r.reference_factor})", patch, "-",
                          verdict) for r in stationary] +
               [Row(f"{case.name}: annular cell C = 0.524", "residual sigma_xz / sigma_zz",
                    f"{dense.sigma_xz:.1f} / {dense.sigma_zz:.1f} Pa", f"{ref['sigma_xz']} / {ref['sigma_zz']} Pa",
                    "[P]'s shear cell (its own computation)", patch, "-", verdict)])
    return ok
