r"""Pieces every solver shares: the result of a time integration, consistent initial
accelerations (Eq. (G4)) and polynomial extrapolation of past values (Eq. (S2)).

They live here so that no integrator imports another (``docs/architecture.md``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ffrf.numerics.rank_revealing import factor
from ffrf.system.multibody import MultibodySystem

__all__ = ["IntegrationResult", "PathJump", "StaticSolution", "consistent_accelerations", "extrapolation_weights"]


@dataclass(frozen=True)
class PathJump:
    """Where a quasi-static path jumps between two equilibria with none between them (a contact with play letting
    go, Eq. (P6); a snap at a fold, Eq. (S6)): the equilibrium it leaves at ``t_from`` and the one it lands on at
    ``t_to`` (the same t for a snap). The energy balance keeps its books apart across it (Eq. (C2))."""

    t_from: float
    q_from: NDArray[np.float64]
    multipliers_from: NDArray[np.float64]
    t_to: float
    q_to: NDArray[np.float64]
    multipliers_to: NDArray[np.float64]


@dataclass(frozen=True)
class StaticSolution:
    """Equilibrium coordinates ``q``, multipliers, and Newton iterations per load step; ``times``, where given, the
    times of the rows (a path that stopped between outputs ends with the last equilibrium it reached); ``jumps``,
    where the path jumped (oldest first)."""

    q: NDArray[np.float64]
    multipliers: NDArray[np.float64]
    iterations: tuple[int, ...]
    times: NDArray[np.float64] | None = None
    jumps: tuple[PathJump, ...] = ()


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
    step_sizes: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))  # one per accepted step
    #: Local error estimate (Eq. (G5)) of the bodies' reference positions, the largest of each accepted step (m);
    #: empty from an integrator without one.
    position_errors: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))


def consistent_accelerations(system: MultibodySystem, q, qd, t: float = 0.0):
    r"""Solve :math:`[M\ C_q^T; C_q\ 0][\ddot q; \lambda] = [Q; -(C_q\dot q)_q\dot q]` (Eq. (G4)).

    With redundant constraints (a closed loop of rigid bodies) the matrix is singular by the rank
    rule (R1); the accelerations are still unique, and the multipliers are the minimum-norm ones."""
    n, k = system.n_coordinates, system.n_constraints
    mass = system.mass_matrix(q)
    forces = -system.body_residuals(q, qd, np.zeros(n), t)  # M*0 - Q = -Q
    cq = system.constraint_jacobian(q, t)
    matrix = np.block([[mass, cq.T], [cq, np.zeros((k, k))]])
    rhs = np.concatenate([forces, -system.constraint_acceleration_term(q, qd, t)])
    solution = factor(matrix, what="consistent-acceleration matrix").solve(rhs)
    return solution[:n], solution[n:]


def extrapolation_weights(times: NDArray, t: float) -> NDArray[np.float64]:
    r"""Eq. (S2): Lagrange weights :math:`\ell_i(t) = \prod_{j\ne i}(t - t_j)/(t_i - t_j)` of the
    polynomial through values at ``times``, evaluated at ``t``."""
    times = np.asarray(times, dtype=float)
    weights = np.ones(times.size)
    for i in range(times.size):
        for j in range(times.size):
            if j != i:
                weights[i] *= (t - times[j]) / (times[i] - times[j])
    return weights
