"""mu(I) rheology with compressible grains, Minatti & Paris (2015) -- MODEL.md section 1.

Per particle and step: the grain density rho_s is the physical root of the cubic [M44]
(given the bulk density rho and strain rate gamma_dot), the pressure follows from the grain
compressibility [M41], and the viscosity is the regularised Bingham-like form [M47]-[M55].

Root of [M44]. With x = rho_s/rho_s0 and rho* = rho/rho_s0, [M44] is equivalent to
    (phi_max - rho*/x)^2 (x - 1) x^(-e) = G,   G = gamma_dot^2 d0^2 rho_s0 K_t (phi_max - phi_min)^2,
with e = 0 in 2D (d = d0 (rho_s0/rho_s)^(1/2), [M43]) and e = 1/3 in 3D (cube root). The left
side rises strictly from 0 at x_m = max(1, rho*/phi_max) to infinity, so the physical root is
unique (the largest real root of the cubic). We solve for t = sqrt(x - 1):
    g(t) = (phi_max - rho*/(1 + t^2)) t (1 + t^2)^(-e/2) - sqrt(G) = 0,
by Newton safeguarded with bisection. In t the double root of the cubic at gamma_dot -> 0
becomes a simple root, and p = (x - 1)/K_t = t^2/K_t carries no cancellation.
"""
import math

import numpy as np
import taichi as ti

from .... import runtime

from ....state import FieldSpec
from ..base import Model
from ....tmath import expm1
from ...stage import Stage
from ...strain_rate import deviator


@ti.data_oriented
class MuIRheology(Model):
    """Constants of one mu(I) material, and the per-particle physics as ``@ti.func``s.

    Units: densities kg/m^3, diameters m, pressures and stresses Pa, strain rates 1/s,
    viscosities Pa s, K_t 1/Pa, m_0 s.
    """

    name = "mu_i"
    fields = (
        FieldSpec("grain_density", "scalar", "grain density rho_s, root of [M44]", "kg/m^3", "material"),
    )

    def __init__(self, material, dim: int, smoothing_length: float, precision: str = "f64", state=None,
                 implicit_viscosity: bool = False):
        super().__init__(material, dim, smoothing_length, state)
        self.implicit_viscosity = implicit_viscosity  # the time step drops [M39]'s viscous limit
        self.rho_s0 = material.grain_density
        self.d0 = material.grain_diameter
        self.mu_s = material.mu_s
        self.mu_2 = material.mu_2
        self.I_0 = material.reference_inertial_number
        self.phi_max = material.solid_fraction_max
        self.phi_min = material.solid_fraction_min
        self.K_t = material.grain_compressibility
        self.tau_0 = material.max_yield_stress
        self.m_0 = material.regularisation_time
        # G = shear_factor * gamma_dot^2 in [M44]
        self.shear_factor = self.d0**2 * self.rho_s0 * self.K_t * (self.phi_max - self.phi_min) ** 2
        self.size_exponent = 0.0 if dim == 2 else 1.0 / 3.0  # e of the module docstring
        self.root_tolerance = 1e-14 if precision == "f64" else 2e-7

    @classmethod
    def from_scene(cls, scene):
        return cls(scene.material, scene.dimension, scene.numerics.smoothing_length, scene.precision,
                   implicit_viscosity=scene.numerics.implicit_viscosity)

    # integrated per-particle quantities besides x, v, rho: none (the stress is algebraic)
    derived_fields = (  # derived_output's, in the VTU files only
        FieldSpec("solid_fraction", "scalar", "phi = rho/rho_s", "-", "material"),
        FieldSpec("inertial_number", "scalar", "I from the solid fraction, inverting [M8]", "-", "material"),
        FieldSpec("grain_diameter", "scalar", "d of the compressed grain [M43]", "m", "material"),
    )

    # ---- [M44], [M41]: grain density and pressure -------------------------------------------

    @ti.func
    def grain_compression(self, rho_star, gamma_dot, guess=-1.0):
        """t = sqrt(rho_s/rho_s0 - 1) solving [M44] for rho* = rho/rho_s0 (dimensionless).
        ``guess``: a start inside the bracket (last step's root: density and strain rate change
        little in a step, so Newton converges in 1-3 iterations instead of 6-10 from the
        bracket's end); outside it the solve starts from the bracket's upper end."""
        phi = self.phi_max
        e = ti.static(self.size_exponent)
        sqrt_G = ti.sqrt(self.shear_factor) * gamma_dot
        x_m = ti.max(1.0, rho_star / phi)
        lo = ti.sqrt(x_m - 1.0)
        t = lo
        if sqrt_G > 0.0:
            # g >= 0 at x_hi: there (phi - rho*/x) >= phi/2 and x - 1 >= x/2 (module docstring)
            x_hi = ti.max(2.0 * x_m, ti.max(2.0, (8.0 * sqrt_G * sqrt_G / (phi * phi)) ** (1.0 / (1.0 - e))))
            hi = ti.sqrt(x_hi - 1.0)
            t = hi
            if lo < guess < hi:
                t = guess
            for _ in range(80):
                x = 1.0 + t * t
                u = phi - rho_star / x
                s = 1.0
                if ti.static(e != 0.0):
                    s = x ** (-0.5 * e)
                g = u * t * s - sqrt_G
                if g > 0.0:
                    hi = t
                else:
                    lo = t
                slope = s * (2.0 * rho_star * t * t / (x * x) + u - e * u * t * t / x)
                t_new = 0.5 * (lo + hi)
                if slope > 0.0:
                    newton = t - g / slope
                    if lo < newton < hi:
                        t_new = newton
                converged = ti.abs(t_new - t) <= self.root_tolerance * ti.max(t_new, 1e-30) or hi - lo <= 0.0
                t = t_new
                if converged:
                    break
        return t

    @ti.func
    def pressure_of(self, compression):
        """p = (rho_s/rho_s0 - 1)/K_t [M41], with rho_s/rho_s0 = 1 + t^2  [Pa]."""
        return compression * compression / self.K_t

    # ---- [M47]-[M55]: regularised viscosity -------------------------------------------------

    @ti.func
    def bingham_viscosity(self, yield_stress, gamma_dot):
        """eta_0(tau_y, gamma_dot) of [M47]  [Pa s]."""
        denominator = gamma_dot + (self.I_0 / self.d0) * ti.sqrt(yield_stress / (self.mu_s * self.rho_s0))
        eta_0 = 0.0
        if denominator > 0.0:
            eta_0 = (self.mu_2 / self.mu_s - 1.0) * yield_stress / denominator
        return eta_0

    @ti.func
    def regularised_viscosity(self, pressure, gamma_dot):
        """eta_hat of [M48] with the yield-stress-dependent exponent m_p of [M55]  [Pa s].

        Written without the logarithm (MODEL.md section 1):
        eta_hat = eta_0 + tau_y (1 - exp(-m_0 gd))/gd - exp(-m_0 gd) eta_0 (tau_0 - tau_y)/(tau_0 + eta_0 gd),
        and its limit m_0 tau_y + eta_0(tau_y, 0) tau_y/tau_0 at gd = 0 ([M53]).
        """
        tau_y = self.mu_s * ti.max(pressure, 0.0)  # [M12]
        eta_0 = self.bingham_viscosity(tau_y, gamma_dot)
        eta = 0.0
        if gamma_dot > 0.0:
            decay = ti.exp(-self.m_0 * gamma_dot)
            eta = (eta_0 + tau_y * (-expm1(-self.m_0 * gamma_dot)) / gamma_dot
                   - decay * eta_0 * (self.tau_0 - tau_y) / (self.tau_0 + eta_0 * gamma_dot))
        else:
            eta = self.m_0 * tau_y + eta_0 * tau_y / self.tau_0
        return eta

    @ti.func
    def viscous_stress(self, viscosity, grad_v):
        """s = 2 eta dev(eps) [M10-11] of a velocity gradient  [Pa]."""
        return viscosity * deviator(grad_v + grad_v.transpose())

    @ti.func
    def deviatoric_stress(self, k):
        """s of particle k, from its stored velocity gradient and viscosity; a dynamic boundary
        particle has neither and carries none of its own (walls/dynamic.py lends it the facing
        grain's)  [Pa]."""
        s = ti.Matrix.zero(float, self.dim, self.dim)
        if k < self.state.n_material:
            s = self.viscous_stress(self.state.viscosity[k], self.state.velocity_gradient[k])
        return s

    # ---- wave speed and time step -----------------------------------------------------------

    @ti.func
    def sound_speed(self, k):
        """c = (K_t phi rho_s0)^(-1/2), from dp/drho at fixed solid fraction phi = rho/rho_s; a
        dynamic boundary particle (no grain density of its own) at phi_max  [m/s]."""
        phi = self.phi_max
        if k < self.state.n_material:
            phi = self.state.density[k] / self.state.grain_density[k]
        return 1.0 / ti.sqrt(self.K_t * phi * self.rho_s0)

    @ti.func
    def stable_time_step(self, i):
        """min(h/c_i, 0.1 rho_i h^2/eta_i) of [M39] (the CFL factor is applied by the caller)  [s].
        With the implicit viscous update the viscous limit goes; the acoustic one stays, with the
        force limit 0.25 sqrt(h/|a_i|) of Monaghan (1992) on the explicit acceleration (0.5 here:
        the CFL of 0.5 makes it 0.25) in its place, a bound [M39] never needed because the
        viscous limit was far below it."""
        acoustic = self.h / self.sound_speed(i)
        limit = acoustic
        if ti.static(self.implicit_viscosity):
            acceleration = self.state.acceleration[i].norm()
            if acceleration > 0.0:
                limit = ti.min(acoustic, 0.5 * ti.sqrt(self.h / acceleration))
        else:
            limit = ti.min(acoustic, 0.1 * self.state.density[i] * self.h**2 / ti.max(self.state.viscosity[i], 1e-30))
        return limit

    @ti.func
    def density_error(self, i):
        """Relative grain compression rho_s/rho_s0 - 1 (= K_t p), the weak-compressibility error."""
        return self.state.grain_density[i] / self.rho_s0 - 1.0

    # ---- numpy side: initial state and derived output ----------------------------------------

    def initial_density(self, pressure: np.ndarray) -> np.ndarray:
        """Bulk density of packed grains at rest under ``pressure`` [M41]: phi_max rho_s0 (1 + K_t p)."""
        return self.phi_max * self.rho_s0 * (1.0 + self.K_t * np.maximum(pressure, 0.0))

    def reference_density(self) -> float:
        return self.phi_max * self.rho_s0

    def reference_sound_speed(self) -> float:
        return 1.0 / math.sqrt(self.K_t * self.phi_max * self.rho_s0)

    def faster_sound(self, factor: float) -> list:
        """The key and value that make c ``factor`` times faster: c ~ K_t^(-1/2) [M41] (mach.py)."""
        return [("material.grain_compressibility", self.K_t / factor**2)]

    def derived_output(self, arrays: dict) -> dict:
        """Solid fraction phi = rho/rho_s, inertial number I from [M8], grain diameter [M43]."""
        rho_s = arrays["grain_density"]
        phi = arrays["density"][: rho_s.shape[0]] / rho_s
        inertial = np.clip((self.phi_max - phi) / (self.phi_max - self.phi_min), 0.0, None)
        exponent = 0.5 if self.dim == 2 else 1.0 / 3.0
        return {"solid_fraction": phi, "inertial_number": inertial,
                "grain_diameter": self.d0 * (self.rho_s0 / rho_s) ** exponent}

    def stage_classes(self, scene):
        from ...continuity import Continuity
        from ...momentum import MOMENTUM
        from ...strain_rate import StrainRate
        return [Continuity, StrainRate, GrainDensityPressure, RegularisedViscosity,
                MOMENTUM[scene.numerics.momentum]]


@ti.data_oriented
class GrainDensityPressure(Stage):
    """EOS stage: rho_s from [M44], then p from [M41], for every material particle; and for the
    dynamic boundary particles, whose density evolves (walls/dynamic.py), the pressure of [M44] at
    rest (gamma_dot = 0: p = (rho/(phi_max rho_s0) - 1)/K_t, zero below phi_max rho_s0), so that
    a wall pushes back as the packed grains would and never pulls."""

    name = "grain_density_pressure"
    slot = "eos"
    category = "eos"
    equation = "[M44] [M41]"

    @ti.kernel
    def _run(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            rho_star = self.state.density[i] / self.model.rho_s0
            last = ti.sqrt(ti.max(self.state.grain_density[i] / self.model.rho_s0 - 1.0, 0.0))
            t = self.model.grain_compression(rho_star, self.state.strain_rate[i], last)
            self.state.grain_density[i] = self.model.rho_s0 * (1.0 + t * t)
            self.state.pressure[i] = self.model.pressure_of(t)
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material, self.state.density_rate.shape[0]):  # none without dynamic walls
            t = self.model.grain_compression(self.state.density[i] / self.model.rho_s0, 0.0)
            self.state.pressure[i] = self.model.pressure_of(t)


@ti.data_oriented
class RegularisedViscosity(Stage):
    """Rheology stage: eta_hat(p, gamma_dot) of [M48]/[M55] for every material particle."""

    name = "regularised_viscosity"
    slot = "rheology"
    category = "rheology"
    equation = "[M47]-[M55]"
    fields = (FieldSpec("viscosity", "scalar", "regularised viscosity eta_hat", "Pa s", "material"),)

    @ti.kernel
    def _run(self):
        ti.loop_config(serialize=runtime.serial_loops)
        for i in range(self.state.n_material):
            self.state.viscosity[i] = self.model.regularised_viscosity(self.state.pressure[i],
                                                                       self.state.strain_rate[i])


MODEL = MuIRheology
