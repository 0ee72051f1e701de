"""YAML scene -> validated, frozen dataclasses.

Every key of a scene is declared exactly once here, with its default and a one-line meaning
(``doc``) and unit. Loading checks everything before any Taichi field exists: unknown keys
(with a close-match suggestion), missing keys, wrong types, vectors of the wrong length and
physically impossible values all raise :class:`ConfigError` naming the key path, e.g.
``material.solid_fraction_min``.

Material models register their parameter class in :data:`MATERIALS`; the ``material.model``
key picks one.
"""
from __future__ import annotations

import dataclasses
import difflib
import itertools
import math
import typing
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal, Optional, Tuple, Union

import yaml

AXES = ("x", "y", "z")


class ConfigError(ValueError):
    """A scene file error, naming the key path it concerns."""

    def __init__(self, path: str, message: str):
        self.path = path
        super().__init__(f"{path}: {message}" if path else message)


def _key(doc: str, default: Any = dataclasses.MISSING, unit: str = "") -> Any:
    """Declare a scene key: its default (none = required), meaning and SI unit."""
    meta = {"doc": doc, "unit": unit}
    if isinstance(default, (list, dict)):
        raise TypeError("use tuples for defaults")
    return field(default=default, metadata=meta)


def _check_friction_angle(path: str, value: Optional[float]) -> None:
    if value is not None and not 0.0 <= value < 90.0:
        raise ConfigError(path, f"friction angle {value} must lie in [0, 90) degrees (not radians)")


def _positive(path: str, value: float, what: str = "must be > 0") -> None:
    if not (value > 0 and math.isfinite(value)):
        raise ConfigError(path, f"{what}, got {value!r}")


# --------------------------------------------------------------------------------------------
# Sections
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class Domain:
    """Axis-aligned box holding every particle (walls included)."""

    lower: Tuple[float, ...] = _key("lower corner of the box", unit="m")
    upper: Tuple[float, ...] = _key("upper corner of the box", unit="m")
    periodic: Tuple[str, ...] = _key("periodic axes, e.g. [x]", ())
    outflow: bool = _key("open faces: material leaving the box is taken out of the flow and counted "
                         "(physics/outflow.py) instead of stopping the run", False)

    def check(self, path: str, dim: int) -> None:
        _check_vector(f"{path}.lower", self.lower, dim)
        _check_vector(f"{path}.upper", self.upper, dim)
        for a, (lo, hi) in enumerate(zip(self.lower, self.upper)):
            if not hi > lo:
                raise ConfigError(f"{path}.upper", f"upper[{a}]={hi} must exceed lower[{a}]={lo}")
        for name in self.periodic:
            if name not in AXES[:dim]:
                raise ConfigError(f"{path}.periodic", f"unknown axis {name!r}; use {list(AXES[:dim])}")
        if len(set(self.periodic)) != len(self.periodic):
            raise ConfigError(f"{path}.periodic", "axis listed twice")

    @property
    def periodic_mask(self) -> Tuple[bool, ...]:
        return tuple(ax in self.periodic for ax in AXES[: len(self.lower)])

    @property
    def size(self) -> Tuple[float, ...]:
        return tuple(hi - lo for lo, hi in zip(self.lower, self.upper))


@dataclass(frozen=True, kw_only=True)
class Gravity:
    """Gravity of the given magnitude, tilted from -y (2D) or -z (3D) towards +x.

    A tilt of theta models a slope of angle theta whose down-slope direction is +x and
    whose bed normal is the vertical axis of the domain.
    """

    magnitude: float = _key("magnitude of gravitational acceleration", 9.81, "m/s^2")
    tilt_deg: float = _key("slope angle: tilt of gravity towards +x", 0.0, "deg")

    def check(self, path: str) -> None:
        if not (self.magnitude >= 0 and math.isfinite(self.magnitude)):
            raise ConfigError(f"{path}.magnitude", f"must be >= 0, got {self.magnitude}")
        if not -90.0 < self.tilt_deg < 90.0:
            raise ConfigError(f"{path}.tilt_deg", f"must lie in (-90, 90) degrees, got {self.tilt_deg}")

    def vector(self, dim: int) -> Tuple[float, ...]:
        t = math.radians(self.tilt_deg)
        g = [0.0] * dim
        g[0] = self.magnitude * math.sin(t)
        g[dim - 1] = -self.magnitude * math.cos(t)
        return tuple(g)


@dataclass(frozen=True, kw_only=True)
class MuIMaterial:
    """mu(I) rheology with compressible grains, Minatti & Paris (2015), MODEL.md section 1."""

    model: Literal["mu_i"] = _key("constitutive model")
    grain_density: float = _key("rho_s0, density of the grain material at zero pressure", unit="kg/m^3")
    grain_diameter: float = _key("d0, grain diameter at zero pressure", unit="m")
    static_friction_deg: float = _key("arctan(mu_s), static friction angle [M7]", unit="deg")
    limit_friction_deg: float = _key("arctan(mu_2), limiting friction angle at large I [M7]", unit="deg")
    reference_inertial_number: float = _key("I_0 of [M7]", unit="-")
    solid_fraction_max: float = _key("phi_max, solid fraction at I = 0 [M8]", 0.6, "-")
    solid_fraction_min: float = _key("phi_min, solid fraction at I = 1 [M8]", 0.5, "-")
    grain_compressibility: float = _key("K_t, artificial grain compressibility [M41]", unit="1/Pa")
    max_yield_stress: float = _key("tau_0, largest yield stress expected [M53]", unit="Pa")
    regularisation_time: float = _key("m_0, regularisation parameter [M48], [M55]", 1.0, "s")

    def check(self, path: str) -> None:
        _positive(f"{path}.grain_density", self.grain_density)
        if not 100.0 <= self.grain_density <= 25000.0:
            raise ConfigError(f"{path}.grain_density",
                              f"{self.grain_density} is not a plausible grain density in kg/m^3")
        _positive(f"{path}.grain_diameter", self.grain_diameter)
        if self.grain_diameter > 0.05:
            raise ConfigError(f"{path}.grain_diameter",
                              f"{self.grain_diameter} m is not a grain; give it in metres (0.5 mm = 0.5e-3)")
        for key in ("static_friction_deg", "limit_friction_deg"):
            value = getattr(self, key)
            if not 1.0 <= value < 90.0:
                raise ConfigError(f"{path}.{key}",
                                  f"friction angle {value} must lie in [1, 90) degrees (not radians, not tan)")
        if not self.limit_friction_deg > self.static_friction_deg:
            raise ConfigError(f"{path}.limit_friction_deg",
                              "mu_2 must exceed mu_s: limit_friction_deg > static_friction_deg")
        _positive(f"{path}.reference_inertial_number", self.reference_inertial_number)
        if not 0.0 < self.solid_fraction_max <= 1.0:
            raise ConfigError(f"{path}.solid_fraction_max", "phi_max must lie in (0, 1]")
        if not 0.0 < self.solid_fraction_min < self.solid_fraction_max:
            raise ConfigError(f"{path}.solid_fraction_min",
                              "phi_min must lie in (0, phi_max): solid_fraction_min < solid_fraction_max")
        _positive(f"{path}.grain_compressibility", self.grain_compressibility)
        _positive(f"{path}.max_yield_stress", self.max_yield_stress)
        _positive(f"{path}.regularisation_time", self.regularisation_time)

    @property
    def mu_s(self) -> float:
        return math.tan(math.radians(self.static_friction_deg))

    @property
    def mu_2(self) -> float:
        return math.tan(math.radians(self.limit_friction_deg))

    @property
    def reference_density(self) -> float:
        """Bulk density of packed grains at zero pressure, phi_max rho_s0 [kg/m^3]."""
        return self.solid_fraction_max * self.grain_density


@dataclass(frozen=True, kw_only=True)
class ElastoplasticMaterial:
    """Elastic-perfectly-plastic Mohr-Coulomb, Abdelrazek et al. (2016) after Bui et al.
    (2008), MODEL.md section 3."""

    model: Literal["elastoplastic"] = _key("constitutive model")
    density: float = _key("rho_0, bulk density of the unstressed material [A5]", unit="kg/m^3")
    youngs_modulus: float = _key("E, Young's modulus [A6]", unit="Pa")
    poisson_ratio: float = _key("nu, Poisson's ratio [A6]", unit="-")
    friction_angle_deg: float = _key("phi, internal friction angle of the Mohr-Coulomb strength", unit="deg")
    cohesion: float = _key("c of S_f = c + p tan(phi) (0 for dry sand)", 0.0, "Pa")
    bulk_modulus: Optional[float] = _key(
        "K of p = K (rho/rho_0 - 1) [A5]; default 50 rho_0 g H_max, H_max the tallest block", None, "Pa")

    def check(self, path: str) -> None:
        _positive(f"{path}.density", self.density)
        if not 100.0 <= self.density <= 25000.0:
            raise ConfigError(f"{path}.density", f"{self.density} is not a plausible bulk density in kg/m^3")
        _positive(f"{path}.youngs_modulus", self.youngs_modulus)
        if self.youngs_modulus < 1e3:
            raise ConfigError(f"{path}.youngs_modulus", f"{self.youngs_modulus} Pa is implausibly soft; give E in Pa")
        if not 0.0 <= self.poisson_ratio < 0.5:
            raise ConfigError(f"{path}.poisson_ratio", f"must lie in [0, 0.5), got {self.poisson_ratio}")
        if not 0.0 <= self.friction_angle_deg < 90.0:
            raise ConfigError(f"{path}.friction_angle_deg",
                              f"friction angle {self.friction_angle_deg} must lie in [0, 90) degrees (not radians)")
        if not (self.cohesion >= 0.0 and math.isfinite(self.cohesion)):
            raise ConfigError(f"{path}.cohesion", f"must be >= 0, got {self.cohesion}")
        if self.bulk_modulus is not None:
            _positive(f"{path}.bulk_modulus", self.bulk_modulus)

    @property
    def shear_modulus(self) -> float:
        """G = E/(2(1 + nu))  [Pa]."""
        return self.youngs_modulus / (2.0 * (1.0 + self.poisson_ratio))

    @property
    def friction_coefficient(self) -> float:
        return math.tan(math.radians(self.friction_angle_deg))

    @property
    def reference_density(self) -> float:
        return self.density


# The parameter tables of [P] (MODEL.md section 2): c1..c4, e_min, (p1, p2, p3), (q1, q2, q3),
# k_v, alpha_i. p3 and q3 in 1/kPa. The annular shear cell takes k_v from its solid fraction.
HYPOPLASTIC_PARAMETER_SETS = {
    "set1": dict(constants=(-50.0, -629.6, -629.6, 1220.8), min_void_ratio=0.597,
                 critical_void_ratio=(0.53, 0.45, -0.0018), density_exponent=(1.0, -0.4, -0.0001),
                 bagnold_coefficient=0.01, dispersion_angle_deg=35.0),
    "set2": dict(constants=(-66.7, -832.9, -832.9, 1594.5), min_void_ratio=0.597,
                 critical_void_ratio=(0.53, 0.45, -0.0011), density_exponent=(1.0, -0.4, -0.0001),
                 bagnold_coefficient=0.1, dispersion_angle_deg=33.0),
    "annular": dict(constants=(-50.0, -746.6, -746.6, 1855.1), min_void_ratio=0.563,
                    critical_void_ratio=(0.65, 0.55, -0.11), density_exponent=(1.0, -0.24, -0.013),
                    bagnold_coefficient=None, dispersion_angle_deg=27.0),
}


@dataclass(frozen=True, kw_only=True)
class HypoplasticMaterial:
    """Unified hypoplastic + Bagnold model of Peng et al. (2016), MODEL.md section 2.

    ``parameter_set`` fills every constant from a [P] table (set1: simple shear; set2: incline,
    drum, pile; annular: the shear cell); a constant given explicitly overrides the table."""

    model: Literal["hypoplastic"] = _key("constitutive model")
    parameter_set: Optional[Literal["set1", "set2", "annular"]] = _key(
        "a parameter table of [P] supplying the constants below (set1, set2, annular)", None)
    grain_density: float = _key("rho_s, density of the grain material", unit="kg/m^3")
    grain_diameter: float = _key("d, grain diameter of the Bagnold stress", unit="m")
    initial_void_ratio: float = _key("e_0, void ratio at t = 0 (bulk density rho_s/(1 + e_0))", unit="-")
    constants: Optional[Tuple[float, ...]] = _key("c1, c2, c3, c4 of the Wu-Bauer-Kolymbas rate law", None, "-")
    min_void_ratio: Optional[float] = _key("e_min of D_c = (e - e_min)/(e_crt - e_min)", None, "-")
    critical_void_ratio: Optional[Tuple[float, ...]] = _key(
        "p1, p2, p3 of e_crt = p1 + p2 exp(p3 |tr T_s|), |tr T_s| in kPa, p3 in 1/kPa", None)
    density_exponent: Optional[Tuple[float, ...]] = _key(
        "q1, q2, q3 of a = q1 + q2 exp(q3 |tr T_s|) in I_e = (1 - a) D_c + a, q3 in 1/kPa", None)
    bagnold_coefficient: Optional[float] = _key("k_v of the collisional (Bagnold) stress", None, "-")
    dispersion_angle_deg: Optional[float] = _key(
        "alpha_i, p_v = tau_v/tan(alpha_i) of the Bagnold stress", None, "deg")
    wave_speed: float = _key("c of the time step dt = chi h/c (chi: numerics.cfl) and of the artificial "
                             "viscosity [P]", 80.0, "m/s")
    tension_guard: float = _key("eps: where tr T_s > -eps, T_s is reset to -(eps/3) I (choice, MODEL.md section 2)",
                                1.0, "Pa")

    def __post_init__(self):
        if self.parameter_set is not None:
            for key, value in HYPOPLASTIC_PARAMETER_SETS[self.parameter_set].items():
                if getattr(self, key) is None:
                    object.__setattr__(self, key, value)

    def check(self, path: str) -> None:
        for key in ("constants", "min_void_ratio", "critical_void_ratio", "density_exponent",
                    "bagnold_coefficient", "dispersion_angle_deg"):
            if getattr(self, key) is None:
                raise ConfigError(f"{path}.{key}", "missing: give it, or a parameter_set that supplies it")
        for key, n in (("constants", 4), ("critical_void_ratio", 3), ("density_exponent", 3)):
            if len(getattr(self, key)) != n:
                raise ConfigError(f"{path}.{key}", f"expected {n} numbers, got {len(getattr(self, key))}")
        _positive(f"{path}.grain_density", self.grain_density)
        if not 100.0 <= self.grain_density <= 25000.0:
            raise ConfigError(f"{path}.grain_density", f"{self.grain_density} is not a plausible grain density in kg/m^3")
        _positive(f"{path}.grain_diameter", self.grain_diameter)
        if self.grain_diameter > 0.05:
            raise ConfigError(f"{path}.grain_diameter",
                              f"{self.grain_diameter} m is not a grain; give it in metres (3 mm = 3e-3)")
        _positive(f"{path}.min_void_ratio", self.min_void_ratio)
        if not self.initial_void_ratio > self.min_void_ratio:
            raise ConfigError(f"{path}.initial_void_ratio",
                              f"e_0 = {self.initial_void_ratio} must exceed e_min = {self.min_void_ratio}")
        p1, p2, p3 = self.critical_void_ratio
        if p3 > 0.0 or self.density_exponent[2] > 0.0:
            raise ConfigError(f"{path}.critical_void_ratio" if p3 > 0.0 else f"{path}.density_exponent",
                              "the exponent (third number, 1/kPa) must be <= 0: e_crt and a fall with pressure")
        if not p1 + p2 > self.min_void_ratio:
            raise ConfigError(f"{path}.critical_void_ratio", "e_crt at zero stress (p1 + p2) must exceed e_min")
        if not (self.bagnold_coefficient >= 0.0 and math.isfinite(self.bagnold_coefficient)):
            raise ConfigError(f"{path}.bagnold_coefficient", f"must be >= 0, got {self.bagnold_coefficient}")
        if not 0.0 < self.dispersion_angle_deg < 90.0:
            raise ConfigError(f"{path}.dispersion_angle_deg",
                              f"angle {self.dispersion_angle_deg} must lie in (0, 90) degrees (not radians)")
        _positive(f"{path}.tension_guard", self.tension_guard, "must be > 0 (a few Pa)")
        _positive(f"{path}.wave_speed", self.wave_speed)

    @property
    def reference_density(self) -> float:
        """Bulk density at the initial void ratio, rho_s/(1 + e_0)  [kg/m^3]."""
        return self.grain_density / (1.0 + self.initial_void_ratio)


MATERIALS = {"mu_i": MuIMaterial, "elastoplastic": ElastoplasticMaterial, "hypoplastic": HypoplasticMaterial}


class AnyMaterial:
    """Annotation marker: the ``model`` key picks the class from :data:`MATERIALS`."""


@dataclass(frozen=True, kw_only=True)
class ParticleBlock:
    """A box filled with material particles on a lattice of spacing dp."""

    lower: Tuple[float, ...] = _key("lower corner of the box", unit="m")
    upper: Tuple[float, ...] = _key("upper corner of the box", unit="m")
    name: str = _key("label used in messages", "block")
    velocity: Optional[Tuple[float, ...]] = _key("initial velocity (default at rest)", None, "m/s")
    initial_stress: Literal["hydrostatic", "zero"] = _key(
        "hydrostatic: pressure of the overburden of this block; zero: unstressed", "hydrostatic")
    shape: Literal["box", "cylinder"] = _key(
        "box: the whole box; cylinder (3D): the vertical cylinder inscribed in the box, whose horizontal "
        "extent must then be square", "box")
    origin: Optional[Tuple[float, ...]] = _key(
        "lay the box in a local frame with this origin (lower and upper are then local coordinates; "
        "default: global coordinates)", None, "m")
    tilt_deg: float = _key("tilt of that frame about y (as obstacles: local x descends a slope of tilt_deg; the "
                           "hydrostatic pressure then acts along the local z axis)", 0.0, "deg")
    clip_circle: Optional[Tuple[float, ...]] = _key(
        "2D: [x, y, radius]: keep only the lattice points at least dp/2 inside this circle (a drum's fill)", None, "m")

    @property
    def framed(self) -> bool:
        return self.origin is not None or self.tilt_deg != 0.0

    def corners(self) -> list:
        """Global coordinates of the box's corners  [m]."""
        from .scene.geometry import to_global

        local = [list(c) for c in itertools.product(*zip(self.lower, self.upper))]
        return to_global(local, self.origin, self.tilt_deg).tolist() if self.framed else local

    def check(self, path: str, dim: int, domain: Domain, spacing: float) -> None:
        _check_vector(f"{path}.lower", self.lower, dim)
        _check_vector(f"{path}.upper", self.upper, dim)
        if self.origin is not None:
            _check_vector(f"{path}.origin", self.origin, dim)
        if not -90.0 < self.tilt_deg < 90.0:
            raise ConfigError(f"{path}.tilt_deg", f"must lie in (-90, 90) deg, got {self.tilt_deg}")
        if self.shape == "cylinder" and self.framed:
            raise ConfigError(f"{path}.shape", "a cylinder block stands upright in global coordinates (no origin "
                                               "or tilt_deg)")
        if self.shape == "cylinder":
            if dim != 3:
                raise ConfigError(f"{path}.shape", "a cylinder needs dimension 3 (in 2D a column is a box)")
            wx, wy = self.upper[0] - self.lower[0], self.upper[1] - self.lower[1]
            if abs(wx - wy) > 1e-9 * max(wx, wy):
                raise ConfigError(f"{path}.upper", f"a cylinder's box needs a square footprint, got {wx} x {wy} m")
        if self.velocity is not None:
            _check_vector(f"{path}.velocity", self.velocity, dim)
        if self.clip_circle is not None:
            if dim != 2 or len(self.clip_circle) != 3:
                raise ConfigError(f"{path}.clip_circle", "a 2D scene's [x, y, radius]")
            _positive(f"{path}.clip_circle[2]", self.clip_circle[2], "the radius must be > 0")
        for a in range(dim):
            if self.upper[a] - self.lower[a] < spacing * (1 - 1e-9):
                raise ConfigError(f"{path}.upper", f"box thinner than one particle spacing along axis {AXES[a]}")
        for corner in self.corners():
            for a in range(dim):
                if not domain.lower[a] - 1e-12 <= corner[a] <= domain.upper[a] + 1e-12:
                    raise ConfigError(path, f"box [{self.lower}, {self.upper}] leaves the domain along axis "
                                            f"{AXES[a]} (corner {[round(c, 6) for c in corner]})")


@dataclass(frozen=True, kw_only=True)
class Wall:
    """A plane wall represented by particles behind it (``type`` selects the boundary model).

    ``ghost`` (mu(I), MODEL.md section 1): fixed ghost particles of [M34]-[M36], laid on the
    material lattice behind the plane, as many layers as the kernel support needs.
    ``dynamic`` ([A], Dalrymple & Knio 2001): fixed boundary particles behind the plane whose
    density follows the continuity equation and whose pressure the equation of state; rows are
    staggered by dp/2 along the wall so that no gap lines up.
    ``extrapolated`` ([P], MODEL.md section 2): boundary particles on the lattice behind the plane
    whose velocity (no slip) and stress (Shepard average with a hydrostatic correction) are
    extrapolated from the material at every rate evaluation.
    """

    normal: Tuple[float, ...] = _key("unit normal of the plane, pointing into the material")
    point: Tuple[float, ...] = _key("a point on the plane", unit="m")
    name: str = _key("label used in messages", "wall")
    type: Literal["ghost", "dynamic", "extrapolated"] = _key(
        "boundary model: ghost (mu(I), [M34]-[M36]), dynamic (boundary particles that obey continuity and "
        "the equation of state, Dalrymple & Knio 2001, as in [A]) or extrapolated (boundary particles whose "
        "velocity and stress are extrapolated from the material, as in [P])", "ghost")
    lower: Optional[Tuple[float, ...]] = _key("lower corner of the box that clips the wall (default domain)", None, "m")
    upper: Optional[Tuple[float, ...]] = _key("upper corner of the box that clips the wall (default domain)", None, "m")
    max_velocity_factor: float = _key(
        "beta_max of [M36]; 6 lets the three ghost rows extrapolate a linear profile exactly for the "
        "first material row (Morris et al. 1997 used 1.5; 1 means zero ghost velocity)", 6.0, "-")
    ghost_stress: Literal["extrapolated", "mirror"] = _key(
        "mirror: sigma_j = sigma_i as in [M]; extrapolated: the traction on planes parallel to the "
        "wall grows by rho_i g (d_i + d_j) (the static momentum balance across the wall)", "extrapolated")
    friction_angle_deg: Optional[float] = _key(
        "dynamic boundaries: Coulomb friction angle delta between the material and this boundary "
        "(|wall shear force| <= tan(delta) |wall normal force|); default none: the wall resists shear "
        "only through the stress it carries (physics/walls/dynamic.py)", None, "deg")
    initial_pressure: Literal["zero", "overburden"] = _key(
        "dynamic boundaries: pressure (and so density, [A5]) of the boundary particles at t = 0: zero "
        "(the reference density, as [A]), or the weight of the material over them (a layer that starts "
        "at rest stays at rest instead of falling into the wall and ringing; scene/__init__.py)", "zero")

    def check(self, path: str, dim: int) -> None:
        _check_vector(f"{path}.normal", self.normal, dim)
        _check_vector(f"{path}.point", self.point, dim)
        norm = math.sqrt(sum(c * c for c in self.normal))
        if abs(norm - 1.0) > 1e-6:
            raise ConfigError(f"{path}.normal", f"must be a unit vector, has length {norm:.6g}")
        for key in ("lower", "upper"):
            if getattr(self, key) is not None:
                _check_vector(f"{path}.{key}", getattr(self, key), dim)
        if not 1.0 <= self.max_velocity_factor <= 100.0:
            raise ConfigError(f"{path}.max_velocity_factor", "beta_max must lie in [1, 100] [M36]")
        if self.initial_pressure != "zero" and self.type != "dynamic":
            raise ConfigError(f"{path}.initial_pressure", "only dynamic boundary particles take their pressure "
                                                          "from their density")
        if self.friction_angle_deg is not None and self.type != "dynamic":
            raise ConfigError(f"{path}.friction_angle_deg", "only dynamic walls take a friction angle "
                                                            "(ghost walls are no-slip)")
        _check_friction_angle(f"{path}.friction_angle_deg", self.friction_angle_deg)


@dataclass(frozen=True, kw_only=True)
class _Obstacle:
    """A fixed solid laid as dynamic boundary particles (scene/geometry.py), placed by a rigid
    frame: ``origin`` and a tilt about the y axis (3D; z in 2D) so that the local x axis runs
    down a slope of ``tilt_deg`` (x' = (cos, 0, -sin), z' = (sin, 0, cos)). Local coordinates
    below are in that frame."""

    name: str = _key("label used in messages", "obstacle")
    origin: Optional[Tuple[float, ...]] = _key("the local frame's origin (default the global origin)", None, "m")
    tilt_deg: float = _key("slope of the local x axis below the horizontal (about y; +: x' descends)", 0.0,
                           "deg")
    friction_angle_deg: Optional[float] = _key(
        "dynamic boundaries: Coulomb friction angle delta between the material and this boundary "
        "(|wall shear force| <= tan(delta) |wall normal force|); default none: the wall resists shear "
        "only through the stress it carries (physics/walls/dynamic.py)", None, "deg")
    dimensions = (3,)

    def check(self, path: str, dim: int) -> None:
        if dim not in self.dimensions:
            raise ConfigError(f"{path}.shape", f"a {self.shape} obstacle needs dimension "
                                               f"{' or '.join(map(str, self.dimensions))}")
        if self.origin is not None:
            _check_vector(f"{path}.origin", self.origin, dim)
        if not -90.0 < self.tilt_deg < 90.0:
            raise ConfigError(f"{path}.tilt_deg", f"must lie in (-90, 90) deg, got {self.tilt_deg}")
        _check_friction_angle(f"{path}.friction_angle_deg", self.friction_angle_deg)

    def _positive_keys(self, path: str, *keys: str) -> None:
        for key in keys:
            _positive(f"{path}.{key}", getattr(self, key))


@dataclass(frozen=True, kw_only=True)
class ChuteSegment:
    length: float = _key("length along the slope", unit="m")
    slope_deg: float = _key("inclination below the horizontal (+: descends along +x)", unit="deg")

    def check(self, path: str) -> None:
        _positive(f"{path}.length", self.length)
        if not -90.0 < self.slope_deg < 90.0:
            raise ConfigError(f"{path}.slope_deg", f"must lie in (-90, 90) deg, got {self.slope_deg}")


@dataclass(frozen=True, kw_only=True)
class ChuteObstacle(_Obstacle):
    """Inclined planes joined at slope breaks, descending along +x from ``origin`` (the top of
    the first plane, on the centre line), each ``width`` wide, with optional vertical side walls.
    ``tilt_deg`` is not used: each segment has its own slope."""

    shape: Literal["chute"] = _key("obstacle kind", "chute")
    segments: Tuple[ChuteSegment, ...] = _key("planes from the top down")
    width: float = _key("width across the chute (3D)", 1.0, "m")
    side_wall_height: float = _key("height of the side walls above the bed (0: none)", 0.0, "m")
    dimensions = (2, 3)

    def check(self, path: str, dim: int) -> None:
        super().check(path, dim)
        if not self.segments:
            raise ConfigError(f"{path}.segments", "a chute needs at least one segment")
        for k, seg in enumerate(self.segments):
            seg.check(f"{path}.segments[{k}]")
        _positive(f"{path}.width", self.width)
        if self.side_wall_height < 0:
            raise ConfigError(f"{path}.side_wall_height", f"must be >= 0, got {self.side_wall_height}")


@dataclass(frozen=True, kw_only=True)
class BoxObstacle(_Obstacle):
    """A solid box [lower, upper] in the local frame (posts, a building, the walls of a release
    box)."""

    shape: Literal["box"] = _key("obstacle kind", "box")
    lower: Tuple[float, ...] = _key("lower corner, local frame", unit="m")
    upper: Tuple[float, ...] = _key("upper corner, local frame", unit="m")
    dimensions = (2, 3)

    def check(self, path: str, dim: int) -> None:
        super().check(path, dim)
        _check_vector(f"{path}.lower", self.lower, dim)
        _check_vector(f"{path}.upper", self.upper, dim)
        for a in range(dim):
            if self.upper[a] <= self.lower[a]:
                raise ConfigError(f"{path}.upper", f"must exceed lower along axis {AXES[a]}")


@dataclass(frozen=True, kw_only=True)
class PostRowsObstacle(_Obstacle):
    """Rows of square posts standing on the local x-y plane (a chute panel): row k at local
    x = k row_spacing, posts of side ``post_size`` separated by ``gap`` across ``width`` centred
    on y = 0; ``staggered`` shifts every other row by half a period (post + gap)."""

    shape: Literal["post_rows"] = _key("obstacle kind", "post_rows")
    post_size: float = _key("side of a square post", unit="m")
    gap: float = _key("clear gap between neighbouring posts of a row", unit="m")
    rows: int = _key("number of rows", 1)
    row_spacing: float = _key("distance between rows along local x (post side included)", 0.0, "m")
    width: float = _key("span of each row across local y", unit="m")
    height: float = _key("height of the posts along local z", unit="m")
    staggered: bool = _key("shift every other row by (post_size + gap)/2", False)

    def check(self, path: str, dim: int) -> None:
        super().check(path, dim)
        self._positive_keys(path, "post_size", "gap", "width", "height")
        if self.rows < 1:
            raise ConfigError(f"{path}.rows", f"must be >= 1, got {self.rows}")
        if self.rows > 1 and self.row_spacing < self.post_size:
            raise ConfigError(f"{path}.row_spacing", f"rows overlap: row_spacing {self.row_spacing} m < post_size")


@dataclass(frozen=True, kw_only=True)
class CylinderObstacle(_Obstacle):
    """A circular cylinder of ``radius`` standing on the local x-y plane at the origin, its axis
    along local z (normal to a chute tilted by ``tilt_deg``)."""

    shape: Literal["cylinder"] = _key("obstacle kind", "cylinder")
    radius: float = _key("radius", unit="m")
    height: float = _key("height along the local z axis", unit="m")

    def check(self, path: str, dim: int) -> None:
        super().check(path, dim)
        self._positive_keys(path, "radius", "height")


@dataclass(frozen=True, kw_only=True)
class WedgeObstacle(_Obstacle):
    """A tetrahedral wedge on the local x-y plane pointing up the slope (-x): its tip at the
    origin, its rear edge at x = length from y = -width/2 to width/2, its top vertex above the
    rear centre at z = height (after Tai et al. 2001)."""

    shape: Literal["wedge"] = _key("obstacle kind", "wedge")
    length: float = _key("tip to rear face along local x", unit="m")
    width: float = _key("rear face width across local y", unit="m")
    height: float = _key("rear face height along local z", unit="m")

    def check(self, path: str, dim: int) -> None:
        super().check(path, dim)
        self._positive_keys(path, "length", "width", "height")


@dataclass(frozen=True, kw_only=True)
class MeshObstacle(_Obstacle):
    """A closed triangle mesh that meshio reads (STL, OBJ, PLY, VTU...), scaled, then placed by
    the local frame; its inside is found by the winding number of its triangles."""

    shape: Literal["mesh"] = _key("obstacle kind", "mesh")
    file: str = _key("mesh file (relative paths: from the scene file's folder)")
    scale: float = _key("factor from the mesh's units to metres", 1.0, "-")

    def check(self, path: str, dim: int) -> None:
        super().check(path, dim)
        _positive(f"{path}.scale", self.scale)
        if not Path(self.file).is_file():
            raise ConfigError(f"{path}.file", f"no such mesh file: {self.file}")


@dataclass(frozen=True, kw_only=True)
class DrumObstacle(_Obstacle):
    """A rotating drum (2D): a circular wall of ``radius`` about ``origin``, its boundary particles
    on rings outside the radius (as many as the kernel support needs), turning rigidly at
    ``angular_velocity`` (counter-clockwise positive) from t = 0. Walls of the hypoplastic model
    ([P]): extrapolated boundary particles carrying the drum's velocity."""

    shape: Literal["drum"] = _key("obstacle kind", "drum")
    radius: float = _key("inner radius R of the drum", unit="m")
    angular_velocity: float = _key("omega, rotation rate, counter-clockwise positive (rad/s, not rpm)", unit="rad/s")
    dimensions = (2,)

    def check(self, path: str, dim: int) -> None:
        super().check(path, dim)
        self._positive_keys(path, "radius")
        if not (math.isfinite(self.angular_velocity) and abs(self.angular_velocity) <= 100.0):
            raise ConfigError(f"{path}.angular_velocity", f"{self.angular_velocity} rad/s is implausible (rad/s, "
                                                          "not rpm: 1 rpm = 0.1047 rad/s)")
        if self.tilt_deg != 0.0:
            raise ConfigError(f"{path}.tilt_deg", "a drum is round: no tilt")
        if self.friction_angle_deg is not None:
            raise ConfigError(f"{path}.friction_angle_deg", "drum walls are extrapolated no-slip walls [P]: no "
                                                            "Coulomb friction angle")


OBSTACLES = {cls.__dataclass_fields__["shape"].default: cls
             for cls in (ChuteObstacle, BoxObstacle, PostRowsObstacle, CylinderObstacle, WedgeObstacle, MeshObstacle,
                         DrumObstacle)}


class AnyObstacle:
    """Annotation marker: the ``shape`` key picks the class from :data:`OBSTACLES`."""


@dataclass(frozen=True, kw_only=True)
class ArtificialViscosity:
    """Monaghan artificial viscosity [M38]; alpha = beta = 0 removes the stage altogether."""

    alpha: float = _key("linear coefficient (0.05 on the inclined plane of [M])", 0.0, "-")
    beta: float = _key("quadratic coefficient (0 in [M], 1 in [A])", 0.0, "-")

    def check(self, path: str) -> None:
        for key in ("alpha", "beta"):
            value = getattr(self, key)
            if not (value >= 0 and math.isfinite(value)):
                raise ConfigError(f"{path}.{key}", f"must be >= 0, got {value}")

    @property
    def enabled(self) -> bool:
        return self.alpha > 0 or self.beta > 0


@dataclass(frozen=True, kw_only=True)
class ArtificialStress:
    """Artificial stress against the tensile instability (Gray, Monaghan & Swift 2001), for
    models with a stress tensor; epsilon = 0 removes the stage altogether."""

    epsilon: float = _key("epsilon of R_a = -epsilon sigma_a/rho^2 for tensile principal stresses (0 = off; "
                          "Gray et al. use 0.3)", 0.0, "-")
    exponent: float = _key("n of the weight (W(r)/W(dp))^n", 4.0, "-")

    def check(self, path: str) -> None:
        if not 0.0 <= self.epsilon <= 1.0:
            raise ConfigError(f"{path}.epsilon", f"must lie in [0, 1], got {self.epsilon}")
        if not 1.0 <= self.exponent <= 8.0:
            raise ConfigError(f"{path}.exponent", f"must lie in [1, 8], got {self.exponent}")

    @property
    def enabled(self) -> bool:
        return self.epsilon > 0.0


@dataclass(frozen=True, kw_only=True)
class ParticleShifting:
    """Particle shifting (after Lind et al. 2012): each step a particle moves by
    dr_i = -coefficient h c_i dt grad C_i down its concentration gradient, its velocity is
    carried along by a Taylor correction; on and next to a free surface only the component
    along the surface is kept.
    coefficient = 0 removes the stage altogether."""

    coefficient: float = _key("zeta in dr = -zeta h c dt grad C (0 = off; 0.2 keeps sheared layers ordered)",
                              0.2, "-")
    free_surface_threshold: float = _key(
        "particles whose kernel sum (Shepard) falls below this are on the free surface (shift along it only)",
        0.9, "-")

    def check(self, path: str) -> None:
        if not (0.0 <= self.coefficient <= 1.0):
            raise ConfigError(f"{path}.coefficient", f"must lie in [0, 1], got {self.coefficient}")
        if not (0.5 <= self.free_surface_threshold <= 1.0):
            raise ConfigError(f"{path}.free_surface_threshold",
                              f"must lie in [0.5, 1], got {self.free_surface_threshold}")

    @property
    def enabled(self) -> bool:
        return self.coefficient > 0


@dataclass(frozen=True, kw_only=True)
class Numerics:
    particle_spacing: float = _key("dp, initial lattice spacing of particles", unit="m")
    smoothing_length_ratio: float = _key("h/dp", 1.3, "-")
    smoothing_function: Literal["wendland_c2", "wendland_c6", "cubic_spline"] = _key(
        "SPH smoothing function (MODEL.md section 0)", "wendland_c2")
    cfl: float = _key("Courant number of the time step [M39]", 0.5, "-")
    integrator: Literal["symplectic_verlet", "predictor_corrector"] = _key(
        "time integration scheme", "symplectic_verlet")
    momentum: Literal["stress_divergence", "viscous_pair"] = _key(
        "stress_divergence: sum m (sigma_i/rho_i^2 + sigma_j/rho_j^2) grad W; viscous_pair: [M27]",
        "stress_divergence")
    gradient_correction: Literal["scalar", "matrix", "none"] = _key(
        "kernel gradient renormalisation: full matrix M^-1 (exact for linear fields, also at walls and "
        "free surfaces), scalar d/tr(M), or none", "matrix")
    artificial_viscosity: ArtificialViscosity = _key("Monaghan artificial viscosity [M38]", ArtificialViscosity())
    density_diffusion: float = _key(
        "delta of the delta-SPH density diffusion term in the continuity equation (0 = off)", 0.02, "-")
    stress_diffusion: float = _key(
        "delta_s of the diffusion of integrated stress tensors (physics/stress_diffusion.py; 0 = off; "
        "models with a stress history only)", 0.0, "-")
    bulk_viscosity: float = _key(
        "alpha_b of a numerical bulk viscosity, T += alpha_b rho c h tr(D) I, that resists compaction and dilation "
        "but not shear (hypoplastic model only; 0 = off; physics/rheology/hypoplastic.py)", 0.0, "-")
    stress_increment: float = _key(
        "largest relative change |dT_s/dt| dt / |T_s| of the frictional stress in one step, a time-step bound "
        "(hypoplastic model only; 0 = off; physics/rheology/hypoplastic.py)", 0.0, "-")
    particle_shifting: ParticleShifting = _key("particle shifting against particle-scale disorder",
                                               ParticleShifting())
    artificial_stress: ArtificialStress = _key("artificial stress against the tensile instability (models with "
                                               "a stress tensor)", ArtificialStress())
    min_time_step: float = _key("the run stops if the stable time step falls below this", 1e-9, "s")

    def check(self, path: str) -> None:
        _positive(f"{path}.particle_spacing", self.particle_spacing)
        if not 1.0 <= self.smoothing_length_ratio <= 3.0:
            raise ConfigError(f"{path}.smoothing_length_ratio", "h/dp must lie in [1, 3]")
        if not 0.0 < self.cfl <= 1.0:
            raise ConfigError(f"{path}.cfl", f"must lie in (0, 1] for a stable explicit step, got {self.cfl}")
        _positive(f"{path}.min_time_step", self.min_time_step)
        self.artificial_viscosity.check(f"{path}.artificial_viscosity")
        self.particle_shifting.check(f"{path}.particle_shifting")
        self.artificial_stress.check(f"{path}.artificial_stress")
        for key in ("density_diffusion", "stress_diffusion"):
            if not 0.0 <= getattr(self, key) <= 1.0:
                raise ConfigError(f"{path}.{key}", f"must lie in [0, 1], got {getattr(self, key)}")
        if not 0.0 <= self.bulk_viscosity <= 5.0:
            raise ConfigError(f"{path}.bulk_viscosity", f"must lie in [0, 5], got {self.bulk_viscosity}")
        if not 0.0 <= self.stress_increment <= 10.0:
            raise ConfigError(f"{path}.stress_increment", f"must lie in [0, 10], got {self.stress_increment}")

    @property
    def smoothing_length(self) -> float:
        return self.particle_spacing * self.smoothing_length_ratio


@dataclass(frozen=True, kw_only=True)
class Run:
    end_time: float = _key("simulated time to reach", unit="s")
    output_interval: float = _key("simulated time between frames (VTU, diagnostics)", unit="s")
    output_dir: Optional[str] = _key("where outputs go (default output/<scene name>)", None)
    write_vtu: bool = _key("write a VTU particle file per frame (a .pvd series)", True)
    max_steps: Optional[int] = _key("stop after this many steps (default: no limit)", None)
    stop_at_rest: Optional[float] = _key(
        "stop once the kinetic energy, checked at each output, has fallen below this fraction of its peak "
        "(e.g. 1e-3 for a collapse at rest; default: run to end_time)", None, "-")
    checkpoint_every: int = _key(
        "write the checkpoint (checkpoint.npz, atomically) every this many frames; `taichi-granular resume` "
        "continues from it", 1)
    guard: Literal["step", "stage"] = _key(
        "when the run-time guard checks every particle for NaN/Inf, leaving the domain and an implausible "
        "density: after each step, or after every stage of it (names the stage that went wrong; slower)", "step")

    def check(self, path: str) -> None:
        _positive(f"{path}.end_time", self.end_time)
        _positive(f"{path}.output_interval", self.output_interval)
        if self.checkpoint_every < 1:
            raise ConfigError(f"{path}.checkpoint_every", f"must be a whole number of frames >= 1, got "
                                                          f"{self.checkpoint_every}")
        if self.stop_at_rest is not None and not 0.0 < self.stop_at_rest < 1.0:
            raise ConfigError(f"{path}.stop_at_rest", f"must lie in (0, 1), got {self.stop_at_rest}")
        if self.max_steps is not None and self.max_steps < 1:
            raise ConfigError(f"{path}.max_steps", "must be >= 1")


@dataclass(frozen=True, kw_only=True)
class Camera:
    """Pinhole camera of 3D frames."""

    position: Tuple[float, ...] = _key("eye position", unit="m")
    look_at: Tuple[float, ...] = _key("point at the centre of the image", unit="m")
    up: Tuple[float, ...] = _key("direction that appears upwards", (0.0, 0.0, 1.0))
    field_of_view_deg: float = _key("vertical field of view", 40.0, "deg")

    def check(self, path: str) -> None:
        for key in ("position", "look_at", "up"):
            _check_vector(f"{path}.{key}", getattr(self, key), 3)
        if math.dist(self.position, self.look_at) == 0.0:
            raise ConfigError(f"{path}.look_at", "must differ from the camera position")
        if not 1.0 <= self.field_of_view_deg <= 170.0:
            raise ConfigError(f"{path}.field_of_view_deg", f"must lie in [1, 170] deg, got {self.field_of_view_deg}")


@dataclass(frozen=True, kw_only=True)
class Render:
    """PNG frames (render/): particles coloured by a field, walls grey, time and colour bar."""

    frames: bool = _key("write a PNG frame at every output time of a run", True)
    width: int = _key("image width", 800, "px")
    height: Optional[int] = _key("image height (default: 2D from the view's aspect, 3D 3/4 of the width)", None,
                                 "px")
    colour_by: str = _key("particle field to colour by: speed, pressure, inertial_number, any output field "
                          "(vectors by magnitude)", "speed")
    range: Optional[Tuple[float, float]] = _key("fixed colour range [min, max] (default: each frame's own)", None)
    view_lower: Optional[Tuple[float, ...]] = _key("2D: lower corner of the view (default domain)", None, "m")
    view_upper: Optional[Tuple[float, ...]] = _key("2D: upper corner of the view (default domain)", None, "m")
    camera: Optional[Camera] = _key("3D: camera (default: from the front-left, above the domain)", None)

    def check(self, path: str, dim: int) -> None:
        if not 32 <= self.width <= 8192:
            raise ConfigError(f"{path}.width", f"must lie in [32, 8192] px, got {self.width}")
        if self.height is not None and not 32 <= self.height <= 8192:
            raise ConfigError(f"{path}.height", f"must lie in [32, 8192] px, got {self.height}")
        if self.range is not None and not self.range[0] < self.range[1]:
            raise ConfigError(f"{path}.range", f"needs min < max, got {list(self.range)}")
        for key in ("view_lower", "view_upper"):
            if getattr(self, key) is not None:
                _check_vector(f"{path}.{key}", getattr(self, key), 2)
        if (self.view_lower is None) != (self.view_upper is None):
            raise ConfigError(f"{path}.view_lower", "give both view_lower and view_upper, or neither")
        if self.view_lower is not None and not all(a < b for a, b in zip(self.view_lower, self.view_upper)):
            raise ConfigError(f"{path}.view_upper", "must lie above view_lower on every axis")
        if self.camera is not None:
            if dim != 3:
                raise ConfigError(f"{path}.camera", "only 3D scenes have a camera")
            self.camera.check(f"{path}.camera")


@dataclass(frozen=True, kw_only=True)
class Scene:
    dimension: Literal[2, 3] = _key("2 or 3")
    domain: Domain = _key("bounding box and periodic axes")
    material: AnyMaterial = _key("constitutive model and its parameters")
    particles: Tuple[ParticleBlock, ...] = _key("blocks of material particles")
    numerics: Numerics = _key("discretisation")
    run: Run = _key("run length and output cadence")
    name: str = _key("scene name (default: file name)", "scene")
    arch: Literal["cpu", "cuda", "vulkan", "metal", "gpu"] = _key("Taichi backend", "cpu")
    precision: Literal["f32", "f64"] = _key("floating point precision of all fields", "f64")
    gravity: Gravity = _key("gravitational acceleration", Gravity())
    walls: Tuple[Wall, ...] = _key("walls as boundary particles", ())
    obstacles: Tuple[AnyObstacle, ...] = _key(
        "solids laid as dynamic boundary particles: chute, box, post_rows, cylinder, wedge, mesh", ())
    render: Render = _key("PNG frames", Render())

    def check(self) -> None:
        dim = self.dimension
        self.render.check("render", dim)
        self.domain.check("domain", dim)
        self.gravity.check("gravity")
        self.material.check("material")
        self.numerics.check("numerics")
        self.run.check("run")
        dp = self.numerics.particle_spacing
        if dp > min(self.domain.size):
            raise ConfigError("numerics.particle_spacing",
                              f"dp = {dp} m is larger than the domain ({min(self.domain.size)} m)")
        if not self.particles:
            raise ConfigError("particles", "at least one block of material is needed")
        for k, block in enumerate(self.particles):
            block.check(f"particles[{k}]", dim, self.domain, dp)
        for k, wall in enumerate(self.walls):
            wall.check(f"walls[{k}]", dim)
            if self.material.model == "mu_i" and wall.type != "ghost":
                raise ConfigError(f"walls[{k}].type", "the mu(I) model of [M] uses ghost walls [M34]-[M36]")
        for k, obstacle in enumerate(self.obstacles):
            obstacle.check(f"obstacles[{k}]", dim)
            if self.material.model != "hypoplastic" and any(w.type != "dynamic" for w in self.walls):
                raise ConfigError(f"obstacles[{k}]", "obstacles are dynamic boundary particles; every wall of the "
                                                     "scene must then be of type dynamic")
            if self.material.model == "mu_i":
                raise ConfigError(f"obstacles[{k}]", "the mu(I) model of [M] uses ghost walls [M34]-[M36]; "
                                                     "obstacles are dynamic boundary particles")
        for k, wall in enumerate(self.walls):
            if (self.material.model == "hypoplastic") != (wall.type == "extrapolated"):
                raise ConfigError(f"walls[{k}].type", "the hypoplastic model of [P] uses extrapolated walls, and "
                                                      "extrapolated walls need its stress (MODEL.md section 2)")
        for k, obstacle in enumerate(self.obstacles):
            if (self.material.model == "hypoplastic") != (obstacle.shape == "drum"):
                raise ConfigError(f"obstacles[{k}].shape", "the hypoplastic model's obstacle is the drum (extrapolated "
                                                           "walls); the other obstacles are dynamic boundary particles")
        if self.material.model == "mu_i" and self.numerics.artificial_stress.enabled:
            raise ConfigError("numerics.artificial_stress.epsilon", "the tensile instability correction needs a "
                                                                    "stress tensor model (elastoplastic); set it to 0")
        if self.material.model != "hypoplastic" and self.numerics.stress_increment > 0.0:
            raise ConfigError("numerics.stress_increment", "bounds the step by the hypoplastic stress rate: only "
                                                           "material.model: hypoplastic has one")
        if self.material.model != "hypoplastic" and self.numerics.bulk_viscosity > 0.0:
            raise ConfigError("numerics.bulk_viscosity", "only the hypoplastic model has no equation of state to resist "
                                                         "compaction; set it to 0")
        if self.material.model == "mu_i" and self.numerics.stress_diffusion > 0.0:
            raise ConfigError("numerics.stress_diffusion", "mu(I) integrates no stress (its stress is algebraic); "
                                                           "set it to 0")
        support = 2.0 * self.numerics.smoothing_length
        for a, name in enumerate(AXES[:dim]):
            if name in self.domain.periodic and self.domain.size[a] < 3 * support:
                raise ConfigError("domain.periodic",
                                  f"periodic axis {name} spans {self.domain.size[a]} m, less than three kernel "
                                  f"supports (3 x {support} m)")

    @property
    def gravity_vector(self) -> Tuple[float, ...]:
        return self.gravity.vector(self.dimension)


# --------------------------------------------------------------------------------------------
# Loading
# --------------------------------------------------------------------------------------------


def _check_vector(path: str, value: Tuple[float, ...], dim: int) -> None:
    if len(value) != dim:
        raise ConfigError(path, f"needs {dim} components (dimension: {dim}), got {len(value)}")


def _join(path: str, key: Union[str, int]) -> str:
    if isinstance(key, int):
        return f"{path}[{key}]"
    return f"{path}.{key}" if path else key


# The papers' symbols, so that a scene written from the equations gets pointed to the key.
SYMBOLS = {
    "mu_s": "static_friction_deg (the angle arctan(mu_s))",
    "mu_2": "limit_friction_deg (the angle arctan(mu_2))",
    "I_0": "reference_inertial_number", "i_0": "reference_inertial_number",
    "phi_max": "solid_fraction_max", "phi_min": "solid_fraction_min",
    "K_t": "grain_compressibility", "k_t": "grain_compressibility",
    "tau_0": "max_yield_stress", "m_0": "regularisation_time",
    "rho_s0": "grain_density", "rho_s": "grain_density", "d0": "grain_diameter", "d": "grain_diameter",
    "dp": "particle_spacing", "h": "smoothing_length_ratio (h/dp)", "h_over_dp": "smoothing_length_ratio",
    "g": "gravity.magnitude", "theta": "gravity.tilt_deg", "slope_deg": "tilt_deg",
}


def _suggest(key: str, allowed) -> str:
    symbol = SYMBOLS.get(key)
    if symbol and symbol.split(" ")[0].split(".")[-1] in allowed:
        return f"did you mean {symbol}?"
    close = difflib.get_close_matches(key, list(allowed), n=1, cutoff=0.6)
    if not close:  # 'cfl_number' for 'cfl', 'density' for 'grain_density'
        close = sorted((a for a in allowed if key.startswith(a) or a.startswith(key) or a.endswith(key)),
                       key=len, reverse=True)
    if close:
        return f"did you mean '{close[0]}'?"
    return "allowed keys: " + ", ".join(sorted(allowed))


def _type_name(value: Any) -> str:
    return type(value).__name__


def _convert(tp: Any, value: Any, path: str) -> Any:
    origin = typing.get_origin(tp)
    args = typing.get_args(tp)
    if origin is Union:  # Optional[X]
        if value is None and type(None) in args:
            return None
        inner = [a for a in args if a is not type(None)]
        if len(inner) == 1:
            return _convert(inner[0], value, path)
        raise TypeError(f"unsupported union at {path}")
    if origin is Literal:
        if value not in args:
            choices = ", ".join(repr(a) for a in args)
            hint = ""
            if isinstance(value, str):
                close = difflib.get_close_matches(value, [str(a) for a in args], n=1)
                hint = f"; did you mean '{close[0]}'?" if close else ""
            raise ConfigError(path, f"{value!r} is not one of {choices}{hint}")
        return value
    if origin in (tuple, Tuple):
        if not isinstance(value, (list, tuple)):
            raise ConfigError(path, f"expected a list, got {_type_name(value)} {value!r}")
        item_tp = args[0]
        return tuple(_convert(item_tp, v, _join(path, k)) for k, v in enumerate(value))
    if tp in TAGGED:
        return _load_tagged(value, path, *TAGGED[tp])
    if dataclasses.is_dataclass(tp):
        return _load_dataclass(tp, value, path)
    if tp is float:
        if isinstance(value, bool):
            raise ConfigError(path, f"expected a number, got {value!r}")
        if isinstance(value, (int, float)):
            return float(value)
        if isinstance(value, str):  # PyYAML reads 1e-5 (no dot) as a string
            try:
                return float(value)
            except ValueError:
                pass
        raise ConfigError(path, f"expected a number, got {_type_name(value)} {value!r}")
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(path, f"expected an integer, got {_type_name(value)} {value!r}")
        return value
    if tp is bool:
        if not isinstance(value, bool):
            raise ConfigError(path, f"expected true or false, got {value!r}")
        return value
    if tp is str:
        if not isinstance(value, str):
            raise ConfigError(path, f"expected text, got {_type_name(value)} {value!r}")
        return value
    raise TypeError(f"unsupported type {tp} at {path}")


def _load_dataclass(cls: type, data: Any, path: str) -> Any:
    if not isinstance(data, dict):
        raise ConfigError(path, f"expected a mapping of keys, got {_type_name(data)} {data!r}")
    fields = {f.name: f for f in dataclasses.fields(cls)}
    for key in data:
        if key not in fields:
            raise ConfigError(_join(path, str(key)), f"unknown key; {_suggest(str(key), fields)}")
    hints = typing.get_type_hints(cls)
    kwargs = {}
    for name, f in fields.items():
        sub = _join(path, name)
        if name in data:
            kwargs[name] = _convert(hints[name], data[name], sub)
        elif f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            raise ConfigError(sub, f"missing required key ({f.metadata.get('doc', '')})")
    return cls(**kwargs)


def _load_tagged(data: Any, path: str, tag: str, registry: dict) -> Any:
    """A section whose ``tag`` key (material.model, obstacles[k].shape) picks its class."""
    if not isinstance(data, dict):
        raise ConfigError(path, f"expected a mapping of keys, got {_type_name(data)}")
    if tag not in data:
        raise ConfigError(_join(path, tag), f"missing required key; one of {sorted(registry)}")
    value = data[tag]
    if value not in registry:
        raise ConfigError(_join(path, tag), f"unknown {tag} {value!r}; {_suggest(str(value), registry)}")
    return _load_dataclass(registry[value], data, path)


TAGGED = {AnyMaterial: ("model", MATERIALS), AnyObstacle: ("shape", OBSTACLES)}


def apply_overrides(data: dict, overrides: typing.Iterable[str]) -> dict:
    """Apply ``dotted.key=value`` overrides (values parsed as YAML) to a raw scene mapping; an
    integer key picks an entry of a list (``walls.0.friction_angle_deg=30``)."""
    for item in overrides:
        if "=" not in item:
            raise ConfigError(item, "override must look like section.key=value")
        dotted, raw = item.split("=", 1)
        keys = dotted.strip().split(".")
        node = data
        for depth, key in enumerate(keys):
            path = ".".join(keys[:depth + 1])
            last = depth == len(keys) - 1
            if isinstance(node, list):
                if not key.isdigit() or int(key) >= len(node):
                    raise ConfigError(path, f"'{key}' is not an index of this list of {len(node)} entries")
                key = int(key)
            elif not isinstance(node, dict):
                raise ConfigError(path, f"'{keys[depth - 1]}' is not a section")
            if last:
                node[key] = yaml.safe_load(raw)
            else:
                node = node.setdefault(key, {}) if isinstance(node, dict) else node[key]
    return data


def scene_from_dict(data: Any, name: str = "scene") -> Scene:
    """Validate a raw mapping and return the frozen :class:`Scene`."""
    if not isinstance(data, dict):
        raise ConfigError("", f"a scene file must be a mapping of keys, got {_type_name(data)}")
    data = dict(data)
    data.setdefault("name", name)
    scene = _load_dataclass(Scene, data, "")
    scene.check()
    return scene


def load_scene(path: Union[str, Path], overrides: typing.Iterable[str] = ()) -> Scene:
    """Read and validate a YAML scene file; ``overrides`` are ``dotted.key=value`` strings."""
    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text())
    except yaml.YAMLError as err:
        raise ConfigError("", f"{path} is not valid YAML: {err}") from None
    if overrides and isinstance(data, dict):
        data = apply_overrides(data, overrides)
    if isinstance(data, dict) and isinstance(data.get("obstacles"), list):  # mesh files: from the scene's folder
        for item in data["obstacles"]:
            if isinstance(item, dict) and isinstance(item.get("file"), str) and not Path(item["file"]).is_absolute():
                item["file"] = str(path.parent / item["file"])
    return scene_from_dict(data, name=path.stem)


def scene_to_dict(scene: Any) -> Any:
    """Plain data (every default made explicit), for the resolved config written with outputs."""
    if dataclasses.is_dataclass(scene):
        return {f.name: scene_to_dict(getattr(scene, f.name)) for f in dataclasses.fields(scene)}
    if isinstance(scene, tuple):
        return [scene_to_dict(v) for v in scene]
    return scene


def dump_scene(scene: Scene) -> str:
    return yaml.safe_dump(scene_to_dict(scene), sort_keys=False)
