r"""The design velocity of a parametric link's mesh: how each node moves per unit change of one dimension of its
:class:`~ffrf.geometry.link_geometry.LinkDesign` (``docs/formulation.md``, Eq. (D5)).

Remeshing a link at a changed dimension gives another mesh (other nodes, other tetrahedra), so a model built on it
is not a differentiable function of the dimension. Its derivative is taken instead along a *morph* of the
nominal mesh, :math:`x(p) = x_0 + (p - p_0)\,V`, with the velocity :math:`V` of every node:

* a node on a vertex, curve or face of the solid moves with that entity: its closest point on the same entity of the
  solids built at :math:`p_0 \pm \delta` (gmsh's OpenCASCADE projection), by central differences,
  :math:`V = (x_+ - x_-)/(2\delta)` (the boxes and cylinders move linearly in the dimension, their intersection
  curves smoothly: truncation :math:`O(\delta^2)`);
* only what defines the shape is prescribed: a vertex's whole velocity, a curve node's velocity across the curve, a
  face node's normal velocity (the whole velocity on the faces of the physical groups, the bores and the mount, whose
  nodes carry the joints' interfaces); along its curve or face a node slides freely, and every free component, with the
  interior nodes' velocities, minimises the velocity's Dirichlet energy :math:`\int |\nabla V|^2` (vector Laplace
  equation, P1 on the tetrahedra). Sliding spreads the motion of an edge (the arm's side sliding along the housing's
  cylinder) over the faces next to it instead of shearing the tetrahedra that touch it, so the morph keeps its
  tetrahedra valid over larger changes; the derivative at the nominal shape is the same to first order for any
  tangential motion of the boundary (it moves no material across the surface).

The entities of the shifted solids are matched to the nominal ones by proximity; a change of topology (an entity
with no counterpart within a few :math:`\delta`) is a :class:`~ffrf.errors.GeometryError`.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.linalg import splu
from scipy.spatial import cKDTree

from ffrf.errors import GeometryError
from ffrf.geometry.link_geometry import LINK_DESIGN_FIELDS, LinkDesign, build_link
from ffrf.mesh.tet_mesh import TetMesh

__all__ = ["SECTION_PARAMETERS", "VELOCITY_STEP", "design_velocity", "harmonic_extension"]

#: The dimensions of a link's section that a design changes without moving its bores (m).
SECTION_PARAMETERS = ("arm_width", "arm_thickness", "housing_outer_radius")
#: Relative change of the dimension in the central differences of the boundary's velocity.
VELOCITY_STEP = 1e-4
#: A node farther than this many steps from its entity's counterpart means the topology changed.
_MATCH_STEPS = 50.0


def design_velocity(build: dict[str, Any], h: float, parameter: str, name: str = "link") -> tuple[TetMesh, NDArray]:
    """The nominal mesh of the link that :func:`~ffrf.geometry.link_geometry.mesh_link` builds from ``build`` (the
    arguments of :func:`~ffrf.geometry.link_geometry.build_link` but ``gmsh``, e.g.
    :func:`ffrf.scenes.builder.parametric_link`'s) at edge ``h``, and the velocity ``(n, 3)`` of its points per unit
    change (m/m) of ``parameter``, a field of :class:`LinkDesign` (module docstring)."""
    from ffrf.geometry.meshing import configure_meshing, gmsh_session, mesh_current_model

    if parameter not in LINK_DESIGN_FIELDS:
        raise GeometryError(f"design parameter {parameter!r} is unknown; choose one of {LINK_DESIGN_FIELDS}")
    design: LinkDesign = build["design"]
    delta = VELOCITY_STEP * float(getattr(design, parameter))
    with gmsh_session(name) as gmsh:
        build_link(gmsh, **build)
        configure_meshing(h)
        mesh = mesh_current_model(name)
        on_entities = _classified_nodes(gmsh, mesh)
        # the faces of physical groups (bores, mount) and their edges carry the joints' interfaces: they do not slide
        faces = [
            (2, int(e))
            for _, group in gmsh.model.getPhysicalGroups(2)
            for e in gmsh.model.getEntitiesForPhysicalGroup(2, group)
        ]
        pinned = set(faces) | {(1, abs(int(tag))) for _, tag in gmsh.model.getBoundary(faces, combined=False)}
        frames = [
            _tangents(gmsh, 0 if (dim, tag) in pinned else dim, tag, coords, len(nodes))
            for dim, tag, nodes, coords in on_entities
        ]
        shifted = []
        for sign in (1.0, -1.0):
            model = f"{name} {sign:+g}"
            gmsh.model.add(model)
            moved = replace(design, **{parameter: getattr(design, parameter) + sign * delta})
            build_link(gmsh, **dict(build, design=moved))
            shifted.append(_projected(gmsh, on_entities, mesh.points, delta, parameter))
    boundary = np.concatenate([nodes for _, _, nodes, _ in on_entities])
    velocity = (shifted[0] - shifted[1]) / (2.0 * delta)
    slides = np.concatenate(frames)  # (k, 3, 2): the free directions of each boundary node (zero columns: none)
    across = velocity - np.einsum("kad,kd->ka", slides, np.einsum("kad,ka->kd", slides, velocity))
    return mesh, harmonic_extension(mesh, boundary, across, slides)


def _classified_nodes(gmsh: Any, mesh: TetMesh) -> list[tuple[int, int, NDArray[np.int64], NDArray[np.float64]]]:
    """``(dim, tag, mesh point indices, parametric coordinates)`` of the nodes gmsh placed on each vertex, curve
    and face of the current model (each node on exactly one entity: the lowest-dimensional one it lies on)."""
    tree = cKDTree(mesh.points)
    out = []
    for dim in (0, 1, 2):
        for _, tag in gmsh.model.getEntities(dim):
            _, coords, parametric = gmsh.model.mesh.getNodes(dim, tag, includeBoundary=False)
            if len(coords) == 0:
                continue
            distance, index = tree.query(np.reshape(coords, (-1, 3)))
            if distance.max() > 0.0:  # mesh_current_model keeps gmsh's coordinates as they are
                raise GeometryError(f"{mesh.name}: gmsh's nodes on entity ({dim}, {tag}) are not the mesh's points")
            out.append((dim, tag, index.astype(np.int64), np.asarray(parametric, dtype=float)))
    return out


def _tangents(gmsh: Any, dim: int, tag: int, parametric: NDArray, count: int) -> NDArray[np.float64]:
    """``(count, 3, 2)``: orthonormal directions in which the nodes at ``parametric`` coordinates of entity
    ``(dim, tag)`` slide (a vertex none, a curve its tangent, a face two directions normal to its normal; ``dim`` 0:
    none); unused columns are zero."""
    out = np.zeros((count, 3, 2))
    if dim == 1:
        tangent = np.reshape(gmsh.model.getDerivative(1, tag, parametric), (-1, 3))
        out[:, :, 0] = tangent / np.linalg.norm(tangent, axis=1, keepdims=True)
    elif dim == 2:
        normal = np.reshape(gmsh.model.getNormal(tag, parametric), (-1, 3))
        normal /= np.linalg.norm(normal, axis=1, keepdims=True)
        helper = np.where(np.abs(normal[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
        first = np.cross(normal, helper)
        first /= np.linalg.norm(first, axis=1, keepdims=True)
        out[:, :, 0], out[:, :, 1] = first, np.cross(normal, first)
    return out


def _projected(
    gmsh: Any, on_entities: list[tuple[int, int, NDArray, NDArray]], points: NDArray, delta: float, parameter: str
) -> NDArray[np.float64]:
    """The boundary nodes (in the order of ``on_entities``) moved onto the matching entities of the current
    model (the solid built with ``parameter`` shifted by ``delta``)."""
    tolerance = _MATCH_STEPS * delta
    candidates = {dim: [tag for _, tag in gmsh.model.getEntities(dim)] for dim in (0, 1, 2)}
    boxes = {
        (dim, tag): np.reshape(gmsh.model.getBoundingBox(dim, tag), (2, 3))
        for dim in (0, 1, 2)
        for tag in candidates[dim]
    }
    out = []
    for dim, tag, nodes, _ in on_entities:
        x = points[nodes]
        best, best_distance = None, np.inf
        for other in candidates[dim]:
            low, high = boxes[dim, other]
            if np.any(x.min(axis=0) < low - tolerance) or np.any(x.max(axis=0) > high + tolerance):
                continue
            projected = _closest(gmsh, dim, other, x)
            distance = float(np.linalg.norm(projected - x, axis=1).max())
            if distance < best_distance:
                best, best_distance = projected, distance
        if best is None or best_distance > tolerance:
            raise GeometryError(
                f"changing {parameter} by {delta:.3g} m changes the link's topology near entity ({dim}, {tag}) "
                f"(closest counterpart {best_distance:.3g} m away): its derivative is not defined there; "
                "take a nominal design away from that change"
            )
        out.append(best)
    return np.concatenate(out)


def _closest(gmsh: Any, dim: int, tag: int, x: NDArray) -> NDArray[np.float64]:
    """The points ``x`` ``(k, 3)`` projected on entity ``(dim, tag)`` of the current model (a vertex: itself)."""
    if dim == 0:
        return np.tile(np.reshape(gmsh.model.getValue(0, tag, []), (1, 3)), (len(x), 1))
    closest, _ = gmsh.model.getClosestPoint(dim, tag, np.ravel(x))
    return np.reshape(closest, (-1, 3))


def harmonic_extension(
    mesh: TetMesh, boundary: NDArray, values: NDArray, slides: NDArray | None = None
) -> NDArray[np.float64]:
    """The field ``(n, 3)`` on the mesh's points of least Dirichlet energy (P1 vector Laplace equation on the
    tetrahedra) that takes ``values`` ``(k, 3)`` at the points ``boundary`` up to any amount along their ``slides``
    ``(k, 3, 2)`` (orthonormal columns, zero where unused; default none: the values exactly); free elsewhere."""
    from skfem import Basis, ElementTetP1, MeshTet, asm
    from skfem.models.poisson import laplace

    n, k = len(mesh.points), len(boundary)
    basis = Basis(MeshTet(np.ascontiguousarray(mesh.points.T), np.ascontiguousarray(mesh.tets.T)), ElementTetP1())
    energy = sp.kron(sp.csr_matrix(asm(laplace, basis)), sp.identity(3), format="csr")  # dof 3 i + c
    slides = np.zeros((k, 3, 2)) if slides is None else np.asarray(slides, dtype=float)
    known = np.zeros((n, 3))
    known[boundary] = values
    # free directions: every component of an interior point, the slides of a boundary point
    interior = np.setdiff1d(np.arange(n), boundary)
    rows = [np.repeat(3 * interior, 3) + np.tile(np.arange(3), len(interior))]
    cols = [np.arange(3 * len(interior))]
    data = [np.ones(3 * len(interior))]
    used = np.abs(slides).sum(axis=1) > 0.0  # (k, 2)
    point, column = np.nonzero(used)
    first = 3 * len(interior)
    for c in range(3):
        rows.append(3 * boundary[point] + c)
        cols.append(first + np.arange(len(point)))
        data.append(slides[point, c, column])
    free = sp.csr_matrix(
        (np.concatenate(data), (np.concatenate(rows), np.concatenate(cols))), shape=(3 * n, first + len(point))
    )
    reduced = (free.T @ energy @ free).tocsc()
    amounts = splu(reduced).solve(-(free.T @ (energy @ known.ravel())))
    return known + (free @ amounts).reshape(n, 3)
