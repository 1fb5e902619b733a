r"""Stability of a static equilibrium: the squared frequencies of small vibrations about it on the constraints.

At an equilibrium :math:`(q, \lambda)` of Eq. (S1) the motions the constraints allow to first order are the null
space :math:`N` of :math:`C_q` (drives held: a position-controlled drive is a constraint). Small vibrations
:math:`q = q^* + N\eta` obey :math:`N^TMN\,\ddot\eta + N^T(K_t + H)N\,\eta = 0` (``docs/formulation.md``, Eq. (B1)),
so the equilibrium is stable when every eigenvalue :math:`\mu` of

.. math:: N^T(K_t + H)N\,x = \mu\,N^TMN\,x                                              \qquad (B1)

is positive; :math:`\mu = \omega^2` (rad^2/s^2) is the squared frequency of the mode :math:`Nx`. The count of
negative :math:`\mu` does not depend on the coordinates (Sylvester's law of inertia), and the smallest
:math:`\mu` passing through zero along a path marks a limit point or a bifurcation.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import eigh

from ffrf.errors import SceneError
from ffrf.system.multibody import MultibodySystem
from ffrf.system.packed_system import newton_model

__all__ = [
    "check_judged_at_equilibria",
    "CriticalPose",
    "EquilibriumStability",
    "LowestMode",
    "critical_pose",
    "equilibrium_stability",
    "frequency_form",
    "lowest_mode",
    "mode_shares",
    "stability_along",
    "stability_summary",
]


def check_judged_at_equilibria(mode: str, stability: bool, remedy: str, where: str = "") -> None:
    """The rule of every run with stability: Eq. (B1) holds at a static equilibrium, so stability is judged along a
    quasi-static run only; a ``dynamic`` ``mode`` with ``stability`` is a :class:`ffrf.errors.SceneError` (after
    ``where``, ending with ``remedy``: what to change where the settings came from). ``auto`` and ``quasi_static``
    pass."""
    if stability and mode == "dynamic":
        raise SceneError(f"{where + ': ' if where else ''}stability is judged at equilibria: {remedy}")


@dataclass(frozen=True)
class EquilibriumStability:
    """The ``count`` smallest :math:`\\mu` of Eq. (B1) (rad^2/s^2, ascending), their modes in ``q`` (columns), the
    number of free motions (dimension of :math:`N`) and the tangent's asymmetry (relative; round-off at an
    equilibrium of a conservative system)."""

    squared_frequencies: NDArray[np.float64]
    modes: NDArray[np.float64]
    free_motions: int
    asymmetry: float

    @property
    def stable(self) -> bool:
        return bool(self.squared_frequencies.size == 0 or self.squared_frequencies[0] > 0.0)


def _null_space(matrix: NDArray) -> NDArray[np.float64]:
    """Orthonormal null space by the rank rule (R1): singular values below ``max(shape) eps`` of the largest."""
    _, values, vt = np.linalg.svd(matrix)
    rank = int(np.sum(values > max(matrix.shape) * np.finfo(float).eps * values[0])) if values.size else 0
    return vt[rank:].T


def equilibrium_stability(
    system: MultibodySystem, q: NDArray, multipliers: NDArray, t: float = 0.0, count: int = 3
) -> EquilibriumStability:
    """Eq. (B1) at the equilibrium ``(q, multipliers)`` at time ``t`` (drives at their prescribed angles)."""
    n = system.n_coordinates
    tangent, jacobian = _pencil(system, q, multipliers, t)
    symmetric = 0.5 * (tangent + tangent.T)
    asymmetry = float(np.abs(tangent - tangent.T).max() / max(np.abs(tangent).max(), 1e-300))
    free = _null_space(jacobian)
    stiffness = free.T @ symmetric @ free
    mass = free.T @ system.mass_matrix(q) @ free
    k = min(count, free.shape[1])
    if k == 0:  # no free motion: nothing can vibrate, nothing can buckle
        return EquilibriumStability(np.zeros(0), np.zeros((n, 0)), 0, asymmetry)
    # only the k smallest (LAPACK's subset solver): Eq. (B1) at every output is the monitoring's cost
    values, vectors = eigh(0.5 * (stiffness + stiffness.T), 0.5 * (mass + mass.T), subset_by_index=[0, k - 1])
    return EquilibriumStability(values, free @ vectors, free.shape[1], asymmetry)


@dataclass(frozen=True)
class LowestMode:
    """The lowest squared frequency ``mu`` of Eq. (B1) at an equilibrium, its mode ``x`` in ``q`` (``x^T M x = 1``,
    in the null space of ``C_q``) and the mode's constraint forces ``y`` (``(K_t + H) x + C_q^T y = mu M x``)."""

    mu: float
    x: NDArray[np.float64]
    y: NDArray[np.float64]


def lowest_mode(system: MultibodySystem, q: NDArray, multipliers: NDArray, t: float = 0.0) -> LowestMode:
    """:class:`LowestMode` at the equilibrium ``(q, multipliers)`` at time ``t``; ``y`` by least squares (unique
    where the constraints are independent)."""
    found = equilibrium_stability(system, q, multipliers, t, count=1)
    if found.squared_frequencies.size == 0:
        raise SceneError(f"the equilibrium at t = {t:g} has no free motion: it has no squared frequency to follow")
    tangent, jacobian = _pencil(system, q, multipliers, t)
    mu, x = float(found.squared_frequencies[0]), found.modes[:, 0]
    # the symmetric part, as in Eq. (B1): the tangent's asymmetry (round-off at an equilibrium) is not differentiated
    unbalanced = mu * (system.mass_matrix(q) @ x) - 0.5 * (tangent + tangent.T) @ x
    y = np.linalg.lstsq(jacobian.T, unbalanced, rcond=None)[0]
    return LowestMode(mu, x, y)


def frequency_form(system: MultibodySystem, q: NDArray, multipliers: NDArray, t: float, mode: LowestMode) -> float:
    r""":math:`x^T (K_t + H) x + 2 y^T C_q x - \mu\, x^T M x` of ``system`` at ``(q, multipliers, t)`` with the
    mode of another (nominal) state (``docs/formulation.md``, Eq. (D7)): zero at the mode's own state, and its
    change with anything the matrices depend on is, to first order, that of the lowest squared frequency (the
    derivative of a simple eigenvalue of the constrained pencil, the mode held fixed: no eigenvalue is re-solved,
    so the eigensolver's round-off is not differenced)."""
    tangent, jacobian = _pencil(system, q, multipliers, t)
    x = mode.x  # x^T K x is that of K's symmetric part
    return float(x @ tangent @ x + 2.0 * mode.y @ (jacobian @ x) - mode.mu * (x @ system.mass_matrix(q) @ x))


def _pencil(system: MultibodySystem, q: NDArray, multipliers: NDArray, t: float) -> tuple[NDArray, NDArray]:
    """The static tangent ``K_t + H`` and the constraint Jacobian ``C_q`` at ``(q, multipliers, t)``."""
    n = system.n_coordinates
    zeros = np.zeros(n)
    matrix = newton_model(system).iteration_matrix(q, zeros, zeros, multipliers, t, 0.0, 1.0, 0.0)
    return matrix[:n, :n], matrix[n:, :n]


def stability_along(
    system: MultibodySystem, times: NDArray, q: NDArray, multipliers: NDArray, count: int = 3
) -> list[EquilibriumStability]:
    """Eq. (B1) at every row of a quasi-static run (``times``, ``q``, ``multipliers``)."""
    return [
        equilibrium_stability(system, row, lam, float(t), count)
        for t, row, lam in zip(times, q, multipliers, strict=True)
    ]


def stability_summary(squared_frequencies: NDArray, along: NDArray, name: str) -> dict:
    """The smallest squared frequency of Eq. (B1) over a run (rad^2/s^2) and where, the unstable poses, and the
    first and last poses' values; ``along`` (one value per pose) locates them, under the keys ``*_{name}``."""
    lowest = squared_frequencies[:, 0]
    k = int(np.argmin(lowest))
    unstable = np.flatnonzero(lowest <= 0.0)
    crossings = np.flatnonzero(np.sign(lowest[1:]) != np.sign(lowest[:-1]))
    # A quasi-static path cannot pass a limit point of its parameter (it stops there, or goes on past a fold
    # through Eq. (S6), between outputs of positive mu): a sign change between two outputs is a branch point.
    changes = [
        {
            name: float(along[j] + (along[j + 1] - along[j]) * lowest[j] / (lowest[j] - lowest[j + 1])),
            "kind": "branch point (bifurcation): the path goes on through it",
            "stability": "lost" if lowest[j] > 0.0 else "regained",
        }
        for j in crossings
    ]
    return {
        "sign_changes": changes,
        "min_squared_frequency": float(lowest[k]),
        "min_frequency_hz": float(np.sqrt(max(lowest[k], 0.0)) / (2.0 * np.pi)),
        f"at_{name}": float(along[k]),
        "unstable_poses": int(unstable.size),
        f"first_unstable_{name}": float(along[unstable[0]]) if unstable.size else None,
        "first_squared_frequencies": squared_frequencies[0].tolist(),
        "last_squared_frequencies": squared_frequencies[-1].tolist(),
        f"last_{name}": float(along[-1]),
    }


def mode_shares(system: MultibodySystem, q: NDArray, mode: NDArray) -> NDArray[np.float64]:
    """Each body's share of a mode's kinetic energy (``x_b^T M_b x_b / x^T M x``, summing to one): which bodies
    the mode moves."""
    energies = np.array(
        [
            mode[system.block(i)] @ body.mass_matrix(q[system.block(i)]) @ mode[system.block(i)]
            for i, body in enumerate(system.bodies)
        ]
    )
    return energies / energies.sum()


@dataclass(frozen=True)
class CriticalPose:
    """The equilibrium of a run closest to instability (``where``: a fold of the path or the least stable output),
    at ``t``, with its smallest squared frequency of Eq. (B1) and that mode."""

    where: str
    t: float
    q: NDArray[np.float64]
    multipliers: NDArray[np.float64]
    squared_frequency: float
    mode: NDArray[np.float64]

    def summary(self, system: MultibodySystem, shares: str = "body_shares") -> dict:
        """Plain data for a run's metadata: where, ``time_s``, the squared frequency, and under ``shares`` each body's
        share of the mode's kinetic energy (:func:`mode_shares`)."""
        weights = mode_shares(system, self.q, self.mode)
        return {
            "where": self.where,
            "time_s": self.t,
            "squared_frequency": self.squared_frequency,
            shares: {body.name: float(w) for body, w in zip(system.bodies, weights, strict=True)},
        }


def critical_pose(system: MultibodySystem, where: str, t: float, q: NDArray, multipliers: NDArray) -> CriticalPose:
    """:class:`CriticalPose` of the equilibrium ``(q, multipliers)`` at ``t``."""
    judged = equilibrium_stability(system, q, multipliers, t, count=1)
    return CriticalPose(where, float(t), q, multipliers, float(judged.squared_frequencies[0]), judged.modes[:, 0])
