r"""A variational midpoint integrator: exact momentum conservation, no energy drift.

Generalized-alpha (:mod:`ffrf.solvers.generalized_alpha`) is the production scheme, but even with
:math:`\rho_\infty = 1` it does not conserve the momentum or the energy of the nonlinear
FFRF equations: both drift as :math:`O(h^2)`. This integrator discretises Hamilton's
principle instead (Marsden and West 2001, "Discrete mechanics and variational integrators",
Sects. 1.2, 3.2 and 3.5; ``docs/formulation.md``, Eqs. (V1)-(V5)):

.. math::
    L_d(q_k, q_{k+1}) = h\,T(q_m, v), \qquad q_m = \tfrac12(q_k + q_{k+1}),\quad v = (q_{k+1} - q_k)/h,

with the elastic, gravity and damping forces :math:`Q(q_m, v)` as half impulses
:math:`\tfrac h2 Q` at both ends of the step, and the constraints (normalisations and joints)
imposed at :math:`q_{k+1}` with their forces at :math:`q_k` (SHAKE). In position-momentum form,
with :math:`F = \partial T/\partial q + Q` (Eq. (V2)):

.. math::
    M(q_m)\,v &= p_k + \tfrac h2 F(q_m, v) - h\,C_q(q_k)^T\lambda_k, \qquad C(q_{k+1}, t_{k+1}) = 0,\\
    p_{k+1} &= M(q_m)\,v + \tfrac h2 F(q_m, v).

The discrete Lagrangian is invariant under translations and rotations of the whole system
(rotations act on Euler parameters linearly, and Eq. (R1) is homogeneous, so
:math:`A(s\,p) = A(s)A(p)` also off the unit sphere), and so are the normalisations and the
joints between bodies: the discrete Noether theorem then conserves the linear and angular
momentum exactly (to Newton's tolerance), and the scheme is symplectic, so a conservative
system's energy oscillates by :math:`O(h^2)` without drift (Eq. (V4)). It is second order,
implicit, and has no numerical damping: unresolved high-frequency modes keep their
amplitude. Use it for free flight, long undamped runs and energy studies; use
generalized-alpha with :math:`\rho_\infty < 1` for everything else.
"""

from __future__ import annotations

import time as wallclock
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from ffrf.errors import NewtonDivergence
from ffrf.numerics.rank_revealing import FactoredMatrix, factor
from ffrf.solvers.common import IntegrationResult, consistent_accelerations
from ffrf.system.multibody import MultibodySystem

__all__ = ["variational_midpoint", "velocities_from_momenta", "momenta_from_velocities"]

_ROUND_OFF_BAND = 100.0  # a residual this close to the tolerance that stops contracting is round-off
_REBUILD_CONTRACTION = 0.1  # rebuilding costs about one iteration; slower contraction costs more
_TIME_STEP_FOR_RATES = 1e-6  # s; central difference of rheonomic constraints, error O(1e-12)


def momenta_from_velocities(system: MultibodySystem, q: NDArray, qd: NDArray) -> NDArray[np.float64]:
    r"""Generalized momenta :math:`p = M(q)\dot q` (the continuous Legendre transform, Eq. (V3))."""
    return system.mass_matrix(q) @ qd


def _constraint_rates(system: MultibodySystem, q: NDArray, t: float) -> NDArray[np.float64]:
    """``dC/dt`` at fixed ``q`` (zero for scleronomic constraints, the drive's speed otherwise)."""
    dt = _TIME_STEP_FOR_RATES
    return (system.constraint_values(q, t + dt) - system.constraint_values(q, t - dt)) / (2.0 * dt)


def velocities_from_momenta(system: MultibodySystem, q: NDArray, p: NDArray, t: float) -> NDArray[np.float64]:
    r"""Eq. (V3): the velocities that carry momenta ``p`` and satisfy the velocity constraints,
    :math:`[M\ C_q^T; C_q\ 0][\dot q; \nu] = [p; -C_t]`. The multiplier :math:`\nu` takes up the
    part of ``p`` along the constraint normals; for a normalisation that is a direction no
    velocity carries (:math:`\bar Gp = 0`, so ``M`` maps ``[0, p, 0]`` to zero)."""
    n, k = system.n_coordinates, system.n_constraints
    cq = system.constraint_jacobian(q, t)
    matrix = np.block([[system.mass_matrix(q), cq.T], [cq, np.zeros((k, k))]])
    rhs = np.concatenate([p, -_constraint_rates(system, q, t)])
    return factor(matrix, what="momentum-to-velocity matrix").solve(rhs)[:n]


def _midpoint_forces(system: MultibodySystem, q: NDArray, v: NDArray) -> NDArray[np.float64]:
    r"""Eq. (V2): :math:`F = \partial T/\partial q + Q` with :math:`Q = Q_g - K_r\zeta - D_r\dot\zeta`
    (Eqs. (F10), (F11)): the body residual at rest is :math:`-Q_g + K_r\zeta`."""
    out = np.empty(system.n_coordinates)
    rest = np.zeros(system.n_coordinates)
    for i, body in enumerate(system.bodies):
        s = system.block(i)
        forces = body.kinetic_energy_gradient(q[s], v[s]) - body.residual(q[s], rest[s], rest[s], system.gravity)
        forces[7:] -= body.damping @ v[s][7:]
        out[s] = forces
    return out


def _newton_matrix(system: MultibodySystem, q_mid: NDArray, v: NDArray, h: float, cq_start: NDArray, cq_end: NDArray):
    r"""Eq. (V5), factored by the rank rule (R1) (redundant constraints give minimum-norm steps):
    :math:`[[M + \tfrac h2 (D_t - \dot M) + \tfrac{h^2}4 K_t, C_q(q_k)^T], [C_q(q_{k+1}), 0]]`
    from the body tangents of generalized-alpha (:math:`K_t, D_t` at zero acceleration).
    It leaves out :math:`\tfrac{h^2}4\partial(\dot M\dot q)/\partial q`, which is
    :math:`O(h^2|\dot q|^2)` against ``M``, so modified Newton contracts by about that factor."""
    n = system.n_coordinates
    jq, jqd = system.body_tangents(q_mid, v, np.zeros(n))
    upper = system.mass_matrix(q_mid) + 0.5 * h * jqd + 0.25 * h * h * jq
    for i, body in enumerate(system.bodies):
        s = system.block(i)
        upper[s, s] -= 0.5 * h * body.mass_matrix_rate(q_mid[s], v[s])
    k = cq_start.shape[0]
    return factor(np.block([[upper, cq_start.T], [cq_end, np.zeros((k, k))]]), what="midpoint Newton matrix")


def _step(
    system: MultibodySystem,
    q0: NDArray,
    p0: NDArray,
    t0: float,
    h: float,
    q_guess: NDArray,
    scaled_lam: NDArray,
    tolerance: float,
    max_iterations: int,
    factors: FactoredMatrix | None,
):
    r"""Solve Eq. (V2) for :math:`q_{k+1}` and :math:`\mu = h^2\lambda_k` (the scaled unknowns keep
    the matrix of Eq. (V5) well conditioned for any h) by modified Newton, starting from the
    factorised matrix of an earlier step when given. Returns ``(q1, mu, p1, iterations,
    factors)`` or ``(None, None, None, diagnostics, None)``."""
    n = system.n_coordinates
    t1 = t0 + h
    cq0 = system.constraint_jacobian(q0, t0)
    momentum_scale = max(np.abs(p0).max(), 1e-300)
    q1, mu = q_guess.copy(), scaled_lam.copy()
    previous = np.inf
    for iteration in range(1, max_iterations + 1):
        q_mid, v = 0.5 * (q0 + q1), (q1 - q0) / h
        forces = _midpoint_forces(system, q_mid, v)
        # Eq. (V2) times h: h (M v - p_k) - h^2/2 F + C_q(q_k)^T mu
        momentum_gap = h * (system.mass_matrix(q_mid) @ v - p0) - 0.5 * h * h * forces + cq0.T @ mu
        gap = system.constraint_values(q1, t1)
        if not (np.all(np.isfinite(momentum_gap)) and np.all(np.isfinite(gap))):
            return None, None, None, f"NaN or inf in the discrete equations (iteration {iteration})", None
        residual = np.abs(momentum_gap).max() / h
        scale = max(momentum_scale, 0.5 * h * np.abs(forces).max())
        constraints_hold = np.abs(gap).max() <= tolerance
        # converged, or stalled at round-off (no contraction while already near the tolerance)
        if constraints_hold and (
            residual <= tolerance * scale
            or (residual <= _ROUND_OFF_BAND * tolerance * scale and residual > 0.5 * previous)
        ):
            # the momentum balance p_k + h F - h C_q^T lambda equals Eq. (V2)'s second line at
            # convergence; unlike it, its leftover Newton residual cannot change a momentum
            # whose force is zero (the linear momentum of a free system stays exact)
            p1 = p0 + h * forces - cq0.T @ mu / h
            return q1, mu, p1, iteration, factors
        if factors is None or residual > _REBUILD_CONTRACTION * previous:  # contraction poor: rebuild
            try:
                factors = _newton_matrix(system, q_mid, v, h, cq0, system.constraint_jacobian(q1, t1))
            except FloatingPointError as error:
                return None, None, None, f"{error} (iteration {iteration})", None
        previous = residual
        delta = factors.solve(-np.concatenate([momentum_gap, gap]))
        q1 += delta[:n]
        mu += delta[n:]
    return (
        None,
        None,
        None,
        (
            f"momentum residual {residual:.3e} (scale {momentum_scale:.3e}), largest constraint "
            f"residual {np.abs(gap).max():.3e} after {max_iterations} iterations"
        ),
        None,
    )


def variational_midpoint(
    system: MultibodySystem,
    q0: NDArray,
    qd0: NDArray,
    t_end: float,
    step: float,
    tolerance: float = 1e-13,
    max_iterations: int = 25,
    output_every: int = 1,
    progress: Callable[[float, float], None] | None = None,
) -> IntegrationResult:
    r"""Integrate Eqs. (V1)-(V3) from ``t = 0`` to ``t_end`` with fixed steps ``step`` (s).

    Newton stops when the momentum balance of Eq. (V2) holds to ``tolerance`` relative to the
    largest momentum or half impulse and the constraints to ``tolerance`` (their own units);
    the default is near round-off because conservation is only as good as this solve. Output
    rows every ``output_every`` steps: positions, velocities from the discrete momenta
    (Eq. (V3)), accelerations as the central difference of the step velocities
    :math:`(v_{k+1/2} - v_{k-1/2})/h` (row 0: Eq. (G4)) and the multipliers :math:`\lambda_k`
    of the step that leaves row k. ``newton_iterations`` has one entry per step. Raises
    :class:`NewtonDivergence` with the rows computed so far and, last, the state the failed step
    started from.
    """
    if step <= 0 or t_end <= 0:
        raise ValueError(f"step and t_end must be positive, got step={step}, t_end={t_end}")
    if system.forces:
        raise ValueError(
            f"the variational midpoint integrator does not take force elements (the system has "
            f"{len(system.forces)}, e.g. {system.forces[0].name!r}); integrate with generalized_alpha"
        )
    n_steps = int(round(t_end / step))
    h = t_end / n_steps
    n = system.n_coordinates
    q, qd0 = np.array(q0, dtype=float), np.array(qd0, dtype=float)
    if q.shape != (n,) or qd0.shape != (n,):
        raise ValueError(f"initial state must have {n} coordinates, got {q.shape} and {qd0.shape}")
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(qd0))):
        raise ValueError("initial state contains NaN or inf; start from a finite state")
    qdd, lam = consistent_accelerations(system, q, qd0, 0.0)
    p = momenta_from_velocities(system, q, qd0)
    history: dict[str, list] = {"time": [], "q": [], "qd": [], "qdd": [], "lam": []}
    iterations: list[int] = []
    started = wallclock.perf_counter()

    def result(complete: bool) -> IntegrationResult:
        return IntegrationResult(
            np.array(history["time"]),
            np.array(history["q"]).reshape(-1, n),
            np.array(history["qd"]).reshape(-1, n),
            np.array(history["qdd"]).reshape(-1, n),
            np.array(history["lam"]).reshape(len(history["time"]), -1),
            np.array(iterations, dtype=np.int64),
            wallclock.perf_counter() - started,
            complete,
            np.full(len(iterations), h),
        )

    def record(k: int, q: NDArray, p: NDArray, qdd: NDArray, scaled_lam: NDArray) -> None:
        history["time"].append(k * h)
        history["q"].append(q.copy())
        history["qd"].append(qd0 if k == 0 else velocities_from_momenta(system, q, p, k * h))
        history["qdd"].append(qdd.copy())
        history["lam"].append(scaled_lam / (h * h))

    # Row k is written once the step that leaves it is known (its multiplier and the velocity
    # after it); the last row needs one step beyond t_end.
    v_before, factors = None, None
    scaled_lam = h * h * lam
    q_guess = q + h * qd0
    for k in range(n_steps + 1):
        q_next, scaled_lam_new, p_next, count, factors = _step(
            system, q, p, k * h, h, q_guess, scaled_lam, tolerance, max_iterations, factors
        )
        if q_next is None:
            record(k, q, p, qdd, scaled_lam)  # the last converged state, with the previous row's qdd and lambda
            raise NewtonDivergence(
                f"variational midpoint step from t = {k * h:.6g} s failed: {count}; reduce the "
                "step size or check the model",
                result(False),
            )
        v_after = (q_next - q) / h
        if v_before is not None:
            qdd = (v_after - v_before) / h
        if k % output_every == 0 or k == n_steps:
            record(k, q, p, qdd, scaled_lam_new)
        if k == n_steps:
            break
        iterations.append(count)
        q_guess = q_next + h * v_after  # constant-velocity predictor, error O(h^2)
        q, p, scaled_lam, v_before = q_next, p_next, scaled_lam_new, v_after
        if progress is not None:
            progress((k + 1) * h, t_end)
    return result(True)
