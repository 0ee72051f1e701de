"""Unified hypoplastic + Bagnold model of Peng et al. (2016) -- MODEL.md section 2.

In this module stress is T, **tension positive** (tr T < 0 in compression), as in the
hypoplasticity literature; D and W are the symmetric and antisymmetric parts of grad v.

Total stress T = T_s + T_v:
- T_s, frictional, a history field integrated in time by the Wu-Bauer-Kolymbas (1996) rate
  law with its Jaumann terms (MODEL.md section 2):
      T_s° = c1 (tr T_s) D + c2 tr(T_s D) T_s/tr T_s + I_e (c3 T_s^2 + c4 T_s*^2)/tr T_s ||D||,
      dT_s/dt = T_s° + W T_s - T_s W,
  T_s* = T_s - (tr T_s/3) I, ||D|| = sqrt(D:D). Density factor I_e = (1 - a) D_c + a with
  D_c = (e - e_min)/(e_crt - e_min), e_crt = p1 + p2 exp(p3 |tr T_s|) (>= e_min + 1e-3),
  a = q1 + q2 exp(q3 |tr T_s|), |tr T_s| in kPa (our choice of argument, MODEL.md). The void
  ratio is read from the density, e = rho_s/rho - 1, which the continuity equation integrates
  (de/dt = (1 + e) tr D is the same statement).
- T_v, collisional (extended Bagnold), algebraic from the current D, never fed back into T_s:
      T_v = -k_v rho_s d^2 gamma_eq^2 cos(alpha_i) I + 2 k_v rho_s d^2 gamma_eq sin(alpha_i) D*,
  gamma_eq = sqrt(2 D*:D*); in simple shear tau_v/p_v = tan(alpha_i) exactly (Bagnold 1954).
- Tension guard (our choice, MODEL.md): the law divides by tr T_s, so where tr T_s > -eps
  (a few Pa: free surface, ballistic grains) T_s is reset to -(eps/3) I after every update;
  the nonlinear term vanishes with ||D|| anyway.

Checked by point integration against the stationary states of MODEL.md (tests and
``taichi-granular validate element-tests``): isochoric triaxial compression, set 1, becomes
stationary at I_e = 1.000 with sigma_1/sigma_3 = 2.454; undrained simple shear at I_e = 0.912
with tau/sigma_n = 0.491.

In 2D (plane strain) T_s stays 3 x 3 (its out-of-plane normal stress is not determined by the
in-plane ones); grad v is embedded with zero out-of-plane rows. Momentum sees the in-plane part
of T through the package's sigma = -p I + s, with p = -tr(T)/3 (3D trace) and s = T + p I.

Units: stresses Pa, rates 1/s, densities kg/m^3.
"""
import math

import numpy as np
import taichi as ti

from ... import runtime

from ...state import FieldSpec
from ..stage import Stage

KPA = 1.0e-3  # |tr T_s| enters e_crt and a in kPa (MODEL.md section 2)


@ti.data_oriented
class HypoplasticBagnold:
    name = "hypoplastic"
    fields = (
        FieldSpec("frictional_stress", "tensor3", "T_s, hypoplastic stress, tension positive [P]", "Pa", "material"),
        FieldSpec("frictional_stress_rate", "tensor3", "dT_s/dt, hypoplastic rate with Jaumann terms [P]", "Pa/s",
                  "material"),
        FieldSpec("frictional_stress_start", "tensor3", "T_s at the start of the step", "Pa", "material"),
        FieldSpec("density_factor", "scalar", "I_e = (1 - a) D_c + a of the last rate evaluation", "-", "material"),
        FieldSpec("deviatoric_stress", "matrix", "s of the total stress T_s + T_v (in-plane part in 2D)", "Pa",
                  "material"),
    )
    history = (("frictional_stress", "frictional_stress_rate", "frictional_stress_start"),)

    def __init__(self, material, dim: int, smoothing_length: float, state=None):
        self.material = material
        self.dim = dim
        self.state = state
        self.h = float(smoothing_length)
        self.c1, self.c2, self.c3, self.c4 = (float(c) for c in material.constants)
        self.e_min = float(material.min_void_ratio)
        self.p1, self.p2, self.p3 = (float(p) for p in material.critical_void_ratio)
        self.q1, self.q2, self.q3 = (float(q) for q in material.density_exponent)
        self.grain_density = float(material.grain_density)
        self.guard = float(material.tension_guard)
        self.wave_speed = float(material.wave_speed)
        self.rho_ref = float(material.reference_density)
        alpha_i = math.radians(material.dispersion_angle_deg)
        # k_v rho_s d^2: the Bagnold stress per squared strain rate [Pa s^2]
        bagnold = material.bagnold_coefficient * material.grain_density * material.grain_diameter**2
        self.bagnold_pressure = bagnold * math.cos(alpha_i)
        self.bagnold_shear = 2.0 * bagnold * math.sin(alpha_i)
        self.collisional = bagnold > 0.0

    @classmethod
    def from_scene(cls, scene):
        return cls(scene.material, scene.dimension, scene.numerics.smoothing_length)

    # ---- the rate law, one particle -------------------------------------------------------------

    @ti.func
    def embed(self, velocity_gradient):
        """grad v as a 3 x 3 matrix (plane strain: zero out-of-plane rows and columns)  [1/s]."""
        L = ti.Matrix.zero(float, 3, 3)
        for a, b in ti.static(ti.ndrange(self.dim, self.dim)):
            L[a, b] = velocity_gradient[a, b]
        return L

    @ti.func
    def density_factor_of(self, stress, void_ratio):
        """I_e = (1 - a) D_c + a, D_c = (e - e_min)/(e_crt - e_min)  [-] (MODEL.md section 2)."""
        mean = ti.abs(stress.trace()) * KPA
        e_crt = ti.max(self.p1 + self.p2 * ti.exp(self.p3 * mean), self.e_min + 1e-3)
        a = self.q1 + self.q2 * ti.exp(self.q3 * mean)
        relative_density = (void_ratio - self.e_min) / (e_crt - self.e_min)
        return (1.0 - a) * relative_density + a

    @ti.func
    def frictional_rate(self, stress, velocity_gradient3, density_factor):
        """dT_s/dt = T_s° + W T_s - T_s W (Wu, Bauer & Kolymbas 1996; MODEL.md section 2)  [Pa/s]."""
        D = 0.5 * (velocity_gradient3 + velocity_gradient3.transpose())
        W = 0.5 * (velocity_gradient3 - velocity_gradient3.transpose())
        trace = stress.trace()
        deviator = stress - (trace / 3.0) * ti.Matrix.identity(float, 3)
        norm_D = ti.sqrt((D * D).sum())
        rate = self.c1 * trace * D + self.c2 * (stress * D).sum() * stress / trace + \
            density_factor * (self.c3 * stress @ stress + self.c4 * deviator @ deviator) / trace * norm_D
        return rate + W @ stress - stress @ W

    @ti.func
    def guarded(self, stress):
        """T_s, or -(eps/3) I where tr T_s > -eps (the tension guard, MODEL.md section 2)  [Pa]."""
        result = stress
        if stress.trace() > -self.guard:
            result = -(self.guard / 3.0) * ti.Matrix.identity(float, 3)
        return result

    @ti.func
    def collisional_stress(self, velocity_gradient3):
        """T_v = -k_v rho_s d^2 gamma_eq^2 cos(alpha_i) I + 2 k_v rho_s d^2 gamma_eq sin(alpha_i) D*,
        gamma_eq = sqrt(2 D*:D*) (extended Bagnold, MODEL.md section 2)  [Pa]."""
        D = 0.5 * (velocity_gradient3 + velocity_gradient3.transpose())
        identity = ti.Matrix.identity(float, 3)
        D_dev = D - (D.trace() / 3.0) * identity
        gamma_eq = ti.sqrt(2.0 * (D_dev * D_dev).sum())
        return -self.bagnold_pressure * gamma_eq**2 * identity + self.bagnold_shear * gamma_eq * D_dev

    @ti.func
    def void_ratio(self, k):
        """e = rho_s/rho - 1  [-]."""
        return self.grain_density / self.state.density[k] - 1.0

    # ---- what the pair loops see ---------------------------------------------------------------

    @ti.func
    def deviatoric_stress(self, k):
        """s of the total stress of particle k (its in-plane part); boundary particles carry one only
        where the wall model gives them one (extrapolated walls)  [Pa]."""
        s = ti.Matrix.zero(float, self.dim, self.dim)
        if k < self.state.deviatoric_stress.shape[0]:
            s = self.state.deviatoric_stress[k]
        return s

    @ti.func
    def sound_speed(self, k):
        """c = 80 m/s of [P] (material.wave_speed): the artificial viscosity's c  [m/s]."""
        return self.wave_speed

    @ti.func
    def stable_time_step(self, i):
        """h/c, so that dt = chi h/c with chi = numerics.cfl (0.05 in [P])  [s]."""
        return self.h / self.wave_speed

    @ti.func
    def density_error(self, i):
        return self.state.density[i] / self.rho_ref - 1.0

    # ---- numpy side --------------------------------------------------------------------------

    def reference_density(self) -> float:
        return self.rho_ref

    def reference_sound_speed(self) -> float:
        return self.wave_speed

    def initial_density(self, pressure: np.ndarray) -> np.ndarray:
        """The density of the initial void ratio, whatever the stress (grains are rigid here)  [kg/m^3]."""
        return np.full(np.shape(pressure), self.reference_density())

    def initial_fields(self, initial) -> dict:
        """T_s at t = 0: isotropic, -p I with the block's hydrostatic pressure p (our choice: K0 = 1),
        at least the tension guard's -(eps/3) I  [Pa]."""
        p = np.maximum(initial.pressure[: initial.n_material], self.guard / 3.0)
        return {"frictional_stress": -p[:, None, None] * np.eye(3)[None]}

    def derived_output(self, arrays: dict) -> dict:
        """Void ratio e = rho_s/rho - 1."""
        n = arrays["frictional_stress"].shape[0]
        return {"void_ratio": self.grain_density / arrays["density"][:n] - 1.0}

    def stage_classes(self, scene):
        from ..continuity import Continuity
        from ..momentum import MOMENTUM
        from ..strain_rate import StrainRate
        return [Continuity, StrainRate, FrictionalStressRate, TotalStress, MOMENTUM["stress_divergence"]]

    def update_stage_classes(self):
        """Run after each integrator update: the tension guard."""
        return [TensionGuard]


@ti.data_oriented
class FrictionalStressRate(Stage):
    """dT_s/dt of every material particle from its grad v, stress and void ratio."""

    name = "hypoplastic_stress_rate"
    category = "rheology"
    equation = "[P] Wu-Bauer-Kolymbas"

    @ti.kernel
    def _run(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            stress = self.state.frictional_stress[i]
            factor = self.model.density_factor_of(stress, self.model.void_ratio(i))
            self.state.density_factor[i] = factor
            self.state.frictional_stress_rate[i] = self.model.frictional_rate(
                stress, self.model.embed(self.state.velocity_gradient[i]), factor)


@ti.data_oriented
class TotalStress(Stage):
    """T = T_s + T_v; writes p = -tr(T)/3 and s = T + p I (in-plane) for the momentum equation."""

    name = "total_stress"
    category = "rheology"
    equation = "[P] T_s + Bagnold"

    @ti.kernel
    def _run(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            stress = self.state.frictional_stress[i]
            if ti.static(self.model.collisional):
                stress += self.model.collisional_stress(self.model.embed(self.state.velocity_gradient[i]))
            pressure = -stress.trace() / 3.0
            s = ti.Matrix.zero(float, self.state.dim, self.state.dim)
            for a, b in ti.static(ti.ndrange(self.state.dim, self.state.dim)):
                s[a, b] = stress[a, b]
            self.state.pressure[i] = pressure
            self.state.deviatoric_stress[i] = s + pressure * ti.Matrix.identity(float, self.state.dim)


@ti.data_oriented
class TensionGuard(Stage):
    name = "tension_guard"
    category = "rheology"
    equation = "MODEL.md section 2 (choice)"

    @ti.kernel
    def _run(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            self.state.frictional_stress[i] = self.model.guarded(self.state.frictional_stress[i])
