"""Unified hypoplastic + Bagnold model of Peng et al. (2016) -- MODEL.md section 2; the equations
as computed here, and the measurements behind each choice, in docs/models/hypoplastic.md.

Stress is T, **tension positive** (tr T < 0 in compression); D and W are the symmetric and
antisymmetric parts of grad v. Total stress T = T_s + T_v:
- T_s, frictional, a history field: the Wu-Bauer-Kolymbas (1996) rate law with its Jaumann terms,
      T_s° = c1 (tr T_s) D + c2 tr(T_s D) T_s/tr T_s + I_e (c3 T_s^2 + c4 T_s*^2)/tr T_s ||D||,
      dT_s/dt = T_s° + W T_s - T_s W,
  I_e = (1 - a) D_c + a, D_c = (e - e_min)/(e_crt - e_min), e_crt = p1 + p2 exp(p3 |tr T_s|)
  (>= e_min + 1e-3), a = q1 + q2 exp(q3 |tr T_s|), |tr T_s| in kPa; e = rho_s/rho - 1.
- T_v, collisional (extended Bagnold), algebraic from the current D, never fed back into T_s:
      T_v = -k_v rho_s d^2 gamma_eq^2 cos(alpha_i) I + 2 k_v rho_s d^2 gamma_eq sin(alpha_i) D*,
  gamma_eq = sqrt(2 D*:D*).
- Tension guard (our choice): where tr T_s > -eps, T_s is scaled back to tr T_s = -eps with its
  direction kept if every principal stress is compressive, else reset to -(eps/3) I (MODEL.md's
  reset): the law is homogeneous of degree one in T_s, and from an isotropic state under fast
  shear its trace rate is tensile, so a reset at every touch never lets T_s leave the guard.

The law is locally stiff (its rate is of order (sum |c_k|) ||D|| |T_s|): each predictor and
corrector update integrates the point ODE dT_s/dt = f(T_s, grad v), grad v fixed over the update,
in midpoint sub-steps of (sum |c_k|) ||D|| dt_sub <= 1/2, the guard after each; where the flow is
slow that is one sub-step, the plain scheme of [P].

Optional, not in [P]: a numerical bulk viscosity (``numerics.bulk_viscosity``, alpha_b),
T += alpha_b rho c h tr(D) I, on the volumetric rate only and cut where it would make the mean
stress tensile (the model has no equation of state; T_s and the void ratio otherwise oscillate),
with its own time-step bound; and a time-step bound on the relative change of T_s in one step
(``numerics.stress_increment``). The momentum equation's residual damping (physics/momentum.py)
takes this model's secant viscosity sqrt(T*:T*/2)/gamma_dot, capped at 0.1 rho c h.

In 2D (plane strain) T_s stays 3 x 3 and grad v is embedded with zero out-of-plane rows; the
momentum equation sees the in-plane part of T through sigma = -p I + s, p = -tr(T)/3, s = T + p I.

Units: stresses Pa, rates 1/s, densities kg/m^3.
"""
import math

import numpy as np
import taichi as ti

from .... import runtime

from ....state import FieldSpec
from ..base import Model
from ...stage import Stage

KPA = 1.0e-3  # |tr T_s| enters e_crt and a in kPa (MODEL.md section 2)


@ti.data_oriented
class HypoplasticBagnold(Model):
    name = "hypoplastic"
    fields = (
        FieldSpec("frictional_stress", "tensor3", "T_s, hypoplastic stress, tension positive [P]", "Pa", "material"),
        FieldSpec("frictional_stress_start", "tensor3", "T_s at the start of the step", "Pa", "material"),
        FieldSpec("density_factor", "scalar", "I_e = (1 - a) D_c + a of the last update", "-", "material"),
        FieldSpec("deviatoric_stress", "matrix", "s of the total stress T_s + T_v (in-plane part in 2D)", "Pa",
                  "material"),
        FieldSpec("viscosity", "scalar", "secant viscosity sqrt(T*:T*/2)/gamma_dot, capped at 0.1 rho c h: the "
                  "strength of the momentum equation's residual damping", "Pa s", "material"),
    )
    derived_fields = (FieldSpec("void_ratio", "scalar", "e = rho_s/rho - 1", "-", "material"),)  # VTU only
    history = ()  # T_s is advanced by its own sub-stepped update (module docstring), not by the integrator
    substep_limit = 0.5  # (sum |c_k|) ||D|| dt_sub
    max_substeps = 256

    def __init__(self, material, dim: int, smoothing_length: float, state=None, numerics=None):
        super().__init__(material, dim, smoothing_length, state)
        self.c1, self.c2, self.c3, self.c4 = (float(c) for c in material.constants)
        self.stiffness = sum(abs(float(c)) for c in material.constants)  # bounds the rate per unit ||D|| |T_s|
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
        self.needs_free_surface = self.collisional  # T_v is left out on the free surface (TotalStress)
        # from the scene's numerics (defaults: a bare law, as the point-integration tests use it)
        self.bulk_viscosity = float(numerics.bulk_viscosity) if numerics else 0.0  # alpha_b (module docstring)
        self.stress_increment = float(numerics.stress_increment) if numerics else 0.0  # stable_time_step
        self.residual_damping = float(numerics.residual_damping) if numerics else 1.0  # secant_viscosity
        self.cfl = float(numerics.cfl) if numerics else 1.0  # the step's CFL factor, undone by alpha_b's own bound
        # Shepard sum below which a grain is on the free surface
        self.free_surface_threshold = float(numerics.particle_shifting.free_surface_threshold) if numerics else 0.9

    @classmethod
    def from_scene(cls, scene):
        return cls(scene.material, scene.dimension, scene.numerics.smoothing_length, numerics=scene.numerics)

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
    def advance(self, stress, velocity_gradient3, void_ratio, duration):
        """T_s after ``duration`` of the point ODE under a fixed grad v: midpoint sub-steps with
        (sum |c_k|) ||D|| dt_sub <= 1/2, the tension guard after each (module docstring).
        Returns (T_s, I_e at the end)  [Pa, -]."""
        D = 0.5 * (velocity_gradient3 + velocity_gradient3.transpose())
        norm_D = ti.sqrt((D * D).sum())
        n = ti.min(ti.max(1, ti.cast(ti.ceil(self.stiffness * norm_D * duration / self.substep_limit), ti.i32)),
                   self.max_substeps)
        dt = duration / n
        for _ in range(n):
            k1 = self.frictional_rate(stress, velocity_gradient3, self.density_factor_of(stress, void_ratio))
            half = self.guarded(stress + 0.5 * dt * k1)
            k2 = self.frictional_rate(half, velocity_gradient3, self.density_factor_of(half, void_ratio))
            stress = self.guarded(stress + dt * k2)
        return stress, self.density_factor_of(stress, void_ratio)

    @ti.func
    def guarded(self, stress):
        """The tension guard (our choice, MODEL.md section 2; module docstring): T_s where
        tr T_s <= -eps; where -eps < tr T_s < 0 and no principal stress is tensile, T_s scaled
        back to tr T_s = -eps with its direction kept; otherwise -(eps/3) I  [Pa]."""
        result = stress
        trace = stress.trace()
        if trace > -self.guard:
            result = -(self.guard / 3.0) * ti.Matrix.identity(float, 3)
            if trace < 0.0:
                eigenvalues, _ = ti.sym_eig(stress)
                if ti.max(eigenvalues[0], eigenvalues[1], eigenvalues[2]) <= 0.0:
                    result = stress * (-self.guard / trace)
        return result

    @ti.func
    def deviatoric_rate(self, velocity_gradient3):
        """(D*, gamma_eq = sqrt(2 D*:D*)): the deviatoric strain rate and its modulus (= |dv_x/dz|
        in simple shear)  [1/s]."""
        D = 0.5 * (velocity_gradient3 + velocity_gradient3.transpose())
        D_dev = D - (D.trace() / 3.0) * ti.Matrix.identity(float, 3)
        return D_dev, ti.sqrt(2.0 * (D_dev * D_dev).sum())

    @ti.func
    def collisional_stress(self, velocity_gradient3):
        """T_v = -k_v rho_s d^2 gamma_eq^2 cos(alpha_i) I + 2 k_v rho_s d^2 gamma_eq sin(alpha_i) D*,
        gamma_eq = sqrt(2 D*:D*) (extended Bagnold, MODEL.md section 2)  [Pa]."""
        D_dev, gamma_eq = self.deviatoric_rate(velocity_gradient3)
        return -self.bagnold_pressure * gamma_eq**2 * ti.Matrix.identity(float, 3) + \
            self.bagnold_shear * gamma_eq * D_dev

    @ti.func
    def bulk_viscous_stress(self, i, stress):
        """zeta tr(D) I, zeta = alpha_b rho c h: the numerical bulk viscosity (module docstring), cut
        so that it never turns the mean of ``stress`` (T_s + T_v) tensile: a dilating grain at the
        free surface would otherwise be pulled back by a tension no granular material carries
        (measured: a surface grain of the inclined plane, at -1.8 kPa, was dragged through the
        layer and the wall at 0.87 s)  [Pa]."""
        rate = ti.static(self.bulk_viscosity * self.wave_speed * self.h) * self.state.density[i] * \
            self.state.velocity_gradient[i].trace()
        return ti.min(rate, -stress.trace() / 3.0) * ti.Matrix.identity(float, 3)

    @ti.func
    def secant_viscosity(self, i, stress):
        """eta = f sqrt(T*:T*/2)/gamma_dot (f tau/gamma_dot in simple shear; f =
        numerics.residual_damping, 1 by default), at most 0.1 rho c h (the [M39] viscous bound
        then equals the step's h/c, so it never shortens dt): how strongly
        the momentum equation damps the particle-scale velocity residual (physics/momentum.py).
        Why: the SPH velocity gradient does not see a velocity alternating from one row of
        particles to the next, so the stress never resists it. Measured on the inclined plane
        (d 5 mm, 28 deg) without it: rows alternated by +-0.15 m/s about the profile by 0.2 s
        (velocity error 14 % per row, the averages of row pairs within a few % of the reference),
        and the lattice broke up between 0.25 and 0.45 s. The drum scenes take f = 0.25: with the
        full secant the damping of the disordered flowing layer added to its friction and the
        surface stuck and slipped (docs/models/hypoplastic.md, Drum)  [Pa s]."""
        deviator = stress - (stress.trace() / 3.0) * ti.Matrix.identity(float, 3)
        _, gamma = self.deviatoric_rate(self.embed(self.state.velocity_gradient[i]))
        cap = ti.static(0.1 * self.wave_speed * self.h) * self.state.density[i]
        eta = cap
        tau = ti.static(self.residual_damping) * ti.sqrt(0.5 * (deviator * deviator).sum())
        if tau < cap * gamma:
            eta = tau / gamma
        return eta

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
    def stiffness_wave_speed(self, i):
        """sqrt((sum |c_k|) |T_s| / rho): the law's tangent stiffness is of order (sum |c_k|) |T_s|
        (degree one in T_s), so this bounds the speed of its waves  [m/s]."""
        stress = self.state.frictional_stress[i]
        return ti.sqrt(self.stiffness * ti.sqrt((stress * stress).sum()) / self.state.density[i])

    @ti.func
    def stress_increment_step(self, i):
        """numerics.stress_increment |T_s| / |dT_s/dt| divided by the caller's CFL factor (the step
        then changes T_s by at most that fraction), where |T_s| > 10 eps. Why: the law's stiffness
        is degree one in T_s, so T_s grows exponentially with compaction (about e^(200 eps_v) in
        isotropic compression with set 2), and a grain compacted quickly by the impact of an
        avalanche can multiply its stress many times within one step fixed by c = 80 m/s and by
        its stress at the start. Measured on the omega = 2 rad/s drum: without the bound the first
        avalanche (from 42 deg, at 0.34 s) blew up (54 kPa and 4.8 m/s inside the bed within
        0.01 s; the same at omega = 1 at 0.8 s); with 1.0 it ran through it and on for two
        seconds, at dt ~1.4e-5 s instead of 2.2e-5 s; with 0.2 the step fell ten-fold  [s]."""
        step = 1e30
        stress = self.state.frictional_stress[i]
        magnitude = ti.sqrt((stress * stress).sum())
        if magnitude > ti.static(10.0 * self.guard):
            L = self.embed(self.state.velocity_gradient[i])
            rate = self.frictional_rate(stress, L, self.density_factor_of(stress, self.void_ratio(i)))
            rate_norm = ti.sqrt((rate * rate).sum())
            if rate_norm > 0.0:
                step = ti.static(self.stress_increment / self.cfl) * magnitude / rate_norm
        return step

    @ti.func
    def stable_time_step(self, i):
        """h/(max(c, c_T) + |v_i|), the caller's CFL factor applied: dt = chi h/c of [P] with
        chi = numerics.cfl, unless the stress makes the law stiffer than c = 80 m/s (c_T of
        stiffness_wave_speed). Measured: a small drum (R = 5 cm, omega = 2 pi rad/s) blew up in
        its bulk at 0.23 s with dt = 0.3 h/c alone, and ran at 0.15 h/c.
        With the bulk viscosity zeta = alpha_b rho c h, also the explicit diffusion limit
        dt <= 0.125 h^2/nu = 0.125 h/(alpha_b c) (Morris et al. 1997): a stability bound of its
        own, so the CFL factor does not shrink it again. Measured on the inclined plane (d 2 mm,
        28 deg): alpha_b = 1 at dt = 0.3 h/c (2.4 times the bound) blew up at 0.28 s  [s]."""
        c = ti.max(self.wave_speed, self.stiffness_wave_speed(i))
        step = self.h / (c + self.state.velocity[i].norm())
        if ti.static(self.stress_increment > 0.0):
            step = ti.min(step, self.stress_increment_step(i))
        if ti.static(self.bulk_viscosity > 0.0):
            step = ti.min(step, ti.static(0.125 * self.h / (self.bulk_viscosity * self.wave_speed * self.cfl)))
        return step

    @ti.func
    def density_error(self, i):
        return self.state.density[i] / self.rho_ref - 1.0

    # ---- numpy side --------------------------------------------------------------------------

    def reference_density(self) -> float:
        return self.rho_ref

    def reference_sound_speed(self) -> float:
        return self.wave_speed

    def faster_sound(self, factor: float) -> list:
        """The key and value that make c ``factor`` times faster (mach.py)."""
        return [("material.wave_speed", self.wave_speed * factor)]

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
        from ...continuity import Continuity
        from ...momentum import MOMENTUM
        from ...strain_rate import StrainRate
        return [Continuity, StrainRate, TotalStress, MOMENTUM["stress_divergence"]]

    def update_stage_classes(self):
        """Run after each integrator update: T_s over the part of the step taken."""
        return [FrictionalStressUpdate]


@ti.data_oriented
class FrictionalStressUpdate(Stage):
    """After the predictor (fraction 1/2 of the step): keep T_s(n), advance it over dt/2 with the
    grad v of the last rate evaluation (n); after the corrector (fraction 1): T_s(n+1) from T_s(n)
    over dt with grad v(n+1/2) [P]. Each by the sub-stepped point ODE (module docstring)."""

    name = "hypoplastic_stress_update"
    slot = "update"
    category = "rheology"
    equation = "[P] Wu-Bauer-Kolymbas"

    def __init__(self, ctx):
        super().__init__(ctx)
        self.time_step, self.step_fraction = ctx.time_step, ctx.step_fraction

    @ti.kernel
    def _run(self):
        fraction = self.step_fraction[None]
        duration = fraction * self.time_step[None]
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            if duration == 0.0:  # placed without a step (t = 0, a resumed run): T_s stays
                continue
            if fraction < 1.0:
                self.state.frictional_stress_start[i] = self.state.frictional_stress[i]
            stress, factor = self.model.advance(self.state.frictional_stress_start[i],
                                                self.model.embed(self.state.velocity_gradient[i]),
                                                self.model.void_ratio(i), duration)
            self.state.frictional_stress[i] = stress
            self.state.density_factor[i] = factor


@ti.data_oriented
class TotalStress(Stage):
    """T = T_s + T_v (+ the numerical bulk viscosity, if on); writes p = -tr(T)/3 and s = T + p I
    (in-plane) for the momentum equation."""

    name = "total_stress"
    slot = "rheology"
    category = "rheology"
    equation = "[P] T_s + Bagnold"

    def __init__(self, ctx):
        super().__init__(ctx)
        if self.model.bulk_viscosity > 0.0:
            self.equation = f"{TotalStress.equation} + bulk viscosity (alpha_b {self.model.bulk_viscosity:g})"

    @ti.kernel
    def _run(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            stress = self.state.frictional_stress[i]
            if ti.static(self.model.collisional):
                # not on the free surface (Shepard sum below the threshold): there the velocity
                # gradient of a few neighbours is poor and T_v ~ gamma_dot^2 amplifies it; measured,
                # grains of the pile collapse's flanks were shot out at 4.5-5.5 m/s (none without T_v)
                if self.state.kernel_sum[i] >= ti.static(self.model.free_surface_threshold):
                    stress += self.model.collisional_stress(self.model.embed(self.state.velocity_gradient[i]))
            if ti.static(self.model.bulk_viscosity > 0.0):
                stress += self.model.bulk_viscous_stress(i, stress)
            pressure = -stress.trace() / 3.0
            self.state.viscosity[i] = self.model.secant_viscosity(i, stress)
            s = ti.Matrix.zero(float, self.state.dim, self.state.dim)
            for a, b in ti.static(ti.ndrange(self.state.dim, self.state.dim)):
                s[a, b] = stress[a, b]
            self.state.pressure[i] = pressure
            self.state.deviatoric_stress[i] = s + pressure * ti.Matrix.identity(float, self.state.dim)


MODEL = HypoplasticBagnold
