"""Modal analysis: free-free modes with the rigid-body modes separated, and clamped modes.

The generalised eigenproblem K phi = omega^2 M phi is solved with scipy's
``eigsh`` in shift-invert mode. The shift is a small negative number, so that
K - sigma M is positive definite even though the free-free K is singular, and
the eigenvalues closest to sigma are the lowest ones.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

from ffrf.errors import FEInputError
from ffrf.fe.fe_model import FEModel
from ffrf.numerics.eigen import fix_signs, shift_invert_eigsh

__all__ = ["Modes", "clamped_modes", "eigenvalue_scale", "free_free_modes"]

logger = logging.getLogger(__name__)

# Shift and rigid threshold relative to the element-level eigenvalue scale
# diag(K).mean() / diag(M).mean(): rigid modes come out at ~1e-15 of it in
# double precision, the first flexible mode of any link meshed with fewer than
# ~1e4 elements along its length at > 1e-8 of it.
_SHIFT_REL = 1e-6
_RIGID_REL_TOL = 1e-10


@dataclass(frozen=True, eq=False)
class Modes:
    """Result of a modal analysis.

    Attributes
    ----------
    frequencies : (n,) natural frequencies of the flexible modes in Hz, ascending.
    shapes : (3N, n) mass-normalised flexible mode shapes (phi^T M phi = I).
    rigid_shapes : (3N, r) mass-normalised rigid-body modes (free-free only; r = 6 for one
        connected body), spanning the same space as :func:`ffrf.fe.fe_model.rigid_body_modes`.
    rigid_eigenvalues : (r,) their omega^2 (numerically ~0), kept for checks.
    """

    frequencies: NDArray[np.float64]
    shapes: NDArray[np.float64]
    rigid_shapes: NDArray[np.float64]
    rigid_eigenvalues: NDArray[np.float64]


def eigenvalue_scale(model: FEModel) -> float:
    """Element-level eigenvalue scale mean(diag K) / mean(diag M) in 1/s^2."""
    return float(model.stiffness.diagonal().mean() / model.mass.diagonal().mean())


def _lowest_eigenpairs(stiffness: sp.spmatrix, mass: sp.spmatrix, k: int, sigma: float):
    if k >= stiffness.shape[0] - 1:
        raise FEInputError(
            f"{k} modes requested but the model has only {stiffness.shape[0]} free DOFs; "
            "refine the mesh or ask for fewer modes"
        )
    values, vectors = shift_invert_eigsh(stiffness.tocsc(), mass.tocsc(), k, sigma)
    return values, fix_signs(vectors)


def free_free_modes(model: FEModel, n_modes: int = 10, *, n_rigid_expected: int = 6) -> Modes:
    """Lowest ``n_modes`` flexible free-free modes; rigid-body modes detected and separated.

    Rigid modes are the eigenpairs with omega^2 below 1e-10 of the element
    eigenvalue scale; a count other than ``n_rigid_expected`` (6 for one
    connected solid) is logged as a warning, since it means a mechanism or a
    poorly conditioned model.
    """
    if n_modes < 1:
        raise FEInputError(f"n_modes={n_modes!r} must be >= 1")
    scale = eigenvalue_scale(model)
    values, vectors = _lowest_eigenpairs(model.stiffness, model.mass, n_modes + n_rigid_expected, -_SHIFT_REL * scale)
    rigid = np.abs(values) < _RIGID_REL_TOL * scale
    if rigid.sum() != n_rigid_expected:
        logger.warning(
            "%s: %d rigid-body modes found, %d expected (eigenvalues %s)",
            model.mesh.name,
            rigid.sum(),
            n_rigid_expected,
            values[: n_rigid_expected + 2],
        )
    flexible = ~rigid
    omega_sq = np.clip(values[flexible], 0.0, None)
    return Modes(np.sqrt(omega_sq) / (2 * np.pi), vectors[:, flexible], vectors[:, rigid], values[rigid])


def clamped_modes(model: FEModel, fixed_dofs: ArrayLike, n_modes: int = 10) -> Modes:
    """Lowest ``n_modes`` modes with the DOFs ``fixed_dofs`` held at zero.

    Shapes are returned on all DOFs (zeros at the fixed ones).
    """
    fixed = np.unique(np.asarray(fixed_dofs, dtype=np.int64))
    if fixed.size == 0:
        raise FEInputError(
            f"{model.mesh.name}: clamped_modes needs at least one fixed DOF; "
            "use free_free_modes for an unsupported body"
        )
    if fixed.min() < 0 or fixed.max() >= model.n_dofs:
        raise FEInputError(f"{model.mesh.name}: fixed DOF index out of range [0, {model.n_dofs})")
    free = np.setdiff1d(np.arange(model.n_dofs), fixed)
    k_ff = model.stiffness[free][:, free]
    m_ff = model.mass[free][:, free]
    values, vectors = _lowest_eigenpairs(k_ff, m_ff, n_modes, -_SHIFT_REL * eigenvalue_scale(model))
    shapes = np.zeros((model.n_dofs, n_modes))
    shapes[free] = vectors
    return Modes(np.sqrt(np.clip(values, 0.0, None)) / (2 * np.pi), shapes, np.zeros((model.n_dofs, 0)), np.zeros(0))
