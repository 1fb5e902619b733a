"""Node sets of a model given by nodes and volume elements: by point, plane or box, and surface weights.

Exudyn's ``FEMinterface`` selection helpers, on plain arrays, so that they serve any model
(:class:`ffrf.fe.external_model.ExternalFEModel` in particular):

* :func:`node_at_point` (``GetNodeAtPoint``), :func:`nodes_in_plane` (``GetNodesInPlane``) and
  :func:`nodes_in_box` (``GetNodesInCube``);
* :func:`on_cylinder`: which points lie on a cylinder surface (a bearing bore), for any point cloud;
* :func:`surface_triangles` (``VolumeToSurfaceElements``): the element faces that belong to one
  element only, by their corner nodes, quadrilaterals split into two triangles as Exudyn does;
* :func:`surface_area_weights` (``GetNodeWeightsFromSurfaceAreas``): every surface triangle whose
  three corners are in the set adds a third of its area to each corner (eq. (X4)).

For quadratic elements only corners carry weight (Exudyn's rule); :mod:`ffrf.fe.interfaces` puts
the consistent load of 6-node triangles on the mid-side nodes instead.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ffrf.errors import InterfaceError, MeshError

__all__ = [
    "FACES",
    "node_at_point",
    "nodes_in_plane",
    "nodes_in_box",
    "on_cylinder",
    "surface_triangles",
    "surface_area_weights",
]

#: Faces of each element type by local corner index (Exudyn's tables; Abaqus node order).
FACES: dict[str, list[list[int]]] = {
    "Tet4": [[0, 1, 2], [0, 3, 1], [1, 3, 2], [2, 3, 0]],
    "Tet10": [[0, 1, 2], [0, 3, 1], [1, 3, 2], [2, 3, 0]],
    "Hex8": [[0, 1, 2, 3], [7, 6, 5, 4], [0, 4, 5, 1], [1, 5, 6, 2], [2, 6, 7, 3], [3, 7, 4, 0]],
    "Hex20": [[0, 1, 2, 3], [7, 6, 5, 4], [0, 4, 5, 1], [1, 5, 6, 2], [2, 6, 7, 3], [3, 7, 4, 0]],
}


def node_at_point(nodes: ArrayLike, point: ArrayLike, tolerance: float = 1e-5) -> int:
    """Index of the node within ``tolerance`` of ``point`` in every coordinate (the nearest one if
    several are)."""
    nodes, point = np.asarray(nodes, dtype=float), np.asarray(point, dtype=float)
    distance = np.abs(nodes - point).max(axis=1)
    nearest = int(np.argmin(np.linalg.norm(nodes - point, axis=1) + np.where(distance <= tolerance, 0.0, np.inf)))
    if distance[nearest] > tolerance:
        closest = int(np.argmin(distance))
        raise InterfaceError(
            f"no node within {tolerance:g} of {point.tolist()}: the nearest, node {closest} at "
            f"{nodes[closest].tolist()}, is {distance[closest]:.3g} away; check the point and the units"
        )
    return nearest


def nodes_in_plane(nodes: ArrayLike, point: ArrayLike, normal: ArrayLike, tolerance: float = 1e-5) -> NDArray[np.int64]:
    """Indices (ascending) of the nodes within ``tolerance`` of the plane through ``point`` with
    ``normal`` (any length; Exudyn assumes a unit normal)."""
    nodes, normal = np.asarray(nodes, dtype=float), np.asarray(normal, dtype=float)
    length = float(np.linalg.norm(normal))
    if not length > 0.0:
        raise InterfaceError(f"plane normal {normal.tolist()} has zero length; give the plane's normal direction")
    found = np.flatnonzero(np.abs((nodes - np.asarray(point, dtype=float)) @ (normal / length)) <= tolerance)
    if found.size == 0:
        raise InterfaceError(
            f"no node within {tolerance:g} of the plane through {np.asarray(point).tolist()} with normal "
            f"{normal.tolist()}; check the plane and the units"
        )
    return found


def on_cylinder(
    points: ArrayLike,
    point: ArrayLike,
    direction: ArrayLike,
    radius: float,
    axial_extent: tuple[float, float],
    tol: float,
) -> NDArray[np.bool_]:
    """Which ``points`` lie on the cylinder surface: distance to the axis within ``tol`` of ``radius`` and
    axial coordinate t = (p - point) . direction (unit) in ``[axial_extent[0] - tol, axial_extent[1] + tol]``."""
    d = np.asarray(direction, dtype=float)
    norm = np.linalg.norm(d)
    if not norm > 0.0:
        raise InterfaceError(f"cylinder selection: axis direction {direction!r} has zero length")
    if not (radius > 0.0 and tol > 0.0):
        raise InterfaceError(f"cylinder selection: radius={radius!r} and tol={tol!r} must be > 0 (metres)")
    t_min, t_max = axial_extent
    if t_max < t_min:
        raise InterfaceError(f"cylinder selection: axial_extent {axial_extent!r} is reversed; give (t_min, t_max)")
    d = d / norm
    rel = np.asarray(points, dtype=float) - np.asarray(point, dtype=float)
    t = rel @ d
    r = np.linalg.norm(rel - np.outer(t, d), axis=1)
    return (np.abs(r - radius) <= tol) & (t >= t_min - tol) & (t <= t_max + tol)


def nodes_in_box(nodes: ArrayLike, lower: ArrayLike, upper: ArrayLike) -> NDArray[np.int64]:
    """Indices (ascending) of the nodes with ``lower <= x <= upper`` in every coordinate (bounds included)."""
    nodes, lower, upper = (np.asarray(v, dtype=float) for v in (nodes, lower, upper))
    if np.any(lower > upper):
        raise InterfaceError(f"box {lower.tolist()} .. {upper.tolist()}: a lower bound exceeds its upper bound")
    found = np.flatnonzero(np.all((nodes >= lower) & (nodes <= upper), axis=1))
    if found.size == 0:
        raise InterfaceError(
            f"no node in the box {lower.tolist()} .. {upper.tolist()}; check the corners and the units"
        )
    return found


def surface_triangles(elements: Mapping[str, ArrayLike]) -> NDArray[np.int64]:
    """(m, 3) corner triangles of the faces that belong to one element only; a quadrilateral face
    (q0, q1, q2, q3) gives (q0, q1, q2) and (q0, q2, q3)."""
    faces: list[NDArray[np.int64]] = []
    for kind, table in elements.items():
        if kind not in FACES:
            raise MeshError(
                f"surface of {kind!r} elements is not known (known: {sorted(FACES)}); select interface nodes and "
                "give their weights explicitly"
            )
        table = np.asarray(table, dtype=np.int64)
        faces += [table[:, face] for face in FACES[kind]]
    if not faces:
        raise MeshError("the model has no volume elements, so no surface; give interface weights explicitly")
    triangles, quads = [f for f in faces if f.shape[1] == 3], [f for f in faces if f.shape[1] == 4]
    boundary = []
    for group in (triangles, quads):
        if group:
            stacked = np.concatenate(group)
            _, first, counts = np.unique(np.sort(stacked, axis=1), axis=0, return_index=True, return_counts=True)
            boundary.append(stacked[np.sort(first[counts == 1])])
    trigs = [b for b in boundary if b.shape[1] == 3]
    quad_faces = [b for b in boundary if b.shape[1] == 4]
    if quad_faces:
        q = quad_faces[0]
        trigs.append(np.stack([q[:, [0, 1, 2]], q[:, [0, 2, 3]]], axis=1).reshape(-1, 3))
    return np.concatenate(trigs) if trigs else np.zeros((0, 3), dtype=np.int64)


def surface_area_weights(
    nodes: ArrayLike, triangles: ArrayLike, node_set: ArrayLike, normalize: bool = True
) -> NDArray[np.float64]:
    """Weights of ``node_set`` (same order) from the surface ``triangles`` whose three corners are
    all in the set: each adds area/3 to its corners (eq. (X4)); normalised to sum 1 unless
    ``normalize=False`` (then they are areas in m^2)."""
    nodes = np.asarray(nodes, dtype=float)
    selected = np.asarray(node_set, dtype=np.int64).reshape(-1)
    triangles = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    if selected.size == 0 or selected.min() < 0 or selected.max() >= len(nodes):
        raise InterfaceError(f"node set is empty or has indices outside [0, {len(nodes)}); pass 0-based node indices")
    local = np.full(len(nodes), -1)
    local[selected] = np.arange(len(selected))
    inside = triangles[(local[triangles] >= 0).all(axis=1)]
    p = nodes[inside]
    areas = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    weights = np.zeros(len(selected))
    np.add.at(weights, local[inside].reshape(-1), np.repeat(areas / 3.0, 3))
    if not weights.sum() > 0.0:
        raise InterfaceError(
            f"the {len(selected)} nodes span no surface triangle, so they carry no area; select surface nodes"
        )
    return weights / weights.sum() if normalize else weights
