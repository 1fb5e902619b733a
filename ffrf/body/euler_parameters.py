r"""Euler parameters (unit quaternions, scalar first) for the floating frame.

``p = [p0, p1, p2, p3]`` with the constraint :math:`p^Tp = 1`. The rotation matrix is the
quadratic form (``docs/formulation.md``, Eq. (R1))

.. math:: A(p) = (p_0^2 - \mathbf p^T\mathbf p) I + 2\mathbf p\mathbf p^T + 2p_0\tilde{\mathbf p},

and the body-frame angular velocity is :math:`\bar\omega = \bar G\dot p` with (Eq. (R2))

.. math:: \bar G = 2\begin{bmatrix} -p_1 & p_0 & p_3 & -p_2\\ -p_2 & -p_3 & p_0 & p_1\\
          -p_3 & p_2 & -p_1 & p_0\end{bmatrix}.

Useful identities (unit ``p``): :math:`\bar G p = 0`, :math:`\bar G(\dot p)\,\dot p = 0` (so
:math:`\dot{\bar\omega} = \bar G\ddot p`), and the variation
:math:`\delta(A u) = -A\tilde u\,\bar G\,\delta p` for variations tangent to :math:`p^Tp = 1`.
All functions are numba kernels on plain arrays; they also run on complex arrays (of one
dtype throughout), for exact complex-step derivatives.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ffrf.numerics.small_linalg import cross3, skew

__all__ = ["rotation_matrix", "g_bar", "rotation_derivative", "transposed_rotation_derivative"]


@njit(cache=True)
def rotation_matrix(p: np.ndarray) -> np.ndarray:
    """Eq. (R1): rotation matrix of Euler parameters ``p`` (exact for unit ``p``)."""
    p0, p1, p2, p3 = p[0], p[1], p[2], p[3]
    out = np.empty((3, 3), dtype=p.dtype)
    out[0, 0] = p0 * p0 + p1 * p1 - p2 * p2 - p3 * p3
    out[1, 1] = p0 * p0 - p1 * p1 + p2 * p2 - p3 * p3
    out[2, 2] = p0 * p0 - p1 * p1 - p2 * p2 + p3 * p3
    out[0, 1] = 2.0 * (p1 * p2 - p0 * p3)
    out[1, 0] = 2.0 * (p1 * p2 + p0 * p3)
    out[0, 2] = 2.0 * (p1 * p3 + p0 * p2)
    out[2, 0] = 2.0 * (p1 * p3 - p0 * p2)
    out[1, 2] = 2.0 * (p2 * p3 - p0 * p1)
    out[2, 1] = 2.0 * (p2 * p3 + p0 * p1)
    return out


@njit(cache=True)
def g_bar(p: np.ndarray) -> np.ndarray:
    r"""Eq. (R2): :math:`\bar G(p)` with :math:`\bar\omega = \bar G\dot p` (body-frame angular velocity)."""
    p0, p1, p2, p3 = p[0], p[1], p[2], p[3]
    out = np.empty((3, 4), dtype=p.dtype)
    out[0, 0], out[0, 1], out[0, 2], out[0, 3] = -p1, p0, p3, -p2
    out[1, 0], out[1, 1], out[1, 2], out[1, 3] = -p2, -p3, p0, p1
    out[2, 0], out[2, 1], out[2, 2], out[2, 3] = -p3, p2, -p1, p0
    return 2.0 * out


@njit(cache=True)
def rotation_derivative(p: np.ndarray, u: np.ndarray) -> np.ndarray:
    r"""Exact Jacobian :math:`\partial(A(p)u)/\partial p` (3x4) of the quadratic form Eq. (R1), Eq. (R3):

    .. math:: \frac{\partial (Au)}{\partial p_0} = 2p_0u + 2\mathbf p\times u,\quad
              \frac{\partial (Au)}{\partial\mathbf p}
              = 2(\mathbf p^Tu)I + 2\mathbf p u^T - 2u\mathbf p^T - 2p_0\tilde u.

    For unit ``p`` and tangent variations it equals :math:`-A\tilde u\bar G`.
    """
    out = np.empty((3, 4), dtype=p.dtype)
    pv = p[1:]
    cross = cross3(pv, u)
    dot = pv[0] * u[0] + pv[1] * u[1] + pv[2] * u[2]
    for i in range(3):
        out[i, 0] = 2.0 * (p[0] * u[i] + cross[i])
        for j in range(3):
            out[i, j + 1] = 2.0 * (pv[i] * u[j] - u[i] * pv[j])
        out[i, i + 1] += 2.0 * dot
    out[:, 1:] -= 2.0 * p[0] * skew(u)
    return out


@njit(cache=True)
def transposed_rotation_derivative(p: np.ndarray, u: np.ndarray) -> np.ndarray:
    r""":math:`\partial(A(p)^Tu)/\partial p` (3 x 4): :math:`A(p)^T = A(p^*)` with :math:`p^* = (p_0, -\mathbf p)`,
    so Eq. (R3) at :math:`p^*`, its last three columns negated. Row ``c`` is also :math:`\partial(u\cdot A(p)e_c)/
    \partial p`."""
    conjugate = np.empty(4, dtype=p.dtype)
    conjugate[0] = p[0]
    conjugate[1:] = -p[1:]
    out = rotation_derivative(conjugate, u)
    out[:, 1:] *= -1.0
    return out
