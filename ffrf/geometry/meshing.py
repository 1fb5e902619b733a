"""Tetrahedral meshing with gmsh: sessions, meshing the current model, STL surfaces.

gmsh is meshed first order only: scikit-fem 12 cannot read the boundary
``triangle6`` cells of second-order gmsh meshes, so quadratic elements are
built later by scikit-fem (``ElementTetP2``) on the linear mesh, and the
interface groups are carried as linear boundary triangles.
"""

from __future__ import annotations

import contextlib
import logging
import math
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from ffrf.errors import MeshError
from ffrf.mesh.tet_mesh import TetMesh, orient_positive, quality_summary, unit_scale

__all__ = ["gmsh_session", "configure_meshing", "mesh_current_model", "mesh_stl"]

logger = logging.getLogger(__name__)

_GMSH_TET4 = 4
_GMSH_TRIANGLE3 = 2


@contextlib.contextmanager
def gmsh_session(model_name: str = "ffrf") -> Iterator[Any]:
    """Headless, single-threaded (hence deterministic) gmsh session; always finalised.

    Yields the ``gmsh`` module with a fresh model named ``model_name``.
    """
    import gmsh

    if gmsh.isInitialized():
        raise MeshError(
            "gmsh is already initialised by someone else; ffrf needs its own session (call gmsh.finalize() first)"
        )
    # gmsh installs a SIGINT handler when interruptible, which Python allows only in the main thread; a
    # worker thread (a Dask task, a thread pool) meshes without it.
    gmsh.initialize(readConfigFiles=False, interruptible=threading.current_thread() is threading.main_thread())
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.NumThreads", 1)
        for dim in ("1D", "2D", "3D"):
            gmsh.option.setNumber(f"Mesh.MaxNumThreads{dim}", 1)
        gmsh.model.add(model_name)
        yield gmsh
    finally:
        gmsh.finalize()


def configure_meshing(h: float, *, elements_per_circle: int = 12, length_scale: float = 1.0) -> None:
    """Set the mesh size options of the open gmsh session.

    Parameters
    ----------
    h : target maximum edge length in metres.
    elements_per_circle : curvature refinement so that small bores stay round at coarse ``h``.
    length_scale : metres per model unit (1e-3 when the gmsh model is in mm).
    """
    import gmsh

    if not h > 0.0:
        raise MeshError(f"mesh size h={h!r} m must be > 0")
    gmsh.option.setNumber("Mesh.MeshSizeMax", h / length_scale)
    gmsh.option.setNumber("Mesh.MeshSizeMin", 0.0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", elements_per_circle)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 1)
    gmsh.option.setNumber("Mesh.Algorithm", 6)  # Frontal-Delaunay 2D
    gmsh.option.setNumber("Mesh.Algorithm3D", 1)  # Delaunay 3D (deterministic single-threaded)
    gmsh.option.setNumber("Mesh.ElementOrder", 1)
    gmsh.option.setNumber("Mesh.Optimize", 1)
    gmsh.option.setNumber("Mesh.RandomSeed", 1)


def mesh_current_model(name: str = "mesh", *, length_scale: float = 1.0) -> TetMesh:
    """Generate the 3D mesh of the open gmsh model and return it as a :class:`TetMesh`.

    Every 2D physical group becomes a named group of boundary triangles.
    """
    import gmsh

    gmsh.model.mesh.generate(3)
    tags, coords, _ = gmsh.model.mesh.getNodes()
    _, tet_nodes = gmsh.model.mesh.getElementsByType(_GMSH_TET4)
    if len(tet_nodes) == 0:
        raise MeshError(f"{name}: gmsh produced no tetrahedra; is the geometry a closed volume?")
    index = np.full(int(tags.max()) + 1, -1, dtype=np.int64)
    index[tags.astype(np.int64)] = np.arange(len(tags))
    points = coords.reshape(-1, 3) * length_scale
    tets = index[tet_nodes.astype(np.int64)].reshape(-1, 4)
    groups: dict[str, np.ndarray] = {}
    for dim, ptag in gmsh.model.getPhysicalGroups(2):
        group_name = gmsh.model.getPhysicalName(dim, ptag) or f"surface_{ptag}"
        tris = []
        for entity in gmsh.model.getEntitiesForPhysicalGroup(dim, ptag):
            types, _, nodes = gmsh.model.mesh.getElements(dim, int(entity))
            for etype, enodes in zip(types, nodes, strict=True):
                if etype == _GMSH_TRIANGLE3:
                    tris.append(index[enodes.astype(np.int64)].reshape(-1, 3))
        groups[group_name] = np.concatenate(tris) if tris else np.zeros((0, 3), dtype=np.int64)
    used = np.unique(tets)
    if len(used) != len(points):
        # Nodes only on geometry of lower dimension not belonging to the volume: drop them.
        renumber = np.full(len(points), -1, dtype=np.int64)
        renumber[used] = np.arange(len(used))
        points, tets = points[used], renumber[tets]
        groups = {k: renumber[v] for k, v in groups.items()}
    tets = orient_positive(points, tets)
    mesh = TetMesh(points, tets, groups, name=name)
    quality = quality_summary(mesh)
    logger.info(
        "%s: meshed %d points, %d tetrahedra, mean-ratio quality min %.3f mean %.3f",
        name,
        quality.n_points,
        quality.n_tets,
        quality.min_quality,
        quality.mean_quality,
    )
    return mesh


def mesh_stl(
    path: str | Path,
    h: float | None = None,
    *,
    unit: str | None = None,
    scale: float | None = None,
    remesh_surface: bool = False,
    feature_angle_deg: float = 40.0,
) -> TetMesh:
    """Fill a closed STL surface with linear tetrahedra.

    Parameters
    ----------
    path : STL file.
    h : maximum edge length in metres for the volume (and the surface when ``remesh_surface``);
        ``None`` keeps gmsh's size from the STL triangles.
    unit, scale : units of the STL coordinates (``unit="mm"`` for millimetre files).
    remesh_surface : re-triangulate the surface at size ``h`` (gmsh classifySurfaces /
        createGeometry, as in gmsh tutorial t13); otherwise the STL triangles are kept.
    feature_angle_deg : angle between facets that marks a sharp edge when remeshing.
    """
    path = Path(path)
    if not path.is_file():
        raise MeshError(f"STL file {path} does not exist")
    factor = unit_scale(unit, scale)
    with gmsh_session(path.stem) as gmsh:
        try:
            gmsh.merge(str(path))
        except Exception as exc:
            raise MeshError(f"{path}: gmsh cannot read it as STL ({exc})") from exc
        gmsh.model.mesh.classifySurfaces(math.radians(feature_angle_deg), True, remesh_surface, math.pi)
        try:
            gmsh.model.mesh.createGeometry()
        except Exception as exc:  # gmsh raises a bare Exception
            if remesh_surface:
                raise MeshError(f"{path}: gmsh cannot rebuild the surface's geometry ({exc})") from exc
            # A patch with holes (a link's bores) has no parametrisation: keep the STL's own triangles as
            # discrete surfaces; the inside is then sized from them.
            logger.info("%s: surface kept as one discrete patch (%s)", path.name, exc)
            gmsh.clear()
            gmsh.merge(str(path))
        surfaces = [tag for _, tag in gmsh.model.getEntities(2)]
        loop = gmsh.model.geo.addSurfaceLoop(surfaces)
        gmsh.model.geo.addVolume([loop])
        gmsh.model.geo.synchronize()
        if h is not None:
            configure_meshing(h, length_scale=factor)
        try:
            mesh = mesh_current_model(path.stem, length_scale=factor)
        except Exception as exc:
            raise MeshError(
                f"{path}: gmsh could not fill the STL surface with tetrahedra ({exc}); "
                "is the surface closed and free of self-intersections?"
            ) from exc
    return mesh
