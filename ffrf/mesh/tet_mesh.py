"""Linear tetrahedral meshes: the data class, checks, quality, meshio import and .vtu export.

Conventions (stated once for the package):

* ``points`` are in metres, shape (n, 3).
* ``tets`` are linear tetrahedra, shape (k, 4), ordered so that the signed
  volume ``det[p1 - p0, p2 - p0, p3 - p0] / 6`` is positive.
* ``groups`` maps a name (a gmsh physical group, e.g. ``"joint0"``) to boundary
  triangles, shape (m, 3), indexing ``points``.
"""

from __future__ import annotations

import contextlib
import io
import logging
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ffrf.errors import MeshError

__all__ = [
    "TetMesh",
    "MeshQuality",
    "MAX_LINK_EXTENT_M",
    "signed_volumes",
    "orient_positive",
    "mesh_quality",
    "quality_summary",
    "check_mesh",
    "unit_scale",
    "read_mesh",
    "write_vtu",
]

logger = logging.getLogger(__name__)

#: Larger models are almost certainly given in millimetres by mistake.
MAX_LINK_EXTENT_M = 10.0

# A tetrahedron whose volume is below this fraction of (mean edge length)^3 is
# degenerate: its stiffness would be ill-conditioned beyond repair.
_DEGENERATE_REL_VOLUME = 1e-10

_UNITS = {"m": 1.0, "mm": 1e-3, "cm": 1e-2}


@dataclass(frozen=True, eq=False)
class TetMesh:
    """Linear tetrahedral mesh with named boundary-triangle groups.

    Parameters
    ----------
    points : (n, 3) float array, metres.
    tets : (k, 4) int array, positive volume node order.
    groups : dict name -> (m, 3) int array of boundary triangles.
    name : label used in error messages.
    """

    points: NDArray[np.float64]
    tets: NDArray[np.int64]
    groups: dict[str, NDArray[np.int64]] = field(default_factory=dict)
    name: str = "mesh"

    def __post_init__(self) -> None:
        points = np.ascontiguousarray(self.points, dtype=np.float64)
        tets = np.ascontiguousarray(self.tets, dtype=np.int64)
        if points.ndim != 2 or points.shape[1] != 3:
            raise MeshError(f"{self.name}: points must have shape (n, 3), got {points.shape}")
        if tets.ndim != 2 or tets.shape[1] != 4:
            raise MeshError(f"{self.name}: tetrahedra must have shape (k, 4) (linear tets), got {tets.shape}")
        bad = np.flatnonzero(~np.isfinite(points).all(axis=1))
        if bad.size:  # scikit-fem would sort them away and every later number would be nan
            raise MeshError(
                f"{self.name}: {bad.size} points have coordinates that are not finite, first point {bad[0]} at "
                f"{points[bad[0]].tolist()}; fix the mesh file (a failed export or a division by zero)"
            )
        groups = {str(k): np.ascontiguousarray(v, dtype=np.int64).reshape(-1, 3) for k, v in self.groups.items()}
        object.__setattr__(self, "points", points)
        object.__setattr__(self, "tets", tets)
        object.__setattr__(self, "groups", groups)

    @property
    def volume(self) -> float:
        """Sum of the tetrahedron volumes (m^3)."""
        return float(signed_volumes(self.points, self.tets).sum())

    def scaled(self, factor: float) -> TetMesh:
        """Copy with all coordinates multiplied by ``factor`` (e.g. 1e-3 for mm -> m)."""
        return TetMesh(self.points * factor, self.tets, dict(self.groups), self.name)

    def group_nodes(self, name: str) -> NDArray[np.int64]:
        """Sorted unique point indices of a group's triangles."""
        if name not in self.groups:
            raise MeshError(f"{self.name}: no group {name!r}; available groups: {sorted(self.groups)}")
        return np.unique(self.groups[name])


@dataclass(frozen=True)
class MeshQuality:
    """Summary of the mean-ratio quality (1 = regular tetrahedron, 0 = flat)."""

    n_points: int
    n_tets: int
    min_quality: float
    mean_quality: float
    n_poor: int  # elements below 0.1

    def as_dict(self) -> dict[str, float | int]:
        return dict(
            n_points=self.n_points,
            n_tets=self.n_tets,
            min_quality=self.min_quality,
            mean_quality=self.mean_quality,
            n_poor_below_0_1=self.n_poor,
        )


def signed_volumes(points: ArrayLike, tets: ArrayLike) -> NDArray[np.float64]:
    """Signed tetrahedron volumes det[p1-p0, p2-p0, p3-p0] / 6.

    >>> signed_volumes([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], [[0, 1, 2, 3], [0, 2, 1, 3]]) * 6
    array([ 1., -1.])
    """
    p = np.asarray(points, dtype=float)[np.asarray(tets)]
    return np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p[:, 3] - p[:, 0]) / 6.0


def _edge_lengths_squared(points: NDArray, tets: NDArray) -> NDArray[np.float64]:
    p = points[tets]
    pairs = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
    return np.stack([np.sum((p[:, i] - p[:, j]) ** 2, axis=1) for i, j in pairs], axis=1)


def _degenerate(points: NDArray, tets: NDArray, volumes: NDArray) -> NDArray[np.bool_]:
    """Tetrahedra flatter than ``_DEGENERATE_REL_VOLUME`` (mean edge length)^3: no orientation, no stiffness."""
    mean_edge = float(np.sqrt(_edge_lengths_squared(points, tets)).mean())
    return np.abs(volumes) <= _DEGENERATE_REL_VOLUME * mean_edge**3


def orient_positive(
    points: ArrayLike, tets: ArrayLike, *, mixed_orders: bool = True, name: str = "mesh"
) -> NDArray[np.int64]:
    """``tets`` (a copy) with nodes 2 and 3 swapped in the tetrahedra of negative signed volume.

    With ``mixed_orders=True`` (for meshes generated here, by gmsh or scikit-fem, whose node order
    is not the convention; scikit-fem's tensor meshes mix both) each tetrahedron is turned on its
    own, silently. With
    ``mixed_orders=False`` (for a mesh read from a file) only a mesh whose every tetrahedron is
    inverted is turned, with a warning: that is the opposite convention (as NGsolve and some
    exporters write it). A mesh with both signs is then broken (folded or tangled elements) and
    refused with :class:`MeshError`, since no node swap repairs it. Degenerate tetrahedra have no
    sign and indices out of range are left alone; :func:`check_mesh` refuses them.

    >>> points = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
    >>> orient_positive(points, [[0, 1, 3, 2]]).tolist()
    [[0, 1, 2, 3]]
    """
    tets = np.array(tets, dtype=np.int64)
    if mixed_orders:
        negative = signed_volumes(points, tets) < 0.0
    else:
        points = np.asarray(points, dtype=float)
        if len(tets) == 0 or tets.min() < 0 or tets.max() >= len(points):
            return tets  # check_mesh names these errors
        volumes = signed_volumes(points, tets)
        signed = ~_degenerate(points, tets, volumes)
        inverted = signed & (volumes < 0.0)
        if not inverted.any():
            return tets
        if inverted.sum() < signed.sum():
            first = np.flatnonzero(inverted)[:3]
            centroids = points[tets[first]].mean(axis=1)
            raise MeshError(
                f"{name}: {int(inverted.sum())} of {int(signed.sum())} tetrahedra are inverted and "
                f"the others are not (first {first.tolist()} at {np.round(centroids, 6).tolist()} m): a "
                "folded or tangled mesh; remesh it"
            )
        warnings.warn(
            f"{name}: every tetrahedron has the opposite node order (negative volume); swapped nodes 2 and 3 of each",
            UserWarning,
            stacklevel=2,
        )
        negative = volumes < 0.0
    tets[negative, 2], tets[negative, 3] = tets[negative, 3], tets[negative, 2].copy()
    return tets


def mesh_quality(points: ArrayLike, tets: ArrayLike) -> NDArray[np.float64]:
    """Mean-ratio quality of each tetrahedron.

    q = 12 (3 ``|V|``)^(2/3) / sum of squared edge lengths, which is 1 for a regular
    tetrahedron and tends to 0 for flat ones (Liu & Joe, "Relationship between
    tetrahedron shape measures", BIT 34 (1994), eq. for eta).

    The regular tetrahedron of alternate cube corners (edges 2 sqrt 2, volume 8/3) has q = 1:

    >>> regular = [[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]]
    >>> mesh_quality(regular, [[0, 1, 2, 3]]).round(12).tolist()
    [1.0]
    """
    points = np.asarray(points, dtype=float)
    tets = np.asarray(tets)
    vol = np.abs(signed_volumes(points, tets))
    return 12.0 * (3.0 * vol) ** (2.0 / 3.0) / _edge_lengths_squared(points, tets).sum(axis=1)


def quality_summary(mesh: TetMesh) -> MeshQuality:
    """Element count and min/mean mean-ratio quality of a mesh."""
    q = mesh_quality(mesh.points, mesh.tets)
    return MeshQuality(len(mesh.points), len(mesh.tets), float(q.min()), float(q.mean()), int((q < 0.1).sum()))


def _face_adjacency_components(tets: NDArray[np.int64]) -> tuple[int, NDArray[np.int64]]:
    """Connected components of tetrahedra that share a face (sharing a vertex is a mechanism)."""
    local = np.array([[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]])
    faces = np.sort(tets[:, local].reshape(-1, 3), axis=1)
    owner = np.repeat(np.arange(len(tets)), 4)
    _, inverse, counts = np.unique(faces, axis=0, return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    order = np.argsort(inverse, kind="stable")
    shared = counts[inverse[order]] == 2
    pairs = owner[order][shared].reshape(-1, 2)
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(tets), len(tets)))
    return connected_components(graph, directed=False)


def check_mesh(mesh: TetMesh) -> None:
    """Raise :class:`MeshError` for meshes that cannot give a sound FE model.

    Checks: indices in range, every point used, extent below 10 m (units),
    no inverted or degenerate element, one face-connected part.
    """
    n = len(mesh.points)
    if len(mesh.tets) == 0:
        raise MeshError(f"{mesh.name}: the mesh has no tetrahedra; pass a volume mesh, not a surface")
    if mesh.tets.min() < 0 or mesh.tets.max() >= n:
        raise MeshError(
            f"{mesh.name}: tetrahedron node index out of range [0, {n}) "
            f"(min {mesh.tets.min()}, max {mesh.tets.max()}); indices must be 0-based"
        )
    unused = np.setdiff1d(np.arange(n), mesh.tets)
    if unused.size:
        raise MeshError(
            f"{mesh.name}: {unused.size} points are not used by any tetrahedron "
            f"(first: {unused[:5].tolist()}); remove them, they would be unconstrained DOFs"
        )
    extent = float(np.ptp(mesh.points, axis=0).max())
    if extent > MAX_LINK_EXTENT_M:
        raise MeshError(
            f"{mesh.name}: the mesh is {extent:.4g} m long (> {MAX_LINK_EXTENT_M} m): "
            "suspicious units, did you pass millimetres? use unit='mm'"
        )
    vol = signed_volumes(mesh.points, mesh.tets)
    degenerate = np.flatnonzero(_degenerate(mesh.points, mesh.tets, vol))
    if degenerate.size:
        raise MeshError(
            f"{mesh.name}: {degenerate.size} degenerate (flat) tetrahedra, first {degenerate[:5].tolist()} "
            f"with volume {vol[degenerate[0]]:.3g} m^3; remesh or remove sliver elements"
        )
    inverted = np.flatnonzero(vol < 0.0)
    if inverted.size:
        raise MeshError(
            f"{mesh.name}: {inverted.size} of {len(vol)} tetrahedra are inverted (negative volume), "
            f"first {inverted[:5].tolist()}; if the whole mesh uses the opposite node order, "
            "fix it with ffrf.mesh.tet_mesh.orient_positive(points, tets)"
        )
    n_parts, labels = _face_adjacency_components(mesh.tets)
    if n_parts > 1:
        sizes = np.bincount(labels)
        raise MeshError(
            f"{mesh.name}: the mesh has {n_parts} disconnected parts (element counts "
            f"{sorted(sizes.tolist(), reverse=True)[:6]}); a flexible body must be one connected solid"
        )


def unit_scale(unit: str | None = None, scale: float | None = None) -> float:
    """Factor that converts input coordinates to metres, from ``unit`` or ``scale``.

    >>> unit_scale("mm"), unit_scale(scale=0.0254), unit_scale()
    (0.001, 0.0254, 1.0)
    """
    if unit is not None and scale is not None:
        raise MeshError(f"give either unit={unit!r} or scale={scale!r}, not both")
    if unit is not None:
        if unit not in _UNITS:
            raise MeshError(f"unknown unit {unit!r}; use one of {sorted(_UNITS)}")
        return _UNITS[unit]
    return 1.0 if scale is None else float(scale)


def _compact(points: NDArray, tets: NDArray, groups: dict[str, NDArray]) -> tuple[NDArray, NDArray, dict]:
    """Drop points not used by any tetrahedron; renumber tets and groups."""
    used = np.unique(tets)
    new_index = np.full(len(points), -1, dtype=np.int64)
    new_index[used] = np.arange(len(used))
    kept = {}
    for name, tris in groups.items():
        mapped = new_index[tris]
        if (mapped < 0).any():
            logger.warning("group %r has triangles on points outside the volume mesh; dropped them", name)
            mapped = mapped[(mapped >= 0).all(axis=1)]
        kept[name] = mapped
    return points[used], new_index[tets], kept


def read_mesh(path: str | Path, *, unit: str | None = None, scale: float | None = None) -> TetMesh:
    """Read any meshio-readable volume mesh (.msh, .vtu, .inp, ...) as a :class:`TetMesh`.

    Quadratic ``tetra10`` cells are reduced to their 4 corner nodes (meshio and
    gmsh both list corners first). Named boundary triangles are taken from gmsh
    physical groups (``gmsh:physical`` + field data) or from an
    ``interface_id`` cell array written by :func:`write_vtu`. STL surfaces go
    through :func:`ffrf.geometry.meshing.mesh_stl` instead.
    """
    import meshio

    path = Path(path)
    if path.suffix.lower() == ".stl":
        raise MeshError(
            f"{path}: an STL file is a surface; use ffrf.geometry.meshing.mesh_stl to fill it with tetrahedra"
        )
    if not path.is_file():
        raise MeshError(f"{path}: mesh file not found")
    said = io.StringIO()  # meshio prints its own error lines (and may exit): keep them for our one line
    try:
        with contextlib.redirect_stdout(said), contextlib.redirect_stderr(said):
            raw = meshio.read(path)
    except (Exception, SystemExit) as exc:  # meshio raises a variety of types, and exits on some broken files
        why = " ".join(said.getvalue().split()) or str(exc)
        raise MeshError(f"{path}: meshio cannot read it ({why}); convert to .msh, .vtu or .inp") from exc
    if said.getvalue().strip():
        logger.info("meshio on %s: %s", path, said.getvalue().strip())
    tet_blocks = [c.data[:, :4] for c in raw.cells if c.type in ("tetra", "tetra10")]
    if not tet_blocks:
        raise MeshError(
            f"{path}: no tetrahedra found (cell types {[c.type for c in raw.cells]}); "
            "mesh the volume first, e.g. with ffrf.geometry.meshing"
        )
    tets = np.concatenate(tet_blocks).astype(np.int64)
    groups = _groups_from_meshio(raw)
    points, tets, groups = _compact(np.asarray(raw.points, dtype=float)[:, :3], tets, groups)
    factor = unit_scale(unit, scale)
    return TetMesh(points * factor, tets, groups, name=path.name)


def _groups_from_meshio(raw) -> dict[str, NDArray[np.int64]]:
    names_by_tag: dict[int, str] = {}
    for name, values in (raw.field_data or {}).items():
        values = np.atleast_1d(values)
        if len(values) >= 2 and int(values[1]) == 2:  # gmsh field data: (tag, dimension)
            names_by_tag[int(values[0])] = name
        elif len(values) == 1:  # written by write_vtu: (interface_id,)
            names_by_tag[int(values[0])] = name
    flagged = sorted(k[len("group:") :] for k in (raw.point_data or {}) if k.startswith("group:"))
    if not names_by_tag and flagged:
        # .vtu written by write_vtu (VTU keeps no field data): ids are 1.. over the sorted names.
        names_by_tag = {i: name for i, name in enumerate(flagged, start=1)}
    key = next((k for k in ("gmsh:physical", "interface_id") if k in raw.cell_data), None)
    groups: dict[str, list[NDArray]] = {}
    if key is None:
        return {}
    for block, tags in zip(raw.cells, raw.cell_data[key], strict=True):
        if block.type not in ("triangle", "triangle6"):
            continue
        for tag in np.unique(tags):
            if int(tag) in names_by_tag:
                groups.setdefault(names_by_tag[int(tag)], []).append(block.data[tags == tag, :3])
    return {k: np.concatenate(v).astype(np.int64) for k, v in groups.items()}


def write_vtu(path: str | Path, mesh: TetMesh, point_data: dict[str, ArrayLike] | None = None) -> Path:
    """Write the mesh, its groups (as triangles with ``interface_id`` and one 0/1
    point array ``group:<name>`` per group) and optional point data as a .vtu file for ParaView.

    Deformed states go in as point data on the mesh vertices, e.g.
    ``{"displacement": model.interleaved(u)[:model.n_vertices]}`` (for P2 models the
    vertex nodes come first, so this drops only the midside values).
    """
    import meshio

    path = Path(path)
    cells = [("tetra", mesh.tets)]
    cell_ids = [np.zeros(len(mesh.tets), dtype=np.int64)]
    field_data = {}
    data = {}
    for gid, (name, tris) in enumerate(sorted(mesh.groups.items()), start=1):
        cells.append(("triangle", tris))
        cell_ids.append(np.full(len(tris), gid, dtype=np.int64))
        field_data[name] = np.array([gid])
        flag = np.zeros(len(mesh.points))
        flag[np.unique(tris)] = 1.0
        data[f"group:{name}"] = flag
    for name, values in (point_data or {}).items():
        values = np.asarray(values, dtype=float)
        if values.shape[0] != len(mesh.points):
            raise MeshError(
                f"write_vtu: point data {name!r} has {values.shape[0]} rows, the mesh has {len(mesh.points)} points"
            )
        data[name] = values
    out = meshio.Mesh(mesh.points, cells, point_data=data, cell_data={"interface_id": cell_ids}, field_data=field_data)
    path.parent.mkdir(parents=True, exist_ok=True)
    out.write(path)
    return path
