r"""Exact derivatives of a static equilibrium with respect to parameters (``docs/formulation.md``, Eq. (D1)).

At an equilibrium :math:`r(q, \lambda; p) = 0`, :math:`g(q, t; p) = 0` of Eq. (S1), the implicit function theorem
gives the response to a parameter :math:`p` from the same tangent Newton factors:

.. math:: \begin{bmatrix} K_t + H & C_q^T \\ C_q & 0 \end{bmatrix}
          \begin{bmatrix} \partial q/\partial p \\ \partial\lambda/\partial p \end{bmatrix}
          = -\begin{bmatrix} \partial r/\partial p \\ \partial g/\partial p \end{bmatrix},

one solve per parameter, no re-run. :func:`material_rates` gives the right-hand side for each link's Young's modulus
and density as relative changes (:math:`p = \ln E_k`, :math:`\ln\rho_k`): the reduced stiffness is proportional to
:math:`E`, the modal moments to :math:`\rho`, and the mode basis depends on neither (the Craig-Bampton and free-free
modes are eigenvectors of the pair :math:`(K, M)`, unchanged when either is scaled), so
:math:`\partial r_k/\partial\ln E_k = K_r\zeta_k` on the body's modal rows and
:math:`\partial r_k/\partial\ln\rho_k = -Q_{g,k}(q)` (the gravity force is linear in the moments), both exact.

Where the tangent is singular the response exists only if the right-hand side lies in its range (redundant
constraints of a near-rigid loop: the multipliers are not unique, the positions are); otherwise the equilibrium is at a
fold (Eq. (B1)), where the derivative is unbounded, and :class:`SensitivityError` says so instead of returning a
number.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ffrf.errors import SensitivityError
from ffrf.solvers.static_solver import tangent_at
from ffrf.system.multibody import MultibodySystem

__all__ = ["RANGE_TOLERANCE", "equilibrium_response", "material_rates"]

#: Largest residual of the response's equations, relative to the right-hand side, for a singular tangent: above it
#: the right-hand side is not in the tangent's range (a fold).
RANGE_TOLERANCE = 1e-8


def equilibrium_response(
    system: MultibodySystem, q: NDArray, lam: NDArray, t: float, rates: NDArray
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(dq, dlam)`` ``(n, k)`` and ``(m, k)``: the equilibrium's response to ``k`` parameters whose rates of the
    static residual and constraints are the columns of ``rates`` ``(n + m, k)`` (module docstring); ``(q, lam)`` an
    equilibrium at time ``t``. Raises :class:`SensitivityError` at a fold."""
    rates = np.asarray(rates, dtype=float)
    if rates.ndim == 1:
        rates = rates[:, None]
    n = system.n_coordinates
    if rates.shape[0] != n + system.n_constraints:
        raise ValueError(f"rates need {n + system.n_constraints} rows (coordinates, constraints), got {rates.shape}")
    tangent = tangent_at(system, q, lam, t)
    response = np.column_stack([tangent.solve(-column) for column in rates.T]) if rates.shape[1] else rates.copy()
    if tangent.rank_deficiency:
        zeros = np.zeros(n)
        matrix = system.iteration_matrix(q, zeros, zeros, lam, t, 0.0, 1.0, 0.0)
        left = np.linalg.norm(matrix @ response + rates, axis=0)
        scale = np.maximum(np.linalg.norm(rates, axis=0), np.finfo(float).tiny)
        worst = int(np.argmax(left / scale))
        if left[worst] > RANGE_TOLERANCE * scale[worst]:
            raise SensitivityError(
                f"the equilibrium at t = {t:g} is at a fold (its static tangent has {tangent.rank_deficiency} free "
                f"motion(s) that parameter {worst} loads, residual {left[worst] / scale[worst]:.2g} of the load): "
                "the derivative is unbounded there; take the poses on either side"
            )
    return response[:n], response[n:]


def material_rates(system: MultibodySystem, q: NDArray, bodies: tuple[int, ...] | None = None) -> NDArray[np.float64]:
    """Columns ``(n + m, 2k)`` of :func:`equilibrium_response`'s ``rates`` for the relative Young's modulus of each
    of ``bodies`` (default all), then their relative density: ``d/d ln E_k`` and ``d/d ln rho_k`` of the static
    residual at ``q`` (module docstring); the constraints do not depend on either."""
    bodies = tuple(range(len(system.bodies))) if bodies is None else tuple(bodies)
    q = np.asarray(q, dtype=float)
    n, rows = system.n_coordinates, system.n_coordinates + system.n_constraints
    stiffness, density = np.zeros((rows, len(bodies))), np.zeros((rows, len(bodies)))
    zeros = np.zeros(n)
    for column, index in enumerate(bodies):
        body, block = system.bodies[index], system.block(index)
        elastic = body.stiffness @ q[block][7:]
        stiffness[block.start + 7 : block.stop, column] = elastic
        at_rest = body.residual(q[block], zeros[block], zeros[block], system.gravity)  # K_r zeta - Q_g
        density[block, column] = at_rest
        density[block.start + 7 : block.stop, column] -= elastic
    return np.hstack([stiffness, density])
