"""Parametric link built with gmsh's OpenCASCADE kernel from its two joint axes (any skew pair).

A link carries two joint axes (lines in space, :mod:`ffrf.geometry.joint_axes`). Its geometry is

* a cylindrical housing coaxial with each axis, with a through bearing bore
  (default radius 9.5 mm: the outer radius of two 626 bearings, 6 mm wide each);
* a solid rectangular arm joining the two housing centres;
* for the base link, a mounting block on the middle of the arm whose outer
  planar face is the clamping interface (physical group ``"mount"``).

Housing offset rule: the joint point of an axis is the foot of the common
normal of the link's two axes. At joint i (axis h_i) the link for which h_i is
its FIRST axis places its housing at +s along h_i's direction, the link for
which h_i is its SECOND axis at -s, with s = housing_length/2 + axial_gap/2,
so the housings of the two links meeting at a joint never overlap. The signed
offsets are recorded in :attr:`LinkGeometry.interface_offsets`.

The default dimensions are our own choice (the paper's STL geometry is not
available): housing outer radius 16 mm, housing length 16 mm (two 6 mm
bearings plus shoulders), arm 16 x 12 mm, 1 mm axial gap between housings.
"""

from __future__ import annotations

import itertools
import logging
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ffrf.errors import GeometryError
from ffrf.geometry.joint_axes import Axis, common_normal_feet
from ffrf.mesh.tet_mesh import MAX_LINK_EXTENT_M, TetMesh

__all__ = [
    "LINK_DESIGN_FIELDS",
    "LinkDesign",
    "LinkGeometry",
    "arm_frame",
    "arm_waypoints",
    "build_link",
    "housing_centers",
    "mesh_link",
    "trim_covering",
    "trim_reach",
]

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class LinkDesign:
    """Dimensions of the parametric link (metres); see the module docstring for the defaults."""

    bore_radius: float = 9.5e-3
    housing_outer_radius: float = 16e-3
    housing_length: float = 16e-3
    axial_gap: float = 1e-3
    arm_width: float = 16e-3  # along the first axis' direction (projected)
    arm_thickness: float = 12e-3
    mount_length: float = 30e-3  # along the arm
    mount_width: float = 24e-3
    mount_height: float = 12e-3  # beyond the arm surface

    def __post_init__(self) -> None:
        for name, value in vars(self).items():
            if not value > 0.0:
                raise GeometryError(f"LinkDesign.{name}={value!r} must be > 0 (metres)")
            if value > MAX_LINK_EXTENT_M:
                raise GeometryError(
                    f"LinkDesign.{name}={value!r} m: suspicious units, did you pass millimetres? "
                    "give metres, e.g. 9.5e-3"
                )
        if self.bore_radius >= self.housing_outer_radius:
            raise GeometryError(
                f"LinkDesign: bore radius {self.bore_radius} m must be smaller than the housing "
                f"outer radius {self.housing_outer_radius} m"
            )

    @property
    def housing_offset(self) -> float:
        """s = housing_length/2 + axial_gap/2: distance of a housing centre from its joint point."""
        return 0.5 * (self.housing_length + self.axial_gap)


#: The names of :class:`LinkDesign`'s dimensions, in order (scene files' ``design`` table).
LINK_DESIGN_FIELDS: tuple[str, ...] = tuple(f.name for f in fields(LinkDesign))


@dataclass(frozen=True)
class LinkGeometry:
    """What :func:`build_link` made: axes, joint points, housing centres and interface offsets."""

    axes: tuple[Axis, Axis]
    interface_names: tuple[str, str]
    joint_points: NDArray[np.float64]  # (2, 3) feet of the common normal
    housing_centers: NDArray[np.float64]  # (2, 3)
    interface_offsets: dict[str, float]  # signed offset of each bore centre from its joint point
    design: LinkDesign
    has_mount: bool
    mount_center: NDArray[np.float64] | None = None
    mount_normal: NDArray[np.float64] | None = None
    surface_tags: dict[str, list[int]] = field(default_factory=dict)

    @property
    def length(self) -> float:
        """Length of the common normal between the two axes (the link's a_i)."""
        return float(np.linalg.norm(self.joint_points[1] - self.joint_points[0]))


def _points_on_axes(points: ArrayLike, axes: tuple[Axis, Axis], names: tuple[str, str]) -> NDArray[np.float64]:
    """The given joint points, checked to lie on their axes (to 1e-9 m)."""
    points = np.asarray(points, dtype=float).reshape(2, 3)
    for point, axis, name in zip(points, axes, names, strict=True):
        rel = point - axis.point
        off = float(np.linalg.norm(rel - (rel @ axis.direction) * axis.direction))
        if not off < 1e-9:
            raise GeometryError(
                f"joint point {point.tolist()} of interface {name!r} is {off:.3g} m off its axis through "
                f"{axis.point.tolist()}; give a point on the axis"
            )
    return points


def arm_frame(start: NDArray, end: NDArray, hint: NDArray) -> NDArray[np.float64]:
    """Right-handed frame (columns e1, e2, e3): e1 along start->end, e2 = hint made orthogonal."""
    e1 = (end - start) / np.linalg.norm(end - start)
    e2 = hint - (hint @ e1) * e1
    if np.linalg.norm(e2) < 1e-6:
        e2 = np.cross(e1, [1.0, 0.0, 0.0] if abs(e1[0]) < 0.9 else [0.0, 1.0, 0.0])
    e2 /= np.linalg.norm(e2)
    return np.column_stack([e1, e2, np.cross(e1, e2)])


#: A straight arm that leaves a housing within this angle of its axis gets a radial stub out of the housing first.
STUB_ANGLE = np.radians(45.0)


def _arm_path(centers: NDArray, axes, design: LinkDesign) -> list[NDArray[np.float64]]:
    """Waypoints of the arm from housing centre 0 to housing centre 1.

    The straight line between the centres, unless it leaves a housing within :data:`STUB_ANGLE` of the
    housing's axis (intersecting or nearly parallel axes with DH offsets: the arm would run along the axis,
    through the neighbour's housing). Then it leaves both housings radially, by a stub of the housing's
    outer radius plus the axial gap plus half the arm's cross-section, and the arm joins the stub ends.
    """
    chord = centers[1] - centers[0]
    unit = chord / np.linalg.norm(chord)
    if all(np.arccos(min(1.0, abs(float(unit @ a.direction)))) >= STUB_ANGLE for a in axes):
        return [centers[0], centers[1]]
    reach = design.housing_outer_radius + design.axial_gap + 0.5 * np.hypot(design.arm_width, design.arm_thickness)
    ends = []
    for center, axis, toward in ((centers[0], axes[0], chord), (centers[1], axes[1], -chord)):
        radial = toward - (toward @ axis.direction) * axis.direction
        if np.linalg.norm(radial) < 1e-9 * np.linalg.norm(toward):  # the arm would run along the axis
            radial = np.cross(axis.direction, [1.0, 0.0, 0.0] if abs(axis.direction[0]) < 0.9 else [0.0, 1.0, 0.0])
        ends.append(center + reach * radial / np.linalg.norm(radial))
    return [centers[0], ends[0], ends[1], centers[1]]


def arm_waypoints(joint_points: ArrayLike, axes, design: LinkDesign = LinkDesign()) -> NDArray[np.float64]:
    """The arm's course from joint point 0 to joint point 1 (``(k, 3)``): the two points, with the ends of the
    radial stubs between them where the arm leaves its housings radially (:func:`_arm_path`)."""
    points = np.asarray(joint_points, dtype=float)
    lines = (Axis.of(axes[0]), Axis.of(axes[1]))
    centers = housing_centers(points, lines, design)
    return np.array([points[0], *_arm_path(centers, lines, design)[1:-1], points[1]])


def housing_centers(joint_points: ArrayLike, axes, design: LinkDesign) -> NDArray[np.float64]:
    """The centres ``(2, 3)`` of a link's two housings: each ``design.housing_offset`` from its joint point along
    its axis, the first housing towards the axis' direction, the second against it (the offset rule that stacks
    the two links' housings at a joint one axial gap apart)."""
    points = np.asarray(joint_points, dtype=float).reshape(2, 3)
    lines = (Axis.of(axes[0]), Axis.of(axes[1]))
    s = design.housing_offset
    return np.stack([points[0] + s * lines[0].direction, points[1] - s * lines[1].direction])


def _placed_box(
    occ, lower: tuple[float, float, float], size: tuple[float, float, float], frame: NDArray, origin: NDArray
) -> int:
    """Box given in the local frame (x along e1), moved to world coordinates by a rigid motion.

    A rotation + translation keeps the faces exact planes; gmsh's general
    affineTransform would turn them into approximate B-spline surfaces.
    """
    from scipy.spatial.transform import Rotation

    tag = occ.addBox(*lower, *size)
    rotvec = Rotation.from_matrix(frame).as_rotvec()
    angle = float(np.linalg.norm(rotvec))
    if angle > 0.0:
        occ.rotate([(3, tag)], 0.0, 0.0, 0.0, *(rotvec / angle), angle)
    occ.translate([(3, tag)], *origin)
    return tag


def _bore_cut_length(design: LinkDesign) -> float:
    """Bore cutting tool length: 1 mm past each housing end so the cut is clean.

    Surface classification allows the same extent, because OCC's parameter
    bounds of a trimmed face are only approximate."""
    return design.housing_length + 2e-3


def _surface_samples(gmsh, tag: int, n: int = 5) -> NDArray[np.float64]:
    lo, hi = gmsh.model.getParametrizationBounds(2, tag)
    u, v = np.meshgrid(np.linspace(lo[0], hi[0], n), np.linspace(lo[1], hi[1], n))
    return np.asarray(gmsh.model.getValue(2, tag, np.column_stack([u.ravel(), v.ravel()]).ravel())).reshape(-1, 3)


def _classify_surfaces(gmsh, geometry_axes, centers, design: LinkDesign, mount) -> dict[int | str, list[int]]:
    """Which gmsh surfaces lie on bore i (0, 1) or on the mount plane ("mount")."""
    tol = 1e-6 + 1e-4 * design.bore_radius
    found: dict[int | str, list[int]] = {0: [], 1: [], "mount": []}
    for _, tag in gmsh.model.getEntities(2):
        pts = _surface_samples(gmsh, tag)
        for i, (axis, center) in enumerate(zip(geometry_axes, centers, strict=True)):
            rel = pts - center
            t = rel @ axis.direction
            r = np.linalg.norm(rel - np.outer(t, axis.direction), axis=1)
            on_bore = np.all(np.abs(r - design.bore_radius) < tol)
            if on_bore and np.all(np.abs(t) <= 0.5 * _bore_cut_length(design) + tol):
                found[i].append(tag)
        if mount is not None and np.all(np.abs((pts - mount[0]) @ mount[1]) < tol):
            found["mount"].append(tag)
    return found


def trim_reach(design: LinkDesign) -> float:
    """How far beyond a housing's end faces :func:`build_link` trims the arm near the axis by default (m)."""
    return 2.0 * (design.arm_width + design.arm_thickness + design.mount_height)


def trim_covering(distance: float, design: LinkDesign) -> float:
    """The trimming's reach (m) that keeps a housing's arm one axial gap from a coaxial housing ``distance`` (m)
    away, centre to centre, beyond that housing's far end face: at least :func:`trim_reach`."""
    return max(trim_reach(design), distance + design.axial_gap)


def _trim_to_housing_slabs(
    occ, parts: list[int], axes, centers, design: LinkDesign, reaches: tuple[float, float]
) -> list[tuple[int, int]]:
    """Cut away arm material that sticks out of a housing's end faces near the axis.

    A straight box cannot follow two skew axes, so its corners could protrude
    axially past a housing end (up to half the cross-section diagonal) and
    clash with the neighbouring link's housing across the axial gap. Removing
    everything within (housing radius + axial gap) of the axis beyond the end
    planes, as far as ``reaches`` (per housing), keeps the neighbour's housing at
    least one gap away in both directions.
    """
    clearance_radius = design.housing_outer_radius + design.axial_gap
    tools = []
    for axis, center, cap in zip(axes, centers, reaches, strict=True):
        for sign in (-1.0, 1.0):
            base = center + sign * 0.5 * design.housing_length * axis.direction
            tools.append((3, occ.addCylinder(*base, *(sign * cap * axis.direction), clearance_radius)))
    trimmed, _ = occ.cut([(3, p) for p in parts], tools)
    return trimmed


def build_link(
    gmsh,
    axis_a,
    axis_b,
    design: LinkDesign = LinkDesign(),
    names: tuple[str, str] = ("joint_a", "joint_b"),
    mount: bool = False,
    joint_points: ArrayLike | None = None,
    trim: tuple[float | None, float | None] | None = None,
) -> LinkGeometry:
    """Build the link solid in the open gmsh session (OCC kernel) with physical groups.

    Parameters
    ----------
    gmsh : the module, inside :func:`ffrf.geometry.meshing.gmsh_session`.
    axis_a, axis_b : first and second joint axis (:class:`Axis`, objects with
        ``.point``/``.direction``, or (point, direction) pairs); misaligned links
        are built simply by passing the misaligned axes.
    design : dimensions.
    names : physical-group names of the two bore surfaces.
    mount : add the base link's mounting block (physical group ``"mount"``).
    joint_points : (2, 3) the joint point on each axis (default: the feet of the common normal).
        Where a loop has DH offsets d_i != 0, the two links meeting at a joint have different
        feet on its axis; giving both the same joint point keeps their housings stacked by the
        offset rule, and the arm, which joins the housing centres, is cranked accordingly.
    trim : per housing, how far beyond its end faces the arm is trimmed near the axis (m; ``None``
        or a ``None`` entry: :func:`trim_reach`); farther where the neighbour's housing on that
        axis sits farther away (:func:`trim_covering`).
    """
    axes = (Axis.of(axis_a), Axis.of(axis_b))
    feet = common_normal_feet(*axes) if joint_points is None else _points_on_axes(joint_points, axes, names)
    s = design.housing_offset
    centers = housing_centers(feet, axes, design)
    span = float(np.linalg.norm(centers[1] - centers[0]))
    if span > MAX_LINK_EXTENT_M:
        raise GeometryError(
            f"link {names}: the housings are {span:.4g} m apart: suspicious units, "
            "did you pass millimetres? use unit='mm' or give metres"
        )
    if span < 2.0 * design.housing_outer_radius:
        raise GeometryError(
            f"link {names}: housing centres only {span:.4g} m apart, less than two housing "
            f"radii ({2 * design.housing_outer_radius} m); reduce housing_outer_radius"
        )
    occ = gmsh.model.occ
    housings = []
    for axis, center in zip(axes, centers, strict=True):
        base = center - 0.5 * design.housing_length * axis.direction
        housings.append(occ.addCylinder(*base, *(design.housing_length * axis.direction), design.housing_outer_radius))
    half_w, half_t = 0.5 * design.arm_width, 0.5 * design.arm_thickness
    path = _arm_path(centers, axes, design)
    parts = []
    for start, end in itertools.pairwise(path):
        # Segments after a stub overlap their neighbours by half an arm width, so the corners are filled.
        extra = 0.0 if len(path) == 2 else half_w
        frame_k = arm_frame(start, end, axes[0].direction)
        length = float(np.linalg.norm(end - start))
        parts.append(
            _placed_box(
                occ,
                (-extra, -half_w, -half_t),
                (length + 2 * extra, design.arm_width, design.arm_thickness),
                frame_k,
                start,
            )
        )
    middle = len(path) // 2 - 1 if len(path) == 4 else 0  # the segment between the stubs (or the whole arm)
    origin = path[middle]
    frame = arm_frame(origin, path[middle + 1], axes[0].direction)
    middle_length = float(np.linalg.norm(path[middle + 1] - origin))
    mount_plane = None
    if mount:
        x0 = 0.5 * (middle_length - design.mount_length)
        parts.append(
            _placed_box(
                occ,
                (x0, -0.5 * design.mount_width, -half_t - design.mount_height),
                (design.mount_length, design.mount_width, design.mount_height + half_t),
                frame,
                origin,
            )
        )
        mount_center = origin + frame @ np.array([0.5 * middle_length, 0.0, -half_t - design.mount_height])
        mount_plane = (mount_center, -frame[:, 2])
    default_reach = trim_reach(design)
    first, second = (None, None) if trim is None else trim
    reaches = (default_reach if first is None else first, default_reach if second is None else second)
    if not all(np.isfinite(r) and r > 0.0 for r in reaches):
        raise GeometryError(f"link {names}: trim reaches {reaches} m must be positive")
    trimmed = _trim_to_housing_slabs(occ, parts, axes, centers, design, reaches)
    solid, _ = occ.fuse([(3, housings[0])], [(3, housings[1])] + trimmed)
    bores = []
    for axis, center in zip(axes, centers, strict=True):
        length = _bore_cut_length(design)
        base = center - 0.5 * length * axis.direction
        bores.append((3, occ.addCylinder(*base, *(length * axis.direction), design.bore_radius)))
    solid, _ = occ.cut(solid, bores)
    occ.synchronize()
    if len(solid) != 1:
        raise GeometryError(
            f"link {names}: the boolean union gave {len(solid)} solids instead of one; "
            "the arm does not join the housings, check the axes"
        )
    tags = _classify_surfaces(gmsh, axes, centers, design, mount_plane)
    surface_tags = {names[0]: tags[0], names[1]: tags[1]}
    if mount:
        surface_tags["mount"] = tags["mount"]
    for group, group_tags in surface_tags.items():
        if not group_tags:
            raise GeometryError(
                f"link {names}: no surface found for interface {group!r}; "
                "the arm or mounting block probably covers it, check the design"
            )
        gmsh.model.addPhysicalGroup(2, group_tags, name=group)
    gmsh.model.addPhysicalGroup(3, [solid[0][1]], name="link")
    logger.info(
        "link %s: common normal %.4g m, housing offsets +-%.4g m, interfaces %s",
        names,
        float(np.linalg.norm(feet[1] - feet[0])),
        s,
        sorted(surface_tags),
    )
    return LinkGeometry(
        axes,
        names,
        feet,
        centers,
        {names[0]: +s, names[1]: -s},
        design,
        mount,
        None if mount_plane is None else mount_plane[0],
        None if mount_plane is None else mount_plane[1],
        surface_tags,
    )


def mesh_link(
    axis_a,
    axis_b,
    *,
    h: float = 2e-3,
    design: LinkDesign = LinkDesign(),
    names: tuple[str, str] = ("joint_a", "joint_b"),
    mount: bool = False,
    msh_path: str | Path | None = None,
    name: str = "link",
    joint_points: ArrayLike | None = None,
    trim: tuple[float | None, float | None] | None = None,
) -> tuple[TetMesh, LinkGeometry]:
    """Build and mesh a link with linear tetrahedra of maximum edge ``h`` (metres).

    Deterministic for given inputs (single-threaded gmsh, fixed seed). Writes
    the gmsh .msh file too when ``msh_path`` is given.
    """
    from ffrf.geometry.meshing import configure_meshing, gmsh_session, mesh_current_model

    with gmsh_session(name) as gmsh:
        geometry = build_link(gmsh, axis_a, axis_b, design, names, mount, joint_points, trim)
        configure_meshing(h)
        mesh = mesh_current_model(name)
        if msh_path is not None:
            Path(msh_path).parent.mkdir(parents=True, exist_ok=True)
            gmsh.write(str(msh_path))
    return mesh, geometry
