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
import os
import re
import typing
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar, FrozenSet, Literal, Optional, Tuple, Union

import yaml

AXES = ("x", "y", "z")


class ConfigError(ValueError):
    """A scene file error, naming the key path it concerns."""

    def __init__(self, path: str, message: str):
        self.path = path
        super().__init__(f"{path}: {message}" if path else message)


@dataclass(frozen=True)
class Bounds:
    """The plausible range of a numeric key, written as an interval: ``"[0, 90)"``, ``"(0, 1e4]"``.

    Every number of a scene (each component of a vector too) is checked against its key's
    bounds when the scene is loaded, so that a value in the wrong unit (radians for degrees,
    rpm for rad/s, mm for m) or a typo of a few orders of magnitude is stopped before anything
    is allocated. The bounds are deliberately wide: they reject what no granular scene means,
    not what an unusual one might."""

    low: float
    high: float
    low_open: bool
    high_open: bool

    @classmethod
    def parse(cls, text: str) -> "Bounds":
        match = re.fullmatch(r"\s*([\[(])\s*([^,\s]+)\s*,\s*([^\])\s]+)\s*([\])])\s*", text)
        if not match:
            raise ValueError(f"bounds {text!r} must look like '[0, 90)'")
        return cls(float(match[2]), float(match[3]), match[1] == "(", match[4] == ")")

    def __contains__(self, value: float) -> bool:
        above = value > self.low if self.low_open else value >= self.low
        below = value < self.high if self.high_open else value <= self.high
        return above and below

    def __str__(self) -> str:
        return f"{'(' if self.low_open else '['}{self.low:g}, {self.high:g}{')' if self.high_open else ']'}"


def _key(doc: str, default: Any = dataclasses.MISSING, unit: str = "", bounds: Optional[str] = None,
         hint: str = "") -> Any:
    """Declare a scene key: its default (none = required), meaning, SI unit and, for numbers,
    the plausible ``bounds`` (:class:`Bounds`; ``hint`` is added to the message of a value
    outside them, e.g. "degrees, not radians")."""
    meta = {"doc": doc, "unit": unit, "bounds": Bounds.parse(bounds) if bounds else None, "hint": hint}
    if isinstance(default, (list, dict)):
        raise TypeError("use tuples for defaults")
    return field(default=default, metadata=meta)


# --------------------------------------------------------------------------------------------
# Sections
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, kw_only=True)
class Domain:
    """Axis-aligned box holding every particle (walls included)."""

    lower: Tuple[float, ...] = _key("lower corner of the box", unit="m", bounds="[-1e5, 1e5]")
    upper: Tuple[float, ...] = _key("upper corner of the box", unit="m", bounds="[-1e5, 1e5]")
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

    magnitude: float = _key("magnitude of gravitational acceleration", 9.81, "m/s^2", bounds="[0, 1000]",
                            hint="m/s^2: 9.81 on Earth, up to 100 g in a centrifuge")
    tilt_deg: float = _key("slope angle: tilt of gravity towards +x", 0.0, "deg", bounds="(-90, 90)",
                           hint="degrees, not radians")

    def vector(self, dim: int) -> Tuple[float, ...]:
        t = math.radians(self.tilt_deg)
        g = [0.0] * dim
        g[0] = self.magnitude * math.sin(t)
        g[dim - 1] = -self.magnitude * math.cos(t)
        return tuple(g)


@dataclass(frozen=True, kw_only=True)
class MuIMaterial:
    """mu(I) rheology with compressible grains, Minatti & Paris (2015), MODEL.md section 1."""

    # what the model supports (Scene.check; one declaration per model instead of tests on its name)
    wall_types: ClassVar[Tuple[str, ...]] = ("ghost",)
    walls_note: ClassVar[str] = "the mu(I) model of [M] uses ghost walls [M34]-[M36]"
    obstacle_shapes: ClassVar[Tuple[str, ...]] = ()
    obstacle_walls: ClassVar[str] = "dynamic"  # the boundary model obstacles are laid as
    numerics_read: ClassVar[FrozenSet[str]] = frozenset({"implicit_viscosity"})

    model: Literal["mu_i"] = _key("constitutive model")
    grain_density: float = _key("rho_s0, density of the grain material at zero pressure", unit="kg/m^3",
                                bounds="[100, 25000]")
    grain_diameter: float = _key("d0, grain diameter at zero pressure", unit="m", bounds="(0, 0.05]",
                                 hint="metres: 0.5 mm = 0.5e-3")
    static_friction_deg: float = _key("arctan(mu_s), static friction angle [M7]", unit="deg", bounds="[1, 90)",
                                      hint="degrees, not radians, not tan")
    limit_friction_deg: float = _key("arctan(mu_2), limiting friction angle at large I [M7]", unit="deg",
                                     bounds="[1, 90)", hint="degrees, not radians, not tan")
    reference_inertial_number: float = _key("I_0 of [M7]", unit="-", bounds="[1e-3, 10]",
                                            hint="Table 1 of [M]: 0.279-2.65")
    solid_fraction_max: float = _key("phi_max, solid fraction at I = 0 [M8]", 0.6, "-", bounds="(0, 1]")
    solid_fraction_min: float = _key("phi_min, solid fraction at I = 1 [M8]", 0.5, "-", bounds="(0, 1)")
    grain_compressibility: float = _key("K_t, artificial grain compressibility [M41]", unit="1/Pa",
                                        bounds="[1e-12, 1e-3]", hint="1/Pa; the papers' K_t lie in 2e-6 to 9e-5")
    max_yield_stress: float = _key("tau_0, largest yield stress expected [M53]", unit="Pa", bounds="(0, 1e8]")
    regularisation_time: float = _key("m_0, regularisation parameter [M48], [M55]", 1.0, "s", bounds="(0, 1e4]")

    def check(self, path: str) -> None:
        """Relations between keys (each key's own range is checked by :func:`check_numbers`)."""
        if not self.limit_friction_deg > self.static_friction_deg:
            raise ConfigError(f"{path}.limit_friction_deg",
                              "mu_2 must exceed mu_s: limit_friction_deg > static_friction_deg")
        if not self.solid_fraction_min < self.solid_fraction_max:
            raise ConfigError(f"{path}.solid_fraction_min",
                              "phi_min must lie in (0, phi_max): solid_fraction_min < solid_fraction_max")

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

    wall_types: ClassVar[Tuple[str, ...]] = ("ghost", "dynamic")
    walls_note: ClassVar[str] = ("extrapolated walls need the hypoplastic model's stress (MODEL.md section 2); "
                                 "the elastoplastic model's walls are dynamic boundary particles")
    obstacle_shapes: ClassVar[Tuple[str, ...]] = ("chute", "box", "post_rows", "cylinder", "wedge", "mesh")
    obstacle_walls: ClassVar[str] = "dynamic"
    numerics_read: ClassVar[FrozenSet[str]] = frozenset({"artificial_stress", "stress_diffusion"})

    model: Literal["elastoplastic"] = _key("constitutive model")
    density: float = _key("rho_0, bulk density of the unstressed material [A5]", unit="kg/m^3", bounds="[100, 25000]")
    youngs_modulus: float = _key("E, Young's modulus [A6]", unit="Pa", bounds="[1e3, 1e12]")
    poisson_ratio: float = _key("nu, Poisson's ratio [A6]", unit="-", bounds="[0, 0.5)")
    friction_angle_deg: float = _key("phi, internal friction angle of the Mohr-Coulomb strength", unit="deg",
                                     bounds="[0, 90)", hint="degrees, not radians")
    cohesion: float = _key("c of S_f = c + p tan(phi) (0 for dry sand; of the order of E keeps the material "
                           "elastic)", 0.0, "Pa", bounds="[0, 1e12]")
    bulk_modulus: Optional[float] = _key(
        "K of p = K (rho/rho_0 - 1) [A5]; default 50 rho_0 g H_max, H_max the tallest block", None, "Pa", bounds="(0, 1e12]")

    def check(self, path: str) -> None:
        """Each key's range is checked by :func:`check_numbers`; no relations between keys."""

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

    wall_types: ClassVar[Tuple[str, ...]] = ("extrapolated",)
    walls_note: ClassVar[str] = ("the hypoplastic model of [P] uses extrapolated walls, and extrapolated walls "
                                 "need its stress (MODEL.md section 2)")
    obstacle_shapes: ClassVar[Tuple[str, ...]] = ("drum",)
    obstacle_walls: ClassVar[str] = "extrapolated"  # [P]'s wall particles, extrapolated from the material
    numerics_read: ClassVar[FrozenSet[str]] = frozenset({"artificial_stress", "stress_diffusion", "stress_increment",
                                                         "bulk_viscosity"})

    model: Literal["hypoplastic"] = _key("constitutive model")
    parameter_set: Optional[Literal["set1", "set2", "annular"]] = _key(
        "a parameter table of [P] supplying the constants below (set1, set2, annular)", None)
    grain_density: float = _key("rho_s, density of the grain material", unit="kg/m^3", bounds="[100, 25000]")
    grain_diameter: float = _key("d, grain diameter of the Bagnold stress", unit="m", bounds="(0, 0.05]",
                                 hint="metres: 3 mm = 3e-3")
    initial_void_ratio: float = _key("e_0, void ratio at t = 0 (bulk density rho_s/(1 + e_0))", unit="-",
                                     bounds="(0, 5]")
    constants: Optional[Tuple[float, ...]] = _key("c1, c2, c3, c4 of the Wu-Bauer-Kolymbas rate law", None, "-",
                        bounds="[-1e5, 1e5]")
    min_void_ratio: Optional[float] = _key("e_min of D_c = (e - e_min)/(e_crt - e_min)", None, "-", bounds="(0, 5]")
    critical_void_ratio: Optional[Tuple[float, ...]] = _key(
        "p1, p2, p3 of e_crt = p1 + p2 exp(p3 |tr T_s|), |tr T_s| in kPa, p3 in 1/kPa", None, bounds="[-100, 100]")
    density_exponent: Optional[Tuple[float, ...]] = _key(
        "q1, q2, q3 of a = q1 + q2 exp(q3 |tr T_s|) in I_e = (1 - a) D_c + a, q3 in 1/kPa", None, bounds="[-100, 100]")
    bagnold_coefficient: Optional[float] = _key("k_v of the collisional (Bagnold) stress", None, "-", bounds="[0, 10]")
    dispersion_angle_deg: Optional[float] = _key(
        "alpha_i, p_v = tau_v/tan(alpha_i) of the Bagnold stress", None, "deg", bounds="(0, 90)", hint="degrees, not radians")
    wave_speed: float = _key("c of the time step dt = chi h/c (chi: numerics.cfl) and of the artificial "
                             "viscosity [P]", 80.0, "m/s", bounds="[1, 1e4]", hint="m/s; [P] uses 80")
    tension_guard: float = _key("eps: where tr T_s > -eps, T_s is reset to -(eps/3) I (choice, MODEL.md section 2)",
                                1.0, "Pa", bounds="(0, 1e4]", hint="Pa: a few")

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
        if not self.initial_void_ratio > self.min_void_ratio:
            raise ConfigError(f"{path}.initial_void_ratio",
                              f"e_0 = {self.initial_void_ratio} must exceed e_min = {self.min_void_ratio}")
        p1, p2, p3 = self.critical_void_ratio
        if p3 > 0.0 or self.density_exponent[2] > 0.0:
            raise ConfigError(f"{path}.critical_void_ratio" if p3 > 0.0 else f"{path}.density_exponent",
                              "the exponent (third number, 1/kPa) must be <= 0: e_crt and a fall with pressure")
        if not p1 + p2 > self.min_void_ratio:
            raise ConfigError(f"{path}.critical_void_ratio", "e_crt at zero stress (p1 + p2) must exceed e_min")

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

    lower: Tuple[float, ...] = _key("lower corner of the box", unit="m", bounds="[-1e5, 1e5]")
    upper: Tuple[float, ...] = _key("upper corner of the box", unit="m", bounds="[-1e5, 1e5]")
    name: str = _key("label used in messages", "block")
    velocity: Optional[Tuple[float, ...]] = _key("initial velocity (default at rest)", None, "m/s",
                       bounds="[-1000, 1000]", hint="m/s")
    initial_stress: Literal["hydrostatic", "zero"] = _key(
        "hydrostatic: pressure of the overburden of this block; zero: unstressed", "hydrostatic")
    shape: Literal["box", "cylinder"] = _key(
        "box: the whole box; cylinder (3D): the vertical cylinder inscribed in the box, whose horizontal "
        "extent must then be square", "box")
    origin: Optional[Tuple[float, ...]] = _key(
        "lay the box in a local frame with this origin (lower and upper are then local coordinates; "
        "default: global coordinates)", None, "m", bounds="[-1e5, 1e5]")
    tilt_deg: float = _key("tilt of that frame about y (as obstacles: local x descends a slope of tilt_deg; the "
                           "hydrostatic pressure then acts along the local z axis)", 0.0, "deg", bounds="(-90, 90)", hint="degrees, not radians")
    clip_circle: Optional[Tuple[float, ...]] = _key(
        "2D: [x, y, radius]: keep only the lattice points at least dp/2 inside this circle (a drum's fill)", None, "m", bounds="[-1e5, 1e5]")

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
            if not self.clip_circle[2] > 0.0:
                raise ConfigError(f"{path}.clip_circle[2]", f"the radius must be > 0, got {self.clip_circle[2]}")
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

    normal: Tuple[float, ...] = _key("unit normal of the plane, pointing into the material", bounds="[-1, 1]")
    point: Tuple[float, ...] = _key("a point on the plane", unit="m", bounds="[-1e5, 1e5]")
    name: str = _key("label used in messages", "wall")
    type: Literal["ghost", "dynamic", "extrapolated"] = _key(
        "boundary model: ghost (mu(I), [M34]-[M36]), dynamic (boundary particles that obey continuity and "
        "the equation of state, Dalrymple & Knio 2001, as in [A]) or extrapolated (boundary particles whose "
        "velocity and stress are extrapolated from the material, as in [P])", "ghost")
    lower: Optional[Tuple[float, ...]] = _key("lower corner of the box that clips the wall (default domain)", None,
                    "m", bounds="[-1e5, 1e5]")
    upper: Optional[Tuple[float, ...]] = _key("upper corner of the box that clips the wall (default domain)", None,
                    "m", bounds="[-1e5, 1e5]")
    max_velocity_factor: float = _key(
        "beta_max of [M36]; 6 lets the three ghost rows extrapolate a linear profile exactly for the "
        "first material row (Morris et al. 1997 used 1.5; 1 means zero ghost velocity)", 6.0, "-", bounds="[1, 100]", hint="beta_max of [M36]")
    ghost_stress: Literal["extrapolated", "mirror"] = _key(
        "mirror: sigma_j = sigma_i as in [M]; extrapolated: the traction on planes parallel to the "
        "wall grows by rho_i g (d_i + d_j) (the static momentum balance across the wall)", "extrapolated")
    friction_angle_deg: Optional[float] = _key(
        "dynamic boundaries: Coulomb friction angle delta between the material and this boundary "
        "(|wall shear force| <= tan(delta) |wall normal force|); default none: the wall resists shear "
        "only through the stress it carries (physics/walls/dynamic.py)", None, "deg", bounds="[0, 90)", hint="degrees, not radians")
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
        if self.initial_pressure != "zero" and self.type != "dynamic":
            raise ConfigError(f"{path}.initial_pressure", "only dynamic boundary particles take their pressure "
                                                          "from their density")
        if self.friction_angle_deg is not None and self.type != "dynamic":
            raise ConfigError(f"{path}.friction_angle_deg", "only dynamic walls take a friction angle "
                                                            "(ghost walls are no-slip)")


@dataclass(frozen=True, kw_only=True)
class _Obstacle:
    """A fixed solid laid as dynamic boundary particles (scene/geometry.py), placed by a rigid
    frame: ``origin`` and a tilt about the y axis (3D; z in 2D) so that the local x axis runs
    down a slope of ``tilt_deg`` (x' = (cos, 0, -sin), z' = (sin, 0, cos)). Local coordinates
    below are in that frame."""

    name: str = _key("label used in messages", "obstacle")
    origin: Optional[Tuple[float, ...]] = _key("the local frame's origin (default the global origin)", None, "m",
                     bounds="[-1e5, 1e5]")
    tilt_deg: float = _key("slope of the local x axis below the horizontal (about y; +: x' descends)", 0.0,
                           "deg", bounds="(-90, 90)", hint="degrees, not radians")
    friction_angle_deg: Optional[float] = _key(
        "dynamic boundaries: Coulomb friction angle delta between the material and this boundary "
        "(|wall shear force| <= tan(delta) |wall normal force|); default none: the wall resists shear "
        "only through the stress it carries (physics/walls/dynamic.py)", None, "deg", bounds="[0, 90)", hint="degrees, not radians")
    dimensions = (3,)

    def check(self, path: str, dim: int) -> None:
        if dim not in self.dimensions:
            raise ConfigError(f"{path}.shape", f"a {self.shape} obstacle needs dimension "
                                               f"{' or '.join(map(str, self.dimensions))}")
        if self.origin is not None:
            _check_vector(f"{path}.origin", self.origin, dim)


@dataclass(frozen=True, kw_only=True)
class ChuteSegment:
    length: float = _key("length along the slope", unit="m", bounds="(0, 1e4]")
    slope_deg: float = _key("inclination below the horizontal (+: descends along +x)", unit="deg", bounds="(-90, 90)",
                            hint="degrees, not radians")


@dataclass(frozen=True, kw_only=True)
class ChuteObstacle(_Obstacle):
    """Inclined planes joined at slope breaks, descending along +x from ``origin`` (the top of
    the first plane, on the centre line), each ``width`` wide, with optional vertical side walls.
    ``tilt_deg`` is not used: each segment has its own slope."""

    shape: Literal["chute"] = _key("obstacle kind", "chute")
    segments: Tuple[ChuteSegment, ...] = _key("planes from the top down")
    width: float = _key("width across the chute (3D)", 1.0, "m", bounds="(0, 1e4]")
    side_wall_height: float = _key("height of the side walls above the bed (0: none)", 0.0, "m", bounds="[0, 1e4]")
    dimensions = (2, 3)

    def check(self, path: str, dim: int) -> None:
        super().check(path, dim)
        if not self.segments:
            raise ConfigError(f"{path}.segments", "a chute needs at least one segment")


@dataclass(frozen=True, kw_only=True)
class BoxObstacle(_Obstacle):
    """A solid box [lower, upper] in the local frame (posts, a building, the walls of a release
    box)."""

    shape: Literal["box"] = _key("obstacle kind", "box")
    lower: Tuple[float, ...] = _key("lower corner, local frame", unit="m", bounds="[-1e5, 1e5]")
    upper: Tuple[float, ...] = _key("upper corner, local frame", unit="m", bounds="[-1e5, 1e5]")
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
    post_size: float = _key("side of a square post", unit="m", bounds="(0, 1e4]")
    gap: float = _key("clear gap between neighbouring posts of a row", unit="m", bounds="(0, 1e4]")
    rows: int = _key("number of rows", 1, bounds="[1, 10000]")
    row_spacing: float = _key("distance between rows along local x (post side included)", 0.0, "m", bounds="[0, 1e4]")
    width: float = _key("span of each row across local y", unit="m", bounds="(0, 1e4]")
    height: float = _key("height of the posts along local z", unit="m", bounds="(0, 1e4]")
    staggered: bool = _key("shift every other row by (post_size + gap)/2", False)

    def check(self, path: str, dim: int) -> None:
        super().check(path, dim)
        if self.rows < 1:
            raise ConfigError(f"{path}.rows", f"must be >= 1, got {self.rows}")
        if self.rows > 1 and self.row_spacing < self.post_size:
            raise ConfigError(f"{path}.row_spacing", f"rows overlap: row_spacing {self.row_spacing} m < post_size")


@dataclass(frozen=True, kw_only=True)
class CylinderObstacle(_Obstacle):
    """A circular cylinder of ``radius`` standing on the local x-y plane at the origin, its axis
    along local z (normal to a chute tilted by ``tilt_deg``)."""

    shape: Literal["cylinder"] = _key("obstacle kind", "cylinder")
    radius: float = _key("radius", unit="m", bounds="(0, 1e4]")
    height: float = _key("height along the local z axis", unit="m", bounds="(0, 1e4]")

    def check(self, path: str, dim: int) -> None:
        super().check(path, dim)


@dataclass(frozen=True, kw_only=True)
class WedgeObstacle(_Obstacle):
    """A tetrahedral wedge on the local x-y plane pointing up the slope (-x): its tip at the
    origin, its rear edge at x = length from y = -width/2 to width/2, its top vertex above the
    rear centre at z = height (after Tai et al. 2001)."""

    shape: Literal["wedge"] = _key("obstacle kind", "wedge")
    length: float = _key("tip to rear face along local x", unit="m", bounds="(0, 1e4]")
    width: float = _key("rear face width across local y", unit="m", bounds="(0, 1e4]")
    height: float = _key("rear face height along local z", unit="m", bounds="(0, 1e4]")

    def check(self, path: str, dim: int) -> None:
        super().check(path, dim)


@dataclass(frozen=True, kw_only=True)
class MeshObstacle(_Obstacle):
    """A closed triangle mesh that meshio reads (STL, OBJ, PLY, VTU...), scaled, then placed by
    the local frame; its inside is found by the winding number of its triangles."""

    shape: Literal["mesh"] = _key("obstacle kind", "mesh")
    file: str = _key("mesh file (relative paths: from the scene file's folder)")
    scale: float = _key("factor from the mesh's units to metres", 1.0, "-", bounds="(0, 1e6]")

    def check(self, path: str, dim: int) -> None:
        super().check(path, dim)
        if not Path(self.file).is_file():
            raise ConfigError(f"{path}.file", f"no such mesh file: {self.file}")


@dataclass(frozen=True, kw_only=True)
class DrumObstacle(_Obstacle):
    """A rotating drum (2D): a circular wall of ``radius`` about ``origin``, its boundary particles
    on rings outside the radius (as many as the kernel support needs), turning rigidly at
    ``angular_velocity`` (counter-clockwise positive) from t = 0. Walls of the hypoplastic model
    ([P]): extrapolated boundary particles carrying the drum's velocity."""

    shape: Literal["drum"] = _key("obstacle kind", "drum")
    radius: float = _key("inner radius R of the drum", unit="m", bounds="(0, 1e3]")
    angular_velocity: float = _key("omega, rotation rate, counter-clockwise positive (rad/s, not rpm)", unit="rad/s",
                                   bounds="[-100, 100]", hint="rad/s, not rpm: 1 rpm = 0.1047 rad/s")
    dimensions = (2,)

    def check(self, path: str, dim: int) -> None:
        super().check(path, dim)
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

    alpha: float = _key("linear coefficient (0.05 on the inclined plane of [M])", 0.0, "-", bounds="[0, 10]")
    beta: float = _key("quadratic coefficient (0 in [M], 1 in [A])", 0.0, "-", bounds="[0, 10]")

    @property
    def enabled(self) -> bool:
        return self.alpha > 0 or self.beta > 0


@dataclass(frozen=True, kw_only=True)
class ArtificialStress:
    """Artificial stress against the tensile instability (Gray, Monaghan & Swift 2001), for
    models with a stress tensor; epsilon = 0 removes the stage altogether."""

    epsilon: float = _key("epsilon of R_a = -epsilon sigma_a/rho^2 for tensile principal stresses (0 = off; "
                          "Gray et al. use 0.3)", 0.0, "-", bounds="[0, 1]")
    exponent: float = _key("n of the weight (W(r)/W(dp))^n", 4.0, "-", bounds="[1, 8]")

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
                              0.2, "-", bounds="[0, 1]")
    free_surface_threshold: float = _key(
        "particles whose kernel sum (Shepard) falls below this are on the free surface (shift along it only)",
        0.9, "-", bounds="[0.5, 1]")
    conserve_momentum: bool = _key(
        "remove the net momentum the Taylor velocity correction adds (exact conservation in closed systems; in a "
        "sheared layer whose particles drift across the shear it slows the whole layer: the Table 2 plane ran "
        "6.7 % off [M56] with it, 2.8 % without, measured)", False)

    @property
    def enabled(self) -> bool:
        return self.coefficient > 0


@dataclass(frozen=True, kw_only=True)
class Numerics:
    particle_spacing: float = _key("dp, initial lattice spacing of particles", unit="m", bounds="[1e-5, 10]",
                                   hint="metres")
    smoothing_length_ratio: float = _key("h/dp", 1.3, "-", bounds="[1, 3]")
    smoothing_function: Literal["wendland_c2", "wendland_c6", "cubic_spline"] = _key(
        "SPH smoothing function (MODEL.md section 0)", "wendland_c2")
    cfl: float = _key("Courant number of the time step [M39]", 0.5, "-", bounds="(0, 1]", hint="a stable explicit step")
    integrator: Literal["symplectic_verlet", "predictor_corrector"] = _key(
        "time integration scheme", "symplectic_verlet")
    momentum: Literal["stress_divergence", "viscous_pair"] = _key(
        "stress_divergence: sum m (sigma_i/rho_i^2 + sigma_j/rho_j^2) grad W; viscous_pair: [M27]",
        "stress_divergence")
    viscosity: Literal["explicit", "implicit"] = _key(
        "mu(I) viscous term: explicit (the step obeys the viscous limit of [M39]) or implicit (the viscosity above "
        "that limit solved by backward Euler, BiCGSTAB, each step: only the acoustic limit sets the step, 90-270x "
        "fewer steps on the collapses; physics/implicit_viscosity.py). Explicit stays the default until the "
        "implicit run-outs of the tall columns match it (docs, implicit viscosity)", "explicit")
    viscous_tolerance: float = _key(
        "implicit viscosity: the solve stops when |residual| <= this x |v*| (the velocities before the viscous "
        "update; against 1e-6, 1e-4 moves the velocities of a collapse by 5e-4 of their largest, measured)",
        1e-4, "-", bounds="[1e-14, 0.1]")
    viscous_max_iterations: int = _key("implicit viscosity: the most BiCGSTAB iterations of one solve; a solve "
                                       "that needs more stops the run", 200, bounds="[1, 1e5]")
    viscous_picard_iterations: int = _key(
        "implicit viscosity: solves per step; after each but the last the strain rate and the viscosity are "
        "re-evaluated at the mid-step velocity (v(n) + v(n+1))/2 (Picard iteration on eta, which one solve "
        "lags by half a step)", 1, bounds="[1, 20]")
    neighbour_skin: float = _key(
        "Verlet-list skin as a fraction of h: each particle's neighbours within 2h + skin are listed and the "
        "list rebuilt only when a particle has moved more than half the skin (neighbours.py; 0.3: 3D coarse collapse "
        "1.5x, 2D 160k block 1.1-1.4x faster than scanning the cells, measured); 0 scans the cells in every pair "
        "loop", 0.3, "-", bounds="[0, 2]")
    reorder_every: int = _key(
        "every this many steps the material particles' fields are sorted by neighbour cell (counting sort), so that "
        "neighbours lie close in memory as the flow mixes them (state.py ParticleOrder; outputs stay in the initial "
        "order, by particle_id); 0 never", 100, "steps", bounds="[0, 1e9]")
    gradient_correction: Literal["scalar", "matrix", "none"] = _key(
        "kernel gradient renormalisation: full matrix M^-1 (exact for linear fields, also at walls and "
        "free surfaces), scalar d/tr(M), or none", "matrix")
    artificial_viscosity: ArtificialViscosity = _key("Monaghan artificial viscosity [M38]", ArtificialViscosity())
    density_diffusion: float = _key(
        "delta of the delta-SPH density diffusion term in the continuity equation (0 = off)", 0.02, "-", bounds="[0, 1]")
    stress_diffusion: float = _key(
        "delta_s of the diffusion of integrated stress tensors (physics/stress_diffusion.py; 0 = off; "
        "models with a stress history only)", 0.0, "-", bounds="[0, 1]")
    bulk_viscosity: float = _key(
        "alpha_b of a numerical bulk viscosity, T += alpha_b rho c h tr(D) I, that resists compaction and dilation "
        "but not shear (hypoplastic model only; 0 = off; physics/rheology/hypoplastic.py)", 0.0, "-", bounds="[0, 5]")
    stress_increment: float = _key(
        "largest relative change |dT_s/dt| dt / |T_s| of the frictional stress in one step, a time-step bound "
        "(hypoplastic model only; 0 = off; physics/rheology/hypoplastic.py)", 0.0, "-", bounds="[0, 10]")
    particle_shifting: ParticleShifting = _key("particle shifting against particle-scale disorder",
                                               ParticleShifting())
    artificial_stress: ArtificialStress = _key("artificial stress against the tensile instability (models with "
                                               "a stress tensor)", ArtificialStress())
    min_time_step: float = _key("the run stops if the stable time step falls below this", 1e-9, "s", bounds="(0, 0.1]")

    @property
    def smoothing_length(self) -> float:
        return self.particle_spacing * self.smoothing_length_ratio


@dataclass(frozen=True, kw_only=True)
class Run:
    end_time: float = _key("simulated time to reach", unit="s", bounds="(0, 1e6]")
    output_interval: float = _key("simulated time between frames (VTU, diagnostics)", unit="s", bounds="(0, 1e6]")
    output_dir: Optional[str] = _key("where outputs go (default output/<scene name>)", None)
    write_vtu: bool = _key("write a VTU particle file per frame (a .pvd series)", True)
    max_steps: Optional[int] = _key("stop after this many steps (default: no limit)", None, bounds="[1, 1e12]")
    mach_warning: float = _key(
        "warn once when the max Mach number |v|/c of a frame exceeds this, with the compressibility that "
        "keeps the flow below it (weakly compressible SPH wants Mach < ~0.3; mach.py)", 0.3, "-", bounds="(0, 10]")
    stop_at_rest: Optional[float] = _key(
        "stop once the kinetic energy, checked at each output, has fallen below this fraction of its peak "
        "(e.g. 1e-3 for a collapse at rest; default: run to end_time)", None, "-", bounds="(0, 1)")
    checkpoint_every: int = _key(
        "write the checkpoint (checkpoint.npz, atomically) every this many frames; `taichi-granular resume` "
        "continues from it", 1, bounds="[1, 1e9]")
    guard: Literal["step", "stage"] = _key(
        "when the run-time guard checks every particle for NaN/Inf, leaving the domain and an implausible "
        "density: after each step, or after every stage of it (names the stage that went wrong; slower)", "step")
    guard_every: int = _key(
        "with guard: step, check every this many steps (and before every frame): one host synchronisation "
        "fewer per step on a GPU; a failure then names the steps within which it arose", 1, bounds="[1, 1e6]")



@dataclass(frozen=True, kw_only=True)
class Camera:
    """Pinhole camera of 3D frames."""

    position: Tuple[float, ...] = _key("eye position", unit="m", bounds="[-1e5, 1e5]")
    look_at: Tuple[float, ...] = _key("point at the centre of the image", unit="m", bounds="[-1e5, 1e5]")
    up: Tuple[float, ...] = _key("direction that appears upwards", (0.0, 0.0, 1.0), bounds="[-1e3, 1e3]")
    field_of_view_deg: float = _key("vertical field of view", 40.0, "deg", bounds="[1, 170]")

    def check(self, path: str) -> None:
        for key in ("position", "look_at", "up"):
            _check_vector(f"{path}.{key}", getattr(self, key), 3)
        if math.dist(self.position, self.look_at) == 0.0:
            raise ConfigError(f"{path}.look_at", "must differ from the camera position")


BYTES_PER_PARTICLE = 1024  # host + device bytes per particle, with margin (``describe``: 0.3-0.6 KiB of fields)
BYTES_PER_CELL = 16  # neighbour grid: start, count, cursor, fixed start (int32)


def max_particles() -> int:
    """The most particles this machine's memory holds (at BYTES_PER_PARTICLE each)."""
    try:
        memory = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, OSError, ValueError):  # not POSIX: assume 16 GiB
        memory = 16 * 2**30
    return int(memory // BYTES_PER_PARTICLE)


COLOUR_BAR_MARGIN = 120  # px right of a 2D view for the colour bar and its labels
MIN_VIEW_PX = 32  # px: the narrowest particle view worth rendering
MAX_FRAME_PX = 8192  # px: the largest frame side


@dataclass(frozen=True, kw_only=True)
class Render:
    """PNG frames (render/): particles coloured by a field, walls grey, time and colour bar."""

    frames: bool = _key("write a PNG frame at every output time of a run", True)
    width: int = _key("image width", 800, "px", bounds="[32, 8192]")
    height: Optional[int] = _key("image height (default: 2D from the view's aspect, 3D 3/4 of the width)", None,
                                 "px", bounds="[32, 8192]")
    colour_by: str = _key("particle field to colour by: speed, pressure, inertial_number, any output field "
                          "(vectors by magnitude)", "speed")
    range: Optional[Tuple[float, float]] = _key("fixed colour range [min, max] (default: each frame's own)", None,
                    bounds="[-1e15, 1e15]")
    view_lower: Optional[Tuple[float, ...]] = _key("2D: lower corner of the view (default domain)", None, "m",
                         bounds="[-1e5, 1e5]")
    view_upper: Optional[Tuple[float, ...]] = _key("2D: upper corner of the view (default domain)", None, "m",
                         bounds="[-1e5, 1e5]")
    camera: Optional[Camera] = _key("3D: camera (default: from the front-left, above the domain)", None)

    def view_box(self, domain: Domain) -> Tuple[Tuple[float, ...], Tuple[float, ...]]:
        """2D: the (lower, upper) corners in metres that the frame shows."""
        return (self.view_lower or domain.lower, self.view_upper or domain.upper)

    def frame_size(self, domain: Domain, dim: int) -> Tuple[int, int, int]:
        """(frame width, frame height, width of the particle view) in pixels; a 2D frame keeps
        COLOUR_BAR_MARGIN px on the right for the colour bar and its labels."""
        if dim == 3:
            return self.width, self.height or int(0.75 * self.width), self.width
        view_width = self.width - COLOUR_BAR_MARGIN
        lower, upper = self.view_box(domain)
        pixel = (upper[0] - lower[0]) / max(view_width, 1)  # metres per pixel
        height = self.height or max(2 * COLOUR_BAR_MARGIN, int(math.ceil((upper[1] - lower[1]) / pixel)))
        return self.width, height, view_width

    def check(self, path: str, dim: int, domain: Domain) -> None:
        if dim == 2 and self.width < COLOUR_BAR_MARGIN + MIN_VIEW_PX:
            raise ConfigError(f"{path}.width", f"a 2D frame needs at least {COLOUR_BAR_MARGIN + MIN_VIEW_PX} px: "
                                               f"{COLOUR_BAR_MARGIN} px for the colour bar and {MIN_VIEW_PX} for the "
                                               f"particles; got {self.width}")
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
        height = self.frame_size(domain, dim)[1]
        if height > MAX_FRAME_PX:
            raise ConfigError(f"{path}.height", f"the view's aspect gives frames {height} px high (at most "
                                                f"{MAX_FRAME_PX}); set render.height or a narrower view")


# numerics keys that only some models read (their materials' ``numerics_read``): the name, whether
# the scene asks for it, the key a message names, and what it is for
MODEL_NUMERICS = {
    "artificial_stress": (lambda n: n.artificial_stress.enabled, "numerics.artificial_stress.epsilon",
                          "the tensile instability correction needs a stress tensor model; set it to 0"),
    "stress_increment": (lambda n: n.stress_increment > 0.0, "numerics.stress_increment",
                         "it bounds the step by the hypoplastic stress rate"),
    "bulk_viscosity": (lambda n: n.bulk_viscosity > 0.0, "numerics.bulk_viscosity",
                       "it resists compaction in a model with no equation of state; set it to 0"),
    "stress_diffusion": (lambda n: n.stress_diffusion > 0.0, "numerics.stress_diffusion",
                         "it smooths an integrated stress (mu(I)'s stress is algebraic); set it to 0"),
    "implicit_viscosity": (lambda n: n.viscosity == "implicit", "numerics.viscosity",
                           "the implicit viscous update is for the regularised viscosity of mu(I); set it to explicit"),
}


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
        check_numbers(self)
        self.domain.check("domain", dim)
        self.render.check("render", dim, self.domain)
        self.material.check("material")
        dp = self.numerics.particle_spacing
        if dp > min(self.domain.size):
            raise ConfigError("numerics.particle_spacing",
                              f"dp = {dp} m is larger than the domain ({min(self.domain.size)} m)")
        if not self.particles:
            raise ConfigError("particles", "at least one block of material is needed")
        for k, block in enumerate(self.particles):
            block.check(f"particles[{k}]", dim, self.domain, dp)
        material = type(self.material)  # what the model declares it supports
        for k, wall in enumerate(self.walls):
            wall.check(f"walls[{k}]", dim)
            if wall.type not in material.wall_types:
                raise ConfigError(f"walls[{k}].type", material.walls_note)
        for k, obstacle in enumerate(self.obstacles):
            obstacle.check(f"obstacles[{k}]", dim)
            if obstacle.shape not in material.obstacle_shapes:
                supported = ", ".join(material.obstacle_shapes) or "none"
                raise ConfigError(f"obstacles[{k}].shape", f"material.model: {self.material.model} supports the "
                                                           f"obstacles: {supported}")
            if any(w.type != material.obstacle_walls for w in self.walls):
                raise ConfigError(f"obstacles[{k}]", f"obstacles of material.model: {self.material.model} are "
                                                     f"{material.obstacle_walls} boundary particles; every wall of "
                                                     f"the scene must then be of type {material.obstacle_walls}")
        for name, (asked, key, why) in MODEL_NUMERICS.items():  # a model-specific key set for a model without it
            if asked(self.numerics) and name not in material.numerics_read:
                raise ConfigError(key, f"{why}; material.model: {self.material.model} does not have it")
        if self.numerics.viscosity == "implicit":  # asked for: must fit
            if self.numerics.integrator != "symplectic_verlet":
                raise ConfigError("numerics.viscosity", "the implicit viscous update runs in the symplectic Verlet "
                                                        "kick; set numerics.integrator: symplectic_verlet")
        if self.run.guard == "stage" and self.run.guard_every > 1:
            raise ConfigError("run.guard_every", "run.guard: stage checks after every stage of every step; "
                                                 "set run.guard_every: 1 (or run.guard: step)")
        self._check_size()
        support = 2.0 * self.numerics.smoothing_length
        for a, name in enumerate(AXES[:dim]):
            if name in self.domain.periodic and self.domain.size[a] < 3 * support:
                raise ConfigError("domain.periodic",
                                  f"periodic axis {name} spans {self.domain.size[a]} m, less than three kernel "
                                  f"supports (3 x {support} m)")

    @property
    def implicit_viscosity(self) -> bool:
        """Whether the viscous term is solved implicitly (physics/implicit_viscosity.py)."""
        return self.numerics.viscosity == "implicit"

    def _check_size(self) -> None:
        """What would not fit in memory fails here, before anything is allocated: the neighbour grid
        (cells of the kernel support 2h, int32-indexed) and the material blocks' particles.
        Walls and obstacles are counted where they are laid (scene/geometry.py lattice_counts)."""
        dp = self.numerics.particle_spacing
        support = 2.0 * self.numerics.smoothing_length
        cells = math.prod(max(1, math.floor(size / support)) for size in self.domain.size)
        if cells > min(2**31 - 2, max_particles() * BYTES_PER_PARTICLE // BYTES_PER_CELL):
            raise ConfigError("domain.upper", f"the neighbour grid would have {cells:.3g} cells (the domain in "
                                              f"cells of 2h = {support:g} m), more than this machine holds; shrink "
                                              "the domain or coarsen numerics.particle_spacing")
        total = 0
        for k, block in enumerate(self.particles):
            count = math.prod(math.floor((hi - lo) / dp + 1e-9) for lo, hi in zip(block.lower, block.upper))
            total += count
            if total > max_particles():
                raise ConfigError(f"particles[{k}]", f"{total:.3g} material particles at dp = {dp:g} m (this block "
                                                     f"{count:.3g}), more than this machine's memory holds "
                                                     f"({max_particles():.3g}); coarsen numerics.particle_spacing")

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


def _number(value: Any, path: str) -> float:
    """A finite float from a YAML number, or from text that reads as one (PyYAML reads 1e-5,
    without a dot, as text). NaN and infinity are refused whatever their spelling (.nan, 'nan',
    'inf', 1e999): no key of a scene means them."""
    number = None
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        number = float(value)
    elif isinstance(value, str):
        try:
            number = float(value)
        except ValueError:
            pass
    if number is None:
        raise ConfigError(path, f"expected a number, got {_type_name(value)} {value!r}")
    if not math.isfinite(number):
        raise ConfigError(path, f"must be a finite number, got {value!r}")
    return number


def check_numbers(section: Any, path: str = "") -> None:
    """Every number of ``section`` and of the sections below it (vector components included)
    is finite and lies within its key's bounds (:class:`Bounds`), else a ConfigError naming the
    key path. Run by :meth:`Scene.check`, so that a scene made in code (``dataclasses.replace``)
    is held to the same ranges as one read from YAML."""
    for f in dataclasses.fields(section):
        value = getattr(section, f.name)
        sub = _join(path, f.name)
        items = list(enumerate(value)) if isinstance(value, tuple) else [(None, value)]
        for k, item in items:
            item_path = sub if k is None else _join(sub, k)
            if dataclasses.is_dataclass(item):
                check_numbers(item, item_path)
            elif isinstance(item, (int, float)) and not isinstance(item, bool):
                if not math.isfinite(item):
                    raise ConfigError(item_path, f"must be a finite number, got {item!r}")
                bounds = f.metadata.get("bounds")
                if bounds is not None and item not in bounds:
                    unit = f" {f.metadata['unit']}" if f.metadata.get("unit", "-") != "-" else ""
                    hint = f" ({f.metadata['hint']})" if f.metadata.get("hint") else ""
                    raise ConfigError(item_path, f"{item:g} is outside the plausible range {bounds}{unit}{hint}")


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
        return _number(value, path)
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


def _check_duplicate_keys(node: yaml.Node, path: str, source: str) -> None:
    """Raise on a key given twice in one mapping (PyYAML would keep the last silently)."""
    if isinstance(node, yaml.MappingNode):
        seen = {}
        for key_node, value_node in node.value:
            key = key_node.value if isinstance(key_node, yaml.ScalarNode) else None
            if key is not None:
                line = key_node.start_mark.line + 1
                if key in seen:
                    raise ConfigError(_join(path, key), f"given twice in {source}, on lines {seen[key]} and {line}; "
                                      "keep one")
                seen[key] = line
            _check_duplicate_keys(value_node, _join(path, key) if key is not None else path, source)
    elif isinstance(node, yaml.SequenceNode):
        for index, item in enumerate(node.value):
            _check_duplicate_keys(item, _join(path, index), source)


def parse_yaml(text: str, path: str = "", source: str = "the scene file") -> Any:
    """Parse YAML text strictly: syntax errors and duplicated keys are :class:`ConfigError` at ``path``."""
    try:
        node = yaml.compose(text, Loader=yaml.SafeLoader)
        if node is not None:
            _check_duplicate_keys(node, path, source)
        return yaml.safe_load(text)
    except yaml.YAMLError as err:
        raise ConfigError(path, f"{source} is not valid YAML: {err}") from None


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
                node[key] = parse_yaml(raw, path, source=f"the value of --set {path}")
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
    """Read and validate a YAML scene file; ``overrides`` are ``dotted.key=value`` strings. A path
    that does not exist but names a bundled scene (``mu_i/inclined_plane.yaml``, paths.py) reads that."""
    from .paths import bundled

    path = Path(path)
    if not path.exists():
        path = bundled(path) or path
    try:
        text = path.read_text()
    except (OSError, UnicodeDecodeError) as err:
        raise ConfigError("", f"cannot read the scene file {path}: {err}") from None
    data = parse_yaml(text, source=str(path))
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
