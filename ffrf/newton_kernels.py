r"""Numba kernels of generalized-alpha's Newton iterations on the fast path.

:func:`alpha_iterations` runs the iterations of one step of :func:`ffrf.generalized_alpha._step`
(``docs/formulation.md``, Eqs. (G2), (G3), (FP6)) between two factorisations of the iteration
matrix: residual (:func:`ffrf.system_kernels.system_residual`), LU solve with the kept factors,
update and convergence test, in one call, so that Python runs once per step and
factorisation instead of once per iteration. It stops, and hands control back, when Newton
has converged, when the residual is not finite, when an iteration contracts the increment by
less than a half (Python refactors and calls again), or after ``max_iterations``; the tests
and their order are those of the Python loop, which stays the reference
(``tests/test_ffrf_body/test_newton_kernels.py``).

:func:`lu_solve` is LAPACK's ``getrs`` (no transpose) as plain loops on the factors of
``scipy.linalg.lu_factor``: for ~100 unknowns a BLAS call from numba costs more than the work.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .system_kernels import system_residual

__all__ = ["lu_solve", "alpha_iterations", "CONVERGED", "REFACTOR", "NOT_FINITE", "EXHAUSTED", "NEAR_TOLERANCE"]

CONVERGED, REFACTOR, NOT_FINITE, EXHAUSTED = 0, 1, 2, 3
# A poorly contracting increment already within this factor of the tolerance is one or two
# cheap iterations from convergence: refactoring then costs more than it saves. (At full drive
# speed the increment of the second iteration is ~0.6 of the first while the residual falls
# 2000-fold; without this guard every step refactored.)
NEAR_TOLERANCE = 100.0


@njit(cache=True)
def lu_solve(lu: np.ndarray, piv: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Solve ``A x = rhs`` with ``(lu, piv)`` of ``scipy.linalg.lu_factor(A)`` (``P A = L U``, unit ``L``;
    ``piv[i]``: row ``i`` was swapped with row ``piv[i]``, in order)."""
    n = rhs.shape[0]
    x = rhs.copy()
    for i in range(n):
        j = piv[i]
        if j != i:
            x[i], x[j] = x[j], x[i]
    for i in range(n):  # L y = P b
        total = x[i]
        for k in range(i):
            total -= lu[i, k] * x[k]
        x[i] = total
    for i in range(n - 1, -1, -1):  # U x = y
        total = x[i]
        for k in range(i + 1, n):
            total -= lu[i, k] * x[k]
        x[i] = total / lu[i, i]
    return x


@njit(cache=True)
def _max_abs(x: np.ndarray, start: int, stop: int) -> float:
    out = 0.0
    for i in range(start, stop):
        out = max(out, abs(x[i]))
    return out


@njit(cache=True)
def alpha_iterations(bodies, joints, gravity, phi, lu, piv, q_base, qd_base, accel_base, to_accel, h2_beta, h_gamma,
                     beta_p, gamma_p, qdd, lam, tolerance, max_iterations, previous):
    r"""Newton iterations of one generalized-alpha step with fixed factors ``(lu, piv)`` of Eq. (G3).

    Unknowns ``qdd`` and ``lam`` are updated in place. With ``a = accel_base + to_accel qdd``, the
    positions and velocities are ``q_base + h2_beta a`` and ``qd_base + h_gamma a`` (Eq. (G2)); the
    right-hand side is ``-[r; g / beta']`` (constraint rows scaled as the matrix). ``previous`` is
    the last increment before this call (``inf`` at the start of a step).

    Returns ``(status, iterations, increment, gap)``: ``status`` one of ``CONVERGED``,
    ``REFACTOR`` (the increment shrank by less than a half while still ``NEAR_TOLERANCE`` times
    above the tolerance: factor at the updated unknowns and
    call again with ``previous = increment``), ``NOT_FINITE`` (residual not finite; nothing
    updated in that iteration), ``EXHAUSTED``; ``increment`` the last ``max |d qdd|`` and ``gap``
    the last ``max |g|``.
    """
    n = qdd.shape[0]
    k = lam.shape[0]
    rhs = np.empty(n + k)
    increment, gap_max = np.inf, np.inf
    for iteration in range(1, max_iterations + 1):
        a_new = accel_base + to_accel * qdd
        q_new = q_base + h2_beta * a_new
        qd_new = qd_base + h_gamma * a_new
        residual, gap = system_residual(bodies, joints, q_new, qd_new, qdd, lam, gravity, phi)
        if not (np.all(np.isfinite(residual)) and np.all(np.isfinite(gap))):
            return NOT_FINITE, iteration, increment, gap_max
        for i in range(n):
            rhs[i] = -residual[i]
        for i in range(k):
            rhs[n + i] = -gap[i] / beta_p
        delta = lu_solve(lu, piv, rhs)
        for i in range(n):
            qdd[i] += delta[i]
        for i in range(k):
            lam[i] += delta[n + i]
        increment = _max_abs(delta, 0, n)
        gap_max = _max_abs(gap, 0, k)
        position_scale = tolerance * max(1.0, _max_abs(q_new, 0, n))
        velocity_scale = tolerance * max(1.0, _max_abs(qd_new, 0, n))
        if beta_p * increment <= position_scale and gamma_p * increment <= velocity_scale and gap_max <= tolerance:
            return CONVERGED, iteration, increment, gap_max
        if increment > 0.5 * previous and (beta_p * increment > NEAR_TOLERANCE * position_scale
                                           or gamma_p * increment > NEAR_TOLERANCE * velocity_scale):
            return REFACTOR, iteration, increment, gap_max
        previous = increment
    return EXHAUSTED, max_iterations, increment, gap_max
