r"""Sensitivities of a study's outputs to its parameters, each with its 95 % interval: Sobol indices of a Saltelli
design, first-order indices from given data of any random design, and standardised regression coefficients.

**Sobol indices** from the Saltelli design (:func:`ffrf.studies.sampling.saltelli_blocks`: :math:`f_A`,
:math:`f_B`, :math:`f_{AB}^{(i)}` the outputs of the rows of :math:`A`, :math:`B` and :math:`A_B^{(i)}`,
:math:`N` each), with the estimators recommended by Saltelli et al. (2010):

.. math::

    S_i = \frac{\frac1N \sum_j \left(f_B^{(j)} - \bar f\right) \left(f_{AB}^{(i)(j)} - f_A^{(j)}\right)}{V},\qquad
    S_{Ti} = \frac{\frac1{2N} \sum_j \left(f_A^{(j)} - f_{AB}^{(i)(j)}\right)^2}{V},

the first-order index (Saltelli et al. 2010, on outputs centred by their mean :math:`\bar f` over the whole design,
which removes a bias of uncentred outputs) and the total index (Jansen 1999), with :math:`V` the variance of
:math:`f_A` and :math:`f_B` together, as SALib computes them (``SALib.analyze.sobol``), with its bootstrap
intervals (:data:`RESAMPLES` resamples of the rows, the normal interval of their spread). A sample row :math:`j`
with a failed variant in :math:`A`, :math:`B` or any :math:`A_B^{(i)}` is left out (the indices then describe the
variants that ran).

**Given-data first-order indices** of any random design (Monte Carlo, Latin hypercube, Sobol' points), from its
rows as they are: RBD-FAST (Plischke 2010, Tarantola et al. 2006; ``SALib.analyze.rbd_fast``, its bootstrap
intervals).

**Standardised regression coefficients** (SRC) from all rows: the least-squares fit
:math:`y \approx b_0 + \sum_i b_i x_i`, and :math:`\beta_i = b_i\,\sigma_{x_i} / \sigma_y`, with the fit's
:math:`R^2`; for a linear model with independent inputs :math:`\beta_i^2 = S_i` and :math:`\sum_i \beta_i^2 = R^2`.
Their 95 % intervals are percentile bootstrap intervals over the rows (``scipy.stats.bootstrap``).

References: A. Saltelli, P. Annoni, I. Azzini, F. Campolongo, M. Ratto, S. Tarantola, "Variance based
sensitivity analysis of model output. Design and estimator for the total sensitivity index", Computer Physics
Communications 181 (2010) 259-270; M. J. W. Jansen, "Analysis of variance designs for model output",
Computer Physics Communications 117 (1999) 35-43; E. Plischke, "An effective algorithm for computing global
sensitivity indices (EASI)", Reliability Engineering & System Safety 95 (2010) 354-360.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from SALib.analyze import rbd_fast, sobol
from scipy.stats import bootstrap

from ffrf.studies.statistics import CONFIDENCE

__all__ = [
    "RESAMPLES",
    "GivenDataIndices",
    "Regression",
    "SobolIndices",
    "given_data_indices",
    "sobol_indices",
    "standardised_regression",
]

#: Bootstrap resamples of every interval here (SALib's default is 100): enough for a 95 % interval's ends to about
#: a tenth of its width, at a cost that keeps a 2000-row report of a dozen outputs within a minute.
RESAMPLES = 200


@dataclass(frozen=True)
class SobolIndices:
    """First-order ``first`` and total ``total`` indices per parameter with the half-widths of their 95 % intervals
    (``first_conf``, ``total_conf``), and the complete sample rows ``used``."""

    first: NDArray[np.float64]
    total: NDArray[np.float64]
    first_conf: NDArray[np.float64]
    total_conf: NDArray[np.float64]
    used: int


@dataclass(frozen=True)
class GivenDataIndices:
    """First-order indices ``first`` per parameter from given data, with the half-widths of their 95 % intervals,
    and the rows ``used``."""

    first: NDArray[np.float64]
    first_conf: NDArray[np.float64]
    used: int


@dataclass(frozen=True)
class Regression:
    """Standardised regression coefficients ``beta`` per parameter with their 95 % intervals ``low``, ``high``,
    and the fit's ``r2``."""

    beta: NDArray[np.float64]
    r2: float
    low: NDArray[np.float64]
    high: NDArray[np.float64]


def _problem(d: int) -> dict:
    """SALib's problem description: only the number of parameters matters to its estimators."""
    return {"num_vars": d, "names": [f"x{i}" for i in range(d)], "bounds": [[0.0, 1.0]] * d}


def sobol_indices(f_a: ArrayLike, f_b: ArrayLike, f_ab: ArrayLike, seed: int = 0) -> SobolIndices:
    """First-order and total Sobol indices with their intervals (module docstring) from ``f_a``, ``f_b`` (``N``) and
    ``f_ab`` (``N x d``, column ``i`` the outputs of :math:`A_B^{(i)}`); NaN entries mark failed variants, whose
    sample rows are left out. The bootstrap is seeded by ``seed``."""
    a, b = np.asarray(f_a, dtype=float), np.asarray(f_b, dtype=float)
    ab = np.asarray(f_ab, dtype=float)
    d = ab.shape[1]
    ok = np.isfinite(a) & np.isfinite(b) & np.all(np.isfinite(ab), axis=1)
    used = int(ok.sum())
    both = np.concatenate([a[ok], b[ok]])
    if used < 2 or float(np.var(both)) == 0.0:
        nan = np.full(d, np.nan)
        return SobolIndices(nan, nan, nan, nan, used)
    # SALib's layout without second-order indices: per sample row A, AB_1 ... AB_d, B
    y = np.column_stack([a[ok], ab[ok], b[ok]]).ravel()
    found = sobol.analyze(
        _problem(d), y, calc_second_order=False, num_resamples=RESAMPLES, conf_level=CONFIDENCE, seed=seed
    )
    return SobolIndices(
        np.asarray(found["S1"], float),
        np.asarray(found["ST"], float),
        np.asarray(found["S1_conf"], float),
        np.asarray(found["ST_conf"], float),
        used,
    )


def given_data_indices(x: ArrayLike, y: ArrayLike, seed: int = 0) -> GivenDataIndices:
    """First-order indices of ``y`` (``n``) by the columns of ``x`` (``n x d``) from given data (RBD-FAST, module
    docstring), rows with a non-finite value left out; NaN where too few rows remain or ``y`` does not vary."""
    inputs, outputs = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    ok = np.isfinite(outputs) & np.all(np.isfinite(inputs), axis=1)
    d, used = inputs.shape[1], int(ok.sum())
    # RBD-FAST reads M = 10 harmonics off the reordered output: it needs well over 2 M rows
    if used < 4 * 10 + 1 or float(np.std(outputs[ok])) == 0.0:
        return GivenDataIndices(np.full(d, np.nan), np.full(d, np.nan), used)
    found = rbd_fast.analyze(
        _problem(d), inputs[ok], outputs[ok], num_resamples=RESAMPLES, conf_level=CONFIDENCE, seed=seed
    )
    return GivenDataIndices(np.asarray(found["S1"], float), np.asarray(found["S1_conf"], float), used)


def _fit(xs: NDArray, ys: NDArray) -> tuple[NDArray[np.float64], float]:
    """The standardised coefficients and R^2 of ``ys`` on the columns of ``xs`` (module docstring)."""
    sx, sy = np.std(xs, axis=0), float(np.std(ys))
    beta = np.zeros(xs.shape[1])
    if sy == 0.0:
        return np.full(xs.shape[1], np.nan), float("nan")
    varying = sx > 0.0
    design = np.column_stack([np.ones(len(ys)), xs[:, varying]])
    coefficients, *_ = np.linalg.lstsq(design, ys, rcond=None)
    beta[varying] = coefficients[1:] * sx[varying] / sy
    residual = ys - design @ coefficients
    return beta, 1.0 - float(np.mean(residual**2)) / sy**2


def standardised_regression(x: ArrayLike, y: ArrayLike, seed: int = 0) -> Regression:
    """SRC of ``y`` (``n``) on the columns of ``x`` (``n x d``) with their percentile bootstrap intervals (seeded by
    ``seed``), rows with a non-finite value left out."""
    inputs, outputs = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    ok = np.isfinite(outputs) & np.all(np.isfinite(inputs), axis=1)
    xs, ys = inputs[ok], outputs[ok]
    d = xs.shape[1]
    nan = np.full(d, np.nan)
    if len(ys) <= d + 1 or float(np.std(ys)) == 0.0:
        return Regression(nan, float("nan"), nan, nan)
    beta, r2 = _fit(xs, ys)
    interval = bootstrap(
        (np.arange(len(ys)),),
        lambda rows: _fit(xs[rows], ys[rows])[0],
        vectorized=False,
        n_resamples=RESAMPLES,
        confidence_level=CONFIDENCE,
        method="percentile",
        rng=np.random.default_rng(seed),
    ).confidence_interval
    return Regression(beta, r2, np.asarray(interval.low, float), np.asarray(interval.high, float))
