r"""Numba kernel: a joint frame on a rigid interface marker and its exact derivatives, in one pass.

For a marker (``docs/formulation.md``, Eqs. (K1)-(K3)) with local point :math:`\bar x`,
position modes ``P``, rotation modes :math:`\Theta`, and a joint frame given by the constant
rotation ``R`` (columns = joint axes in marker coordinates) and offset ``o`` (marker
coordinates), with :math:`\theta = \Theta\zeta`, :math:`E = \exp(\tilde\theta)` and its right
Jacobian :math:`T(\theta)`:

.. math::
    p &= R_0 + A(p_E)\,(\bar x + P\zeta + E o),\qquad a_k = A\,E\,R e_k,\\
    \partial p/\partial q &= [\,I,\ \partial(A u)/\partial p_E,\ A P - A E\tilde o T\Theta\,],\\
    \partial a_k/\partial q &= [\,0,\ \partial(A w_k)/\partial p_E,\ -A E \tilde{(Re_k)} T\Theta\,],\quad w_k = E R e_k,

using :math:`d\exp(\tilde\theta)v = -\exp(\tilde\theta)\tilde v\,T\,d\theta`. All arrays passed
to one call share one dtype (float64, or complex128 for complex-step derivatives).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .euler_parameters import rotation_derivative, rotation_matrix, skew

__all__ = ["exp_so3_kernel", "exp_so3_tangent_kernel", "marker_frame"]


@njit(cache=True)
def exp_so3_kernel(theta: np.ndarray) -> np.ndarray:
    """Rodrigues' formula, Eq. (K3) (Taylor series below |theta|^2 = 1e-8)."""
    phi2 = theta @ theta
    s = skew(theta)
    if abs(phi2) < 1e-8:
        a = 1.0 - phi2 / 6.0
        b = 0.5 - phi2 / 24.0
    else:
        phi = np.sqrt(phi2)
        a = np.sin(phi) / phi
        b = (1.0 - np.cos(phi)) / phi2
    return np.eye(3) + a * s + b * (s @ s)


@njit(cache=True)
def exp_so3_tangent_kernel(theta: np.ndarray) -> np.ndarray:
    """Right Jacobian T(theta) of the exponential map."""
    phi2 = theta @ theta
    s = skew(theta)
    if abs(phi2) < 1e-8:
        a = 0.5 - phi2 / 24.0
        b = 1.0 / 6.0 - phi2 / 120.0
    else:
        phi = np.sqrt(phi2)
        a = (1.0 - np.cos(phi)) / phi2
        b = (phi - np.sin(phi)) / (phi2 * phi)
    return np.eye(3) - a * s + b * (s @ s)


@njit(cache=True)
def marker_frame(q, point, position_modes, rotation_modes, rotation, offset):
    """Joint point ``p`` (3), axes (3x3, columns), ``dp/dq`` (3 x n) and ``d axes/dq`` (3, 3, n)."""
    n = q.shape[0]
    m = n - 7
    a_body = rotation_matrix(q[3:7])
    theta = np.zeros(3, dtype=q.dtype)
    local = point.copy()
    if m > 0:
        theta = rotation_modes @ q[7:]
        local = point + position_modes @ q[7:]
    turn = exp_so3_kernel(theta)
    tangent = exp_so3_tangent_kernel(theta)
    turned_offset = turn @ offset
    body_point = local + turned_offset
    position = q[:3] + a_body @ body_point
    axes_local = turn @ rotation
    axes = a_body @ axes_local
    d_position = np.zeros((3, n), dtype=q.dtype)
    d_axes = np.zeros((3, 3, n), dtype=q.dtype)
    for i in range(3):
        d_position[i, i] = 1.0
    d_position[:, 3:7] = rotation_derivative(q[3:7], body_point)
    if m > 0:
        a_turn = a_body @ turn
        d_position[:, 7:] = a_body @ position_modes - ((a_turn @ skew(offset)) @ tangent) @ rotation_modes
    for k in range(3):
        w = axes_local[:, k].copy()
        d_axes[k, :, 3:7] = rotation_derivative(q[3:7], w)
        if m > 0:
            d_axes[k, :, 7:] = -(((a_body @ turn) @ skew(rotation[:, k].copy())) @ tangent) @ rotation_modes
    return position, axes, d_position, d_axes
