"""Hurty/Craig-Bampton (HCB) component modes with rigid (RBE2-type) interfaces.

u = Psi q with static (constraint) modes, i.e. unit rigid motions of one interface with
the others fixed and the interior statically condensed (Craig and Bampton 1968, eq. 6;
Hurty 1965; ``docs/formulation.md`` eq. (HCB-3)), and the lowest fixed-interface normal
modes (Craig and Bampton 1968, eq. 4; eq. (HCB-4)). Each interface moves rigidly about
its weighted centre: 6 coordinates, translations then rotations (eq. (HCB-2)). The
default reference condition drops the first interface's static modes, as Exudyn's
``ComputeHurtyCraigBamptonModes(..., computationMode=RBE2, excludeRigidBodyMotion=True)``:
every column vanishes there and the frame is attached to it (eq. (HCB-5)). Rotation
columns follow the right-hand rule u_j = e_i x (x_j - p0); Exudyn's have the opposite sign.
Input is duck-typed: ``.nodes`` (N, 3), ``.mass``, ``.stiffness`` (3N, 3N), DOFs [x0, y0, z0, x1, ...].
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import eigh

from ffrf.errors import InterfaceError, ReductionError
from ffrf.fe.fe_model import rigid_body_modes
from ffrf.numerics.eigen import factorize_spd, fix_signs, lowest_eigenpairs
from ffrf.reduction.mode_basis import ReducedMatrices

__all__ = [
    "REFERENCE_CONDITIONS",
    "RigidInterface",
    "aligned_modes",
    "CraigBamptonBasis",
    "craig_bampton",
    "rigid_interfaces",
    "checked_model",
]

logger = logging.getLogger(__name__)

#: "interface": frame attached to the first interface (Exudyn RBE2, excludeRigidBodyMotion=True);
#: "mean_axis": linearised Tisserand / Buckens conditions Phi_t^T M Psi = 0, x~^T M Psi = 0;
#: "none": all 6K static modes kept (the basis contains the rigid-body motions).
REFERENCE_CONDITIONS = ("interface", "mean_axis", "none")

# Rank test of the rigid motions seen by the interfaces (singular value ratio).
_RESTRAINT_RANK_TOL = 1e-8


_NOT_RESTRAINED = "interfaces do not restrain the body; check that interface node sets are non-empty and not collinear"


@dataclass(frozen=True, eq=False)
class RigidInterface:
    """One rigid (RBE2-type) interface: node indices (order as given), weights (>= 0, sum 1)
    and weighted centre p0 = sum_j w_j x_j (eq. (HCB-1))."""

    nodes: NDArray[np.int64]
    weights: NDArray[np.float64]
    center: NDArray[np.float64]

    @property
    def dofs(self) -> NDArray[np.int64]:
        """DOF indices [x, y, z] of every node, node by node."""
        return (3 * self.nodes[:, None] + np.arange(3)).reshape(-1)


@dataclass(frozen=True, eq=False)
class CraigBamptonBasis(ReducedMatrices):
    """Result of :func:`craig_bampton`.

    Attributes
    ----------
    basis : (3N, m) mode matrix Psi, static modes first, then fixed-interface modes.
    n_static_modes : number of static (constraint) columns (6 per retained interface).
    fixed_interface_frequencies_hz : (n_m,) frequencies of the fixed-interface modes, ascending.
    reduced_mass, reduced_stiffness : (m, m) Psi^T M Psi and Psi^T K Psi (symmetrised).
    interfaces : the rigid interfaces, first = frame interface.
    mode_labels : one text label per column, e.g. ``"interface 1 rx"``, ``"fixed-interface 3"``.
    reference : one of :data:`REFERENCE_CONDITIONS`.
    orthonormalized : True if the columns were rotated to diagonalise reduced M and K.
    """

    basis: NDArray[np.float64]
    n_static_modes: int
    fixed_interface_frequencies_hz: NDArray[np.float64]
    reduced_mass: NDArray[np.float64]
    reduced_stiffness: NDArray[np.float64]
    interfaces: tuple[RigidInterface, ...]
    mode_labels: tuple[str, ...]
    reference: str = "interface"
    orthonormalized: bool = False

    def summary(self) -> str:
        """Mode count and order as text, for logs and reports."""
        lines = [
            f"HCB basis: {self.n_modes} modes ({self.n_static_modes} static, "
            f"{len(self.fixed_interface_frequencies_hz)} fixed-interface), reference={self.reference!r}, "
            f"orthonormalized={self.orthonormalized}"
        ]
        lines += [f"  {i:3d}: {label}" for i, label in enumerate(self.mode_labels)]
        return "\n".join(lines)


def checked_model(fe_model: Any) -> tuple[NDArray[np.float64], sp.csr_matrix, sp.csr_matrix]:
    """(nodes, mass, stiffness) of a duck-typed FE model, checked for shape and NaN/inf."""
    nodes = np.asarray(fe_model.nodes, dtype=float)
    if nodes.ndim != 2 or nodes.shape[1] != 3 or not np.all(np.isfinite(nodes)):
        raise ReductionError(f"fe_model.nodes must be a finite (N, 3) array, got shape {nodes.shape}")
    matrices = []
    for name in ("mass", "stiffness"):
        matrix = sp.csr_matrix(getattr(fe_model, name), dtype=float)
        if matrix.shape != (3 * len(nodes),) * 2:
            raise ReductionError(
                f"{name} matrix has shape {matrix.shape}, expected {(3 * len(nodes),) * 2} for "
                f"{len(nodes)} nodes (DOF layout [x0, y0, z0, x1, ...])"
            )
        if not np.all(np.isfinite(matrix.data)):
            raise ReductionError(f"{name} matrix contains NaN or inf entries; check material data and elements")
        matrices.append(matrix)
    return nodes, matrices[0], matrices[1]


def rigid_interfaces(
    nodes: NDArray[np.float64], interfaces: Sequence[Any], weights: Sequence[ArrayLike] | None = None
) -> tuple[RigidInterface, ...]:
    """Validate interface node sets and weights; compute the weighted centres.

    ``interfaces`` holds node-index arrays or objects with ``.nodes`` and
    ``.weights`` (e.g. :class:`ffrf.fe.interfaces.InterfaceNodes`). Weights default
    to the objects' weights, else uniform 1/n_k (as Exudyn); they are normalised to sum 1.
    """
    if len(interfaces) == 0:
        raise InterfaceError(
            "no interfaces given; pass a list of node-index arrays, the first one being the frame interface"
        )
    if weights is not None and len(weights) != len(interfaces):
        raise InterfaceError(f"{len(weights)} weight arrays for {len(interfaces)} interfaces; give one per interface")
    result, seen = [], np.zeros(len(nodes), dtype=np.int64)
    for k, item in enumerate(interfaces):
        ids = np.asarray(getattr(item, "nodes", item))
        if ids.size == 0:
            raise InterfaceError(f"interface {k} has an empty node set; select at least 3 non-collinear nodes")
        if not np.issubdtype(ids.dtype, np.integer):
            raise InterfaceError(f"interface {k}: node indices must be integers, got dtype {ids.dtype}")
        ids = ids.astype(np.int64).reshape(-1)
        if ids.min() < 0 or ids.max() >= len(nodes):
            bad = ids[(ids < 0) | (ids >= len(nodes))][:5].tolist()
            raise InterfaceError(
                f"interface {k}: node index out of range [0, {len(nodes)}): {bad}; indices are rows of fe_model.nodes"
            )
        if len(np.unique(ids)) != len(ids):
            raise InterfaceError(f"interface {k} lists a node more than once; pass unique node indices")
        seen[ids] += 1
        if np.any(seen[ids] > 1):
            raise InterfaceError(
                f"interface {k} overlaps an earlier interface (shared nodes "
                f"{ids[seen[ids] > 1][:5].tolist()}); interfaces must be disjoint node sets"
            )
        w = weights[k] if weights is not None else getattr(item, "weights", None)
        w = np.full(len(ids), 1.0 / len(ids)) if w is None else np.asarray(w, dtype=float).reshape(-1)
        if len(w) != len(ids):
            raise InterfaceError(f"interface {k}: {len(w)} weights for {len(ids)} nodes; give one weight per node")
        if not (np.all(np.isfinite(w)) and np.all(w >= 0.0) and w.sum() > 0.0):
            raise InterfaceError(f"interface {k}: weights must be finite, >= 0 and not all zero")
        w = w / w.sum()
        result.append(RigidInterface(ids, w, w @ nodes[ids]))
    return tuple(result)


def _check_restraint(nodes: NDArray, boundary_dofs: NDArray[np.int64]) -> None:
    """Raise if a rigid motion leaves every interface node at rest: for a connected body K_ii is
    regular iff the rigid modes restricted to the boundary DOFs have rank 6."""
    rigid = rigid_body_modes(nodes)
    rigid[:, 3:] /= max(np.ptp(nodes, axis=0).max(), np.finfo(float).tiny)  # rotations in length units
    s = np.linalg.svd(rigid[boundary_dofs], compute_uv=False)
    if len(s) < 6 or s[-1] <= _RESTRAINT_RANK_TOL * s[0]:
        raise ReductionError(_NOT_RESTRAINED)


def _mean_axis_projection(basis: NDArray, mass: sp.csr_matrix, nodes: NDArray) -> NDArray[np.float64]:
    """Remove the M-projection onto the rigid modes: Phi_t^T M Psi = 0 and x~^T M Psi = 0 (eq. (HCB-6))."""
    rigid = rigid_body_modes(nodes)
    m_rigid = mass @ rigid
    return basis - rigid @ np.linalg.solve(rigid.T @ m_rigid, m_rigid.T @ basis)


def craig_bampton(
    fe_model: Any,
    interfaces: Sequence[Any],
    n_modes: int,
    weights: Sequence[ArrayLike] | None = None,
    *,
    reference: str = "interface",
    orthonormalize: bool = False,
    verify_mode_count: bool = True,
) -> CraigBamptonBasis:
    """Hurty/Craig-Bampton basis with rigid interfaces (Craig and Bampton 1968; Hurty 1965).

    The mode count and order are logged (INFO) and available as ``result.summary()``.

    Parameters
    ----------
    fe_model : object with ``.nodes`` (N, 3), ``.mass``, ``.stiffness`` (3N, 3N) sparse.
    interfaces : node-index arrays into ``fe_model.nodes`` (or objects with ``.nodes`` and
        ``.weights``); the first is the frame interface.
    n_modes : number n_m of fixed-interface normal modes (>= 0).
    weights : optional weight arrays, one per interface (default: the objects' weights or uniform).
    reference : see :data:`REFERENCE_CONDITIONS`; "interface" reproduces Exudyn's
        ``excludeRigidBodyMotion=True``.
    orthonormalize : rotate the basis so that reduced M = I and reduced K is diagonal
        (same span; columns ordered by frequency; eq. (HCB-7)).
    verify_mode_count : check with a Sturm sequence count that no fixed-interface mode was missed.
    """
    if reference not in REFERENCE_CONDITIONS:
        raise ReductionError(f"reference={reference!r} is unknown; choose one of {REFERENCE_CONDITIONS}")
    if int(n_modes) != n_modes or n_modes < 0:
        raise ReductionError(f"n_modes={n_modes!r} must be a non-negative integer")
    nodes, mass, stiffness = checked_model(fe_model)
    n_dofs = 3 * len(nodes)
    rigid = rigid_interfaces(nodes, interfaces, weights)

    boundary = np.concatenate([itf.dofs for itf in rigid])
    _check_restraint(nodes, boundary)
    interior = np.setdiff1d(np.arange(n_dofs), boundary)
    if n_modes > len(interior) - 1:
        raise ReductionError(
            f"too many modes requested: n_modes={n_modes}, but the interior has only "
            f"{len(interior)} DOFs; ask for at most {max(len(interior) - 1, 0)} or refine the mesh"
        )
    k_rows = stiffness[interior]
    k_ii = k_rows[:, interior].tocsc()
    k_ib = k_rows[:, boundary]
    m_ii = mass[interior][:, interior].tocsc()
    solve = factorize_spd(k_ii, _NOT_RESTRAINED)

    # Static modes, eq. (HCB-3): boundary rows = T, interior rows = -K_ii^{-1} K_ib T.
    kept = list(range(0 if reference == "none" else 1, len(rigid)))
    offsets = np.cumsum([0] + [len(itf.dofs) for itf in rigid])
    t_all = np.zeros((len(boundary), 6 * len(kept)))
    for col, k in enumerate(kept):
        t_all[offsets[k] : offsets[k + 1], 6 * col : 6 * col + 6] = rigid_body_modes(
            nodes[rigid[k].nodes], rigid[k].center
        )
    n_static = t_all.shape[1]
    basis = np.zeros((n_dofs, n_static + n_modes))
    basis[boundary, :n_static] = t_all
    if n_static:
        basis[interior, :n_static] = solve(-(k_ib @ t_all))

    # Fixed-interface modes, eq. (HCB-4), with the factorisation of K_ii reused for shift-invert.
    eigenvalues, vectors = lowest_eigenpairs(k_ii, m_ii, n_modes, solve, verify_count=verify_mode_count)
    basis[interior, n_static:] = vectors
    frequencies = np.sqrt(np.clip(eigenvalues, 0.0, None)) / (2.0 * np.pi)
    labels = [f"interface {k} {c}" for k in kept for c in ("tx", "ty", "tz", "rx", "ry", "rz")]
    labels += [f"fixed-interface {i + 1} ({f:.6g} Hz)" for i, f in enumerate(frequencies)]

    if reference == "mean_axis":
        basis = _mean_axis_projection(basis, mass, nodes)
        labels = [f"{label}, mean-axis projected" for label in labels]
    reduced_mass, reduced_stiffness = _reduced_matrices(basis, mass, stiffness)
    if orthonormalize:
        basis, reduced_mass, reduced_stiffness, labels = _orthonormalized(basis, reduced_mass, reduced_stiffness)
    result = CraigBamptonBasis(
        basis, n_static, frequencies, reduced_mass, reduced_stiffness, rigid, tuple(labels), reference, orthonormalize
    )
    logger.info("%s", result.summary())
    return result


def aligned_modes(basis: CraigBamptonBasis, reference: CraigBamptonBasis, fe_model: Any) -> CraigBamptonBasis:
    """``basis`` with its fixed-interface modes turned by the orthogonal matrix that brings them closest to
    ``reference``'s in the mass norm (the polar factor of their overlap ``Phi^T M Phi_ref``), and its reduced matrices
    for ``fe_model`` (the model ``basis`` reduces). For a morph of the reference's mesh this makes the modal
    coordinates a smooth function of the morph: eigenvectors alone flip sign and, where frequencies are close,
    turn within their span. The span, hence the reduced model's solutions, is unchanged."""
    _, mass, stiffness = checked_model(fe_model)
    start = basis.n_static_modes
    if reference.n_static_modes != start or reference.basis.shape != basis.basis.shape:
        raise ReductionError("aligned_modes: the reference basis reduces another model (other sizes)")
    modes = basis.basis[:, start:]
    u, singular, vt = np.linalg.svd(modes.T @ (mass @ reference.basis[:, start:]))
    if singular.size and singular.min() < 0.5:
        raise ReductionError(
            f"aligned_modes: the fixed-interface modes left the reference's span (overlap {singular.min():.3g}); "
            "the shape change crosses a mode beyond the kept ones: keep more modes"
        )
    turned = basis.basis.copy()
    turned[:, start:] = modes @ (u @ vt)
    reduced_mass, reduced_stiffness = _reduced_matrices(turned, mass, stiffness)
    return replace(basis, basis=turned, reduced_mass=reduced_mass, reduced_stiffness=reduced_stiffness)


def _symmetric(a: NDArray) -> NDArray[np.float64]:
    return 0.5 * (a + a.T)


def _reduced_matrices(basis: NDArray, mass: sp.csr_matrix, stiffness: sp.csr_matrix):
    """Psi^T M Psi and Psi^T K Psi, symmetrised (round-off only)."""
    return _symmetric(basis.T @ (mass @ basis)), _symmetric(basis.T @ (stiffness @ basis))


def _orthonormalized(basis: NDArray, m_red: NDArray, k_red: NDArray):
    """Psi V with K_red V = M_red V Lambda, V^T M_red V = I (eq. (HCB-7)); the span, and hence the
    reference condition (e.g. zero on the frame interface), is unchanged."""
    values, v = eigh(k_red, m_red)
    v = fix_signs(v)
    labels = [f"orthonormal {i + 1} ({f:.6g} Hz)" for i, f in enumerate(np.sqrt(np.clip(values, 0, None)) / 2 / np.pi)]
    return basis @ v, _symmetric(v.T @ m_red @ v), _symmetric(v.T @ k_red @ v), labels
