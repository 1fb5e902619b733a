r"""Generalized-alpha for index-3 constrained mechanical systems (Arnold and Bruels 2007).

Parameters from the spectral radius at infinity :math:`\rho_\infty` (Chung and Hulbert 1993):

.. math:: \alpha_m = \frac{2\rho_\infty - 1}{\rho_\infty + 1},\quad \alpha_f = \frac{\rho_\infty}{\rho_\infty + 1},\quad
          \gamma = \tfrac12 + \alpha_f - \alpha_m,\quad \beta = \tfrac14(\gamma + \tfrac12)^2.

Step ``n -> n+1`` with the algorithmic acceleration ``a`` (Arnold and Bruels, Alg. 1; ``docs/formulation.md`` Eq. (G2)):

.. math::
    q_{n+1} &= q_n + h\dot q_n + h^2(\tfrac12 - \beta)a_n + h^2\beta a_{n+1},\\
    \dot q_{n+1} &= \dot q_n + h(1-\gamma)a_n + h\gamma a_{n+1},\\
    (1-\alpha_m)a_{n+1} + \alpha_m a_n &= (1-\alpha_f)\ddot q_{n+1} + \alpha_f\ddot q_n,

and the equations of motion and position constraints hold at :math:`t_{n+1}`. Newton's
unknowns are :math:`\ddot q_{n+1}` and :math:`\lambda_{n+1}`; with
:math:`\beta' = h^2\beta(1-\alpha_f)/(1-\alpha_m)` and :math:`\gamma' = h\gamma(1-\alpha_f)/(1-\alpha_m)`
the iteration matrix is (Eq. (G3))

.. math:: \begin{bmatrix} M + \beta'(K_t + H) + \gamma' D_t & C_q^T\\ C_q & 0\end{bmatrix},

the constraint rows divided by :math:`\beta'` so that it stays well conditioned for small
steps and stiff bodies (Bottasso, Dopico and Trainelli 2008). :math:`K_t, D_t` are the exact
derivatives of :math:`M\ddot q - Q` (including :math:`\partial(M\ddot q)/\partial q`) and
:math:`H = \partial(C_q^T\lambda)/\partial q`, so full Newton converges quadratically.
"""

from __future__ import annotations

import logging
import time as wallclock
from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import scipy.linalg
from numpy.typing import NDArray
from scipy.linalg.lapack import dgetrs as getrs

from .packed_system import PackedSystem, newton_model
from .system import MultibodySystem

__all__ = ["AlphaParameters", "IntegrationResult", "NewtonDivergence", "generalized_alpha", "consistent_accelerations"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class AlphaParameters:
    """Generalized-alpha coefficients from the spectral radius ``rho_inf`` in [0, 1]."""

    rho_inf: float
    alpha_m: float = field(init=False)
    alpha_f: float = field(init=False)
    gamma: float = field(init=False)
    beta: float = field(init=False)

    def __post_init__(self):
        if not 0.0 <= self.rho_inf <= 1.0:
            raise ValueError(f"rho_inf must lie in [0, 1], got {self.rho_inf}")
        am = (2.0 * self.rho_inf - 1.0) / (self.rho_inf + 1.0)
        af = self.rho_inf / (self.rho_inf + 1.0)
        gamma = 0.5 + af - am
        object.__setattr__(self, "alpha_m", am)
        object.__setattr__(self, "alpha_f", af)
        object.__setattr__(self, "gamma", gamma)
        object.__setattr__(self, "beta", 0.25 * (gamma + 0.5) ** 2)


@dataclass
class IntegrationResult:
    """Time histories at the output steps (rows) and solver statistics."""

    time: NDArray[np.float64]
    q: NDArray[np.float64]
    qd: NDArray[np.float64]
    qdd: NDArray[np.float64]
    multipliers: NDArray[np.float64]
    newton_iterations: NDArray[np.int64]
    wall_time: float
    complete: bool = True


class NewtonDivergence(RuntimeError):
    """Newton did not converge; ``partial`` holds the results up to the last converged step."""

    def __init__(self, message: str, partial: IntegrationResult):
        super().__init__(message)
        self.partial = partial


def consistent_accelerations(system: MultibodySystem, q, qd, t: float = 0.0):
    r"""Solve :math:`[M\ C_q^T; C_q\ 0][\ddot q; \lambda] = [Q; -(C_q\dot q)_q\dot q]` (Eq. (G4))."""
    n, k = system.n_coordinates, system.n_constraints
    mass = system.mass_matrix(q)
    forces = -system.body_residuals(q, qd, np.zeros(n))  # M*0 - Q = -Q
    cq = system.constraint_jacobian(q, t)
    matrix = np.block([[mass, cq.T], [cq, np.zeros((k, k))]])
    rhs = np.concatenate([forces, -system.constraint_acceleration_term(q, qd, t)])
    solution = np.linalg.solve(matrix, rhs)
    return solution[:n], solution[n:]


def _factor_iteration_matrix(model: MultibodySystem | PackedSystem, q, qd, qdd, lam, t: float, beta_p: float,
                             gamma_p: float):
    """Eq. (G3), LU-factored."""
    return scipy.linalg.lu_factor(model.iteration_matrix(q, qd, qdd, lam, t, 1.0, beta_p, gamma_p), check_finite=False)


def generalized_alpha(
    system: MultibodySystem,
    q0: NDArray,
    qd0: NDArray,
    t_end: float,
    step: float,
    rho_inf: float = 0.9,
    tolerance: float = 1e-10,
    max_iterations: int = 12,
    modified_newton: bool = True,
    output_every: int = 1,
    progress: Callable[[float, float], None] | None = None,
    *,
    fast_path: bool = True,
) -> IntegrationResult:
    """Integrate from ``t = 0`` to ``t_end`` with fixed steps ``step`` (s).

    Newton stops when the increments it makes in positions (``beta' |dqdd|``) and velocities
    (``gamma' |dqdd|``) are below ``tolerance`` times ``max(1, |q|)`` and ``max(1, |qd|)`` and the
    constraints hold to ``tolerance`` (their own units, m or dimensionless). With
    ``modified_newton`` the factorised iteration matrix is kept across iterations and steps
    and rebuilt only when an iteration contracts the increment by less than a half (or a
    step fails, which is then retried with a fresh matrix); the converged solution is the
    same, only the work differs. Raises :class:`NewtonDivergence` with the partial results.
    ``fast_path`` evaluates Newton's residual and matrix with the whole-system kernels of
    :mod:`ffrf.packed_system` when the system is supported (else, and with ``False``, with the
    reference Python implementation of :class:`MultibodySystem`; both agree to round-off).
    """
    if step <= 0 or t_end <= 0:
        raise ValueError(f"step and t_end must be positive, got step={step}, t_end={t_end}")
    par = AlphaParameters(rho_inf)
    n_steps = int(round(t_end / step))
    h = t_end / n_steps
    beta_p = h * h * par.beta * (1.0 - par.alpha_f) / (1.0 - par.alpha_m)
    gamma_p = h * par.gamma * (1.0 - par.alpha_f) / (1.0 - par.alpha_m)
    to_accel = (1.0 - par.alpha_f) / (1.0 - par.alpha_m)
    n = system.n_coordinates
    model = newton_model(system, fast_path)

    q, qd = np.array(q0, dtype=float), np.array(qd0, dtype=float)
    if q.shape != (n,) or qd.shape != (n,):
        raise ValueError(f"initial state must have {n} coordinates, got {q.shape} and {qd.shape}")
    qdd, lam = consistent_accelerations(system, q, qd, 0.0)
    accel = qdd.copy()
    history = {"time": [0.0], "q": [q.copy()], "qd": [qd.copy()], "qdd": [qdd.copy()], "lam": [lam.copy()]}
    iterations = []
    started = wallclock.perf_counter()
    factors = None

    def result(complete: bool) -> IntegrationResult:
        return IntegrationResult(np.array(history["time"]), np.array(history["q"]), np.array(history["qd"]),
                                 np.array(history["qdd"]), np.array(history["lam"]), np.array(iterations, dtype=np.int64),
                                 wallclock.perf_counter() - started, complete)

    for k in range(1, n_steps + 1):
        t = k * h
        q_base = q + h * qd + h * h * (0.5 - par.beta) * accel
        qd_base = qd + h * (1.0 - par.gamma) * accel
        accel_base = (par.alpha_f * qdd - par.alpha_m * accel) / (1.0 - par.alpha_m)
        total = 0  # Newton iterations of this step, retries included
        for attempt in range(2 if modified_newton else 1):
            qdd_new, lam_new = qdd.copy(), lam.copy()
            converged, previous = False, np.inf
            for iteration in range(1, max_iterations + 1):
                a_new = accel_base + to_accel * qdd_new
                q_new = q_base + h * h * par.beta * a_new
                qd_new = qd_base + h * par.gamma * a_new
                residual, gap = model.residual(q_new, qd_new, qdd_new, lam_new, t)
                if not (np.all(np.isfinite(residual)) and np.all(np.isfinite(gap))):
                    raise NewtonDivergence(f"NaN in the residual at t = {t:.6g} s (iteration {iteration}); "
                                           "reduce the step or check the model", result(False))
                if factors is None or not modified_newton or attempt == 1:
                    factors = _factor_iteration_matrix(model, q_new, qd_new, qdd_new, lam_new, t, beta_p, gamma_p)
                # LAPACK getrs directly: what lu_solve calls, without its ~30 us of wrapper per iteration
                delta = getrs(*factors, -np.concatenate([residual, gap / beta_p]))[0]
                qdd_new += delta[:n]
                lam_new += delta[n:]
                increment = np.abs(delta[:n]).max()
                if (beta_p * increment <= tolerance * max(1.0, np.abs(q_new).max())
                        and gamma_p * increment <= tolerance * max(1.0, np.abs(qd_new).max())
                        and np.abs(gap).max() <= tolerance):
                    converged = True
                    break
                if increment > 0.5 * previous:
                    factors = None  # poor contraction: rebuild the iteration matrix
                previous = increment
            total += iteration
            if converged:
                break
            factors = None
        if not converged:
            raise NewtonDivergence(
                f"Newton did not converge at t = {t:.6g} s after {max_iterations} iterations: largest "
                f"constraint residual {np.abs(gap).max():.3e}, last acceleration increment {increment:.3e}; "
                "reduce the step size or check the constraints", result(False))
        accel = accel_base + to_accel * qdd_new
        q = q_base + h * h * par.beta * accel
        qd = qd_base + h * par.gamma * accel
        qdd, lam = qdd_new, lam_new
        iterations.append(total)
        if k % output_every == 0 or k == n_steps:
            history["time"].append(t)
            history["q"].append(q.copy())
            history["qd"].append(qd.copy())
            history["qdd"].append(qdd.copy())
            history["lam"].append(lam.copy())
        if progress is not None:
            progress(t, t_end)
    return result(True)
