r"""Numba kernels of generalized-alpha's Newton iterations on the fast path.

:func:`alpha_iterations` runs the iterations of one step of :func:`ffrf.solvers.generalized_alpha._step`
(``docs/formulation.md``, Eqs. (G2), (G3), (FP6)) between two factorisations of the iteration
matrix: residual (:func:`ffrf.system.system_kernels.system_residual`), LU solve with the kept factors,
update and convergence test, in one call, so that Python runs once per step and
factorisation instead of once per iteration. It stops, and hands control back, when Newton
has converged, when the residual is not finite, when :func:`should_refactor` asks for a new
matrix (Python refactors and calls again), or after ``max_iterations``; the tests
and their order are those of the Python loop, which stays the reference
(``tests/test_ffrf_body/test_newton_kernels.py``).

:func:`static_iterations` does the same for the static Newton iterations of
:func:`ffrf.solvers.static_solver._newton` (Eq. (S1)) with kept factors of the equilibrated tangent.

:func:`lu_solve` is LAPACK's ``getrs`` (no transpose) as plain loops on the factors of
``scipy.linalg.lu_factor``: for ~100 unknowns a BLAS call from numba costs more than the work.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ffrf.system.system_kernels import system_residual

__all__ = [
    "lu_solve",
    "static_rhs",
    "static_update",
    "static_iterations",
    "alpha_iterations",
    "should_refactor",
    "CONVERGED",
    "REFACTOR",
    "NOT_FINITE",
    "EXHAUSTED",
    "NEAR_TOLERANCE",
]

CONVERGED, REFACTOR, NOT_FINITE, EXHAUSTED = 0, 1, 2, 3
#: Machine epsilon of float64.
EPS = float(np.finfo(np.float64).eps)
# A poorly contracting increment already within this factor of the tolerance is one or two
# cheap iterations from convergence: refactoring then costs more than it saves.
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
def should_refactor(
    step_iteration: int,
    increment: float,
    previous: float,
    beta_p: float,
    gamma_p: float,
    position_scale: float,
    velocity_scale: float,
) -> bool:
    """Rebuild the iteration matrix after iteration ``step_iteration`` of a step? From the third iteration on, yes.
    At the second, if the increment more than doubled, unless the position and velocity increments are within
    ``NEAR_TOLERANCE`` of their tolerances (``*_scale``).

    Why not judge the second iteration by its contraction: the first iteration of a step with
    factors kept from earlier steps corrects the predictor's constraint gap, and on the index-3
    matrix factors only one step old repeat that correction in the second iteration before the
    third converges (PLA scene at full drive speed, velocity increments 2.1e-9, 2.0e-9, then
    8e-12; with fresh factors 2.1e-9, then 8e-14; over a revolution the second increment exceeds
    the first on a quarter of the steps, but never twice it). Why refactor from the third: with the analytic body
    tangents (Eqs. (F12)-(F14)) a factorisation costs about three iterations (the matrix 0.37 ms and its LU 0.1 ms
    against 0.16 ms per iteration, ``bench/iteration_cost.py``, 4 modes). On the default scene's first 5 s of
    ramp (500 steps of 10 ms, ``bench/iteration_cost.py``): refactoring from the fifth iteration gave 4.17 iterations
    per step at 0.67 ms per step, from the third 2.99 at 0.66 ms (fresher factors at the same cost), from the second
    2.43 and steps about a third slower in a side-by-side run."""
    if step_iteration >= 3:
        return True
    if beta_p * increment <= NEAR_TOLERANCE * position_scale and gamma_p * increment <= NEAR_TOLERANCE * velocity_scale:
        return False
    return increment > 2.0 * previous


@njit(cache=True)
def _max_abs(x: np.ndarray, start: int, stop: int) -> float:
    out = 0.0
    for i in range(start, stop):
        out = max(out, abs(x[i]))
    return out


@njit(cache=True)
def _max_abs_nan(x: np.ndarray, start: int, stop: int) -> float:
    """``np.abs(x[start:stop]).max(initial=0.0)``, NaN if any entry is NaN (as numpy's)."""
    out = 0.0
    for i in range(start, stop):
        value = abs(x[i])
        if value != value:
            return value
        if value > out:
            out = value
    return out


@njit(cache=True)
def static_rhs(residual: np.ndarray, gap: np.ndarray) -> tuple[np.ndarray, bool]:
    """The right-hand side ``-[r; g]`` of a static Newton step (Eq. (S1)) and whether ``r`` and ``g`` are finite."""
    n, k = residual.shape[0], gap.shape[0]
    out = np.empty(n + k)
    finite = True
    for i in range(n):
        out[i] = -residual[i]
        finite = finite and np.isfinite(residual[i])
    for i in range(k):
        out[n + i] = -gap[i]
        finite = finite and np.isfinite(gap[i])
    return out, finite


@njit(cache=True)
def static_update(q: np.ndarray, lam: np.ndarray, delta: np.ndarray, gap: np.ndarray, tolerance: float):
    r"""One static Newton update (:func:`ffrf.solvers.static_solver._newton`): ``q + delta[:n]``, ``lam + delta[n:]``,
    the increment ``max |delta[:n]|`` and the convergence test: the increment within ``tolerance`` of
    ``max(1, max |q|)``, ``max |g| <= tolerance``, and the multiplier step within ``tolerance`` of
    ``max(1, max |lam|)`` or the increment at round-off (``1e3 eps`` of that scale). The same arithmetic as numpy's
    elementwise sums and maxima (NaN propagates), in one call instead of a dozen."""
    n, k = q.shape[0], lam.shape[0]
    q_new = np.empty(n)
    lam_new = np.empty(k)
    for i in range(n):
        q_new[i] = q[i] + delta[i]
    for i in range(k):
        lam_new[i] = lam[i] + delta[n + i]
    increment = _max_abs_nan(delta, 0, n)
    scale = _max_abs_nan(q_new, 0, n)
    scale = scale if scale > 1.0 else 1.0  # Python's max(1.0, x): 1.0 unless x > 1 (so also for NaN)
    converged = False
    if increment <= tolerance * scale and _max_abs_nan(gap, 0, k) <= tolerance:
        multipliers = _max_abs_nan(lam_new, 0, k)
        multipliers = multipliers if multipliers > 1.0 else 1.0
        converged = _max_abs_nan(delta, n, n + k) <= tolerance * multipliers or increment <= 1e3 * EPS * scale
    return q_new, lam_new, increment, converged


@njit(cache=True)
def static_iterations(
    bodies, joints, gravity, phi, rows, cols, lu, piv, q, lam, tolerance, refactor_above, previous, increments, done
):
    r"""Static Newton iterations (Eq. (S1)) with fixed LU factors ``(lu, piv)`` of the tangent equilibrated by
    ``rows`` and ``cols`` (:class:`ffrf.numerics.rank_revealing.FactoredMatrix`): residual, solve, update and the
    convergence test of :func:`static_update`, as :func:`ffrf.solvers.static_solver._newton` does them one by one.

    ``increments[done:]`` receives each iteration's ``max |dq|``; ``previous`` is the increment before this call
    (``inf`` at the start). Returns ``(status, iterations, q, lam, gap)``: ``CONVERGED``, ``REFACTOR`` (an
    increment above ``refactor_above`` times the one before: factor at the returned ``(q, lam)`` and call again),
    ``NOT_FINITE`` (the residual at the returned state is not finite; that iteration counted, nothing updated) or
    ``EXHAUSTED`` (``increments`` full); ``gap`` is the last constraint residual's ``max |g|``."""
    n = q.shape[0]
    zeros = np.zeros(n)
    gap_max = np.inf
    for iteration in range(done, increments.shape[0]):
        residual, gap = system_residual(bodies, joints, q, zeros, zeros, lam, gravity, phi)
        rhs, finite = static_rhs(residual, gap)
        if not finite:
            return NOT_FINITE, iteration + 1 - done, q, lam, gap_max
        delta = lu_solve(lu, piv, rows * rhs)
        for i in range(delta.shape[0]):
            delta[i] *= cols[i]
        q, lam, increment, converged = static_update(q, lam, delta, gap, tolerance)
        increments[iteration] = increment
        gap_max = _max_abs_nan(gap, 0, gap.shape[0])
        if converged:
            return CONVERGED, iteration + 1 - done, q, lam, gap_max
        if increment > refactor_above * previous:
            return REFACTOR, iteration + 1 - done, q, lam, gap_max
        previous = increment
    return EXHAUSTED, increments.shape[0] - done, q, lam, gap_max


@njit(cache=True)
def alpha_iterations(
    bodies,
    joints,
    gravity,
    phi,
    lu,
    piv,
    q_base,
    qd_base,
    accel_base,
    to_accel,
    h2_beta,
    h_gamma,
    beta_p,
    gamma_p,
    qdd,
    lam,
    tolerance,
    max_iterations,
    previous,
    done,
):
    r"""Newton iterations of one generalized-alpha step with fixed factors ``(lu, piv)`` of Eq. (G3).

    Unknowns ``qdd`` and ``lam`` are updated in place. With ``a = accel_base + to_accel qdd``, the
    positions and velocities are ``q_base + h2_beta a`` and ``qd_base + h_gamma a`` (Eq. (G2)); the
    right-hand side is ``-[r; g / beta']`` (constraint rows scaled as the matrix). ``previous`` is
    the last increment before this call (``inf`` at the start of a step), ``done`` the iterations
    of this step before this call.

    Returns ``(status, iterations, increment, gap)``: ``status`` one of ``CONVERGED``,
    ``REFACTOR`` (:func:`should_refactor`: factor at the updated unknowns and call again with
    ``previous = increment``), ``NOT_FINITE`` (residual not finite; nothing
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
        if should_refactor(done + iteration, increment, previous, beta_p, gamma_p, position_scale, velocity_scale):
            return REFACTOR, iteration, increment, gap_max
        previous = increment
    return EXHAUSTED, max_iterations, increment, gap_max
