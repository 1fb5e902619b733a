r"""Linear solves whose verdict "singular or not" does not depend on rounding (``docs/formulation.md``, Eq. (R1)).

Newton matrices of overconstrained linkages can be singular for physical reasons: a body that
can still move freely (a mechanism, a missing support), constraints made redundant by a closed
loop of (near-)rigid links, a folded pose with one more instantaneous freedom. Whether LU meets
an exact zero pivot there is decided by the last bits of the arithmetic, so it changes with the
BLAS kernel (``OPENBLAS_CORETYPE``) and the thread count. The rule used here instead:

1. equilibrate rows and columns by :math:`1/\sqrt{\max|a|}` (one Ruiz pass), so that stiffness
   rows of near-rigid links and unit constraint rows are compared on one scale;
2. LU-factor; if LAPACK's reciprocal condition estimate (1-norm) exceeds
   :data:`WELL_CONDITIONED`, the matrix is regular with a wide margin and LU solves it;
3. otherwise take the SVD and count singular values :math:`\sigma_i \le n\varepsilon\,\sigma_1`
   as zero (:func:`rank_tolerance`, the rule of LAPACK's and NumPy's rank estimates); solves use
   the truncated pseudo-inverse (minimum-norm Newton steps, which leave free motions and the
   multipliers of redundant constraints where they are).

A backward-stable SVD computes the zero singular values of an exactly singular matrix within a
few :math:`\varepsilon\sigma_1` (measured: at most :math:`1.3\cdot10^{-15}\sigma_1` on the
two-bar chain's free motions, :math:`n = 44`, on every OpenBLAS core type), an order of
magnitude or more below :math:`n\varepsilon\sigma_1`. Physical small singular values are far
above it: the nearly redundant constraints of the near-rigid Bennett loop (links of 1e15 Pa)
give :math:`6\cdot10^{-13}\sigma_1`, 26 times the threshold at its :math:`n = 105`
(``tests/test_ffrf_body/test_rank_revealing.py`` checks both). So every kernel gives the same
rank. Step 2's gate is consistent with step 3: :math:`\mathrm{rcond} > 10^{-8}` bounds
:math:`\sigma_n/\sigma_1` from below by about :math:`10^{-8}/n`, far above :math:`n\varepsilon`.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import scipy.linalg
from numpy.typing import NDArray
from scipy.linalg.lapack import dgecon as gecon
from scipy.linalg.lapack import dgetrs as getrs

__all__ = ["WELL_CONDITIONED", "FactoredMatrix", "equilibration", "factor", "rank_tolerance", "singular_values"]

WELL_CONDITIONED = 1e-8  # LAPACK's reciprocal condition estimate above which LU is used without an SVD


def rank_tolerance(n: int) -> float:
    """Singular values at most this fraction of the largest count as zero in an ``n`` x ``n`` matrix."""
    return n * np.finfo(float).eps


def equilibration(matrix: NDArray) -> tuple[NDArray, NDArray]:
    """Row and column scalings 1/sqrt(max ``|a|``) (one Ruiz pass; zero rows and columns keep 1)."""
    magnitude = np.abs(matrix)
    row_max, col_max = magnitude.max(axis=1), magnitude.max(axis=0)
    rows = 1.0 / np.sqrt(np.where(row_max > 0, row_max, 1.0))
    cols = 1.0 / np.sqrt(np.where(col_max > 0, col_max, 1.0))
    return rows, cols


@dataclass
class FactoredMatrix:
    """An equilibrated square matrix ready to solve with: LU factors when it is regular, else
    its truncated pseudo-inverse and the dimension of its null space (``rank_deficiency``)."""

    rows: NDArray
    cols: NDArray
    factors: tuple | None
    pseudo_inverse: NDArray | None = None
    rank_deficiency: int = 0

    def solve(self, rhs: NDArray) -> NDArray:
        """``x`` with ``A x = rhs`` (least squares, minimum norm in the equilibrated unknowns, if singular)."""
        scaled = self.rows * rhs
        if self.factors is not None:
            return self.cols * getrs(*self.factors, scaled)[0]  # what lu_solve calls, without its wrapper
        return self.cols * (self.pseudo_inverse @ scaled)


def singular_values(scaled: NDArray, compute_uv: bool = True):
    """SVD by LAPACK's divide and conquer, falling back to the QR iteration (``gesvd``) where the
    former fails to converge (seen once on a 2 mm Bennett tangent)."""
    try:
        return scipy.linalg.svd(scaled, compute_uv=compute_uv, check_finite=False)
    except np.linalg.LinAlgError:
        return scipy.linalg.svd(scaled, compute_uv=compute_uv, check_finite=False, lapack_driver="gesvd")


def factor(matrix: NDArray, what: str = "matrix") -> FactoredMatrix:
    """Equilibrate and factor ``matrix`` by the rule of this module; ``what`` names it in errors.

    Raises ``FloatingPointError`` if the matrix has entries that are not finite."""
    if not np.all(np.isfinite(matrix)):
        raise FloatingPointError(f"the {what} has entries that are not finite; check the model and the state")
    rows, cols = equilibration(matrix)
    scaled = rows[:, None] * matrix * cols[None, :]
    with warnings.catch_warnings():
        # An exact zero pivot is no verdict here (step 3 decides), so LAPACK's warning is noise
        warnings.simplefilter("ignore", scipy.linalg.LinAlgWarning)
        factors = scipy.linalg.lu_factor(scaled, check_finite=False)
    with np.errstate(divide="ignore", invalid="ignore"):
        rcond, _ = gecon(factors[0], np.abs(scaled).sum(axis=0).max(), norm="1")
    if rcond > WELL_CONDITIONED:
        return FactoredMatrix(rows, cols, factors)
    u, sigma, vt = singular_values(scaled)
    keep = sigma > rank_tolerance(sigma.size) * sigma[0]
    deficiency = int(sigma.size - np.count_nonzero(keep))
    if deficiency == 0:
        return FactoredMatrix(rows, cols, factors)
    pseudo_inverse = (vt[keep].T / sigma[keep]) @ u[:, keep].T
    return FactoredMatrix(rows, cols, None, pseudo_inverse, deficiency)
