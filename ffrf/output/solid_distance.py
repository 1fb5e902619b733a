r"""Signed distance between two closed triangulated solids at one relative pose: the clearance of two links.

For solids :math:`A`, :math:`B` with surfaces :math:`\partial A`, :math:`\partial B` (``docs/formulation.md``,
"Clearance between links", Eqs. (CL1)-(CL3)):

.. math:: c(A, B) = \operatorname{dist}(\partial A, \partial B) \quad \text{when they do not overlap,} \qquad
          c(A, B) = -\max\Big(\max_{p \in \partial A \cap B} d_{\partial B}(p),\;
                              \max_{p \in \partial B \cap A} d_{\partial A}(p)\Big) \quad \text{when they do,}

with :math:`d_{\partial B}(p)` the distance of the point :math:`p` to the surface :math:`\partial B`: the smallest
distance between the solids, or minus their penetration depth, the largest distance from a point of one surface
inside the other solid to that solid's surface (exact for two parallel or crossing cylinders, ``r1 + r2 - d``, and
for a box face pushed ``t`` into a box, ``t``).

The libraries do the geometry: python-fcl's BVH gives the exact triangle-triangle distance and whether the surfaces
cross, and the exact point-triangle distance; manifold3d's boolean intersection :math:`A \cap B` gives the region
:math:`\partial A \cap B` (its triangles that come from :math:`\partial A`) also when one solid lies wholly inside
the other. The depth over that region is found by branch and bound (:func:`_deepest`): the distance to the other
surface is at most that to the surface's point (or triangle) nearest any corner of a piece of the region, which is
convex, so below the linear interpolation of its corner values. Pieces whose bound exceeds the deepest value found
by more than ``tolerance`` are split in four until none is left: the depth of the faceted solids is found to within
``tolerance`` (default 0.05 mm); the positive distance is exact.

Joint zone (Eq. (CL3)): two links that share a joint have coaxial housings one axial gap apart by construction
(:mod:`ffrf.geometry.link_geometry`), whatever the joint's angle. For such a pair the surface of each link within the
joint's zone, a cylinder about the joint axis (:class:`JointZone`), is left out: manifold3d cuts the zone out of both
solids, and the rest of each surface is measured against the other link's whole surface, so an arm passing a
neighbour's housing is seen. The zone is cut as a prism circumscribing the cylinder, 1 um larger all round.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from functools import cached_property

import fcl
import manifold3d
import numpy as np
import trimesh
from numpy.typing import ArrayLike, NDArray

from ffrf.errors import GeometryError

__all__ = ["JointZone", "LinkSolid", "SolidPair", "signed_distance", "DEPTH_TOLERANCE", "ZONE_SLACK"]

#: Default accuracy of the penetration depth (m): the branch and bound stops within it.
DEPTH_TOLERANCE = 5e-5
#: A joint zone is cut as a prism of this many sides circumscribing its cylinder (overshoot 0.008 % of the radius) ...
ZONE_SIDES = 256
#: ... grown by this much (m) all round: surfaces on the zone's boundary (a housing's outer end face, the arm cut
#: at the zone's radius) lie inside it.
ZONE_SLACK = 1e-6
#: Exact point-triangle distances (FCL's own solver; libccd's GJK stops at a tolerance of about 1e-6 m).
_POINT_REQUEST = fcl.DistanceRequest(enable_nearest_points=True, gjk_solver_type=fcl.GJKSolverType.GST_INDEP)


@dataclass(frozen=True, eq=False)
class LinkSolid:
    """A link as a solid: its closed surface at home, ``vertices`` ``(m, 3)`` (m) and ``triangles`` ``(k, 3)``
    (indices, ordered so that the normals point out of the solid), and a ``name`` for messages."""

    vertices: NDArray[np.float64]
    triangles: NDArray[np.int64]
    name: str = "solid"

    def __post_init__(self) -> None:
        vertices = np.array(self.vertices, dtype=np.float64, order="C")  # an own, writable copy (manifold3d's
        triangles = np.array(self.triangles, dtype=np.int64, order="C")  # constructor refuses read-only arrays)
        if vertices.ndim != 2 or vertices.shape[1] != 3 or triangles.ndim != 2 or triangles.shape[1] != 3:
            raise GeometryError(
                f"{self.name}: expected vertices (m, 3) and triangles (k, 3), got {vertices.shape} and "
                f"{triangles.shape}"
            )
        object.__setattr__(self, "vertices", vertices)
        object.__setattr__(self, "triangles", triangles)

    @cached_property
    def corners(self) -> NDArray[np.float64]:
        """The triangles' corners, ``(k, 3, 3)``."""
        return self.vertices[self.triangles]

    @cached_property
    def bvh(self) -> fcl.BVHModel:
        """FCL's bounding-volume hierarchy of the whole surface."""
        return _bvh(self.vertices, self.triangles)

    @cached_property
    def manifold(self) -> tuple[manifold3d.Manifold, int]:
        """The solid for manifold3d's booleans and its original id, by which a boolean's triangles name the surface
        they come from. Refused when the surface is not closed and consistently oriented."""
        original = manifold3d.Manifold.reserve_ids(1)
        n = len(self.triangles)
        mesh = manifold3d.Mesh64(
            self.vertices,
            self.triangles.astype(np.uint64),
            run_index=np.array([0, 3 * n], dtype=np.uint64),
            run_original_id=np.array([original], dtype=np.uint32),
        )
        solid = manifold3d.Manifold(mesh)
        if solid.status() != manifold3d.Error.NoError or solid.is_empty():
            raise GeometryError(
                f"{self.name}: its surface ({len(self.vertices)} vertices, {n} triangles) is not a closed, "
                f"consistently oriented 2-manifold ({solid.status()}); give the boundary of a solid, normals outward"
            )
        return solid, original

    @cached_property
    def size(self) -> float:
        """The diagonal of the bounding box (m)."""
        return float(np.linalg.norm(np.ptp(self.vertices, axis=0)))


@dataclass(frozen=True)
class JointZone:
    """The zone of a joint shared by two links: the cylinder of ``radius`` about the joint axis through ``point``
    along ``direction`` (unit), from ``lower`` to ``upper`` along it (m from ``point``); home coordinates, which are
    both links' own (the axis moves with both)."""

    point: NDArray[np.float64]
    direction: NDArray[np.float64]
    radius: float
    lower: float
    upper: float

    @classmethod
    def around_housings(
        cls,
        point: ArrayLike,
        direction: ArrayLike,
        centres: ArrayLike,
        housing_length: float,
        outer_radius: float,
        axial_gap: float,
    ) -> JointZone:
        """The zone of the two housings centred at ``centres`` ``(2, 3)`` on the axis: radius ``outer_radius +
        axial_gap``, from the lower end of one housing to the upper end of the other (Eq. (CL3))."""
        origin = np.asarray(point, dtype=float)
        unit = np.asarray(direction, dtype=float) / np.linalg.norm(direction)
        along = (np.asarray(centres, dtype=float) - origin) @ unit
        half = 0.5 * housing_length
        return cls(origin, unit, outer_radius + axial_gap, float(along.min() - half), float(along.max() + half))

    def prism(self) -> manifold3d.Manifold:
        """The zone as a solid for manifold3d: a prism of :data:`ZONE_SIDES` sides circumscribing the cylinder,
        grown by :data:`ZONE_SLACK` all round (so that surfaces on the zone's boundary, a housing's end face, lie
        inside it)."""
        radius = (self.radius + ZONE_SLACK) / np.cos(np.pi / ZONE_SIDES)
        prism = manifold3d.Manifold.cylinder(self.upper - self.lower + 2 * ZONE_SLACK, radius, -1.0, ZONE_SIDES)
        helper = np.eye(3)[int(np.argmin(np.abs(self.direction)))]
        first = np.cross(self.direction, helper)
        first /= np.linalg.norm(first)
        placement = np.column_stack(
            [
                first,
                np.cross(self.direction, first),
                self.direction,
                self.point + (self.lower - ZONE_SLACK) * self.direction,
            ]
        )
        return prism.transform(placement)


class _Side:
    """One solid of a pair and what of its surface is measured: all of it, or with the pair's joint zone cut away
    (the solid less the zone; its triangles that come from the solid's surface are the measured surface)."""

    def __init__(self, solid: LinkSolid, zone: JointZone | None) -> None:
        self.solid = solid
        body, self.original = solid.manifold
        self.cut = body if zone is None else body - zone.prism()
        self.whole = fcl.CollisionObject(solid.bvh)
        if zone is None:
            self.rest, self.rest_vertices = self.whole, solid.vertices
        else:
            mesh = self.cut.to_mesh64()
            points = np.asarray(mesh.vert_properties)[:, :3]
            triangles = _triangles_from(mesh, self.original)
            self.rest = fcl.CollisionObject(_bvh(points, triangles)) if len(triangles) else None
            self.rest_vertices = points[np.unique(triangles)]

    def place(self, transform: NDArray[np.float64]) -> None:
        placed = fcl.Transform(transform[:3, :3], transform[:3, 3])
        self.whole.setTransform(placed)
        if self.rest is not None and self.rest is not self.whole:
            self.rest.setTransform(placed)

    def point_distances(self, points: NDArray[np.float64]) -> tuple[NDArray, NDArray, NDArray]:
        """Exact distance of each of ``points`` (home coordinates) to the whole surface, the nearest point and the
        triangle FCL names with it (the nearest one, or, not always, another)."""
        surface = fcl.CollisionObject(self.solid.bvh)
        probe = fcl.CollisionObject(fcl.Sphere(0.0))
        distances, nearest = np.empty(len(points)), np.empty((len(points), 3))
        named = np.empty(len(points), dtype=np.int64)
        for k, point in enumerate(points):
            probe.setTranslation(point)
            result = fcl.DistanceResult()
            distances[k] = fcl.distance(surface, probe, _POINT_REQUEST, result)
            nearest[k], named[k] = result.nearest_points[0], result.b1
        return distances, nearest, named


class SolidPair:
    """Two solids ``a``, ``b`` and, for links that share a joint, its ``zone``: :meth:`clearance` at any relative
    pose (module docstring). Built once per pair, used at every pose; ``tolerance``: of the depth (m)."""

    def __init__(
        self, a: LinkSolid, b: LinkSolid, zone: JointZone | None = None, tolerance: float = DEPTH_TOLERANCE
    ) -> None:
        self.zone = zone
        self.tolerance = tolerance
        self.sides = tuple(_Side(s, zone) for s in (a, b))

    def clearance(self, relative: ArrayLike) -> float:
        r"""The signed clearance (m) with ``b`` moved by ``relative`` ``(4, 4)`` into ``a``'s frame (both at home
        for the identity): Eqs. (CL1)-(CL3)."""
        relative = np.asarray(relative, dtype=float)
        a, b = self.sides
        a.place(np.eye(4))
        b.place(relative)
        checks = [(a.whole, b.whole)] if self.zone is None else [(a.rest, b.whole), (a.whole, b.rest)]
        checks = [(x, y) for x, y in checks if x is not None and y is not None]
        if not checks:  # both surfaces lie wholly in the joint zone: nothing is measured
            return np.inf
        crossing = any(fcl.collide(x, y, fcl.CollisionRequest(), fcl.CollisionResult()) > 0 for x, y in checks)
        if crossing or self._may_nest(relative):
            depth = self._depth(relative)
            if depth is not None:
                return -depth
        return min(fcl.distance(x, y, fcl.DistanceRequest(), fcl.DistanceResult()) for x, y in checks)

    def _may_nest(self, relative: NDArray[np.float64]) -> bool:
        """Whether the measured surface of one solid lies within the bounding box of the other (both in ``a``'s
        frame): only then can it lie wholly inside it without the surfaces crossing."""
        a, b = self.sides
        inner_b = b.rest_vertices @ relative[:3, :3].T + relative[:3, 3]
        box_a = a.solid.vertices.min(axis=0), a.solid.vertices.max(axis=0)
        vertices_b = b.solid.vertices @ relative[:3, :3].T + relative[:3, 3]
        box_b = vertices_b.min(axis=0), vertices_b.max(axis=0)
        return _within(inner_b, box_a) or _within(a.rest_vertices, box_b)

    def _depth(self, relative: NDArray[np.float64]) -> float | None:
        """The penetration depth (Eq. (CL2)) over the measured surfaces, ``None`` when no measured part of either
        surface lies inside the other solid. The regions are the triangles of the (zone-cut) solids' intersection
        that come from each surface; their distances are to the other's whole surface."""
        a, b = self.sides
        common = (a.cut ^ b.cut.transform(relative[:3, :4])).to_mesh64()
        points = np.asarray(common.vert_properties)[:, :3]
        inverse = np.linalg.inv(relative)
        depth = None
        for side, other, to_other in ((a, b, inverse), (b, a, np.eye(4))):
            region = _triangles_from(common, side.original)
            if len(region):
                moved = points @ to_other[:3, :3].T + to_other[:3, 3]
                deepest = _deepest(moved, region, other, self.tolerance)
                depth = deepest if depth is None else max(depth, deepest)
        return depth


def signed_distance(
    a: LinkSolid,
    b: LinkSolid,
    relative: ArrayLike | None = None,
    zone: JointZone | None = None,
    tolerance: float = DEPTH_TOLERANCE,
) -> float:
    """The signed clearance of ``a`` and ``b`` (m; negative: penetration depth), ``b`` moved by ``relative``
    (default: as given), Eqs. (CL1)-(CL3); for many poses of one pair build a :class:`SolidPair` once."""
    return SolidPair(a, b, zone, tolerance).clearance(np.eye(4) if relative is None else relative)


def _bvh(vertices: NDArray[np.float64], triangles: NDArray[np.int64]) -> fcl.BVHModel:
    model = fcl.BVHModel()
    model.beginModel(len(vertices), len(triangles))
    model.addSubModel(vertices, triangles)
    model.endModel()
    return model


def _triangles_from(mesh: manifold3d.Mesh64, original: int) -> NDArray[np.int64]:
    """The triangles of a boolean's ``mesh`` that come from the solid with id ``original``."""
    triangles = np.asarray(mesh.tri_verts, dtype=np.int64).reshape(-1, 3)
    runs = np.asarray(mesh.run_index, dtype=np.int64) // 3
    ids = np.asarray(mesh.run_original_id)
    return np.concatenate(
        [triangles[runs[k] : runs[k + 1]] for k in np.flatnonzero(ids == original)] or [triangles[:0]]
    )


def _within(points: NDArray[np.float64], box: tuple[NDArray, NDArray]) -> bool:
    return bool(len(points)) and bool(np.all(points.min(axis=0) >= box[0]) and np.all(points.max(axis=0) <= box[1]))


def _deepest(points: NDArray[np.float64], triangles: NDArray[np.int64], other: _Side, tolerance: float) -> float:
    r"""Largest distance to ``other``'s surface over the region ``triangles`` (indices into ``points``, given in
    ``other``'s home frame), to within ``tolerance``, by branch and bound (module docstring).

    For a piece with corners :math:`v_i`, the distance to the surface is at most the distance to any point
    :math:`q_j` of it (the nearest to corner ``j``) and to any triangle :math:`T_j` of it (the one FCL names with
    that point); these six distances are convex, so each is at most the linear interpolation of its corner values;
    the bound is the largest value over the piece of the least of these interpolants (:func:`_max_min_linear`;
    exact where the distance is that to one plane, too high only to second order in the piece's size elsewhere).
    A piece is split in four (at its edges' midpoints, each midpoint evaluated once) while its bound exceeds the
    largest distance found by more than ``tolerance``."""
    used, local = np.unique(triangles, return_inverse=True)
    points = points[used]
    pieces = local.reshape(-1, 3)
    distances, nearest, named = other.point_distances(points)
    best = float(distances.max())
    corners = other.solid.corners
    while len(pieces):
        at = points[pieces]  # (m, 3 corners, 3)
        to_points = np.linalg.norm(at[:, None, :, :] - nearest[pieces][:, :, None, :], axis=3)
        triangles_j = np.repeat(corners[named[pieces]], 3, axis=1).reshape(-1, 3, 3)
        flat = np.tile(at, (1, 3, 1)).reshape(-1, 3)
        to_triangles = np.linalg.norm(_closest_on_triangles(triangles_j, flat) - flat, axis=1).reshape(-1, 3, 3)
        bound = _max_min_linear(np.concatenate([to_points, to_triangles], axis=1))
        pieces = pieces[bound > best + tolerance]
        if not len(pieces):
            break
        pieces, points, new = _split(pieces, points)
        added, added_nearest, added_named = other.point_distances(points[new:])
        nearest = np.concatenate([nearest, added_nearest])
        named = np.concatenate([named, added_named])
        best = max(best, float(added.max()))
    return best


def _max_min_linear(values: NDArray[np.float64]) -> NDArray[np.float64]:
    r"""Per piece, :math:`\max_\lambda \min_j \sum_i \lambda_i F_{ji}` over the barycentric coordinates
    :math:`\lambda` of a triangle, ``values`` ``(m, J, 3)`` holding :math:`F_{ji}`: the largest of the least of
    ``J`` linear functions given at the corners. A linear programme whose optimum lies at a corner, where two
    functions cross on an edge, or where three are equal inside; all these candidates are tried."""
    functions = values.shape[1]
    best = values.min(axis=1).max(axis=1)  # the corners
    for i0, i1 in ((0, 1), (1, 2), (2, 0)):
        for j, k in itertools.combinations(range(functions), 2):
            start = values[:, j, i0] - values[:, k, i0]
            end = values[:, j, i1] - values[:, k, i1]
            crosses = start * end < 0.0
            s = np.where(crosses, start / np.where(crosses, start - end, 1.0), 0.0)
            at = (1.0 - s)[:, None] * values[:, :, i0] + s[:, None] * values[:, :, i1]
            best = np.where(crosses, np.maximum(best, at.min(axis=1)), best)
    scale = np.maximum(1.0, np.abs(values).max(axis=(1, 2))) ** 2
    for j, k, m in itertools.combinations(range(functions), 3):
        system = np.stack(
            [values[:, j] - values[:, k], values[:, j] - values[:, m], np.ones_like(values[:, j])], axis=1
        )
        solvable = np.abs(np.linalg.det(system)) > 1e-12 * scale
        if not solvable.any():
            continue
        inner = np.zeros((len(values), 3))
        rhs = np.broadcast_to(np.array([0.0, 0.0, 1.0]), (int(solvable.sum()), 3))
        inner[solvable] = np.linalg.solve(system[solvable], rhs[:, :, None])[:, :, 0]
        inside = solvable & np.all(inner >= 0.0, axis=1)
        level = np.einsum("mji,mi->mj", values, inner).min(axis=1)
        best = np.where(inside, np.maximum(best, level), best)
    return best


def _split(pieces: NDArray[np.int64], points: NDArray[np.float64]) -> tuple[NDArray, NDArray, int]:
    """Each triangle into four at its edges' midpoints: the new triangles, the points with the midpoints appended
    (one per edge) and the index of the first midpoint."""
    edges = np.sort(np.stack([pieces[:, [0, 1]], pieces[:, [1, 2]], pieces[:, [2, 0]]], axis=1), axis=2)
    unique, index = np.unique(edges.reshape(-1, 2), axis=0, return_inverse=True)
    first = len(points)
    points = np.concatenate([points, 0.5 * (points[unique[:, 0]] + points[unique[:, 1]])])
    ab, bc, ca = (first + index.reshape(-1, 3)).T
    a, b, c = pieces.T
    children = np.concatenate([np.stack(t, axis=1) for t in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))])
    return children, points, first


def _closest_on_triangles(triangles: NDArray[np.float64], points: NDArray[np.float64]) -> NDArray[np.float64]:
    """The point of each triangle ``(m, 3, 3)`` closest to the corresponding point ``(m, 3)`` (trimesh, exact)."""
    return np.asarray(trimesh.triangles.closest_point(triangles, points))
