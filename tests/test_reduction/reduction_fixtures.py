"""Small FE models, interface sets and reference computations for the reduction tests.

Meshes are built here (scikit-fem tensor meshes, gmsh for a plate with two
bores) and assembled with scikit-fem directly, so these tests do not depend on
the state of :mod:`ffrf.fe.fe_model`. The models are duck-typed like
``ffrf.fe.fe_model.FEModel``: ``.nodes`` (N, 3), ``.mass``, ``.stiffness``
(3N, 3N CSR, DOF layout [x0, y0, z0, x1, ...]).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np
import scipy.sparse as sp
from scipy.linalg import subspace_angles

# PLA-like material (SI units), as in the paper's printed links.
E_PLA, NU_PLA, RHO_PLA = 3.5e9, 0.36, 1250.0


@dataclass(frozen=True, eq=False)
class SmallFEModel:
    nodes: np.ndarray
    mass: sp.csr_matrix
    stiffness: sp.csr_matrix
    tets: np.ndarray


def assemble(
    points: np.ndarray, tets: np.ndarray, E: float = E_PLA, nu: float = NU_PLA, rho: float = RHO_PLA
) -> SmallFEModel:
    """Consistent mass and linear elastic stiffness of P1 tetrahedra, node-interleaved DOFs."""
    from skfem import Basis, BilinearForm, ElementTetP1, ElementVector, MeshTet, asm
    from skfem.helpers import dot
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    mesh = MeshTet(np.asarray(points, float).T, np.asarray(tets).T)
    basis = Basis(mesh, ElementVector(ElementTetP1()), intorder=2)

    @BilinearForm
    def mass_form(u, v, w):
        return rho * dot(u, v)

    perm = basis.nodal_dofs.T.reshape(-1)  # perm[3k + c] = scikit-fem DOF of component c at node k
    stiffness = asm(linear_elasticity(*lame_parameters(E, nu)), basis)[perm][:, perm]
    mass = asm(mass_form, basis)[perm][:, perm]
    return SmallFEModel(mesh.p.T.copy(), sp.csr_matrix(mass), sp.csr_matrix(stiffness), mesh.t.T.copy())


@cache
def bar_model(
    length: float = 0.16, width: float = 0.02, height: float = 0.012, divisions: tuple[int, int, int] = (16, 3, 2)
) -> SmallFEModel:
    """Prismatic bar along x on a structured tetrahedral grid."""
    from skfem import MeshTet

    mesh = MeshTet.init_tensor(
        np.linspace(0.0, length, divisions[0] + 1),
        np.linspace(0.0, width, divisions[1] + 1),
        np.linspace(0.0, height, divisions[2] + 1),
    )
    return assemble(mesh.p.T, mesh.t.T)


def end_faces(model: SmallFEModel) -> list[np.ndarray]:
    """Node sets of the faces x = min and x = max."""
    x = model.nodes[:, 0]
    return [np.flatnonzero(np.isclose(x, x.min())), np.flatnonzero(np.isclose(x, x.max()))]


def boundary_triangles(tets: np.ndarray) -> np.ndarray:
    faces = tets[:, [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]]].reshape(-1, 3)
    _, index, counts = np.unique(np.sort(faces, axis=1), axis=0, return_index=True, return_counts=True)
    return faces[index[counts == 1]]


def surface_area_weights(model: SmallFEModel, node_set: np.ndarray) -> np.ndarray:
    """Exudyn's GetNodeWeightsFromSurfaceAreas: area/3 per node of every boundary triangle in the set."""
    tris = boundary_triangles(model.tets)
    inside = np.isin(tris, node_set).all(axis=1)
    p = model.nodes[tris[inside]]
    areas = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    weights = np.zeros(len(model.nodes))
    np.add.at(weights, tris[inside].reshape(-1), np.repeat(areas / 3.0, 3))
    return weights[node_set] / weights[node_set].sum()


@cache
def plate_with_bores(h: float = 4e-3) -> tuple[SmallFEModel, tuple[np.ndarray, ...]]:
    """Plate 120 x 40 x 10 mm with two 12 mm bores (axes along z at x = 20 and 100 mm); gmsh P1.

    Returns the model and the node sets on the two bore surfaces.
    """
    import gmsh

    centers, radius, thickness = [(0.02, 0.02), (0.10, 0.02)], 0.006, 0.01
    gmsh.initialize(["-noenv"], readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.NumThreads", 1)
        gmsh.model.add("plate")
        occ = gmsh.model.occ
        plate = occ.addBox(0.0, 0.0, 0.0, 0.12, 0.04, thickness)
        holes = [(3, occ.addCylinder(cx, cy, -0.001, 0.0, 0.0, thickness + 0.002, radius)) for cx, cy in centers]
        occ.cut([(3, plate)], holes)
        occ.synchronize()
        gmsh.option.setNumber("Mesh.MeshSizeMax", h)
        gmsh.option.setNumber("Mesh.MeshSizeMin", 0.5 * h)
        gmsh.model.mesh.generate(3)
        tags, coords, _ = gmsh.model.mesh.getNodes()
        _, _, connectivity = gmsh.model.mesh.getElements(3)
    finally:
        gmsh.finalize()
    index = np.full(int(tags.max()) + 1, -1)
    index[tags.astype(int)] = np.arange(len(tags))
    points = coords.reshape(-1, 3)
    tets = index[np.asarray(connectivity[0], dtype=int).reshape(-1, 4)]
    used = np.unique(tets)
    compact = np.full(len(points), -1)
    compact[used] = np.arange(len(used))
    model = assemble(points[used], compact[tets])
    bores = tuple(
        np.flatnonzero(np.abs(np.hypot(model.nodes[:, 0] - cx, model.nodes[:, 1] - cy) - radius) < 1e-6)
        for cx, cy in centers
    )
    return model, bores


def exudyn_hcb(model: SmallFEModel, interfaces, weights, n_modes: int):
    """Exudyn's own HCB (RBE2, excludeRigidBodyMotion=True) on the same nodes, M and K.

    Returns (mode basis (3N, m), fixed-interface frequencies in Hz).
    """
    from exudyn.FEM import FEMinterface, HCBstaticModeSelection

    fem = FEMinterface()
    fem.nodes = {"Position": np.asarray(model.nodes)}
    fem.massMatrix = sp.csr_matrix(model.mass)
    fem.stiffnessMatrix = sp.csr_matrix(model.stiffness)
    fem.ComputeHurtyCraigBamptonModes(
        boundaryNodesList=[list(map(int, i)) for i in interfaces],
        nEigenModes=n_modes,
        useSparseSolver=True,
        computationMode=HCBstaticModeSelection.RBE2,
        boundaryNodesWeights=[np.asarray(w, float) for w in weights],
        excludeRigidBodyMotion=True,
    )
    return np.asarray(fem.modeBasis["matrix"]), np.asarray(fem.GetEigenFrequenciesHz())


def max_principal_angle(a: np.ndarray, b: np.ndarray) -> float:
    """Largest principal angle (rad) between the column spaces of a and b."""
    return float(np.max(subspace_angles(a, b)))


def mac(a: np.ndarray, b: np.ndarray) -> float:
    """Modal assurance criterion |a.b|^2 / (|a|^2 |b|^2) (Allemang and Brown 1982)."""
    return float((a @ b) ** 2 / ((a @ a) * (b @ b)))


def frequency_clusters(frequencies: np.ndarray, rel_gap: float = 1e-6) -> list[np.ndarray]:
    """Index groups of (nearly) repeated frequencies; isolated modes are groups of one."""
    breaks = np.flatnonzero(np.diff(frequencies) > rel_gap * frequencies[1:]) + 1
    return np.split(np.arange(len(frequencies)), breaks)


def reduced_elastic_frequencies_hz(model: SmallFEModel, basis: np.ndarray, n: int) -> np.ndarray:
    """Free-free elastic frequencies of span([rigid modes, basis]) by a dense Rayleigh-Ritz (reference).

    Rigid modes are built here independently (u = t + w x x) and the span is made
    M-orthonormal by an eigen-decomposition of the projected mass, so columns that
    already contain rigid motions do no harm.
    """
    from scipy.linalg import eigh

    x = model.nodes
    rigid = np.zeros((len(x), 3, 6))
    rigid[:, :, :3] = np.eye(3)
    for i in range(3):
        rigid[:, :, 3 + i] = np.cross(np.eye(3)[i], x - x.mean(axis=0))
    span = np.hstack([rigid.reshape(-1, 6), basis])
    m_span = span.T @ (model.mass @ span)
    s, v = eigh(m_span)
    q = span @ (v[:, s > 1e-12 * s.max()] / np.sqrt(s[s > 1e-12 * s.max()]))
    values = eigh(q.T @ (model.stiffness @ q), q.T @ (model.mass @ q), eigvals_only=True)
    return np.sqrt(np.clip(values[6 : 6 + n], 0.0, None)) / (2 * np.pi)


def full_free_free_frequencies_hz(model: SmallFEModel, n: int) -> np.ndarray:
    """Lowest n elastic free-free frequencies of the full FE model (shift-invert Lanczos below 0)."""
    from scipy.sparse.linalg import eigsh

    scale = model.stiffness.diagonal().mean() / model.mass.diagonal().mean()
    values = eigsh(
        model.stiffness.tocsc(),
        k=n + 6,
        M=model.mass.tocsc(),
        sigma=-1e-6 * scale,
        which="LM",
        return_eigenvectors=False,
    )
    return np.sqrt(np.clip(np.sort(values)[6:], 0.0, None)) / (2 * np.pi)


def rigid_interface_transformation(model: SmallFEModel, rigid_sets, weights, clamped=()) -> sp.csr_matrix:
    """Sparse T with u = T z: z = [free non-interface DOFs, (t, w) per rigid set]; ``clamped`` nodes fixed.

    Built by hand (u_j = t + w x (x_j - c), c the weighted centre), independently of ffrf.
    """
    n_dofs = 3 * len(model.nodes)
    special = np.concatenate([np.asarray(s) for s in rigid_sets] + [np.asarray(clamped, dtype=int)])
    free = np.setdiff1d(np.arange(n_dofs), (3 * special[:, None] + np.arange(3)).reshape(-1))
    rows, cols, vals = list(free), list(range(len(free))), [1.0] * len(free)
    for k, (node_set, w) in enumerate(zip(rigid_sets, weights, strict=True)):
        center = np.asarray(w) @ model.nodes[node_set]
        base = len(free) + 6 * k
        for node in node_set:
            r = model.nodes[node] - center
            # w x r = [w1 r2 - w2 r1, w2 r0 - w0 r2, w0 r1 - w1 r0]
            cross = {0: [(1, r[2]), (2, -r[1])], 1: [(2, r[0]), (0, -r[2])], 2: [(0, r[1]), (1, -r[0])]}
            for c in range(3):
                rows.append(3 * node + c)
                cols.append(base + c)
                vals.append(1.0)
                for axis, value in cross[c]:
                    rows.append(3 * node + c)
                    cols.append(base + 3 + axis)
                    vals.append(value)
    return sp.csr_matrix((vals, (rows, cols)), shape=(n_dofs, len(free) + 6 * len(rigid_sets)))


def rigid_interface_free_free_frequencies_hz(model: SmallFEModel, rigid_sets, weights, n: int) -> np.ndarray:
    """Free-free elastic frequencies of the full model with rigid interfaces (the limit of HCB as n_m grows)."""
    from scipy.sparse.linalg import eigsh

    t = rigid_interface_transformation(model, rigid_sets, weights)
    k, m = (t.T @ model.stiffness @ t).tocsc(), (t.T @ model.mass @ t).tocsc()
    scale = model.stiffness.diagonal().mean() / model.mass.diagonal().mean()
    values = eigsh(k, k=n + 6, M=m, sigma=-1e-6 * scale, which="LM", return_eigenvectors=False)
    return np.sqrt(np.clip(np.sort(values)[6:], 0.0, None)) / (2 * np.pi)


@cache
def symmetric_bar_model(n_length: int = 8, n_side: int = 2, cube: float = 0.01) -> SmallFEModel:
    """Square bar along x made of cubes split into 24 tetrahedra each (corners, face centres, cube centre).

    The mesh is invariant under 90-degree rotations about the bar axis, so bending
    and other modes come in exactly repeated pairs (to round-off).
    """
    corners = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)], dtype=float)
    faces = []  # each face: 4 corner indices in cyclic order
    for axis in range(3):
        for side in (0.0, 1.0):
            on = np.flatnonzero(corners[:, axis] == side)
            others = [a for a in range(3) if a != axis]
            angle = np.arctan2(corners[on, others[1]] - 0.5, corners[on, others[0]] - 0.5)
            faces.append(on[np.argsort(angle)])
    points: list[np.ndarray] = []
    tets: list[list[int]] = []
    offset = np.array([0.0, -n_side / 2, -n_side / 2])
    for i in range(n_length):
        for j in range(n_side):
            for k in range(n_side):
                base = offset + (i, j, k)
                centre = len(points)
                points.append(base + 0.5)
                for face in faces:
                    fc = len(points)
                    points.append(base + corners[face].mean(axis=0))
                    for a in range(4):
                        p, q = len(points), len(points) + 1
                        points.extend([base + corners[face[a]], base + corners[face[(a + 1) % 4]]])
                        tets.append([centre, fc, p, q])
    coordinates = np.array(points) * cube
    unique, inverse = np.unique(np.round(coordinates / cube * 2).astype(np.int64), axis=0, return_inverse=True)
    return assemble(unique * cube / 2, inverse.reshape(-1)[np.array(tets)])
