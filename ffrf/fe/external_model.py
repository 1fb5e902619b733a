"""A solid FE model given from outside by its nodes, mass and stiffness matrices.

Another program (Abaqus, Ansys, NGsolve, ...) assembled M and K; here they are only checked and,
where Exudyn's ``FEMinterface`` offers it, modified: a lumped point mass at a node
(``AddNodeMass``) and a scaled stiffness (``ScaleStiffnessMatrix``). The model is duck-typed like
:class:`ffrf.fe.fe_model.FEModel` (``.nodes`` (N, 3), ``.mass``, ``.stiffness`` (3N, 3N) CSR, DOF
layout [x0, y0, z0, x1, ...]), so :func:`ffrf.reduction.craig_bampton.craig_bampton`, the free-free
modes (:mod:`ffrf.reduction.free_free`) and :func:`ffrf.body.modal_moments.modal_moments` take it
as it is. The readers are in :mod:`ffrf.fe.matrix_import`; ``docs/formulation.md``, section
"External FE models", eqs. (X1)-(X3).
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

from ffrf.errors import ExternalFEError

__all__ = ["ExternalFEModel", "ELEMENT_NODES", "dof_name"]

logger = logging.getLogger(__name__)

#: Nodes per element of the volume elements whose topology is known (Exudyn's names; the Abaqus
#: types C3D4, C3D10*, C3D8*, C3D20* are read as these). Other types keep their own name.
ELEMENT_NODES: dict[str, int] = {"Tet4": 4, "Tet10": 10, "Hex8": 8, "Hex20": 20}

# |M - M^T| above this fraction of max|M| is not round-off of a symmetric assembly.
_SYMMETRY_REL_TOL = 1e-10


def dof_name(dof: int) -> str:
    """'node 12 y' for DOF 37 (layout [x0, y0, z0, x1, ...], 0-based nodes)."""
    return f"node {dof // 3} {'xyz'[dof % 3]}"


@dataclass(frozen=True, eq=False)
class ExternalFEModel:
    """Nodes and matrices of one solid body from another FE program (SI units).

    Attributes
    ----------
    nodes : (N, 3) reference positions in the body frame.
    mass, stiffness : (3N, 3N) symmetric CSR matrices, DOFs [x0, y0, z0, x1, ...].
    elements : element type -> (k, nodes per element) 0-based node indices; only used to find
        surfaces (:mod:`ffrf.fe.node_selection`). Keys of :data:`ELEMENT_NODES` or another
        program's type name.
    name : label used in messages.
    """

    nodes: NDArray[np.float64]
    mass: sp.csr_matrix
    stiffness: sp.csr_matrix
    elements: Mapping[str, NDArray[np.int64]] = field(default_factory=dict)
    name: str = "external model"

    def __post_init__(self):
        nodes = np.asarray(self.nodes, dtype=float)
        if nodes.ndim != 2 or nodes.shape[1] != 3 or len(nodes) == 0:
            raise ExternalFEError(
                f"{self.name}: nodes must be an (N, 3) array of coordinates, got shape {nodes.shape}; "
                "only solid models with 3 displacement DOFs per node are supported"
            )
        if not np.all(np.isfinite(nodes)):
            raise ExternalFEError(f"{self.name}: node coordinates contain NaN or inf; check the node table")
        object.__setattr__(self, "nodes", nodes)
        for label in ("mass", "stiffness"):
            object.__setattr__(self, label, self._checked_matrix(label, getattr(self, label)))
        object.__setattr__(self, "elements", self._checked_elements(self.elements))

    def _checked_matrix(self, label: str, matrix) -> sp.csr_matrix:
        matrix = sp.csr_matrix(matrix, dtype=float)
        expected = (3 * len(self.nodes),) * 2
        if matrix.shape != expected:
            raise ExternalFEError(
                f"{self.name}: {label} matrix is {matrix.shape[0]} x {matrix.shape[1]}, expected {expected[0]} x "
                f"{expected[1]} for {len(self.nodes)} nodes (3 DOFs each); are the matrix and the nodes from one model?"
            )
        if not np.all(np.isfinite(matrix.data)):
            raise ExternalFEError(f"{self.name}: {label} matrix contains NaN or inf; export it again")
        matrix.sum_duplicates()
        scale = float(np.abs(matrix.data).max()) if matrix.nnz else 0.0
        asymmetry = abs(matrix - matrix.T)
        if asymmetry.nnz and asymmetry.max() > _SYMMETRY_REL_TOL * scale:
            row, col = (int(i) for i in np.unravel_index(int(asymmetry.argmax()), matrix.shape))
            raise ExternalFEError(
                f"{self.name}: {label} matrix is not symmetric (entry ({dof_name(row)}, {dof_name(col)}) differs from "
                f"its transpose by {asymmetry.max():.3g}, max entry {scale:.3g}); export the full symmetric matrix"
            )
        diagonal = matrix.diagonal()
        bad = np.flatnonzero(diagonal <= 0.0) if label == "mass" else np.flatnonzero(diagonal < 0.0)
        if bad.size:
            sign = "<= 0" if label == "mass" else "< 0"
            raise ExternalFEError(
                f"{self.name}: {bad.size} diagonal entries of the {label} matrix are {sign} (first "
                f"{dof_name(int(bad[0]))}: {diagonal[bad[0]]:.3g}); a node without elements, or rows of another model?"
            )
        return matrix

    def _checked_elements(self, elements: Mapping[str, ArrayLike]) -> dict[str, NDArray[np.int64]]:
        checked = {}
        for kind, table in elements.items():
            array = np.asarray(table)
            if array.size == 0:
                continue
            if array.ndim != 2 or not np.issubdtype(array.dtype, np.integer):
                raise ExternalFEError(
                    f"{self.name}: elements {kind!r} must be a 2-D integer array (one row of node indices per "
                    f"element), got dtype {array.dtype} and shape {array.shape}"
                )
            if kind in ELEMENT_NODES and array.shape[1] != ELEMENT_NODES[kind]:
                raise ExternalFEError(
                    f"{self.name}: a {kind} element has {ELEMENT_NODES[kind]} nodes, the table has {array.shape[1]} "
                    "columns"
                )
            if array.min() < 0 or array.max() >= len(self.nodes):
                bad = int(array.min()) if array.min() < 0 else int(array.max())
                raise ExternalFEError(
                    f"{self.name}: elements {kind!r} refer to node {bad}, outside [0, {len(self.nodes)}); element "
                    "node indices are 0-based rows of the node table"
                )
            checked[kind] = array.astype(np.int64)
        return checked

    @property
    def n_nodes(self) -> int:
        return len(self.nodes)

    @property
    def n_dofs(self) -> int:
        return 3 * len(self.nodes)

    @property
    def total_mass(self) -> float:
        """m = e_x-translation^T M e_x-translation, the (0, 0) entry of Phi_t^T M Phi_t (eq. (INV-1))."""
        return float(self.mass[0::3, 0::3].sum())

    def with_node_mass(self, node: int, mass: float) -> ExternalFEModel:
        """The model with a point mass at ``node`` (eq. (X2)): ``mass`` added to the three diagonal
        entries of the node, no rotary inertia (Exudyn's ``FEMinterface.AddNodeMass``)."""
        if isinstance(node, bool) or int(node) != node or not 0 <= int(node) < self.n_nodes:
            raise ExternalFEError(
                f"{self.name}: point mass at node {node!r}: node indices are 0-based integers in [0, {self.n_nodes})"
            )
        if not (np.isfinite(mass) and mass >= 0.0):
            raise ExternalFEError(
                f"{self.name}: point mass {mass!r} kg at node {node} must be finite and >= 0; remove mass by "
                "changing the model, not by a negative point mass"
            )
        dofs = 3 * int(node) + np.arange(3)
        added = sp.csr_matrix((np.full(3, float(mass)), (dofs, dofs)), shape=self.mass.shape)
        logger.info("%s: point mass %.6g kg at node %d", self.name, mass, node)
        return replace(self, mass=self.mass + added)

    def with_scaled_stiffness(self, factor: float) -> ExternalFEModel:
        """The model with K multiplied by ``factor`` (eq. (X3); Exudyn's ``ScaleStiffnessMatrix``):
        every elastic frequency scales by sqrt(factor), the mass is unchanged."""
        if not (np.isfinite(factor) and factor > 0.0):
            raise ExternalFEError(
                f"{self.name}: stiffness factor {factor!r} must be finite and > 0 (a softer body: 0 < factor < 1)"
            )
        return replace(self, stiffness=self.stiffness * float(factor))
