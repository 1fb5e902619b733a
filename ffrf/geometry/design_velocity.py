r"""The design velocity of a parametric link's mesh: how each node moves per unit change of one dimension of its
:class:`~ffrf.geometry.link_geometry.LinkDesign` (``docs/formulation.md``, Eq. (D5)), or of its axes as a change of
the loop's own DH parameters moves them (Eq. (D12)).

Remeshing a link at a changed dimension gives another mesh (other nodes, other tetrahedra), so a model built on it
is not a differentiable function of the dimension. Its derivative is taken instead along a *morph* of the
nominal mesh, :math:`x(p) = x_0 + (p - p_0)\,V`, with the velocity :math:`V` of every node:

* the link's own frame (at its first housing: z on its axis, x towards the other housing) moves rigidly with the
  solids built at :math:`p_0 \pm \delta`, :math:`V = V_T + V_r` with :math:`V_T` the rigid motion's velocity; the rest
  is the morph :math:`V_r` relative to that frame (zero for a link the change only carries along);
* a boundary node stays on the faces it lies on: each face of the nominal solid is matched to the face of the shifted
  solid (relative to the link's frame) whose surface its nodes are closest to, and the node's velocity normal to each
  of its faces is its closest point's on that surface (gmsh's OpenCASCADE projection, continued beyond the face's
  parameter box by Gauss-Newton steps; of faces on one surface, the one that holds the most of the face's triangle
  centres), by central differences, :math:`n \cdot V_r = n \cdot (x_+ - x_-)/(2\delta)` (the boxes and cylinders move
  linearly in the dimension: truncation :math:`O(\delta^2)`). A face node's normal velocity, a node on an edge its
  velocity across the edge (its two faces' normals), a corner node's whole velocity are so prescribed; faces that meet
  tangentially (one cylinder cut by a seam or by the arm) count as one direction. Working with faces alone makes the
  matching blind to how OpenCASCADE splits curves and places the seams of cylinders, which jumps as an axis crosses a
  coordinate plane;
* the faces of the physical groups (the bores and the mount, whose nodes carry the joints' interfaces) move rigidly
  with their feature (a bore with its housing's frame, the mount with its own), their nodes wholly prescribed;
* along its faces a node slides freely, and every free component, with the interior nodes' velocities, minimises
  the velocity's Dirichlet energy :math:`\int |\nabla V_r|^2` (vector Laplace equation, P1 on the tetrahedra).
  Sliding spreads the motion of an edge (the arm's side sliding along the housing's cylinder) over the faces next to
  it instead of shearing the tetrahedra that touch it, so the morph keeps its tetrahedra valid over larger changes;
  the derivative at the nominal shape is the same to first order for any tangential motion of the boundary (it
  moves no material across the surface).

A face with no counterpart within a few :math:`\delta` of its motion is a change of topology, a
:class:`~ffrf.errors.GeometryError`.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, NamedTuple

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.linalg import splu
from scipy.spatial import cKDTree

from ffrf.errors import GeometryError
from ffrf.geometry.link_geometry import LINK_DESIGN_FIELDS, LinkDesign, LinkGeometry, build_link
from ffrf.mesh.tet_mesh import TetMesh

__all__ = ["SECTION_PARAMETERS", "VELOCITY_STEP", "design_velocity", "harmonic_extension", "shape_velocity"]

#: The dimensions of a link's section that a design changes without moving its bores (m).
SECTION_PARAMETERS = ("arm_width", "arm_thickness", "housing_outer_radius")
#: Relative change of the dimension in the central differences of the boundary's velocity.
VELOCITY_STEP = 1e-4
#: A face farther than this many times its features' motion from its counterpart means the topology changed.
_MATCH_STEPS = 50.0
#: How far (m) gmsh's projection of a node onto its own face may land from it (a link the change only carries along).
_PROJECTION_ERROR = 1e-8
#: Gauss-Newton steps of a projection on a face's untrimmed surface (:func:`_surface_projection`).
_PROJECTION_STEPS = 8
#: Faces at a node whose normals span a direction less than this (relative singular value) meet tangentially there
#: (one surface cut in two, to round-off); faces that meet almost tangentially make an edge that moves much faster
#: than the change, which is refused (a change of topology is next to it).
_TANGENTIAL = 1e-8


def design_velocity(build: dict[str, Any], h: float, parameter: str, name: str = "link") -> tuple[TetMesh, NDArray]:
    """The nominal mesh of the link that :func:`~ffrf.geometry.link_geometry.mesh_link` builds from ``build`` (the
    arguments of :func:`~ffrf.geometry.link_geometry.build_link` but ``gmsh``, e.g.
    :func:`ffrf.scenes.builder.parametric_link`'s) at edge ``h``, and the velocity ``(n, 3)`` of its points per unit
    change (m/m) of ``parameter``, a field of :class:`LinkDesign` (module docstring)."""
    if parameter not in LINK_DESIGN_FIELDS:
        raise GeometryError(f"design parameter {parameter!r} is unknown; choose one of {LINK_DESIGN_FIELDS}")
    design: LinkDesign = build["design"]
    delta = VELOCITY_STEP * float(getattr(design, parameter))
    shifted = tuple(
        dict(build, design=replace(design, **{parameter: getattr(design, parameter) + sign * delta}))
        for sign in (1.0, -1.0)
    )
    return shape_velocity(
        build, h, (shifted[0], shifted[1]), delta, f"changing {parameter} by {delta:.3g} m", name, reach=delta
    )


def shape_velocity(
    build: dict[str, Any],
    h: float,
    shifted: tuple[dict[str, Any], dict[str, Any]],
    delta: float,
    change: str,
    name: str = "link",
    reach: float = 0.0,
) -> tuple[TetMesh, NDArray]:
    """The nominal mesh of the link built from ``build`` (as :func:`design_velocity`) at edge ``h`` and the velocity
    ``(n, 3)`` of its points per unit of a change whose solids at ``+delta`` and ``-delta`` are built from
    ``shifted`` (the same arguments changed: its design, or its axes and joint points, as a change of the loop's
    DH parameters moves them): the link's own frame moves rigidly, the rest of the mesh morphs relative to it
    (module docstring). ``change`` names it in errors; ``reach`` (m): how far its faces move at ``+-delta`` beyond
    the motion of its housings and mount relative to the link's frame (a section dimension's ``delta``)."""
    from ffrf.geometry.meshing import configure_meshing, gmsh_session, mesh_current_model

    with gmsh_session(name) as gmsh:
        nominal = build_link(gmsh, **build)
        configure_meshing(h)
        mesh = mesh_current_model(name)
        faces = _face_nodes(gmsh, mesh)
        inner = _inner_points(gmsh, faces)
        adjacent = _adjacent_faces(gmsh)
        normals = {face: _normals(gmsh, face, mesh.points[nodes]) for face, nodes in faces.items()}
        pinned = _pinned_nodes(nominal, faces)
        links, normal_moves, pinned_moves, tolerances = [], [], [], []
        for sign, arguments in zip((1.0, -1.0), shifted, strict=True):
            gmsh.model.add(f"{name} {sign:+g}")
            geometry = build_link(gmsh, **arguments)
            link = _Motion.between(_feature_frames(nominal)[0], _feature_frames(geometry)[0])
            features = [
                link.inverse().after(_Motion.between(before, after))
                for before, after in zip(_feature_frames(nominal), _feature_frames(geometry), strict=True)
            ]
            moves_by = max(feature.largest_move(_landmarks(nominal)) for feature in features)
            tolerance = _MATCH_STEPS * max(reach, moves_by, _PROJECTION_ERROR)
            tolerances.append(tolerance)
            projected = _projected(gmsh, faces, inner, adjacent, mesh.points, link, tolerance, change)
            normal_moves.append(
                {
                    face: np.einsum("ka,ka->k", normals[face], projected[face] - mesh.points[faces[face]])
                    for face in faces
                }
            )
            pinned_moves.append({group: features[i](mesh.points[nodes]) for i, (group, nodes) in enumerate(pinned)})
            links.append(link)
    rates = {face: (normal_moves[0][face] - normal_moves[1][face]) / (2.0 * delta) for face in faces}
    boundary, prescribed, slides = _prescribed(faces, normals, rates)
    speed = np.linalg.norm(prescribed, axis=1)
    if speed.max() * delta > max(tolerances):
        fastest = boundary[int(np.argmax(speed))]
        times = speed.max() * delta / max(tolerances) * _MATCH_STEPS
        raise GeometryError(
            f"{change} changes the link's topology near its point {np.round(mesh.points[fastest], 6).tolist()}: an "
            f"edge there moves {times:.3g} times as far as the change moves the link's features (faces meet almost "
            "tangentially there); its derivative is not defined there; take a nominal design away from that change"
        )
    for group, nodes in pinned:
        rows = np.searchsorted(boundary, nodes)
        prescribed[rows] = (pinned_moves[0][group] - pinned_moves[1][group]) / (2.0 * delta)
        slides[rows] = 0.0
    rigid = (links[0](mesh.points) - links[1](mesh.points)) / (2.0 * delta)
    return mesh, rigid + harmonic_extension(mesh, boundary, prescribed, slides)


class _Motion(NamedTuple):
    """A rigid motion ``x -> x R^T + t``."""

    rotation: NDArray[np.float64]
    translation: NDArray[np.float64]

    @classmethod
    def between(cls, before: tuple[NDArray, NDArray], after: tuple[NDArray, NDArray]) -> _Motion:
        """The motion that takes frame ``before`` (origin, axes as columns) to ``after``; the identity, exactly,
        between equal frames."""
        if all(np.array_equal(a, b) for a, b in zip(before, after, strict=True)):
            return cls(np.eye(3), np.zeros(3))
        rotation = after[1] @ before[1].T
        return cls(rotation, after[0] - rotation @ before[0])

    def __call__(self, x: NDArray) -> NDArray[np.float64]:
        return x @ self.rotation.T + self.translation

    def inverse(self) -> _Motion:
        return _Motion(self.rotation.T, -self.rotation.T @ self.translation)

    def after(self, first: _Motion) -> _Motion:
        """This motion applied after ``first``."""
        return _Motion(self.rotation @ first.rotation, self.rotation @ first.translation + self.translation)

    def largest_move(self, points: NDArray) -> float:
        return float(np.linalg.norm(self(points) - points, axis=1).max())


def _frame(origin: NDArray, axis: NDArray, toward: NDArray) -> tuple[NDArray, NDArray]:
    """The frame at ``origin`` with z along ``axis`` and x along ``toward`` made normal to it."""
    z = axis / np.linalg.norm(axis)
    x = toward - (toward @ z) * z
    x /= np.linalg.norm(x)
    return np.asarray(origin, dtype=float), np.column_stack([x, np.cross(z, x), z])


def _feature_names(geometry: LinkGeometry) -> list[str]:
    """The link's physical groups of faces in the order of :func:`_feature_frames`: its two bores, its mount."""
    return [*geometry.interface_names, *(["mount"] if geometry.has_mount else [])]


def _feature_frames(geometry: LinkGeometry) -> list[tuple[NDArray, NDArray]]:
    """A frame on each of :func:`_feature_names`: a bore's at its housing's centre (z on its axis, x towards the other
    housing), the mount's at its centre (z its normal); the first bore's is the link's own frame."""
    centers = geometry.housing_centers
    frames = [_frame(centers[i], geometry.axes[i].direction, centers[1 - i] - centers[i]) for i in range(2)]
    if geometry.has_mount and geometry.mount_center is not None and geometry.mount_normal is not None:
        frames.append(_frame(geometry.mount_center, geometry.mount_normal, centers[1] - centers[0]))
    return frames


def _landmarks(geometry: LinkGeometry) -> NDArray[np.float64]:
    """Points that locate the link's features: its housings' centres and joint points (and its mount's centre)."""
    points = [geometry.housing_centers, geometry.joint_points]
    if geometry.mount_center is not None:
        points.append(np.reshape(geometry.mount_center, (1, 3)))
    return np.concatenate(points)


def _face_nodes(gmsh: Any, mesh: TetMesh) -> dict[int, NDArray[np.int64]]:
    """Per face of the current model, the mesh points on it (its edges' and corners' included)."""
    tree = cKDTree(mesh.points)
    out = {}
    for _, face in gmsh.model.getEntities(2):
        _, coords, _ = gmsh.model.mesh.getNodes(2, face, includeBoundary=True)
        distance, index = tree.query(np.reshape(coords, (-1, 3)))
        if len(distance) and distance.max() > 0.0:  # mesh_current_model keeps gmsh's coordinates as they are
            raise GeometryError(f"{mesh.name}: gmsh's nodes on face {face} are not the mesh's points")
        out[int(face)] = np.unique(index).astype(np.int64)
    return out


def _inner_points(gmsh: Any, faces: dict[int, NDArray]) -> dict[int, NDArray[np.float64]]:
    """Per face of the current model's mesh, the centres ``(k, 3)`` of its surface triangles (of their corners):
    points inside the face, near its surface."""
    tags, coords, _ = gmsh.model.mesh.getNodes()
    order = np.argsort(tags)
    coords = np.reshape(coords, (-1, 3))[order]
    out = {}
    for face in faces:
        types, _, nodes = gmsh.model.mesh.getElements(2, face)
        corners = np.concatenate(
            [
                np.reshape(n, (-1, gmsh.model.mesh.getElementProperties(t)[3]))[:, :3]
                for t, n in zip(types, nodes, strict=True)
            ]
        )
        out[face] = coords[np.searchsorted(tags[order], corners)].mean(axis=1)
    return out


def _normals(gmsh: Any, face: int, points: NDArray) -> NDArray[np.float64]:
    """Unit normals ``(k, 3)`` of ``face`` at ``points`` on it."""
    parametric = gmsh.model.getParametrization(2, face, np.ravel(points))
    normal = np.reshape(gmsh.model.getNormal(face, parametric), (-1, 3))
    return normal / np.linalg.norm(normal, axis=1, keepdims=True)


def _pinned_nodes(geometry: LinkGeometry, faces: dict[int, NDArray]) -> list[tuple[str, NDArray[np.int64]]]:
    """The nodes on each physical group's faces (their edges' included), in the order of :func:`_feature_names`."""
    return [
        (group, np.unique(np.concatenate([faces[int(tag)] for tag in geometry.surface_tags[group]])))
        for group in _feature_names(geometry)
    ]


def _projected(
    gmsh: Any,
    faces: dict[int, NDArray],
    inner: dict[int, NDArray],
    adjacent: set[frozenset[int]],
    points: NDArray,
    link: _Motion,
    tolerance: float,
    change: str,
) -> dict[int, NDArray[np.float64]]:
    """Per face, its nodes carried by the link's own motion ``link``, projected on the surface of the face of the
    current model (the shifted solid) they are closest to, and carried back: their place relative to the link's
    frame. A surface is the face's untrimmed one (a cylinder's whole cylinder), so a face cut differently in the
    shifted solid still finds it; of faces on one surface, the one that holds the most of the face's ``inner`` points
    (:func:`_inner_points`), carried and projected alike. The faces must match one to one and meet as ``adjacent``,
    the nominal ones do (:func:`_check_topology`)."""
    candidates = [int(tag) for _, tag in gmsh.model.getEntities(2)]
    boxes = {tag: np.reshape(gmsh.model.getBoundingBox(2, tag), (2, 3)) for tag in candidates}
    back = link.inverse()
    out, matched = {}, {}
    for face, nodes in faces.items():
        x = link(points[nodes])
        found = {}
        for other in candidates:
            low, high = boxes[other]
            if np.any(x.max(axis=0) < low - tolerance) or np.any(x.min(axis=0) > high + tolerance):
                continue  # no overlap
            projected = _surface_projection(gmsh, other, x)
            found[other] = (float(np.linalg.norm(projected - x, axis=1).max()), projected)
        closest = min((distance for distance, _ in found.values()), default=np.inf)
        if closest > tolerance:
            raise GeometryError(
                f"{change} changes the link's topology near its face {face} (closest counterpart "
                f"{closest:.3g} m away): its derivative is not defined there; take a nominal design away from "
                "that change"
            )
        # Faces on one surface (a housing's end face cut in two by the arm) are equally close; their nodes may all
        # lie on their edges (a sliver face), so the points inside the face tell them apart.
        tied = [other for other, (distance, _) in found.items() if distance <= closest * (1.0 + 1e-6) + 1e-12]
        if len(tied) > 1:
            samples = link(inner[face])
            tied.sort(key=lambda o: -gmsh.model.isInside(2, o, np.ravel(_surface_projection(gmsh, o, samples))))
        matched[face] = tied[0]
        out[face] = back(found[matched[face]][1])
    _check_topology(matched, adjacent, _adjacent_faces(gmsh), change)
    return out


def _surface_projection(gmsh: Any, face: int, x: NDArray) -> NDArray[np.float64]:
    """The closest points ``(k, 3)`` to ``x`` on the untrimmed surface of ``face`` of the current model: gmsh's
    projection, which stays within the face's parameter box (OpenCASCADE's extrema search may stop on its boundary
    millimetres away for points that lie just beyond it), refined by Gauss-Newton steps on the surface's
    parametrization, which extends beyond the box (planes exactly in one step, cylinders in a few)."""
    _, start = gmsh.model.getClosestPoint(2, face, np.ravel(x))
    uv = np.reshape(start, (-1, 2))
    for _ in range(_PROJECTION_STEPS):
        value = np.reshape(gmsh.model.getValue(2, face, np.ravel(uv)), (-1, 3))
        tangents = np.reshape(gmsh.model.getDerivative(2, face, np.ravel(uv)), (-1, 2, 3))
        normal = np.einsum("kij,kj->ki", tangents, x - value)
        metric = np.einsum("kij,klj->kil", tangents, tangents)
        step = np.linalg.solve(metric, normal[..., None])[..., 0]
        uv = uv + step
        if np.all(np.abs(step) <= 1e-14 * (1.0 + np.abs(uv))):
            break
    return np.reshape(gmsh.model.getValue(2, face, np.ravel(uv)), (-1, 3))


def _adjacent_faces(gmsh: Any) -> set[frozenset[int]]:
    """The pairs of faces of the current model that meet along an edge (a seam, where a face meets itself, is none)."""
    pairs = set()
    for _, curve in gmsh.model.getEntities(1):
        faces = {int(face) for face in gmsh.model.getAdjacencies(1, curve)[0]}
        if len(faces) == 2:
            pairs.add(frozenset(faces))
    return pairs


def _check_topology(
    matched: dict[int, int], adjacent: set[frozenset[int]], shifted: set[frozenset[int]], change: str
) -> None:
    """A :class:`GeometryError` unless the faces matched one to one and meet as the nominal ones do: the change does
    not make or remove a face or an edge (where a derivative is one-sided, not defined)."""
    images = sorted(matched.values())
    if len(set(images)) != len(images):
        raise GeometryError(
            f"{change} changes the link's topology: two of its faces meet one face of the changed solid; its "
            "derivative is not defined there; take a nominal design away from that change"
        )
    mapped = {frozenset(matched[face] for face in pair) for pair in adjacent}
    if mapped != shifted:
        lost = sorted(tuple(sorted(pair)) for pair in adjacent if frozenset(matched[f] for f in pair) not in shifted)
        raise GeometryError(
            f"{change} changes the link's topology: an edge appears or vanishes (between its faces {lost} or new "
            "ones); its derivative is not defined there; take a nominal design away from that change"
        )


def _prescribed(
    faces: dict[int, NDArray], normals: dict[int, NDArray], rates: dict[int, NDArray]
) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]:
    """The boundary nodes (sorted), the part ``(k, 3)`` of their velocity their faces' normal rates prescribe (least
    squares over the directions the normals span) and the directions ``(k, 3, 2)`` in which they slide (orthonormal,
    zero columns where unused)."""
    boundary = np.unique(np.concatenate(list(faces.values())))
    rows = {face: np.searchsorted(boundary, nodes) for face, nodes in faces.items()}
    count = np.zeros(len(boundary), dtype=np.int64)
    for face in faces:
        np.add.at(count, rows[face], 1)
    most = max(3, int(count.max()))  # zero rows pad every node to three: the SVD then gives all three directions
    stacked_normals = np.zeros((len(boundary), most, 3))
    stacked_rates = np.zeros((len(boundary), most))
    filled = np.zeros(len(boundary), dtype=np.int64)
    for face in faces:
        r = rows[face]
        stacked_normals[r, filled[r]] = normals[face]
        stacked_rates[r, filled[r]] = rates[face]
        filled[r] += 1
    u, singular, vt = np.linalg.svd(stacked_normals, full_matrices=False)  # (k, m, 3), (k, 3), (k, 3, 3)
    spans = singular > _TANGENTIAL * singular[:, :1]
    inverse = np.where(spans, 1.0 / np.where(spans, singular, 1.0), 0.0)
    amounts = np.einsum("kma,km->ka", u, stacked_rates) * inverse  # along vt's rows
    prescribed = np.einsum("kar,ka->kr", vt, amounts)
    slides = np.zeros((len(boundary), 3, 2))
    free = ~spans
    for column in range(3):  # the free rows of vt, at most two per node (every node has a face)
        place = np.cumsum(free, axis=1)[:, column] - 1
        use = free[:, column] & (place < 2)
        slides[use, :, place[use]] = vt[use, column]
    return boundary, prescribed, slides


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
