r"""Equilibria where Newton's tangent is singular at the start: pseudo-transient continuation (``docs/formulation.md``,
Eq. (P6)).

A pin inside its clearance (:mod:`ffrf.system.clearance_joint`) is held by nothing until it touches its bore, so the
static tangent of Eq. (S1) is singular there and a Newton step is either undefined or, with a tiny stiffness,
enormous. Pseudo-transient continuation (Kelley and Keyes, SIAM J. Numer. Anal. 35 (1998)) adds the mass matrix
over a pseudo time step squared to the tangent,

.. math:: \begin{bmatrix} M/\Delta\tau^2 + K_t + H & C_q^T \\ C_q & 0\end{bmatrix}
          \begin{bmatrix}\Delta q\\ \Delta\lambda\end{bmatrix} = -\begin{bmatrix} r \\ g\end{bmatrix},

so that a free body falls by :math:`\Delta\tau^2` times its load over its mass per step, as an implicit Euler step
from rest would move it. A step that doubles the residual and raises the stored energy (strain, gravity, contacts:
what settling lowers) is retried with half the pseudo time step; after an accepted step the pseudo time step
doubles. Only the iteration matrix changes: the converged state solves the same
equations :math:`r = 0,\ g = 0` as Newton's, which finishes once :math:`M/\Delta\tau^2` no longer matters.
"""

from __future__ import annotations

import logging

import numpy as np
from numpy.typing import NDArray

from ffrf.errors import StaticDivergence
from ffrf.numerics.rank_revealing import factor
from ffrf.solvers.common import StaticSolution
from ffrf.solvers.newton_kernels import static_rhs, static_update
from ffrf.system.multibody import MultibodySystem
from ffrf.system.packed_system import PackedSystem, newton_model

__all__ = ["settle"]

log = logging.getLogger(__name__)

#: Pseudo time step (s) of the first iteration: a free body falls g * 1e-6 s^2 = 10 um under gravity.
FIRST_STEP = 1e-3
#: Pseudo time step (s) beyond which the mass term is round-off for any linkage (M / dtau^2 < 1e-12 of a stiffness
#: of 1 N/m per kg): the iterations are Newton's.
NEWTON_STEP = 1e6
#: Relative rise of the stored energy that a settling step may make (round-off of the energy's sum).
ENERGY_ROUNDOFF = 1e-12
#: Halvings of one pseudo time step before the start is declared out of reach.
MAX_HALVINGS = 30


def _residual(
    model: MultibodySystem | PackedSystem, q: NDArray, lam: NDArray, t: float
) -> tuple[NDArray, NDArray, float]:
    zeros = np.zeros(model.n_coordinates)
    residual, gap = model.residual(q, zeros, zeros, lam, t)
    rhs, finite = static_rhs(residual, gap)
    return rhs, gap, float(np.max(np.abs(rhs))) if finite else np.inf


def settle(
    system: MultibodySystem,
    q0: NDArray,
    t: float = 0.0,
    tolerance: float = 1e-10,
    max_iterations: int = 400,
    first_step: float = FIRST_STEP,
) -> StaticSolution:
    """The equilibrium that the bodies settle into from ``q0`` at time ``t`` (Eq. (P6)); ``iterations`` has the
    number of iterations taken. Raises :class:`~ffrf.errors.StaticDivergence` when ``max_iterations`` do not reach
    it."""
    q = np.array(q0, dtype=float)
    lam = np.zeros(system.n_constraints)
    zeros = np.zeros(system.n_coordinates)
    model = newton_model(system)
    rhs, gap, size = _residual(model, q, lam, t)
    if not np.isfinite(size):
        raise StaticDivergence("NaN in the static residual at the start; check the model and the start")
    energy = system.potential_energy(q, t)
    conservative = all(element.conservative for element in system.forces)
    dtau, halvings = first_step, 0
    for iteration in range(1, max_iterations + 1):
        mass_factor = 0.0 if dtau >= NEWTON_STEP else 1.0 / dtau**2
        matrix = model.iteration_matrix(q, zeros, zeros, lam, t, mass_factor, 1.0, 0.0)
        delta = factor(matrix, what=f"pseudo-transient tangent at t = {t:g}").solve(rhs)
        q_new, lam_new, _, converged = static_update(q, lam, delta, gap, tolerance)
        rhs_new, gap_new, size_new = _residual(model, q_new, lam_new, t)
        energy_new = system.potential_energy(q_new, t) if np.isfinite(size_new) else np.inf
        # Settling lowers the stored energy, while the residual may rise on the way (a pin meeting its bore); the
        # energy misses the work of loads without a potential (torques), so a residual that does not double passes
        if converged and mass_factor == 0.0:
            return StaticSolution(q_new, lam_new, (iteration,))
        # A start off the constraints (a drive moved on, Eq. (P6)'s jump) is first brought onto them: there the drive
        # does work, so the energy cannot judge a step; one that brings the constraints closer passes
        off = np.max(np.abs(gap), initial=0.0)
        projecting = off > tolerance and np.isfinite(size_new) and np.max(np.abs(gap_new), initial=0.0) < off
        if conservative:  # every force has a potential: a step may not raise it (a trust region in the metric M),
            # counted as the Lagrangian E + lambda . g with the step's multipliers: a step that closes the linearised
            # constraints' gap moves along them, where the energy alone may rise by lambda . dg (measured on the
            # loose Bennett: every Newton step near the equilibrium raised E by 1e-14..1e-11 J, none the Lagrangian)
            merit_new = energy_new + float(lam_new @ gap_new)
            rejected = not merit_new <= energy + float(lam_new @ gap) + ENERGY_ROUNDOFF * abs(energy)
            # where every pseudo time step raised it, the merit is at its round-off: Newton's own step (no mass term)
            # is judged by its residual (measured: 2e-5 -> 2.6e-9 N with the Lagrangian up by 1e-15 J)
            rejected = rejected and not (mass_factor == 0.0 and size_new < 0.5 * size)
        else:
            rejected = size_new > 2.0 * size and not energy_new < energy
        if not projecting and rejected:
            halvings += 1
            if halvings == MAX_HALVINGS:  # at round-off neither falls: see whether Newton's step converges here
                dtau = NEWTON_STEP
                continue
            if halvings > MAX_HALVINGS:
                raise StaticDivergence(
                    f"pseudo-transient continuation stalled at iteration {iteration}: the residual {size:.3e} and the "
                    f"stored energy rise for every pseudo time step down to {dtau:.3e} s; check the model's contacts "
                    "and the start"
                )
            dtau *= 0.5
            continue
        growth = 2.0
        dtau, halvings = dtau * growth, 0
        if converged:
            dtau = NEWTON_STEP
        q, lam, rhs, gap, size, energy = q_new, lam_new, rhs_new, gap_new, size_new, energy_new
        log.debug("pseudo-transient iteration %d: residual %.3e, pseudo time step %.3e s", iteration, size, dtau)
    raise StaticDivergence(
        f"pseudo-transient continuation did not reach an equilibrium in {max_iterations} iterations (residual "
        f"{size:.3e}, pseudo time step {dtau:.3e} s); raise max_iterations or start closer to the equilibrium"
    )
