r"""Sensitivities of a study's outputs to its parameters: Sobol indices and standardised regression coefficients.

**Sobol indices** from the Saltelli design (:func:`ffrf.studies.sampling.saltelli_blocks`: :math:`f_A`,
:math:`f_B`, :math:`f_{AB}^{(i)}` the outputs of the rows of :math:`A`, :math:`B` and :math:`A_B^{(i)}`,
:math:`N` each), with the estimators recommended by Saltelli et al. (2010):

.. math::

    S_i = \frac{\frac1N \sum_j f_B^{(j)} \left(f_{AB}^{(i)(j)} - f_A^{(j)}\right)}{V},\qquad
    S_{Ti} = \frac{\frac1{2N} \sum_j \left(f_A^{(j)} - f_{AB}^{(i)(j)}\right)^2}{V},

the first-order index (Saltelli et al. 2010) and the total index (Jansen 1999), with :math:`V` the
variance of :math:`f_A` and :math:`f_B` together. A sample row :math:`j` with a failed variant in
:math:`A`, :math:`B` or :math:`A_B^{(i)}` is left out of index :math:`i` (the indices then describe the
variants that ran).

**Standardised regression coefficients** (SRC) from all rows: the least-squares fit
:math:`y \approx b_0 + \sum_i b_i x_i`, and :math:`\beta_i = b_i\,\sigma_{x_i} / \sigma_y`, with the fit's
:math:`R^2`; for a linear model with independent inputs :math:`\beta_i^2 = S_i` and :math:`\sum_i \beta_i^2 = R^2`.

References: A. Saltelli, P. Annoni, I. Azzini, F. Campolongo, M. Ratto, S. Tarantola, "Variance based
sensitivity analysis of model output. Design and estimator for the total sensitivity index", Computer Physics
Communications 181 (2010) 259-270; M. J. W. Jansen, "Analysis of variance designs for model output",
Computer Physics Communications 117 (1999) 35-43.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["SobolIndices", "Regression", "sobol_indices", "standardised_regression"]


@dataclass(frozen=True)
class SobolIndices:
    """First-order ``first`` and total ``total`` indices per parameter, and the rows ``used`` for each."""

    first: NDArray[np.float64]
    total: NDArray[np.float64]
    used: NDArray[np.int64]


@dataclass(frozen=True)
class Regression:
    """Standardised regression coefficients ``beta`` per parameter and the fit's ``r2``."""

    beta: NDArray[np.float64]
    r2: float


def sobol_indices(f_a: ArrayLike, f_b: ArrayLike, f_ab: ArrayLike) -> SobolIndices:
    """First-order and total Sobol indices (module docstring) from ``f_a``, ``f_b`` (``N``) and ``f_ab``
    (``N x d``, column ``i`` the outputs of :math:`A_B^{(i)}`); NaN entries mark failed variants."""
    a, b = np.asarray(f_a, dtype=float), np.asarray(f_b, dtype=float)
    ab = np.asarray(f_ab, dtype=float)
    both = np.concatenate([a, b])
    variance = float(np.var(both[np.isfinite(both)]))
    d = ab.shape[1]
    first, total, used = np.full(d, np.nan), np.full(d, np.nan), np.zeros(d, dtype=np.int64)
    for i in range(d):
        ok = np.isfinite(a) & np.isfinite(b) & np.isfinite(ab[:, i])
        used[i] = int(ok.sum())
        if used[i] == 0 or variance == 0.0:
            continue
        first[i] = float(np.mean(b[ok] * (ab[ok, i] - a[ok]))) / variance
        total[i] = 0.5 * float(np.mean((a[ok] - ab[ok, i]) ** 2)) / variance
    return SobolIndices(first, total, used)


def standardised_regression(x: ArrayLike, y: ArrayLike) -> Regression:
    """SRC of ``y`` (``n``) on the columns of ``x`` (``n x d``), rows with a non-finite ``y`` left out."""
    inputs, outputs = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    ok = np.isfinite(outputs) & np.all(np.isfinite(inputs), axis=1)
    xs, ys = inputs[ok], outputs[ok]
    d = xs.shape[1]
    sx, sy = np.std(xs, axis=0), float(np.std(ys))
    if len(ys) <= d + 1 or sy == 0.0:
        return Regression(np.full(d, np.nan), float("nan"))
    varying = sx > 0.0
    design = np.column_stack([np.ones(len(ys)), xs[:, varying]])
    coefficients, *_ = np.linalg.lstsq(design, ys, rcond=None)
    beta = np.zeros(d)
    beta[varying] = coefficients[1:] * sx[varying] / sy
    residual = ys - design @ coefficients
    return Regression(beta, 1.0 - float(np.mean(residual**2)) / sy**2)
