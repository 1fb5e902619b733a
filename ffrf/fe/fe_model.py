"""Finite-element model of one link: consistent mass and linear elastic stiffness.

DOF layout (the package convention): ``[x0, y0, z0, x1, y1, z1, ...]`` over
:attr:`FEModel.nodes`. For quadratic tetrahedra the nodes are the mesh vertices
first (same order as the mesh points), then one midside node per mesh edge, in
the order of :attr:`FEModel.edges`.

Shape functions, mapping and quadrature are scikit-fem's (``ElementTetP1/P2``); the element matrices of
linear elasticity (Lame's ``lam``, ``mu`` from ``lame_parameters``) and of the consistent mass ``rho u.v`` are
formed for all elements at once from the scalar basis functions' gradients and values, in our DOF layout
(``docs/fe_models.md``; scikit-fem's vector forms, which loop over the 30 x 30 pairs of a P2 element's vector basis
functions, give the same matrices to 2e-16 and took four times as long).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

from ffrf.errors import FEInputError
from ffrf.fe.materials import Material
from ffrf.mesh.tet_mesh import TetMesh, check_mesh, orient_positive

__all__ = ["FEModel", "rigid_body_modes"]

logger = logging.getLogger(__name__)


def rigid_body_modes(nodes: ArrayLike, center: ArrayLike | None = None) -> NDArray[np.float64]:
    """The six infinitesimal rigid-body motions as columns of a (3N, 6) array.

    Columns 0-2 translate along x, y, z; columns 3-5 rotate about x, y, z
    through ``center`` (default: the centroid of the nodes): u = omega x (p - c). For the nodes of
    an interface about its centre this is the map T from interface motion [t; theta] to nodal
    displacements of eq. (HCB-2); Exudyn uses Skew(x_j - p0) for the rotation block, i.e. the
    opposite sign.

    >>> rigid_body_modes([[1.0, 0.0, 0.0]], center=[0.0, 0.0, 0.0])[:, 5].tolist()  # about z: e_z x e_x = e_y
    [0.0, 1.0, 0.0]
    """
    nodes = np.asarray(nodes, dtype=float)
    r = nodes - (nodes.mean(axis=0) if center is None else np.asarray(center, dtype=float))
    modes = np.zeros((nodes.shape[0], 3, 6))
    for axis in range(3):
        modes[:, axis, axis] = 1.0
        omega = np.eye(3)[axis]
        modes[:, :, 3 + axis] = np.cross(omega, r)
    return modes.reshape(-1, 6)


@dataclass(frozen=True, eq=False)
class FEModel:
    """Linear elastic tetrahedral FE model of one body (SI units).

    Attributes
    ----------
    nodes : (N, 3) coordinates of all FE nodes (vertices, then midside nodes for order 2).
    mass, stiffness : (3N, 3N) scipy CSR matrices, DOF layout [x0, y0, z0, x1, ...].
    mesh : the linear :class:`TetMesh` the model was built from (groups included).
    material : :class:`Material`.
    order : 1 (linear) or 2 (quadratic) tetrahedra.
    edges : (n_edges, 2) vertex pairs; node ``mesh.n_points + e`` is the midpoint of edge e.
        Empty for order 1.
    """

    nodes: NDArray[np.float64]
    mass: sp.csr_matrix
    stiffness: sp.csr_matrix
    mesh: TetMesh
    material: Material
    order: int
    edges: NDArray[np.int64] = field(default_factory=lambda: np.zeros((0, 2), dtype=np.int64))

    @classmethod
    def from_mesh(
        cls,
        points: ArrayLike,
        tetrahedra: ArrayLike,
        E: float,
        nu: float,
        rho: float,
        order: int = 1,
        *,
        groups: dict[str, ArrayLike] | None = None,
        name: str = "link",
    ) -> FEModel:
        """Assemble the model from points (n x 3, metres) and linear tetrahedra (k x 4)."""
        named = {key: np.asarray(value) for key, value in (groups or {}).items()}  # TetMesh makes them int64
        mesh = TetMesh(np.asarray(points, dtype=float), np.asarray(tetrahedra), named, name)
        return cls.from_tet_mesh(mesh, Material(float(E), float(nu), float(rho), name=f"{name} material"), order)

    @classmethod
    def from_tet_mesh(cls, mesh: TetMesh, material: Material, order: int = 1) -> FEModel:
        """Assemble the model of a checked :class:`TetMesh` (see :func:`ffrf.mesh.tet_mesh.check_mesh`); a mesh in the
        opposite node order is reoriented with a warning (:func:`ffrf.mesh.tet_mesh.orient_positive`)."""
        if order not in (1, 2):
            raise FEInputError(f"{mesh.name}: element order {order!r} is not supported; use 1 (P1) or 2 (P2)")
        tets = orient_positive(mesh.points, mesh.tets, mixed_orders=False, name=mesh.name)
        if not np.array_equal(tets, mesh.tets):
            mesh = TetMesh(mesh.points, tets, dict(mesh.groups), mesh.name)
        check_mesh(mesh)
        nodes, mass, stiffness, edges = _assemble(mesh, material, order)
        logger.info("%s: P%d model with %d nodes, %d DOFs", mesh.name, order, len(nodes), 3 * len(nodes))
        return cls(nodes, mass, stiffness, mesh, material, order, edges)

    @property
    def n_dofs(self) -> int:
        return 3 * len(self.nodes)

    @property
    def n_vertices(self) -> int:
        return len(self.mesh.points)

    @property
    def total_mass(self) -> float:
        """Total mass in kg, 1^T M_xx 1 (exact: constants are in the FE space)."""
        return float(self._moments()[0])

    @property
    def center_of_mass(self) -> NDArray[np.float64]:
        """Centre of mass in metres."""
        m, first, _ = self._moments()
        return first / m

    @property
    def inertia_tensor(self) -> NDArray[np.float64]:
        """Inertia tensor about the centre of mass (kg m^2), world axes.

        J = tr(S) I - S with S_ij = integral rho (x_i - c_i)(x_j - c_j) dV
        (Goldstein, Classical Mechanics, 3rd ed., eq. 5.7). The integrals are
        exact because coordinates are interpolated exactly by P1 and P2 fields
        and the consistent mass integrates their products exactly.
        """
        m, first, second = self._moments()
        c = first / m
        s = second - m * np.outer(c, c)
        return np.trace(s) * np.eye(3) - s

    def _moments(self) -> tuple[float, NDArray, NDArray]:
        m_xx = self.mass[0::3, 0::3]
        ones = np.ones(len(self.nodes))
        weighted = m_xx @ self.nodes  # column j: M_xx x_j
        return float(ones @ m_xx @ ones), ones @ weighted, self.nodes.T @ weighted

    def vertex_strains(self, displacement: ArrayLike) -> NDArray[np.float64]:
        """Small-strain tensors eps = (H + H^T)/2 at the four vertices of every tetrahedron, shape
        (n_tets, 4, 3, 3), for nodal ``displacement`` (N, 3) or (3N,): scikit-fem's gradients of
        the P1 or P2 field evaluated at the reference element's corners. For P1 the four are equal;
        for P2 the strain is linear in each straight-sided element, so its extremes are at corners."""
        u = np.asarray(displacement, dtype=float).reshape(-1)
        if u.shape[0] != self.n_dofs:
            raise FEInputError(
                f"{self.mesh.name}: displacement of length {u.shape[0]} does not match {self.n_dofs} DOFs"
            )
        basis, permutation = self._corner_basis
        field_dofs = np.empty(basis.N)
        field_dofs[permutation] = u
        gradient = np.moveaxis(np.asarray(basis.interpolate(field_dofs).grad), (2, 3), (0, 1))  # H_ij = du_i/dx_j
        return 0.5 * (gradient + np.swapaxes(gradient, -1, -2))

    @cached_property
    def _corner_basis(self) -> tuple[Any, NDArray[np.int64]]:
        """scikit-fem's basis of the model's field with the reference element's corners as quadrature points, and
        the permutation from our DOF layout to its own (built once per model: every strain evaluation uses it)."""
        from skfem import Basis, MeshTet

        sk_mesh = MeshTet(np.ascontiguousarray(self.mesh.points.T), np.ascontiguousarray(self.mesh.tets.T))
        corners = np.array([[0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
        basis = Basis(sk_mesh, _vector_element(self.order), quadrature=(corners, np.full(4, 1.0 / 24.0)))
        return basis, _node_dof_permutation(basis, len(self.mesh.points), len(self.edges))

    def interleaved(self, values: ArrayLike) -> NDArray[np.float64]:
        """Reshape a DOF vector (3N,) into nodal vectors (N, 3)."""
        values = np.asarray(values)
        if values.shape[0] != self.n_dofs:
            raise FEInputError(
                f"{self.mesh.name}: vector of length {values.shape[0]} does not match {self.n_dofs} DOFs"
            )
        return values.reshape(len(self.nodes), 3, *values.shape[1:])


def _node_dof_permutation(basis, n_vertices: int, n_edges: int) -> NDArray[np.int64]:
    """perm[3 k + c] = scikit-fem DOF of component c at node k (vertices, then edges)."""
    blocks = [basis.nodal_dofs.T]
    if n_edges:
        blocks.append(basis.edge_dofs.T)
    perm = np.concatenate(blocks).reshape(-1)
    if len(perm) != basis.N:
        raise RuntimeError(f"unexpected scikit-fem DOF layout: {len(perm)} node DOFs vs {basis.N} in total")
    return perm


def _scalar_element(order: int):
    from skfem import ElementTetP1, ElementTetP2

    return ElementTetP1() if order == 1 else ElementTetP2()


def _vector_element(order: int):
    from skfem import ElementVector

    return ElementVector(_scalar_element(order))


def _scalar_basis(mesh: Any, order: int, intorder: int) -> tuple[Any, NDArray[np.int64]]:
    """scikit-fem's scalar P_k basis on ``mesh`` with quadrature of order ``intorder``, and each element's DOFs as our
    node numbers ``(n_tets, n_basis)`` (vertices, then one midside node per edge in scikit-fem's edge order)."""
    from skfem import Basis

    basis = Basis(mesh, _scalar_element(order), intorder=intorder)
    blocks = [basis.nodal_dofs.T] + ([basis.edge_dofs.T] if order == 2 else [])
    dof_of_node = np.concatenate(blocks).reshape(-1)
    if len(dof_of_node) != basis.N:
        raise RuntimeError(f"unexpected scikit-fem scalar DOF layout: {len(dof_of_node)} node DOFs vs {basis.N}")
    node_of_dof = np.empty_like(dof_of_node)
    node_of_dof[dof_of_node] = np.arange(len(dof_of_node))
    return basis, node_of_dof[basis.element_dofs.T]


def _scattered(local: NDArray, dofs: NDArray[np.int64], n_dofs: int) -> sp.csr_matrix:
    """The global matrix (duplicates summed, exact zeros dropped) of element matrices ``local`` ``(n_tets, n, n)``
    over the elements' DOFs ``dofs`` ``(n_tets, n)``."""
    size = dofs.shape[1]
    rows, cols = np.repeat(dofs, size, axis=1).ravel(), np.tile(dofs, (1, size)).ravel()
    matrix = sp.coo_matrix((local.ravel(), (rows, cols)), shape=(n_dofs, n_dofs)).tocsr()
    matrix.eliminate_zeros()
    return matrix


def _stiffness(mesh: Any, order: int, material: Material) -> sp.csr_matrix:
    r"""Linear elasticity :math:`K_{(ia)(jb)} = \int \lambda\, \partial_a\phi_i \partial_b\phi_j
    + \mu\, (\delta_{ab} \nabla\phi_i \cdot \nabla\phi_j + \partial_b\phi_i \partial_a\phi_j)` (DOF ``3 i + a``).
    On straight-sided tets the strain of a P_k field is of degree k-1, so quadrature of order 2(k-1) is exact."""
    from skfem.models.elasticity import lame_parameters

    basis, nodes = _scalar_basis(mesh, order, max(2 * (order - 1), 1))
    lam, mu = lame_parameters(material.E, material.nu)
    gradients = np.transpose(np.array([phi[0].grad for phi in basis.basis]), (2, 3, 0, 1))  # (tets, points, n, 3)
    products = np.einsum("eqia,eqjb->eiajb", gradients * basis.dx[:, :, None, None], gradients)
    local = lam * products + mu * np.transpose(products, (0, 1, 4, 3, 2))
    local += mu * np.einsum("eiaja->eij", products)[:, :, None, :, None] * np.eye(3)[None, None, :, None, :]
    n = local.shape[1]
    dofs = (3 * nodes[:, :, None] + np.arange(3)).reshape(len(nodes), -1)  # DOF 3 node + component
    return _scattered(local.reshape(len(nodes), 3 * n, 3 * n), dofs, 3 * basis.N)


def _vector_mass(mesh: Any, order: int, rho: float) -> sp.csr_matrix:
    r"""The consistent mass :math:`M_{3a+i,\,3b+j} = \delta_{ij} \int \rho\, \phi_a \phi_b` in our DOF layout
    (quadrature of order 2k: exact for P_k)."""
    basis, nodes = _scalar_basis(mesh, order, 2 * order)
    values = np.transpose(np.array([phi[0].value for phi in basis.basis]), (1, 2, 0))  # (tets, points, n)
    scalar = _scattered(np.einsum("eqi,eqj->eij", values * (rho * basis.dx)[:, :, None], values), nodes, basis.N)
    return sp.csr_matrix(sp.kron(scalar, sp.identity(3), format="csr"))


def _assemble(mesh: TetMesh, material: Material, order: int):
    from skfem import MeshTet

    sk_mesh = MeshTet(np.ascontiguousarray(mesh.points.T), np.ascontiguousarray(mesh.tets.T))
    if not np.array_equal(sk_mesh.p.T, mesh.points):
        raise RuntimeError(f"{mesh.name}: scikit-fem reordered the mesh points; cannot keep the node numbering")
    edges = sk_mesh.edges.T.astype(np.int64) if order == 2 else np.zeros((0, 2), dtype=np.int64)
    # Exact coordinates (scikit-fem's doflocs carry mapping round-off); checked against them.
    nodes = np.vstack([mesh.points, mesh.points[edges].mean(axis=1)])
    basis, element_nodes = _scalar_basis(sk_mesh, order, 1)
    located = np.empty_like(nodes)
    located[element_nodes.ravel()] = basis.doflocs[:, basis.element_dofs.T].reshape(3, -1).T
    if not np.allclose(located, nodes, rtol=0.0, atol=1e-12 * np.ptp(nodes, axis=0).max()):
        raise RuntimeError(
            f"{mesh.name}: scikit-fem DOF locations do not match vertices + edge midpoints; "
            "its DOF layout changed, update ffrf.fe.fe_model._scalar_basis"
        )
    return nodes, _vector_mass(sk_mesh, order, material.rho), _stiffness(sk_mesh, order, material), edges
