r"""Free-free (unconstrained) eigenmodes as a mode basis, the alternative to Craig-Bampton.

The lowest eigenpairs of the unconstrained body, K phi = omega^2 M phi, with the 6 rigid-body
modes (omega = 0) left out (``docs/formulation.md``, eqs. (FF-1), (FF-2)); this is Exudyn's
``FEMinterface.ComputeEigenmodes(nModes, excludeRigidBodyModes=6, useSparseSolver=True)``. K is
singular, so the pencil is shifted: (K + s M) phi = (omega^2 + s) M phi with s > 0 small, which
is positive definite and has the same eigenvectors (Exudyn factorises the singular K itself,
sigma = 0). The solve is :func:`ffrf.numerics.eigen.lowest_eigenpairs` (fixed Lanczos start,
Sturm-checked count, deterministic signs), so the basis does not depend on the BLAS kernel.

The elastic modes are M-orthogonal to the rigid-body modes R (eq. (FF-3)): R^T M Psi = 0, the
linearised Tisserand (mean-axis) conditions of (HCB-6). No interface is involved; the floating
frame keeps the centre of mass of the deformed body fixed and has no first-order angular momentum
relative to it. Input is duck-typed as for :func:`ffrf.reduction.craig_bampton.craig_bampton`.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ffrf.errors import ReductionError
from ffrf.fe.fe_model import rigid_body_modes
from ffrf.numerics.eigen import SHIFT_REL, eigenvalue_scale, factorize_spd, lowest_eigenpairs
from ffrf.reduction.craig_bampton import checked_model
from ffrf.reduction.mode_basis import ReducedMatrices

__all__ = ["FreeFreeBasis", "free_free_basis", "rigid_body_coupling"]

logger = logging.getLogger(__name__)

# |omega^2| below this fraction of the eigenvalue scale is zero (rigid modes: ~1e-15 of it) ...
_ZERO_EIGENVALUE_REL = 1e-10
# ... and zero modes must lie in span(R) to this M-norm residual (unit modes).
_RIGID_SPAN_TOL = 1e-6


@dataclass(frozen=True, eq=False)
class FreeFreeBasis(ReducedMatrices):
    """Result of :func:`free_free_basis`; a :class:`ffrf.reduction.mode_basis.ModeBasis`.

    Attributes
    ----------
    basis : (3N, m) elastic eigenmodes, M-orthonormal, ascending frequency, deterministic signs.
    frequencies_hz : (m,) their frequencies omega / (2 pi).
    reduced_mass, reduced_stiffness : (m, m) Psi^T M Psi (= I) and Psi^T K Psi (= diag omega^2), symmetrised.
    rigid_body_eigenvalues : (n_rigid,) omega^2 of the left-out modes (round-off, ~0).
    reference_residual : max ``|R_hat^T M Psi|`` over the M-normalised rigid modes R_hat: how exactly
        the reference conditions (FF-3) hold (round-off).
    mode_labels : one text label per column, e.g. ``"free-free 1 (123.4 Hz)"``.
    reference : "mean_axis" (eq. (FF-3)), as for Craig-Bampton with ``reference="mean_axis"``.
    """

    basis: NDArray[np.float64]
    frequencies_hz: NDArray[np.float64]
    reduced_mass: NDArray[np.float64]
    reduced_stiffness: NDArray[np.float64]
    rigid_body_eigenvalues: NDArray[np.float64]
    reference_residual: float
    mode_labels: tuple[str, ...]
    reference: str = "mean_axis"

    def summary(self) -> str:
        """Mode count and order as text, for logs and reports."""
        lines = [
            f"free-free basis: {self.n_modes} elastic modes, {len(self.rigid_body_eigenvalues)} rigid-body modes "
            f"left out, reference={self.reference!r} (residual {self.reference_residual:.1e})"
        ]
        lines += [f"  {i:3d}: {label}" for i, label in enumerate(self.mode_labels)]
        return "\n".join(lines)


def rigid_body_coupling(nodes: NDArray, mass: sp.spmatrix, basis: NDArray) -> NDArray[np.float64]:
    """R_hat^T M Psi (6, m) with R_hat the rigid-body modes, M-orthonormalised: zero when Psi
    satisfies the reference conditions (FF-3); entries are cosines if Psi is M-normalised."""
    rigid = rigid_body_modes(nodes)
    gram = rigid.T @ (mass @ rigid)
    factor = np.linalg.cholesky(0.5 * (gram + gram.T))
    normalised = np.linalg.solve(factor, rigid.T).T  # R L^-T: M-orthonormal columns
    return normalised.T @ (mass @ basis)


def _check_rigid_modes(nodes, mass, vectors: NDArray, values: NDArray, n_rigid: int, scale: float) -> None:
    """Exactly n_rigid of the computed modes have zero frequency, and they are rigid-body motions."""
    n_zero = int(np.count_nonzero(np.abs(values) <= _ZERO_EIGENVALUE_REL * scale))
    next_hz = np.sqrt(abs(values[min(n_zero, len(values) - 1)])) / (2.0 * np.pi)
    if n_zero > n_rigid:
        raise ReductionError(
            f"{n_zero} modes have zero frequency where {n_rigid} rigid-body modes are expected: a mechanism, nodes "
            "without elements, or parts that are not connected; fix the model"
        )
    if n_zero < n_rigid:
        raise ReductionError(
            f"only {n_zero} modes have zero frequency (the next: {next_hz:.4g} Hz), {n_rigid} rigid-body modes "
            f"expected: the body is supported; pass n_rigid={n_zero}, or use craig_bampton for a supported body"
        )
    if n_rigid:
        rigid = rigid_body_modes(nodes)
        m_rigid = mass @ rigid
        error = vectors[:, :n_rigid] - rigid @ np.linalg.solve(rigid.T @ m_rigid, m_rigid.T @ vectors[:, :n_rigid])
        residual = float(np.sqrt(np.max(np.einsum("ij,ij->j", error, mass @ error))))
        if residual > _RIGID_SPAN_TOL:
            raise ReductionError(
                f"the {n_rigid} zero-frequency modes are not rigid-body motions of the nodes (M-norm residual "
                f"{residual:.2g}): do the matrices number the DOFs as the node table, [x0, y0, z0, x1, ...]?"
            )


def free_free_basis(fe_model: Any, n_modes: int, *, n_rigid: int = 6, verify_mode_count: bool = True) -> FreeFreeBasis:
    """The ``n_modes`` lowest elastic free-free modes of ``fe_model`` (eqs. (FF-1)-(FF-3)).

    Parameters
    ----------
    fe_model : object with ``.nodes`` (N, 3), ``.mass``, ``.stiffness`` (3N, 3N) sparse.
    n_modes : number m >= 1 of elastic modes kept.
    n_rigid : rigid-body modes left out (Exudyn's ``excludeRigidBodyModes``): 6 for one free solid;
        fewer if the model is partly supported. They are checked to be rigid motions.
    verify_mode_count : check with a Sturm sequence count that no mode was missed.
    """
    if isinstance(n_modes, bool) or int(n_modes) != n_modes or n_modes < 1:
        raise ReductionError(f"n_modes={n_modes!r} must be a positive integer")
    if isinstance(n_rigid, bool) or int(n_rigid) != n_rigid or not 0 <= n_rigid <= 6:
        raise ReductionError(f"n_rigid={n_rigid!r} must be an integer from 0 to 6 (a free solid has 6 rigid motions)")
    nodes, mass, stiffness = checked_model(fe_model)
    n_total = int(n_rigid) + int(n_modes)
    if n_total > 3 * len(nodes) - 1:
        raise ReductionError(
            f"too many modes requested: {n_modes} + {n_rigid} rigid, but the model has {3 * len(nodes)} DOFs; "
            f"ask for at most {max(3 * len(nodes) - 1 - n_rigid, 0)} or refine the mesh"
        )
    scale = eigenvalue_scale(mass, stiffness)
    shift = SHIFT_REL * scale  # eq. (FF-1)
    shifted = sp.csc_matrix(stiffness + shift * mass)
    solve = factorize_spd(
        shifted,
        "K + s M is not positive definite: K has negative eigenvalues or M is singular; check the matrices",
    )
    values, vectors = lowest_eigenpairs(shifted, mass.tocsc(), n_total, solve, verify_count=verify_mode_count)
    values = values - shift
    _check_rigid_modes(nodes, mass, vectors, values, int(n_rigid), scale)

    basis = vectors[:, n_rigid:]  # eq. (FF-2)
    omega_sq = values[n_rigid:]
    frequencies = np.sqrt(np.clip(omega_sq, 0.0, None)) / (2.0 * np.pi)
    reduced_mass = basis.T @ (mass @ basis)
    reduced_stiffness = basis.T @ (stiffness @ basis)
    result = FreeFreeBasis(
        basis,
        frequencies,
        0.5 * (reduced_mass + reduced_mass.T),
        0.5 * (reduced_stiffness + reduced_stiffness.T),
        values[:n_rigid],
        float(np.abs(rigid_body_coupling(nodes, mass, basis)).max()) if n_rigid == 6 else float("nan"),
        tuple(f"free-free {i + 1} ({f:.6g} Hz)" for i, f in enumerate(frequencies)),
        "mean_axis" if n_rigid == 6 else "none",  # partly supported: (FF-3) holds only for the free motions
    )
    logger.info("%s", result.summary())
    return result
