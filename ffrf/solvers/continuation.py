r"""Equilibrium paths through limit points: pseudo-arclength continuation in the load parameter t.

A quasi-static run (:func:`ffrf.solvers.static_solver.quasi_static`) prescribes t (the drive angle's or a load's
time law) and solves Eq. (S1) for ``(q, lambda)``; at a limit point the path turns back in t and there is no
equilibrium beyond it. Continuation makes t an unknown and prescribes the distance along the path instead
(Keller's pseudo-arclength, ``docs/formulation.md``, Eq. (S5)):

.. math::
    F(q, \lambda, t) = 0,\qquad \tau_q\cdot(q - \hat q) + c^2\,\tau_t\,(t - \hat t) = 0,

with :math:`(\hat q, \hat t) = (q_k, t_k) + \Delta s\,\tau` the predictor along the unit tangent :math:`\tau`
(in the norm :math:`|\delta q|^2 + c^2\,\delta t^2`, ``c`` the start's :math:`|dq/dt|` so that both count). Newton
solves the bordered system :math:`[F_y, F_t; \tau_q^T, 0, c^2\tau_t]`, regular at limit points where
:math:`F_y` alone is singular. The tangent at a new point solves the same bordered matrix with right-hand side
:math:`(0, 1)`, which keeps the direction of travel. ``F_t`` is a central difference in t.
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ffrf.errors import StaticDivergence
from ffrf.numerics.rank_revealing import factor
from ffrf.solvers.static_solver import path_rate, residual_rate
from ffrf.system.multibody import MultibodySystem
from ffrf.system.packed_system import newton_model

__all__ = ["EquilibriumPath", "continue_path", "equilibrium_path", "path_points", "parabola_vertex", "path_speed"]

#: Largest Newton correction from the predicted point of a continuation step, as a share of the step (Eq. (S5)), as
#: Eq. (S4) bounds a quasi-static step's: a step whose equilibrium lies farther has crossed to another branch.
MAX_CORRECTION = 0.5

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class EquilibriumPath:
    """Equilibria along the path: parameter ``t``, coordinates ``q``, multipliers, arclength ``s`` (path order)."""

    t: NDArray[np.float64]
    q: NDArray[np.float64]
    multipliers: NDArray[np.float64]
    s: NDArray[np.float64]

    def limit_points(self) -> NDArray[np.float64]:
        """The path's extrema in t (limit points), each from the parabola through the three points around it."""
        out = []
        for k in range(1, len(self.t) - 1):
            before, after = self.t[k] - self.t[k - 1], self.t[k + 1] - self.t[k]
            if before * after < 0.0:
                out.append(parabola_vertex(self.s[k - 1 : k + 2], self.t[k - 1 : k + 2])[0])
        return np.array(out)


def parabola_vertex(s: NDArray, t: NDArray) -> tuple[float, NDArray]:
    """The extremum of the parabola t(s) through three points: ``(t at the vertex, Lagrange weights of the three
    points at the vertex's s)``, so that any quantity along the path can be interpolated there the same way."""
    a, b, c = np.polyfit(s - s[1], t, 2)
    vertex = -b / (2.0 * a)
    nodes = s - s[1]
    weights = np.array(
        [np.prod([(vertex - nodes[j]) / (nodes[i] - nodes[j]) for j in range(3) if j != i]) for i in range(3)]
    )
    return float(c - b * b / (4.0 * a)), weights


class _Model:
    """F(y) = [R; g] of Eq. (S1) and its bordered Jacobian for y = (q, lambda), t."""

    def __init__(self, system: MultibodySystem):
        self.model = newton_model(system)
        self.n = system.n_coordinates
        self.zeros = np.zeros(self.n)

    def residual(self, q: NDArray, lam: NDArray, t: float) -> NDArray[np.float64]:
        forces, gap = self.model.residual(q, self.zeros, self.zeros, lam, t)
        return np.concatenate([forces, gap])

    def jacobians(self, q: NDArray, lam: NDArray, t: float) -> tuple[NDArray, NDArray]:
        matrix = self.model.iteration_matrix(q, self.zeros, self.zeros, lam, t, 0.0, 1.0, 0.0)
        return matrix, residual_rate(self.model, q, lam, t)


def _bordered(matrix: NDArray, rate: NDArray, tangent_q: NDArray, tangent_t: float, weight: float, n: int):
    size = matrix.shape[0]
    out = np.zeros((size + 1, size + 1))
    out[:size, :size] = matrix
    out[:size, size] = rate
    out[size, :n] = tangent_q
    out[size, size] = weight * tangent_t
    return out


def _unit(dq: NDArray, dt: float, weight: float) -> tuple[NDArray, float]:
    norm = np.sqrt(dq @ dq + weight * dt * dt)
    return dq / norm, dt / norm


def path_points(
    system: MultibodySystem,
    q0: NDArray,
    multipliers0: NDArray,
    t0: float,
    direction: float,
    step: float,
    tolerance: float = 1e-10,
    max_iterations: int = 12,
    min_step: float | None = None,
    max_step: float | None = None,
    speed: float | None = None,
) -> Iterator[tuple[float, NDArray, NDArray, float]]:
    """The equilibria of ``system`` along its path from ``(q0, multipliers0)`` at ``t0`` (Eq. (S5)), the start
    first, as ``(t, q, multipliers, s)``, leaving the start towards growing t (``direction`` 1) or falling t (-1);
    endless: the caller stops. Arclength steps and ``s`` in units of t (the norm of the module docstring divided
    by c; ``speed`` sets c, default :func:`path_speed` at the start), as in :func:`continue_path`. Passes limit
    points in t."""
    n = system.n_coordinates
    model = _Model(system)
    q, lam, t = np.array(q0, dtype=float), np.array(multipliers0, dtype=float), float(t0)
    min_step = step / 1024.0 if min_step is None else min_step
    max_step = 8.0 * step if max_step is None else max_step
    matrix, rate = model.jacobians(q, lam, t)
    start = factor(matrix, what="static tangent at the path's start").solve(-rate)
    weight = (_speed(start, n) if speed is None else speed) ** 2
    tangent_q, tangent_t = _unit(direction * start[:n], direction, weight)
    tangent_lam = direction * start[n:] / np.sqrt(start[:n] @ start[:n] + weight)
    scale = np.sqrt(weight)  # arclength in units of t: the norm divided by c
    count, arclength, size = 1, 0.0, step * scale
    min_step, max_step = min_step * scale, max_step * scale
    yield t, q.copy(), lam.copy(), 0.0
    while True:
        guess_q, guess_lam, guess_t = q + size * tangent_q, lam + size * tangent_lam, t + size * tangent_t
        converged = None
        y_q, y_lam, y_t = guess_q.copy(), guess_lam.copy(), guess_t
        for iteration in range(1, max_iterations + 1):
            matrix, rate = model.jacobians(y_q, y_lam, y_t)
            residual = model.residual(y_q, y_lam, y_t)
            arc = tangent_q @ (y_q - guess_q) + weight * tangent_t * (y_t - guess_t)
            try:
                bordered = factor(_bordered(matrix, rate, tangent_q, tangent_t, weight, n), what="bordered tangent")
            except FloatingPointError:  # Newton left for infinity (a pin thrown out of its bore): a shorter step
                break
            delta = bordered.solve(-np.append(residual, arc))
            y_q, y_lam, y_t = y_q + delta[:n], y_lam + delta[n:-1], y_t + delta[-1]
            if (
                np.abs(delta[:n]).max() <= tolerance * max(1.0, np.abs(y_q).max())
                and np.abs(residual[n:]).max() <= tolerance
            ):
                converged = iteration
                break
        if converged is not None and _correction(y_q - guess_q, y_t - guess_t, weight) > MAX_CORRECTION * size:
            # Newton converged far from the predicted point: onto another branch across a sharp turn of this one
            # (Eq. (S5)); a shorter step stays on it
            converged = None
        if converged is None:
            if size <= min_step:
                raise StaticDivergence(
                    f"continuation stopped at t = {t:.6g} after {count} points: no equilibrium within "
                    f"arclength {size:.3g} (min_step); the path may branch here"
                )
            size *= 0.5
            log.debug("continuation step halved to %g at t = %g", size, t)
            continue
        matrix, rate = model.jacobians(y_q, y_lam, y_t)
        bordered = _bordered(matrix, rate, tangent_q, tangent_t, weight, n)
        right = np.zeros(bordered.shape[0])
        right[-1] = 1.0
        new = factor(bordered, what="bordered tangent").solve(right)
        norm = np.sqrt(new[:n] @ new[:n] + weight * new[-1] ** 2)
        tangent_q, tangent_t, tangent_lam = new[:n] / norm, new[-1] / norm, new[n:-1] / norm
        arclength += size
        q, lam, t = y_q, y_lam, float(y_t)
        count += 1
        yield t, q.copy(), lam.copy(), arclength / scale
        size = min(max_step, 1.5 * size) if converged <= 4 else size


def _correction(dq: NDArray, dt: float, weight: float) -> float:
    """Length of Newton's correction from the predicted point in the arclength's norm (Eq. (S5))."""
    return float(np.sqrt(dq @ dq + weight * dt * dt))


def _speed(rate_of_change: NDArray, n: int) -> float:
    """c: the largest ``|dq/dt|`` of the path's tangent (y_t of ``F_y y_t = -F_t``), floored at 1e-12."""
    return float(max(np.abs(rate_of_change[:n]).max(), 1e-12))


def path_speed(system: MultibodySystem, q: NDArray, multipliers: NDArray, t: float) -> float:
    """c of Eq. (S5) at an equilibrium: how fast the coordinates move with t there (largest ``|dq/dt|``)."""
    return _speed(path_rate(newton_model(system), q, multipliers, t)[0], system.n_coordinates)


def continue_path(
    system: MultibodySystem,
    q0: NDArray,
    multipliers0: NDArray,
    t0: float,
    t_end: float,
    step: float,
    max_points: int = 400,
    tolerance: float = 1e-10,
    max_iterations: int = 12,
    min_step: float | None = None,
    max_step: float | None = None,
) -> EquilibriumPath:
    """Follow the equilibria of ``system`` from the equilibrium ``(q0, multipliers0)`` at ``t0`` (Eq. (S5)) until
    t passes ``t_end`` (the last point lies beyond it) or ``max_points`` points: ``step`` is the first arclength
    step in units of t (the norm of the module docstring divided by c: a step of the start's tangent that
    moves t by ``step / sqrt(2)``), halved on a failed correction down to ``min_step`` (default
    step / 1024), grown by 1.5 after easy ones up to ``max_step`` (default 8 step). Passes limit points in t."""
    direction = 1.0 if t_end >= t0 else -1.0
    points = []
    for point in path_points(
        system, q0, multipliers0, t0, direction, step, tolerance, max_iterations, min_step, max_step
    ):
        points.append(point)
        if len(points) >= max_points or (len(points) > 1 and (point[0] - t_end) * direction >= 0.0):
            break
    return equilibrium_path(points)


def equilibrium_path(points: list[tuple[float, NDArray, NDArray, float]]) -> EquilibriumPath:
    """The :class:`EquilibriumPath` of the points of :func:`path_points`."""
    t, q, lam, s = zip(*points, strict=True)
    return EquilibriumPath(np.array(t), np.array(q), np.array(lam), np.array(s))
