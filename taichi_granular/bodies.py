"""The solids and the material blocks of a scene: blocks of particles, plane walls and obstacles
(keys.py says how a key is declared; scene/ lays them as particles)."""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Literal, Optional, Tuple

from .keys import AXES, ConfigError, check_vector, scene_key
from .local_frame import to_global
from .sections import Domain


@dataclass(frozen=True, kw_only=True)
class _Friction:
    """How a dynamic boundary resists the material sliding along it (physics/walls/dynamic.py)."""

    friction: Optional[Literal["coulomb", "rough", "pressure_only"]] = scene_key(
        "dynamic boundaries: coulomb (the default: the wall's shear force is at most tan(delta) times its normal "
        "force, delta = friction_angle_deg), rough (the wall carries the facing grain's deviatoric stress, so its "
        "friction is the material's own strength: none for grains at zero pressure, which then slide freely) or "
        "pressure_only ([A] section 4.3: the boundary particles carry only their equation-of-state pressure and no rule of "
        "their own; what shear the wall passes comes from the grain's own stress and the artificial viscosity)", None)
    friction_angle_deg: Optional[float] = scene_key(
        "dynamic boundaries, coulomb: the friction angle delta between the material and this boundary; default the "
        "material's friction angle (elastoplastic phi, mu(I) arctan(mu_s))", None, "deg", bounds="[0, 90)",
        hint="degrees, not radians")

    def check_friction(self, path: str, dynamic: bool) -> None:
        for key in ("friction", "friction_angle_deg"):
            if getattr(self, key) is not None and not dynamic:
                raise ConfigError(f"{path}.{key}", "only dynamic boundary particles take a friction rule (ghost and "
                                                   "extrapolated walls are no-slip)")
        if self.friction in ("rough", "pressure_only") and self.friction_angle_deg is not None:
            raise ConfigError(f"{path}.friction_angle_deg", f"a wall with friction: {self.friction} takes no Coulomb "
                                                            "friction angle")


@dataclass(frozen=True, kw_only=True)
class ParticleBlock:
    """A box filled with material particles on a lattice of spacing dp."""

    lower: Tuple[float, ...] = scene_key("lower corner of the box", unit="m", bounds="[-1e5, 1e5]")
    upper: Tuple[float, ...] = scene_key("upper corner of the box", unit="m", bounds="[-1e5, 1e5]")
    name: str = scene_key("label used in messages", "block")
    velocity: Optional[Tuple[float, ...]] = scene_key("initial velocity (default at rest)", None, "m/s",
                       bounds="[-1000, 1000]", hint="m/s")
    initial_stress: Literal["hydrostatic", "zero"] = scene_key(
        "hydrostatic: pressure of the overburden of this block; zero: unstressed", "hydrostatic")
    shape: Literal["box", "cylinder"] = scene_key(
        "box: the whole box; cylinder (3D): the vertical cylinder inscribed in the box, whose horizontal "
        "extent must then be square", "box")
    origin: Optional[Tuple[float, ...]] = scene_key(
        "lay the box in a local frame with this origin (lower and upper are then local coordinates; "
        "default: global coordinates)", None, "m", bounds="[-1e5, 1e5]")
    tilt_deg: float = scene_key("tilt of that frame about y (as obstacles: local x descends a slope of tilt_deg; the "
                                "hydrostatic pressure then acts along the local z axis)", 0.0, "deg", bounds="(-90, 90)", hint="degrees, not radians")
    clip_circle: Optional[Tuple[float, ...]] = scene_key(
        "2D: [x, y, radius]: keep only the lattice points at least dp/2 inside this circle (a drum's fill)", None, "m", bounds="[-1e5, 1e5]")

    @property
    def framed(self) -> bool:
        return self.origin is not None or self.tilt_deg != 0.0

    def corners(self) -> list:
        """Global coordinates of the box's corners  [m]."""
        local = [list(c) for c in itertools.product(*zip(self.lower, self.upper))]
        return to_global(local, self.origin, self.tilt_deg).tolist() if self.framed else local

    def check(self, path: str, dim: int, domain: Domain, spacing: float) -> None:
        check_vector(f"{path}.lower", self.lower, dim)
        check_vector(f"{path}.upper", self.upper, dim)
        if self.origin is not None:
            check_vector(f"{path}.origin", self.origin, dim)
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
            check_vector(f"{path}.velocity", self.velocity, dim)
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
class Wall(_Friction):
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

    normal: Tuple[float, ...] = scene_key("unit normal of the plane, pointing into the material", bounds="[-1, 1]")
    point: Tuple[float, ...] = scene_key("a point on the plane", unit="m", bounds="[-1e5, 1e5]")
    name: str = scene_key("label used in messages", "wall")
    angular_velocity = 0.0  # a plane wall does not turn (not a key; drums do)
    type: Literal["ghost", "dynamic", "extrapolated"] = scene_key(
        "boundary model: ghost (mu(I), [M34]-[M36]), dynamic (boundary particles that obey continuity and "
        "the equation of state, Dalrymple & Knio 2001, as in [A]) or extrapolated (boundary particles whose "
        "velocity and stress are extrapolated from the material, as in [P])", "ghost")
    lower: Optional[Tuple[float, ...]] = scene_key("lower corner of the box that clips the wall (default domain)", None,
                    "m", bounds="[-1e5, 1e5]")
    upper: Optional[Tuple[float, ...]] = scene_key("upper corner of the box that clips the wall (default domain)", None,
                    "m", bounds="[-1e5, 1e5]")
    max_velocity_factor: float = scene_key(
        "beta_max of [M36]; 6 lets the three ghost rows extrapolate a linear profile exactly for the "
        "first material row (Morris et al. 1997 used 1.5; 1 means zero ghost velocity)", 6.0, "-", bounds="[1, 100]", hint="beta_max of [M36]")
    ghost_stress: Literal["extrapolated", "mirror"] = scene_key(
        "mirror: sigma_j = sigma_i as in [M]; extrapolated: the traction on planes parallel to the "
        "wall grows by rho_i g (d_i + d_j) (the static momentum balance across the wall)", "extrapolated")
    initial_pressure: Literal["zero", "overburden"] = scene_key(
        "dynamic boundaries: pressure (and so density, [A5]) of the boundary particles at t = 0: zero "
        "(the reference density, as [A]), or the weight of the material over them (a layer that starts "
        "at rest stays at rest instead of falling into the wall and ringing; scene/__init__.py)", "zero")

    def check(self, path: str, dim: int) -> None:
        check_vector(f"{path}.normal", self.normal, dim)
        check_vector(f"{path}.point", self.point, dim)
        norm = math.sqrt(sum(c * c for c in self.normal))
        if abs(norm - 1.0) > 1e-6:
            raise ConfigError(f"{path}.normal", f"must be a unit vector, has length {norm:.6g}")
        for key in ("lower", "upper"):
            if getattr(self, key) is not None:
                check_vector(f"{path}.{key}", getattr(self, key), dim)
        if self.initial_pressure != "zero" and self.type != "dynamic":
            raise ConfigError(f"{path}.initial_pressure", "only dynamic boundary particles take their pressure "
                                                          "from their density")
        self.check_friction(path, self.type == "dynamic")


@dataclass(frozen=True, kw_only=True)
class _Obstacle(_Friction):
    """A fixed solid laid as boundary particles (scene/geometry.py; of the model's
    ``obstacle_walls`` type), placed by a rigid frame: ``origin`` and a tilt about the y axis
    (3D; z in 2D) so that the local x axis runs down a slope of ``tilt_deg``
    (x' = (cos, 0, -sin), z' = (sin, 0, cos)). Local coordinates below are in that frame."""

    name: str = scene_key("label used in messages", "obstacle")
    origin: Optional[Tuple[float, ...]] = scene_key("the local frame's origin (default the global origin)", None, "m",
                     bounds="[-1e5, 1e5]")
    tilt_deg: float = scene_key("slope of the local x axis below the horizontal (about y; +: x' descends)", 0.0,
                                "deg", bounds="(-90, 90)", hint="degrees, not radians")
    dimensions = (3,)
    angular_velocity = 0.0  # a fixed solid (not a key; the drum's is)

    def check(self, path: str, dim: int) -> None:
        if dim not in self.dimensions:
            raise ConfigError(f"{path}.shape", f"a {self.shape} obstacle needs dimension "
                                               f"{' or '.join(map(str, self.dimensions))}")
        if self.origin is not None:
            check_vector(f"{path}.origin", self.origin, dim)


@dataclass(frozen=True, kw_only=True)
class ChuteSegment:
    length: float = scene_key("length along the slope", unit="m", bounds="(0, 1e4]")
    slope_deg: float = scene_key("inclination below the horizontal (+: descends along +x)", unit="deg", bounds="(-90, 90)",
                                 hint="degrees, not radians")


@dataclass(frozen=True, kw_only=True)
class ChuteObstacle(_Obstacle):
    """Inclined planes joined at slope breaks, descending along +x from ``origin`` (the top of
    the first plane, on the centre line), each ``width`` wide, with optional vertical side walls.
    ``tilt_deg`` is not used: each segment has its own slope."""

    shape: Literal["chute"] = scene_key("obstacle kind", "chute")
    segments: Tuple[ChuteSegment, ...] = scene_key("planes from the top down")
    width: float = scene_key("width across the chute (3D)", 1.0, "m", bounds="(0, 1e4]")
    side_wall_height: float = scene_key("height of the side walls above the bed (0: none)", 0.0, "m", bounds="[0, 1e4]")
    dimensions = (2, 3)

    def check(self, path: str, dim: int) -> None:
        super().check(path, dim)
        if not self.segments:
            raise ConfigError(f"{path}.segments", "a chute needs at least one segment")


@dataclass(frozen=True, kw_only=True)
class BoxObstacle(_Obstacle):
    """A solid box [lower, upper] in the local frame (posts, a building, the walls of a release
    box)."""

    shape: Literal["box"] = scene_key("obstacle kind", "box")
    lower: Tuple[float, ...] = scene_key("lower corner, local frame", unit="m", bounds="[-1e5, 1e5]")
    upper: Tuple[float, ...] = scene_key("upper corner, local frame", unit="m", bounds="[-1e5, 1e5]")
    dimensions = (2, 3)

    def check(self, path: str, dim: int) -> None:
        super().check(path, dim)
        check_vector(f"{path}.lower", self.lower, dim)
        check_vector(f"{path}.upper", self.upper, dim)
        for a in range(dim):
            if self.upper[a] <= self.lower[a]:
                raise ConfigError(f"{path}.upper", f"must exceed lower along axis {AXES[a]}")


@dataclass(frozen=True, kw_only=True)
class PostRowsObstacle(_Obstacle):
    """Rows of square posts standing on the local x-y plane (a chute panel): row k at local
    x = k row_spacing, posts of side ``post_size`` separated by ``gap`` across ``width`` centred
    on y = 0; ``staggered`` shifts every other row by half a period (post + gap)."""

    shape: Literal["post_rows"] = scene_key("obstacle kind", "post_rows")
    post_size: float = scene_key("side of a square post", unit="m", bounds="(0, 1e4]")
    gap: float = scene_key("clear gap between neighbouring posts of a row", unit="m", bounds="(0, 1e4]")
    rows: int = scene_key("number of rows", 1, bounds="[1, 10000]")
    row_spacing: float = scene_key("distance between rows along local x (post side included)", 0.0, "m", bounds="[0, 1e4]")
    width: float = scene_key("span of each row across local y", unit="m", bounds="(0, 1e4]")
    height: float = scene_key("height of the posts along local z", unit="m", bounds="(0, 1e4]")
    staggered: bool = scene_key("shift every other row by (post_size + gap)/2", False)

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

    shape: Literal["cylinder"] = scene_key("obstacle kind", "cylinder")
    radius: float = scene_key("radius", unit="m", bounds="(0, 1e4]")
    height: float = scene_key("height along the local z axis", unit="m", bounds="(0, 1e4]")


@dataclass(frozen=True, kw_only=True)
class WedgeObstacle(_Obstacle):
    """A tetrahedral wedge on the local x-y plane pointing up the slope (-x): its tip at the
    origin, its rear edge at x = length from y = -width/2 to width/2, its top vertex above the
    rear centre at z = height (after Tai et al. 2001)."""

    shape: Literal["wedge"] = scene_key("obstacle kind", "wedge")
    length: float = scene_key("tip to rear face along local x", unit="m", bounds="(0, 1e4]")
    width: float = scene_key("rear face width across local y", unit="m", bounds="(0, 1e4]")
    height: float = scene_key("rear face height along local z", unit="m", bounds="(0, 1e4]")


@dataclass(frozen=True, kw_only=True)
class MeshObstacle(_Obstacle):
    """A closed triangle mesh that meshio reads (STL, OBJ, PLY, VTU...), scaled, then placed by
    the local frame; its inside is found by the winding number of its triangles."""

    shape: Literal["mesh"] = scene_key("obstacle kind", "mesh")
    file: str = scene_key("mesh file (relative paths: from the scene file's folder)")
    scale: float = scene_key("factor from the mesh's units to metres", 1.0, "-", bounds="(0, 1e6]")

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

    shape: Literal["drum"] = scene_key("obstacle kind", "drum")
    radius: float = scene_key("inner radius R of the drum", unit="m", bounds="(0, 1e3]")
    angular_velocity: float = scene_key("omega, rotation rate, counter-clockwise positive (rad/s, not rpm)", unit="rad/s",
                                        bounds="[-100, 100]", hint="rad/s, not rpm: 1 rpm = 0.1047 rad/s")
    dimensions = (2,)

    def check(self, path: str, dim: int) -> None:
        super().check(path, dim)
        if self.tilt_deg != 0.0:
            raise ConfigError(f"{path}.tilt_deg", "a drum is round: no tilt")


OBSTACLES = {cls.__dataclass_fields__["shape"].default: cls
             for cls in (ChuteObstacle, BoxObstacle, PostRowsObstacle, CylinderObstacle, WedgeObstacle, MeshObstacle,
                         DrumObstacle)}


class AnyObstacle:
    """Annotation marker: the ``shape`` key picks the class from :data:`OBSTACLES`."""
