"""Interface node sets (joint bores, clamping faces) with surface-area weights.

Weights are the consistent nodal loads of a uniform unit traction on the
interface surface, normalised to sum 1; they are what Exudyn's
``GetNodeWeightsFromSurfaceAreas`` computes for linear triangles (only
triangles whose three nodes are all in the set count).

* P1: every triangle adds area/3 to each of its three vertices.
* P2: the set holds the vertices *and* the midside nodes of the interface
  triangles, so that the whole bore surface moves with the joint. The exact
  consistent load of the 6-node triangle is 0 at the corners and area/3 at
  each midside node (Zienkiewicz, Taylor & Zhu, The Finite Element Method:
  Its Basis and Fundamentals, 7th ed., sec. 6.3.5, uniform load on quadratic
  triangles), so corner weights are 0 there. Weighted averages of interface
  motion then use midside nodes only, which is exact for the surface integral.

One rule for every selector (group, cylinder, node list or nodes file): the
weights come from the boundary triangles the selection spans, unless the user
gives a weight per node explicitly.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ffrf.errors import InterfaceError
from ffrf.fe.fe_model import FEModel
from ffrf.fe.node_selection import on_cylinder
from ffrf.mesh.tet_mesh import TetMesh

__all__ = [
    "InterfaceNodes",
    "boundary_triangles",
    "checked_node_list",
    "given_weights",
    "interface_from_group",
    "interface_from_nodes",
    "interface_from_nodes_file",
    "interface_from_triangles",
    "interface_in_cylinder",
    "interface_around_axis",
    "read_nodes_file",
    "triangles_in_cylinder",
    "triangles_spanned_by",
]

logger = logging.getLogger(__name__)

# Relative size of the second singular value below which a node cloud is a line.
_COLLINEAR_REL_TOL = 1e-9


@dataclass(frozen=True, eq=False)
class InterfaceNodes:
    """Nodes of one interface surface and their area weights (sum 1).

    Attributes
    ----------
    name : interface name, e.g. ``"joint0"`` or ``"mount"``.
    nodes : indices into :attr:`FEModel.nodes`, sorted.
    weights : same length as ``nodes``, non-negative, sum 1.
    area : total surface area in m^2 (NaN for sets built from bare nodes).
    """

    name: str
    nodes: NDArray[np.int64]
    weights: NDArray[np.float64]
    area: float

    @property
    def dofs(self) -> NDArray[np.int64]:
        """DOF indices [x, y, z] of every node, in the package layout."""
        return (3 * self.nodes[:, None] + np.arange(3)).reshape(-1)

    def weighted_center(self, nodes: ArrayLike) -> NDArray[np.float64]:
        """Area-weighted centre of the interface, given all model node coordinates."""
        return self.weights @ np.asarray(nodes)[self.nodes]


def boundary_triangles(mesh: TetMesh, outward: bool = False) -> NDArray[np.int64]:
    """All boundary faces (faces used by exactly one tetrahedron), shape (m, 3); with ``outward`` each ordered so
    that its normal (right-hand rule) points out of the mesh (the tetrahedra's positive order makes that so)."""
    local = np.array(
        [[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]] if outward else [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]]
    )
    faces = mesh.tets[:, local].reshape(-1, 3)
    _, first, counts = np.unique(np.sort(faces, axis=1), axis=0, return_index=True, return_counts=True)
    return faces[np.sort(first[counts == 1])]


def _triangle_areas(points: NDArray, tris: NDArray) -> NDArray[np.float64]:
    p = points[tris]
    return 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)


def _midside_nodes(model: FEModel, tris: NDArray[np.int64]) -> NDArray[np.int64]:
    """(m, 3) node indices of the midpoints of edges (0,1), (1,2), (2,0) of each triangle."""
    nv = model.n_vertices
    keys = np.sort(model.edges, axis=1) @ np.array([nv, 1])
    order = np.argsort(keys)
    pairs = np.stack([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]], axis=1)
    query = np.sort(pairs, axis=2) @ np.array([nv, 1])
    pos = np.searchsorted(keys, query, sorter=order)
    found = order[np.clip(pos, 0, len(order) - 1)]
    if not np.array_equal(keys[found], query):
        raise InterfaceError(f"{model.mesh.name}: interface triangle edges are not edges of the volume mesh")
    return nv + found


def interface_from_triangles(model: FEModel, name: str, triangles: ArrayLike) -> InterfaceNodes:
    """Interface from boundary triangles of the linear mesh (indices into ``model.mesh.points``)."""
    tris = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    if len(tris) == 0:
        raise InterfaceError(
            f"interface {name!r} of {model.mesh.name}: no surface triangles selected; "
            "check the group name, the cylinder radius/axis/extent and the units (metres)"
        )
    if tris.min() < 0 or tris.max() >= model.n_vertices:
        raise InterfaceError(
            f"interface {name!r} of {model.mesh.name}: triangle vertex index out of range "
            f"[0, {model.n_vertices}); triangles index the linear mesh points"
        )
    areas = _triangle_areas(model.mesh.points, tris)
    # P1: area/3 to each vertex; P2: area/3 to each midside node, 0 to the corners (module docstring).
    loads = np.repeat(areas[:, None] / 3.0, 3, axis=1)
    if model.order == 1:
        carriers = tris
        all_nodes = tris.reshape(-1)
    else:
        carriers = _midside_nodes(model, tris)
        all_nodes = np.concatenate([tris.reshape(-1), carriers.reshape(-1)])
    nodes = np.unique(all_nodes)
    weights = np.zeros(len(nodes))
    np.add.at(weights, np.searchsorted(nodes, carriers.reshape(-1)), loads.reshape(-1))
    total = float(areas.sum())
    if not total > 0.0:
        raise InterfaceError(f"interface {name!r} of {model.mesh.name}: the selected triangles have zero area")
    _check_not_collinear(name, model, nodes[weights > 0.0])
    return InterfaceNodes(name, nodes, weights / weights.sum(), total)


def _check_not_collinear(name: str, model: FEModel, nodes: NDArray[np.int64]) -> None:
    coords = model.nodes[nodes]
    if len(coords) < 3:
        raise InterfaceError(
            f"interface {name!r} of {model.mesh.name}: only {len(coords)} weighted nodes; "
            "an interface needs at least 3 non-collinear nodes to transmit moments"
        )
    s = np.linalg.svd(coords - coords.mean(axis=0), compute_uv=False)
    if s[1] <= _COLLINEAR_REL_TOL * s[0]:
        raise InterfaceError(
            f"interface {name!r} of {model.mesh.name}: its {len(coords)} nodes are collinear; "
            "it cannot transmit a moment about that line, select a surface patch instead"
        )


def triangles_spanned_by(mesh: TetMesh, nodes: ArrayLike) -> NDArray[np.int64]:
    """Boundary triangles whose three vertices are all in ``nodes`` (indices of ``mesh.points``)."""
    inside = np.zeros(len(mesh.points), dtype=bool)
    vertices = np.asarray(nodes, dtype=np.int64)
    inside[vertices[vertices < len(mesh.points)]] = True
    tris = boundary_triangles(mesh)
    return tris[inside[tris].all(axis=1)]


def interface_from_nodes(
    model: FEModel, name: str, nodes: ArrayLike, weights: ArrayLike | None = None
) -> InterfaceNodes:
    """Interface from an explicit node list (e.g. a user's box selection).

    Without ``weights`` the rule of every selector applies: area weights of the
    boundary triangles the nodes span (:func:`triangles_spanned_by`, then
    :func:`interface_from_triangles`, which adds a P2 model's midside nodes);
    listed nodes on no spanned triangle stay in the set with weight 0. Given
    ``weights`` are used as they are, normalised to sum 1.
    """
    where = f"interface {name!r} of {model.mesh.name}"
    unique, first = checked_node_list(nodes, len(model.nodes), where)
    if weights is None:
        return _area_weighted(model, name, unique)
    w = given_weights(weights, first, where)
    _check_not_collinear(name, model, unique[w > 0.0])
    return InterfaceNodes(name, unique, w, float("nan"))


def checked_node_list(nodes: ArrayLike, n_nodes: int, where: str) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """(sorted unique nodes, index of each in ``nodes``) of a node list of a model with ``n_nodes``
    nodes; an empty list, an index outside [0, n_nodes) or a repeated node is refused, naming ``where``."""
    nodes = np.asarray(nodes, dtype=np.int64).reshape(-1)
    if nodes.size == 0:
        raise InterfaceError(f"{where}: the node set is empty; check the selection and the units (metres)")
    if nodes.min() < 0 or nodes.max() >= n_nodes:
        raise InterfaceError(f"{where}: node index out of range [0, {n_nodes}); indices are 0-based")
    unique, first = np.unique(nodes, return_index=True)
    if len(unique) != len(nodes):
        raise InterfaceError(f"{where}: {len(nodes) - len(unique)} duplicate nodes; pass each node once")
    return unique, first


def given_weights(weights: ArrayLike, first: NDArray[np.int64], where: str) -> NDArray[np.float64]:
    """Weights given per listed node, checked and normalised to sum 1, in the order of the unique nodes
    (``first`` from :func:`checked_node_list`)."""
    w = np.asarray(weights, dtype=float).reshape(-1)
    if w.shape != first.shape or not np.all(np.isfinite(w)) or np.any(w < 0.0) or not w.sum() > 0.0:
        raise InterfaceError(f"{where}: weights must be {len(first)} finite non-negative numbers with a positive sum")
    return w[first] / w.sum()


def _area_weighted(model: FEModel, name: str, nodes: NDArray[np.int64]) -> InterfaceNodes:
    """Area weights of the boundary triangles spanned by ``nodes``; other listed nodes get weight 0."""
    tris = triangles_spanned_by(model.mesh, nodes)
    if len(tris) == 0:
        raise InterfaceError(
            f"interface {name!r} of {model.mesh.name}: its {len(nodes)} nodes span no boundary "
            "triangle, so they carry no surface area; select surface nodes, or give a weight "
            "per node (second column of a nodes_file)"
        )
    surface = interface_from_triangles(model, name, tris)
    extra = np.setdiff1d(nodes, surface.nodes)
    if extra.size == 0:
        return surface
    logger.warning(
        "interface %r of %s: %d listed nodes lie on no spanned boundary triangle; they stay in the "
        "interface with weight 0",
        name,
        model.mesh.name,
        extra.size,
    )
    all_nodes = np.union1d(surface.nodes, extra)
    weights = np.zeros(len(all_nodes))
    weights[np.searchsorted(all_nodes, surface.nodes)] = surface.weights
    return InterfaceNodes(name, all_nodes, weights, surface.area)


def read_nodes_file(name: str, path: str | Path) -> tuple[NDArray[np.int64], NDArray[np.float64] | None]:
    """0-based node indices of a text file, one per line, and the optional second column of weights
    (``None`` without it), for interface ``name``."""
    path = Path(path)
    if not path.is_file():
        raise InterfaceError(f"interface {name!r}: nodes_file {path} not found; give a path relative to the scene file")
    if not path.read_text().strip():
        raise InterfaceError(f"interface {name!r}: nodes_file {path} is empty; write one node index per line")
    try:
        table = np.loadtxt(path, ndmin=2)
    except ValueError as error:
        raise InterfaceError(
            f"interface {name!r}: nodes_file {path} is not a table of numbers ({error}); "
            "write one node index per line, optionally followed by its weight"
        ) from error
    if table.shape[1] > 2:
        raise InterfaceError(
            f"interface {name!r}: nodes_file {path} has {table.shape[1]} columns; write one "
            "node index per line, optionally followed by its weight"
        )
    indices = table[:, 0]
    if not np.all(indices == np.round(indices)):
        raise InterfaceError(
            f"interface {name!r}: nodes_file {path} lists non-integer node indices; the first "
            "column holds 0-based node indices"
        )
    return indices.astype(np.int64), (table[:, 1] if table.shape[1] == 2 else None)


def interface_from_nodes_file(model: FEModel, name: str, path: str | Path) -> InterfaceNodes:
    """Interface from a text file of 0-based node indices, one per line, with an optional second
    column of weights (otherwise area weights, as :func:`interface_from_nodes`)."""
    indices, weights = read_nodes_file(name, path)
    return interface_from_nodes(model, name, indices, weights)


def interface_from_group(model: FEModel, name: str, group: str | None = None) -> InterfaceNodes:
    """Interface from a named group (gmsh physical group) of the model's mesh."""
    group = name if group is None else group
    if group not in model.mesh.groups:
        raise InterfaceError(
            f"{model.mesh.name}: no physical group {group!r} for interface {name!r}; "
            f"available: {sorted(model.mesh.groups)}"
        )
    return interface_from_triangles(model, name, model.mesh.groups[group])


def triangles_in_cylinder(
    mesh: TetMesh, point: ArrayLike, direction: ArrayLike, radius: float, axial_extent: tuple[float, float], tol: float
) -> NDArray[np.int64]:
    """Boundary triangles whose three vertices lie on the cylinder surface.

    A vertex is on it by :func:`ffrf.fe.node_selection.on_cylinder`.
    """
    on_surface = on_cylinder(mesh.points, point, direction, radius, axial_extent, tol)
    tris = boundary_triangles(mesh)
    return tris[on_surface[tris].all(axis=1)]


def interface_in_cylinder(
    model: FEModel,
    name: str,
    point: ArrayLike,
    direction: ArrayLike,
    radius: float,
    axial_extent: tuple[float, float],
    tol: float = 1e-4,
) -> InterfaceNodes:
    """Interface of the boundary triangles on a cylinder (e.g. a bearing bore); see
    :func:`triangles_in_cylinder` for the selection rule."""
    tris = triangles_in_cylinder(model.mesh, point, direction, radius, axial_extent, tol)
    if len(tris) == 0:
        shown = np.round(np.asarray(point, dtype=float), 6).tolist()
        raise InterfaceError(
            f"interface {name!r} of {model.mesh.name}: no boundary triangle lies on the cylinder "
            f"(point {shown}, radius {radius!r} m, extent {axial_extent!r} m, "
            f"tol {tol!r} m); check the axis, the radius and the units (metres)"
        )
    return interface_from_triangles(model, name, tris)


def interface_around_axis(
    model: FEModel, name: str, point: ArrayLike, direction: ArrayLike, tol: float = 1e-4
) -> InterfaceNodes:
    """The bore around a joint axis, found from the axis alone: the boundary triangles on the
    cylinder through the boundary vertices nearest to the axis (radius r_min, within ``tol``), over
    the axial extent of those vertices. For meshes of parts whose joint axes are known (scans,
    STL files) but whose bores carry no named group."""
    d = np.asarray(direction, dtype=float)
    norm = np.linalg.norm(d)
    if not norm > 0.0:
        raise InterfaceError(f"interface {name!r}: axis direction {direction!r} has zero length")
    d = d / norm
    mesh = model.mesh
    vertices = np.unique(boundary_triangles(mesh))
    rel = mesh.points[vertices] - np.asarray(point, dtype=float)
    t = rel @ d
    r = np.linalg.norm(rel - np.outer(t, d), axis=1)
    radius = float(r.min())
    if radius <= tol:
        shown = np.round(np.asarray(point, dtype=float), 6).tolist()
        raise InterfaceError(
            f"interface {name!r} of {mesh.name}: the axis through {shown} touches the body's "
            f"surface ({radius:.3g} m away); a bore around it has a radius > 0: check the axis and the units"
        )
    on_bore = np.abs(r - radius) <= tol
    extent = (float(t[on_bore].min()), float(t[on_bore].max()))
    return interface_in_cylinder(model, name, point, d, radius, extent, tol)
