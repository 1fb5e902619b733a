"""Generalized symmetric eigenproblems K x = lambda M x that give the same answer on every run.

ARPACK's ``eigsh`` starts Lanczos from a random vector unless given one, so two identical runs
differed (Craig-Bampton bases by 1.4e-11, a near-rigid loop's driving torque by 1.5e-6 N m).
Here Lanczos always starts from :func:`lanczos_start`, and every mode's sign follows
:func:`fix_signs`, so a rerun on the same machine reproduces every bit. :func:`lowest_eigenpairs`
(the fixed-interface modes of :mod:`ffrf.reduction.craig_bampton`, the free-free modes of
:mod:`ffrf.reduction.free_free`) checks its count of modes with a
Sturm sequence (:func:`count_eigenvalues_below`), so no mode of a cluster is missed.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.linalg import eigh
from scipy.sparse.linalg import LinearOperator, eigsh, splu

from ffrf.errors import ReductionError

__all__ = [
    "SHIFT_REL",
    "eigenvalue_scale",
    "fix_signs",
    "lanczos_start",
    "shift_invert_eigsh",
    "factorize_spd",
    "count_eigenvalues_below",
    "lowest_eigenpairs",
]

#: Shift of a pencil whose K is singular (free-free) or has rigid-like modes, as a fraction of
#: :func:`eigenvalue_scale`: small against any elastic eigenvalue of a sensible mesh, large against
#: round-off in K R (rigid modes come out at ~1e-15 of the scale).
SHIFT_REL = 1e-6
_START_SEED = 20261124
# Below this many interior DOFs the fixed-interface problem is solved densely (exact and cheap).
_DENSE_LIMIT = 600
# Relative eigenvalue gap below which two eigenvalues count as one repeated (clustered) value.
_CLUSTER_REL_GAP = 1e-6
# Pivot of the LDL^T of K_ii below this fraction of max|diag K_ii|: K_ii is singular.
_PIVOT_REL_TOL = 1e-13
_SIGN_BAND = 1e-6  # entries this close (relative) to the largest magnitude compete for deciding the sign

logger = logging.getLogger(__name__)


def eigenvalue_scale(mass: sp.spmatrix, stiffness: sp.spmatrix) -> float:
    """mean(diag K) / mean(diag M) (1/s^2): the eigenvalue of a single element; sets shifts and zero tolerances.

    >>> eigenvalue_scale(np.eye(2), np.diag([4.0, 8.0]))
    6.0
    """
    scale = float(stiffness.diagonal().mean() / mass.diagonal().mean())
    if not (np.isfinite(scale) and scale > 0.0):
        raise ReductionError(
            f"eigenvalue scale mean(diag K)/mean(diag M) = {scale!r}; the stiffness or the mass matrix is zero"
        )
    return scale


def lanczos_start(size: int) -> NDArray[np.float64]:
    """A fixed start vector: seeded normal entries, so that no mode is missed by symmetry (a
    constant vector is orthogonal to the antisymmetric modes of a symmetric mesh)."""
    return np.random.default_rng(_START_SEED).standard_normal(size)


def fix_signs(vectors: NDArray) -> NDArray[np.float64]:
    """Each column turned so that its first entry of (nearly) largest magnitude is positive.

    "First within 1e-6 of the largest" rather than "the largest": symmetric meshes have mode
    shapes whose extreme entries come in mirrored pairs of opposite sign that round-off orders at
    random.

    >>> fix_signs([[-2.0, 1.0], [1.0, -1.0]]).tolist()  # column 0 turned; column 1: a tie, its first entry decides
    [[2.0, 1.0], [-1.0, -1.0]]
    """
    vectors = np.array(vectors, dtype=float)
    magnitude = np.abs(vectors)
    if vectors.size == 0:
        return vectors
    deciding = np.argmax(magnitude >= (1.0 - _SIGN_BAND) * magnitude.max(axis=0), axis=0)
    signs = np.sign(vectors[deciding, np.arange(vectors.shape[1])])
    return vectors * np.where(signs < 0.0, -1.0, 1.0)


def shift_invert_eigsh(stiffness: Any, mass: Any, k: int, sigma: float, opinv: Any = None):
    """The ``k`` eigenpairs nearest ``sigma`` (ARPACK shift-invert, deterministic start), ascending."""
    values, vectors = eigsh(
        stiffness, k=k, M=mass, sigma=sigma, which="LM", OPinv=opinv, v0=lanczos_start(stiffness.shape[0])
    )
    order = np.argsort(values)
    return values[order], vectors[:, order]


def _symmetric_lu(matrix: sp.csc_matrix):
    """SuperLU in symmetric mode: diagonal pivots only, so U's diagonal is D of A = L D L^T."""
    return splu(matrix, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})


def factorize_spd(matrix: sp.csc_matrix, singular_message: str) -> Callable[[NDArray], NDArray]:
    """Factorise a symmetric positive definite sparse matrix once and return its solver; raise
    :class:`ReductionError` with ``singular_message`` on a non-positive or off-diagonal pivot."""
    try:
        lu = _symmetric_lu(matrix)
    except RuntimeError as exc:
        raise ReductionError(f"{singular_message} (sparse LU: {exc})") from exc
    pivots = lu.U.diagonal()
    if not np.array_equal(lu.perm_r, lu.perm_c) or pivots.min() <= _PIVOT_REL_TOL * abs(matrix.diagonal()).max():
        raise ReductionError(singular_message)
    return lu.solve


def count_eigenvalues_below(stiffness: sp.spmatrix, mass: sp.spmatrix, sigma: float) -> int | None:
    """Number of eigenvalues of K x = lambda M x below ``sigma``: the negative pivots of
    K - sigma M = L D L^T (Sturm sequence property; Bathe, Finite Element Procedures, 2nd ed.,
    sec. 11.4.3). None if the factorisation pivoted off the diagonal (count unavailable)."""
    lu = _symmetric_lu(sp.csc_matrix(stiffness - sigma * mass))
    if not np.array_equal(lu.perm_r, lu.perm_c):
        return None
    return int(np.count_nonzero(lu.U.diagonal() < 0.0))


def _ritz_cleanup(stiffness, mass, vectors: NDArray):
    """Rayleigh-Ritz on the computed subspace: exact M-orthonormality, sorted, deterministic signs."""
    values, q = eigh(vectors.T @ (stiffness @ vectors), vectors.T @ (mass @ vectors))
    vectors = vectors @ q
    return values, fix_signs(vectors)


def _verified_lanczos(stiffness, mass, n: int, solve, verify_count: bool):
    """Shift-invert Lanczos about 0 with guard modes; Sturm-checked count, re-run if modes were missed."""
    size, guard = stiffness.shape[0], max(4, n // 4)
    request = min(n + guard, size - 1)
    inverse = LinearOperator(stiffness.shape, matvec=solve, dtype=float)
    for _ in range(4):
        values, vectors = shift_invert_eigsh(stiffness, mass, request, 0.0, inverse)
        gaps = np.flatnonzero(values[n:] > values[n - 1 : -1] * (1.0 + _CLUSTER_REL_GAP)) + n
        if not verify_count or request == size - 1:
            return values, vectors
        if len(gaps) == 0:  # the guard modes are all in one cluster with mode n: look further
            request = min(2 * request, size - 1)
            continue
        j = int(gaps[0])
        count = count_eigenvalues_below(stiffness, mass, 0.5 * (values[j - 1] + values[j]))
        if count is None:
            logger.warning("Sturm count unavailable (off-diagonal pivoting); the mode count is not verified")
        if count is None or count == j:
            return values, vectors
        logger.warning("shift-invert Lanczos missed %d of the lowest %d eigenvalues; recomputing", count - j, count)
        request = min(count + guard, size - 1)
    raise ReductionError(
        f"could not verify the lowest {n} eigenmodes after 4 attempts; "
        "ask for fewer modes or pass verify_mode_count=False"
    )


def lowest_eigenpairs(
    stiffness: sp.csc_matrix,
    mass: sp.csc_matrix,
    n: int,
    solve: Callable[[NDArray], NDArray],
    *,
    verify_count: bool = True,
):
    """The n lowest eigenpairs of K x = lambda M x (K positive definite, ``solve`` applies K^-1), M-orthonormal.

    Shift-invert Lanczos (ARPACK ``eigsh``) with a few guard modes; with
    ``verify_count`` a Sturm count (:func:`count_eigenvalues_below`) at a shift in
    the first clear gap above the n-th value detects modes missed in clusters.
    Small problems are solved densely.
    """
    size = stiffness.shape[0]
    if n == 0:
        return np.zeros(0), np.zeros((size, 0))
    if size <= _DENSE_LIMIT:
        values, vectors = eigh(stiffness.toarray(), mass.toarray(), subset_by_index=[0, min(n, size - 1)])
    else:
        values, vectors = _verified_lanczos(stiffness, mass, n, solve, verify_count)
    if len(values) > n and values[n] <= values[n - 1] * (1.0 + _CLUSTER_REL_GAP):
        logger.warning(
            "modes %d and %d have the same frequency: the basis holds an arbitrary part "
            "of a repeated-mode space; choose n_modes so that repeated modes are kept together",
            n,
            n + 1,
        )
    return _ritz_cleanup(stiffness, mass, vectors[:, :n])
