"""Elastic-perfectly-plastic Mohr-Coulomb, Abdelrazek et al. (2016) after Bui et al. (2008) --
MODEL.md section 3.

Stress sigma = -p I + s (tension positive in sigma, p positive in compression).
- Pressure, linear equation of state [A5]: p = K (rho/rho_0 - 1), K = 50 rho_0 g H_max by
  default (50 times the largest initial pressure: nearly incompressible, not stiff).
- Deviatoric stress, Jaumann rate [A6], integrated in time (a history field):
      ds/dt = 2 G (eps - tr(eps)/3 I) + s omega^T + omega s,
  eps and omega the symmetric and antisymmetric parts of grad v (grad v_ab = d v_a/d x_b).
  With omega_ab = (d v_a/d x_b - d v_b/d x_a)/2, a rigid rotation R(t) gives s(t) = R s(0) R^T:
  the stress turns with the material and its invariants stay (tested).
- Plastic correction [A, Sec 4.1], after every update of s: tau = sqrt(J2) = sqrt(s:s/2) is
  scaled back to the strength S_f = c + p tan(phi) where it exceeds it (s <- s S_f/tau), so the
  stress lands exactly on the yield surface; zero dilatancy.
- Tension rule (our choice; Bui et al. 2008 reset the stress of cracked particles): the pressure
  is cut off at the apex of the Mohr-Coulomb cone, p >= -c/tan(phi) (p >= 0 for dry sand), and
  there S_f = 0, so s = 0: a particle pulled apart carries no stress, as loose grains do. Its
  density is reset to that of the apex, rho >= rho_0 (1 - c/(K tan(phi))) (rho_0 for dry sand):
  grains that separate and meet again are stress-free at contact, not owed the volume they
  gained. Without the reset the integrated density [A11] of a flowing layer falls steadily
  (measured on a 2D collapse: 1 % of particles below 0.6 rho_0 after 0.6 s), those particles
  keep p = 0 and S_f = 0 until recompressed by as much, and the deposit spreads as a frictionless
  fluid (run-out +75 % on the 2D a = 0.9 column, still moving at 0.6 s).

In 2D (plane strain) s holds the in-plane components; the out-of-plane one is s_zz = -tr(s),
since s is traceless in 3D (its rate is, and the in-plane Jaumann terms are traceless), and
J2 = (s:s + tr(s)^2)/2.

Units: densities kg/m^3, moduli and stresses Pa, rates 1/s.
"""
import math

import numpy as np
import taichi as ti

from .... import runtime

from ....state import FieldSpec
from ..base import Model
from ...stage import Stage


@ti.data_oriented
class ElastoplasticMohrCoulomb(Model):
    name = "elastoplastic"
    pressure_equation = "[A5]"  # the equation-of-state stage's tag (physics/equation_of_state.py)
    fields = (
        FieldSpec("deviatoric_stress", "matrix", "deviatoric stress s [A6] (in-plane part in 2D)", "Pa", "material"),
        FieldSpec("deviatoric_stress_rate", "matrix", "Jaumann rate ds/dt [A6]", "Pa/s", "material"),
        FieldSpec("deviatoric_stress_start", "matrix", "s at the start of the step", "Pa", "material"),
        FieldSpec("plastic", "scalar", "1 where the last update was scaled back to the yield surface", "-",
                  "material"),
    )
    # (field, its rate, its start-of-step copy): integrated by the integrator like the density
    derived_fields = (  # derived_output's, in the VTU files only
        FieldSpec("shear_stress", "scalar", "tau = sqrt(J2) of the deviatoric stress", "Pa", "material"),
        FieldSpec("mobilised_strength", "scalar", "tau / (c + p tan phi): 1 on the yield surface", "-", "material"),
    )
    history = (("deviatoric_stress", "deviatoric_stress_rate", "deviatoric_stress_start"),)

    def __init__(self, material, dim: int, smoothing_length: float, precision: str = "f64", state=None,
                 bulk_modulus: float = None):
        super().__init__(material, dim, smoothing_length, state)
        self.rho_0 = material.density
        self.G = material.shear_modulus
        self.K = float(bulk_modulus if bulk_modulus is not None else material.bulk_modulus)
        self.tan_phi = material.friction_coefficient
        self.cohesion = material.cohesion
        # the apex of the cone: S_f = 0 at p = -c/tan(phi) (the cut-off pressure)
        self.min_pressure = -self.cohesion / self.tan_phi if self.tan_phi > 0.0 else -math.inf
        # the density at the apex: the tension cut-off acts on the density (module docstring)
        self.min_density = max(self.rho_0 * (1.0 + self.min_pressure / self.K), 0.0)
        # longitudinal wave speed at rho_0: both the pressure and the shear stiffness load a wave
        self.wave_speed = math.sqrt((self.K + 4.0 * self.G / 3.0) / self.rho_0)
        # the artificial viscosity's c [A16-19] (material.sound_speed)
        self.viscosity_sound_speed = self.wave_speed if material.sound_speed == "longitudinal" else \
            math.sqrt(self.K / self.rho_0)

    @classmethod
    def from_scene(cls, scene):
        """K defaults to 50 rho_0 g H_max [A5], H_max the tallest block along the vertical axis."""
        m = scene.material
        dim = scene.dimension
        K = m.bulk_modulus
        if K is None:
            H_max = max(b.upper[dim - 1] - b.lower[dim - 1] for b in scene.particles)
            K = 50.0 * m.density * max(scene.gravity.magnitude, 1e-12) * H_max
        return cls(m, dim, scene.numerics.smoothing_length, scene.precision, bulk_modulus=K)

    # ---- [A5]: pressure ---------------------------------------------------------------------

    @ti.func
    def pressure_of(self, density):
        """p = K (rho/rho_0 - 1) [A5], cut off at the apex of the yield cone (module docstring)  [Pa]."""
        return ti.max(self.K * (density / self.rho_0 - 1.0), self.min_pressure)

    # ---- [A6]: Jaumann rate, and the plastic correction ---------------------------------------

    @ti.func
    def jaumann_rate(self, s, velocity_gradient):
        """ds/dt = 2 G dev(eps) + s omega^T + omega s [A6]  [Pa/s]."""
        eps = 0.5 * (velocity_gradient + velocity_gradient.transpose())
        omega = 0.5 * (velocity_gradient - velocity_gradient.transpose())
        identity = ti.Matrix.identity(float, self.dim)
        return 2.0 * self.G * (eps - (eps.trace() / 3.0) * identity) + s @ omega.transpose() + omega @ s

    @ti.func
    def shear_stress_measure(self, s):
        """tau = sqrt(J2) = sqrt(s:s/2), with s_zz = -tr(s) in 2D  [Pa]."""
        j2 = 0.5 * (s * s).sum()
        if ti.static(self.dim == 2):
            j2 += 0.5 * s.trace() ** 2
        return ti.sqrt(j2)

    @ti.func
    def yield_stress(self, pressure):
        """S_f = c + p tan(phi), zero at and beyond the apex  [Pa]."""
        return ti.max(self.cohesion + pressure * self.tan_phi, 0.0)

    @ti.func
    def return_to_yield(self, s, pressure):
        """(s scaled back onto tau = S_f where tau > S_f [A, Sec 4.1], 1 if it was)."""
        tau = self.shear_stress_measure(s)
        strength = self.yield_stress(pressure)
        plastic = 0.0
        if tau > strength:
            plastic = 1.0
            s = s * (strength / tau) if tau > 0.0 else s * 0.0
        return s, plastic

    @ti.func
    def deviatoric_stress(self, k):
        """s of particle k; boundary particles carry none  [Pa]."""
        s = ti.Matrix.zero(float, self.dim, self.dim)
        if k < self.state.n_material:
            s = self.state.deviatoric_stress[k]
        return s

    # ---- wave speed and time step ---------------------------------------------------------

    @ti.func
    def sound_speed(self, k):
        """The c of the artificial viscosity [A16-19], by ``material.sound_speed``: the longitudinal
        elastic wave speed sqrt((K + 4G/3)/rho_0), with which alpha c grows as sqrt(E) (a scene
        that lowers E then raises alpha by sqrt(E_paper/E)), or the sound speed of the equation
        of state sqrt(K/rho_0) [A5], with which E reaches the flow only through the elastic
        strains (docs/models/elastoplastic.md, the artificial viscosity's c)  [m/s]."""
        return self.viscosity_sound_speed

    @ti.func
    def stable_time_step(self, i):
        """h/(c + |v_i|), c the longitudinal wave speed (MODEL.md section 0: [A] needs the shear
        stiffness in it, not the sound speed of K alone)  [s]."""
        return self.h / (self.wave_speed + self.state.velocity[i].norm())

    @ti.func
    def density_error(self, i):
        return self.state.density[i] / self.rho_0 - 1.0

    # ---- numpy side -------------------------------------------------------------------------

    def initial_density(self, pressure: np.ndarray) -> np.ndarray:
        """rho = rho_0 (1 + p/K) [A5]  [kg/m^3]."""
        return self.rho_0 * (1.0 + np.asarray(pressure, float) / self.K)

    def reference_density(self) -> float:
        return self.rho_0

    def reference_sound_speed(self) -> float:
        return math.sqrt(self.K / self.rho_0)

    def faster_sound(self, factor: float) -> list:
        """The key and value that make the sound speed of compression sqrt(K/rho_0) ``factor`` times
        faster (mach.py; the density error is p/K [A5])."""
        return [("material.bulk_modulus", self.K * factor**2)]

    def derived_output(self, arrays: dict) -> dict:
        """tau = sqrt(J2) and the mobilised friction tau/S_f."""
        s = arrays["deviatoric_stress"]
        j2 = 0.5 * np.einsum("nab,nab->n", s, s)
        if self.dim == 2:
            j2 += 0.5 * np.einsum("naa->n", s) ** 2
        tau = np.sqrt(j2)
        p = arrays["pressure"][: s.shape[0]]
        strength = np.maximum(self.cohesion + p * self.tan_phi, 0.0)
        return {"shear_stress": tau, "mobilised_strength": np.where(strength > 0, tau / np.maximum(strength, 1e-300),
                                                                     0.0)}

    def stage_classes(self, scene):
        from ...continuity import Continuity
        from ...equation_of_state import DensityPressure
        from ...momentum import MOMENTUM
        from ...strain_rate import StrainRate
        from ...stress_diffusion import StressDiffusion
        diffusion = [StressDiffusion] if scene.numerics.stress_diffusion > 0.0 else []
        # the strain rate does not need the pressure: before it, so that it shares continuity's pass
        return [Continuity, StrainRate, DensityPressure, JaumannStressRate] + diffusion + \
            [MOMENTUM["stress_divergence"]]

    def update_stage_classes(self):
        """Stages run after each integrator update: the return to the yield surface."""
        return [PlasticCorrection]


@ti.data_oriented
class JaumannStressRate(Stage):
    name = "jaumann_stress_rate"
    slot = "rheology"
    category = "rheology"
    equation = "[A6]"

    @ti.kernel
    def _run(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            self.state.deviatoric_stress_rate[i] = self.model.jaumann_rate(self.state.deviatoric_stress[i],
                                                                          self.state.velocity_gradient[i])


@ti.data_oriented
class PlasticCorrection(Stage):
    """After every update: the tension cut-off on the density (module docstring), p from the new
    density [A5], then s back onto the yield surface."""

    name = "plastic_correction"
    slot = "update"
    category = "rheology"
    equation = "[A Sec 4.1]"

    @ti.kernel
    def _run(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.density_rate.shape[0]):  # material and dynamic boundary particles
            self.state.density[i] = ti.max(self.state.density[i], self.model.min_density)
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            p = self.model.pressure_of(self.state.density[i])
            s, plastic = self.model.return_to_yield(self.state.deviatoric_stress[i], p)
            self.state.deviatoric_stress[i] = s
            self.state.plastic[i] = plastic


MODEL = ElastoplasticMohrCoulomb
