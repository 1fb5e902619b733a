r"""Static equilibrium: Newton on the constrained static equations, with load continuation.

With :math:`\dot q = \ddot q = 0` the quadratic velocity vector vanishes and the body
residual reduces to elastic and gravity forces (``docs/formulation.md``, Eq. (S1)):

.. math:: K_r\zeta - Q_g(q) + C_q^T\lambda = 0,\qquad g(q, t) = 0,

solved by Newton with the exact tangent :math:`[K_t + H,\ C_q^T;\ C_q,\ 0]`. Gravity can be
applied in ``load_steps`` increments (load continuation); each increment starts from the
previous equilibrium. A singular tangent means the system can still move freely (a
mechanism or an unconstrained body): the error says so and names the remedy.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, replace

import numpy as np
import scipy.linalg
from numpy.typing import NDArray

from .system import MultibodySystem

__all__ = ["StaticSolution", "StaticDivergence", "static_equilibrium", "quasi_static"]

log = logging.getLogger(__name__)


class StaticDivergence(RuntimeError):
    """Newton found no static equilibrium."""


@dataclass(frozen=True)
class StaticSolution:
    """Equilibrium coordinates ``q``, multipliers, and Newton iterations per load step."""

    q: NDArray[np.float64]
    multipliers: NDArray[np.float64]
    iterations: tuple[int, ...]


def _equilibration(matrix: NDArray) -> tuple[NDArray, NDArray]:
    """Row and column scalings 1/sqrt(max |a|) (one Ruiz pass; zero rows and columns keep 1)."""
    row_max, col_max = np.abs(matrix).max(axis=1), np.abs(matrix).max(axis=0)
    rows = 1.0 / np.sqrt(np.where(row_max > 0, row_max, 1.0))
    cols = 1.0 / np.sqrt(np.where(col_max > 0, col_max, 1.0))
    return rows, cols


def _newton(system: MultibodySystem, q: NDArray, lam: NDArray, t: float, tolerance: float, max_iterations: int):
    n = system.n_coordinates
    zeros = np.zeros(n)
    for iteration in range(1, max_iterations + 1):
        cq = system.constraint_jacobian(q, t)
        residual = system.body_residuals(q, zeros, zeros) + cq.T @ lam
        gap = system.constraint_values(q, t)
        if not (np.all(np.isfinite(residual)) and np.all(np.isfinite(gap))):
            raise StaticDivergence(f"NaN in the static residual (iteration {iteration}); check the model and the start")
        jq, _ = system.body_tangents(q, zeros, zeros)
        tangent = jq + system.constraint_hessian(q, lam, t)
        matrix = np.block([[tangent, cq.T], [cq, np.zeros((cq.shape[0], cq.shape[0]))]])
        # Judge singularity after equilibrating rows and columns: forces, moments and
        # constraint rows differ by many orders of magnitude without meaning a free motion.
        # Equilibrate rows and columns before judging singularity and solving: stiffness rows of
        # near-rigid links (E = 1e15 Pa) and unit constraint rows differ by 15 orders of magnitude.
        rows, cols = _equilibration(matrix)
        scaled = rows[:, None] * matrix * cols[None, :]
        singular_values = scipy.linalg.svdvals(scaled)
        if singular_values[-1] <= 1e-15 * singular_values[0]:
            free = int(np.sum(singular_values <= 1e-15 * singular_values[0]))
            raise StaticDivergence(
                f"the static tangent is singular ({free} free motion(s)): the system is a mechanism or a body is "
                "not held; prescribe the drive or add the missing support before a static solve")
        delta = cols * scipy.linalg.solve(scaled, -rows * np.concatenate([residual, gap]))
        q = q + delta[:n]
        lam = lam + delta[n:]
        if np.abs(delta[:n]).max() <= tolerance * max(1.0, np.abs(q).max()) and np.abs(gap).max() <= tolerance:
            return q, lam, iteration
    raise StaticDivergence(
        f"static Newton did not converge in {max_iterations} iterations: last increment {np.abs(delta[:n]).max():.3e}, "
        f"constraint residual {np.abs(gap).max():.3e}; use more load_steps or a better start")


def static_equilibrium(
    system: MultibodySystem,
    q0: NDArray,
    t: float = 0.0,
    load_steps: int = 1,
    tolerance: float = 1e-10,
    max_iterations: int = 25,
) -> StaticSolution:
    """Equilibrium near ``q0`` at time ``t`` (for prescribed motions), gravity in ``load_steps`` increments."""
    if load_steps < 1:
        raise ValueError(f"load_steps must be >= 1, got {load_steps}")
    q = np.array(q0, dtype=float)
    lam = np.zeros(system.n_constraints)
    counts = []
    for k in range(1, load_steps + 1):
        scaled = replace(system, gravity=system.gravity * (k / load_steps))
        q, lam, iterations = _newton(scaled, q, lam, t, tolerance, max_iterations)
        counts.append(iterations)
        log.debug("load step %d/%d converged in %d iterations", k, load_steps, iterations)
    return StaticSolution(q, lam, tuple(counts))


def quasi_static(
    system: MultibodySystem,
    q0: NDArray,
    times: NDArray,
    tolerance: float = 1e-10,
    max_iterations: int = 25,
    progress=None,
) -> StaticSolution:
    """A sequence of static equilibria at ``times`` (prescribed motions follow their time laws;
    no inertia), each starting from the previous one. Returns ``q`` and ``multipliers`` with one
    row per time (``iterations`` per time)."""
    times = np.asarray(times, dtype=float)
    q = np.array(q0, dtype=float)
    lam = np.zeros(system.n_constraints)
    qs, lams, counts = [], [], []
    for k, t in enumerate(times):
        try:
            q, lam, iterations = _newton(system, q, lam, float(t), tolerance, max_iterations)
        except StaticDivergence as error:
            raise StaticDivergence(f"quasi-static step {k} at t = {t:.6g} s: {error}") from error
        qs.append(q.copy())
        lams.append(lam.copy())
        counts.append(iterations)
        if progress is not None:
            progress(float(t), float(times[-1]))
    return StaticSolution(np.array(qs), np.array(lams), tuple(counts))
