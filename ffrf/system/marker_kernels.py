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

from ffrf.body.euler_parameters import rotation_derivative, rotation_matrix, transposed_rotation_derivative
from ffrf.numerics.small_linalg import cross3, dot, mat_mat, mat_vec, skew, vec_mat

__all__ = [
    "exp_so3_kernel",
    "exp_so3_tangent_kernel",
    "marker_frame",
    "marker_pose",
    "marker_frame_transpose",
    "exp_so3_hessian",
    "marker_frame_hessian",
]


@njit(cache=True)
def exp_so3_kernel(theta: np.ndarray) -> np.ndarray:
    """Rodrigues' formula, Eq. (K3) (Taylor series below ``|theta|^2 = 1e-8``)."""
    phi2 = dot(theta, theta)
    s = skew(theta)
    if abs(phi2) < 1e-8:
        a = 1.0 - phi2 / 6.0
        b = 0.5 - phi2 / 24.0
    else:
        phi = np.sqrt(phi2)
        a = np.sin(phi) / phi
        b = (1.0 - np.cos(phi)) / phi2
    return np.eye(3) + a * s + b * mat_mat(s, s)


@njit(cache=True)
def exp_so3_tangent_kernel(theta: np.ndarray) -> np.ndarray:
    """Right Jacobian T(theta) of the exponential map."""
    phi2 = dot(theta, theta)
    s = skew(theta)
    if abs(phi2) < 1e-8:
        a = 0.5 - phi2 / 24.0
        b = 1.0 / 6.0 - phi2 / 120.0
    else:
        phi = np.sqrt(phi2)
        a = (1.0 - np.cos(phi)) / phi2
        b = (phi - np.sin(phi)) / (phi2 * phi)
    return np.eye(3) - a * s + b * mat_mat(s, s)


@njit(cache=True)
def _marker_state(q, point, position_modes, rotation_modes):
    """Eqs. (K1)-(K3) pieces: ``A(p)``, ``theta``, local point, ``exp(theta~)`` and ``T(theta)``."""
    a_body = rotation_matrix(q[3:7])
    theta = np.zeros(3, dtype=q.dtype)
    local = point.copy()
    if q.shape[0] > 7:
        theta = mat_vec(rotation_modes, q[7:])
        local = point + mat_vec(position_modes, q[7:])
    return a_body, theta, local, exp_so3_kernel(theta), exp_so3_tangent_kernel(theta)


@njit(cache=True)
def marker_frame(q, point, position_modes, rotation_modes, rotation, offset):
    """Joint point ``p`` (3), axes (3x3, columns), ``dp/dq`` (3 x n) and ``d axes/dq`` (3, 3, n)."""
    n = q.shape[0]
    m = n - 7
    a_body, theta, local, turn, tangent = _marker_state(q, point, position_modes, rotation_modes)
    turned_offset = mat_vec(turn, offset)
    body_point = local + turned_offset
    position = q[:3] + mat_vec(a_body, body_point)
    axes_local = mat_mat(turn, rotation)
    axes = mat_mat(a_body, axes_local)
    a_turn = mat_mat(a_body, turn)
    d_position = np.zeros((3, n), dtype=q.dtype)
    d_axes = np.zeros((3, 3, n), dtype=q.dtype)
    for i in range(3):
        d_position[i, i] = 1.0
    d_position[:, 3:7] = rotation_derivative(q[3:7], body_point)
    if m > 0:
        d_position[:, 7:] = mat_mat(a_body, position_modes) - mat_mat(
            mat_mat(mat_mat(a_turn, skew(offset)), tangent), rotation_modes
        )
    for k in range(3):
        w = axes_local[:, k].copy()
        d_axes[k, :, 3:7] = rotation_derivative(q[3:7], w)
        if m > 0:
            d_axes[k, :, 7:] = -mat_mat(mat_mat(mat_mat(a_turn, skew(rotation[:, k])), tangent), rotation_modes)
    return position, axes, d_position, d_axes


# The residual's kernels below hold 3-vectors and 3 x 3 matrices (row-major) as tuples of floats: numba keeps them in
# registers, where small arrays would each be a heap allocation (bench/memory.py counts them per iteration).


@njit(cache=True, inline="always")
def _mv(a, v):
    """``a @ v`` for a 3 x 3 tuple and a 3-tuple."""
    return (
        a[0] * v[0] + a[1] * v[1] + a[2] * v[2],
        a[3] * v[0] + a[4] * v[1] + a[5] * v[2],
        a[6] * v[0] + a[7] * v[1] + a[8] * v[2],
    )


@njit(cache=True, inline="always")
def _mtv(a, v):
    """``a.T @ v`` for a 3 x 3 tuple and a 3-tuple."""
    return (
        a[0] * v[0] + a[3] * v[1] + a[6] * v[2],
        a[1] * v[0] + a[4] * v[1] + a[7] * v[2],
        a[2] * v[0] + a[5] * v[1] + a[8] * v[2],
    )


@njit(cache=True, inline="always")
def _cross(u, v):
    return (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])


@njit(cache=True, inline="always")
def _rotation_rows(p0, p1, p2, p3):
    """Eq. (R1) as a row-major 9-tuple."""
    return (
        p0 * p0 + p1 * p1 - p2 * p2 - p3 * p3,
        2.0 * (p1 * p2 - p0 * p3),
        2.0 * (p1 * p3 + p0 * p2),
        2.0 * (p1 * p2 + p0 * p3),
        p0 * p0 - p1 * p1 + p2 * p2 - p3 * p3,
        2.0 * (p2 * p3 - p0 * p1),
        2.0 * (p1 * p3 - p0 * p2),
        2.0 * (p2 * p3 + p0 * p1),
        p0 * p0 - p1 * p1 - p2 * p2 + p3 * p3,
    )


@njit(cache=True, inline="always")
def _so3_rows(t, a, b):
    """``I + a t~ + b t~ t~`` as a 9-tuple (``t~ t~ = t t^T - |t|^2 I``): Rodrigues' formula and its right Jacobian."""
    d = 1.0 - b * (t[0] * t[0] + t[1] * t[1] + t[2] * t[2])
    return (
        d + b * t[0] * t[0],
        -a * t[2] + b * t[0] * t[1],
        a * t[1] + b * t[0] * t[2],
        a * t[2] + b * t[1] * t[0],
        d + b * t[1] * t[1],
        -a * t[0] + b * t[1] * t[2],
        -a * t[1] + b * t[2] * t[0],
        a * t[0] + b * t[2] * t[1],
        d + b * t[2] * t[2],
    )


@njit(cache=True, inline="always")
def _exp_and_tangent(t):
    """``exp(t~)`` (Eq. (K3)) and its right Jacobian ``T(t)`` as 9-tuples, with the Taylor series of
    :func:`exp_so3_kernel` and :func:`exp_so3_tangent_kernel` below ``|t|^2 = 1e-8``."""
    phi2 = t[0] * t[0] + t[1] * t[1] + t[2] * t[2]
    if phi2 < 1e-8:
        a, b = 1.0 - phi2 / 6.0, 0.5 - phi2 / 24.0
        ta, tb = 0.5 - phi2 / 24.0, 1.0 / 6.0 - phi2 / 120.0
    else:
        phi = np.sqrt(phi2)
        sine, cosine = np.sin(phi), np.cos(phi)
        a, b = sine / phi, (1.0 - cosine) / phi2
        ta, tb = (1.0 - cosine) / phi2, (phi - sine) / (phi2 * phi)
    return _so3_rows(t, a, b), _so3_rows(t, -ta, tb)


@njit(cache=True, inline="always")
def _pose_pieces(q, point, position_modes, rotation_modes, offset):
    """``A``, ``exp(theta~)``, ``T(theta)`` (9-tuples) and the body-frame joint point ``x_bar + P zeta + E o``."""
    theta = (0.0, 0.0, 0.0)
    local = (point[0], point[1], point[2])
    if q.shape[0] > 7:
        t = [0.0, 0.0, 0.0]
        x = [point[0], point[1], point[2]]
        for i in range(3):
            for k in range(q.shape[0] - 7):
                t[i] += rotation_modes[i, k] * q[7 + k]
                x[i] += position_modes[i, k] * q[7 + k]
        theta = (t[0], t[1], t[2])
        local = (x[0], x[1], x[2])
    turn, tangent = _exp_and_tangent(theta)
    turned = _mv(turn, (offset[0], offset[1], offset[2]))
    body_point = (local[0] + turned[0], local[1] + turned[1], local[2] + turned[2])
    return _rotation_rows(q[3], q[4], q[5], q[6]), turn, tangent, body_point


@njit(cache=True)
def marker_pose(q, point, position_modes, rotation_modes, rotation, offset):
    """Joint point ``p`` (3) and axes (3x3, columns) of :func:`marker_frame`, without their derivatives (float64)."""
    a_body, turn, _, body_point = _pose_pieces(q, point, position_modes, rotation_modes, offset)
    position = np.empty(3)
    moved = _mv(a_body, body_point)
    for i in range(3):
        position[i] = q[i] + moved[i]
    axes = np.empty((3, 3))
    for k in range(3):
        axis = _mv(a_body, _mv(turn, (rotation[0, k], rotation[1, k], rotation[2, k])))
        for i in range(3):
            axes[i, k] = axis[i]
    return position, axes


@njit(cache=True, inline="always")
def _add_rotation_gradient(out, p, u, w):
    r"""Adds :math:`\partial(w\cdot A(p)u)/\partial p = (\partial(Au)/\partial p)^Tw` (Eq. (R3) transposed) to
    ``out[3:7]`` (``u``, ``w`` 3-tuples): from :math:`w\cdot Au = p_0^2\,w\cdot u + 2p_0\,\mathbf p\cdot(u\times w)
    + \mathbf p^T(wu^T + uw^T - (w\cdot u)I)\mathbf p`."""
    wu = w[0] * u[0] + w[1] * u[1] + w[2] * u[2]
    pu = p[1] * u[0] + p[2] * u[1] + p[3] * u[2]
    pw = p[1] * w[0] + p[2] * w[1] + p[3] * w[2]
    cross = _cross(u, w)
    out[3] += 2.0 * (p[0] * wu + p[1] * cross[0] + p[2] * cross[1] + p[3] * cross[2])
    for i in range(3):
        out[4 + i] += 2.0 * (p[0] * cross[i] + w[i] * pu + u[i] * pw - wu * p[1 + i])


@njit(cache=True)
def marker_frame_transpose(q, point, position_modes, rotation_modes, rotation, offset, weight_point, weight_axes):
    r"""The generalized force :math:`(\partial p/\partial q)^Tw + \sum_k(\partial a_k/\partial q)^TW_{:k}` (n) of a
    force ``w`` at the joint point and weights ``W`` on its axes (column ``k`` on axis ``k``), Eqs. (K1)-(K3)
    transposed without forming the derivatives of :func:`marker_frame` (float64; Eq. (FP7)):

    .. math:: [\,w;\ (\partial(Au)/\partial p_E)^Tw + \textstyle\sum_k(\partial(Aw_k)/\partial p_E)^TW_{:k};\
              P^TA^Tw + \Theta^TT^T(o\times E^TA^Tw + \textstyle\sum_k Re_k\times E^TA^TW_{:k})\,]

    (from :math:`\tilde a^T = -\tilde a`). What the residual needs of a joint: :math:`C_q^T\lambda` as weights."""
    n = q.shape[0]
    a_body, turn, tangent, body_point = _pose_pieces(q, point, position_modes, rotation_modes, offset)
    out = np.zeros(n)
    w = (weight_point[0], weight_point[1], weight_point[2])
    for i in range(3):
        out[i] = w[i]
    p = q[3:7]
    _add_rotation_gradient(out, p, body_point, w)
    bracket = (0.0, 0.0, 0.0)
    for k in range(3):
        column = (rotation[0, k], rotation[1, k], rotation[2, k])
        w_k = (weight_axes[0, k], weight_axes[1, k], weight_axes[2, k])
        _add_rotation_gradient(out, p, _mv(turn, column), w_k)
        turned = _cross(column, _mtv(turn, _mtv(a_body, w_k)))
        bracket = (bracket[0] + turned[0], bracket[1] + turned[1], bracket[2] + turned[2])
    if n > 7:
        a_w = _mtv(a_body, w)  # A^T w
        turned = _cross((offset[0], offset[1], offset[2]), _mtv(turn, a_w))
        bracket = (bracket[0] + turned[0], bracket[1] + turned[1], bracket[2] + turned[2])
        t_bracket = _mtv(tangent, bracket)
        for k in range(n - 7):
            total = 0.0
            for i in range(3):
                total += position_modes[i, k] * a_w[i] + rotation_modes[i, k] * t_bracket[i]
            out[7 + k] = total
    return out


@njit(cache=True)
def _exp_so3_coefficients(c: float):
    r"""Eq. (FP1): :math:`a(c) = \sin\phi/\phi` and :math:`b(c) = (1-\cos\phi)/\phi^2` of :math:`c = \phi^2`,
    with their first and second derivatives in ``c``: power series below c = 1, where the closed
    forms cancel (the one of b'' loses 1e-10 at c = 0.1); 13 terms leave < 1e-19 there."""
    if c < 1.0:
        a = a1 = a2 = b = b1 = b2 = 0.0
        fa, fb = 1.0, 2.0  # (2k+1)! and (2k+2)!
        c_k2, c_k1, c_k = 0.0, 0.0, 1.0  # c^(k-2), c^(k-1), c^k (running products: no pow calls in the hot loop)
        for k in range(13):
            sign = -1.0 if k % 2 else 1.0
            a += sign * c_k / fa
            b += sign * c_k / fb
            a1 += sign * k * c_k1 / fa
            b1 += sign * k * c_k1 / fb
            a2 += sign * k * (k - 1) * c_k2 / fa
            b2 += sign * k * (k - 1) * c_k2 / fb
            fa *= (2 * k + 2) * (2 * k + 3)
            fb *= (2 * k + 3) * (2 * k + 4)
            c_k2, c_k1, c_k = c_k1, c_k, c_k * c
        return a, a1, a2, b, b1, b2
    phi = np.sqrt(c)
    s, co = np.sin(phi), np.cos(phi)
    a = s / phi
    a1 = (phi * co - s) / (2.0 * phi**3)
    a2 = -s / (4.0 * phi**3) - 3.0 * (phi * co - s) / (4.0 * phi**5)
    b = (1.0 - co) / c
    b1 = s / (2.0 * phi**3) - (1.0 - co) / phi**4
    b2 = co / (4.0 * phi**4) - 5.0 * s / (4.0 * phi**5) + 2.0 * (1.0 - co) / phi**6
    return a, a1, a2, b, b1, b2


@njit(cache=True)
def exp_so3_hessian(theta: np.ndarray, v: np.ndarray, z: np.ndarray) -> np.ndarray:
    r"""Eq. (FP2): :math:`\partial^2 (z\cdot\exp(\tilde\theta)v)/\partial\theta^2` (3x3, float64), from
    :math:`\exp(\tilde\theta)v = v + a\,\theta\times v + b\,((\theta\cdot v)\theta - c\,v)`,
    :math:`c = \theta\cdot\theta`."""
    return _exp_so3_hessian(_exp_so3_coefficients(dot(theta, theta)), theta, v, z)


@njit(cache=True, inline="always")
def _exp_so3_hessian(coefficients, theta, v, z):
    """:func:`exp_so3_hessian` with the coefficients of :func:`_exp_so3_coefficients` at ``theta``, which depend on
    ``theta`` only: a marker's four Hessians share them."""
    c = dot(theta, theta)
    a, a1, a2, b, b1, b2 = coefficients
    zv, tv, tz = dot(z, v), dot(theta, v), dot(theta, z)
    g1 = cross3(v, z)
    s1 = dot(theta, g1)  # z . (theta x v)
    s2 = tv * tz - c * zv
    g2 = v * tz + z * tv - 2.0 * zv * theta
    curvature = 4.0 * a2 * s1 + 4.0 * b2 * s2
    diagonal = 2.0 * a1 * s1 + 2.0 * b1 * s2 - 2.0 * b * zv
    out = np.empty((3, 3))
    for i in range(3):  # the outer products as loops: numba's np.outer costs more than this arithmetic
        for j in range(3):
            out[i, j] = (
                curvature * theta[i] * theta[j]
                + 2.0 * a1 * (theta[i] * g1[j] + g1[i] * theta[j])
                + 2.0 * b1 * (theta[i] * g2[j] + g2[i] * theta[j])
                + b * (v[i] * z[j] + z[i] * v[j])
            )
        out[i, i] += diagonal
    return out


@njit(cache=True, inline="always")
def _add_rotation_hessian(out, u, w):
    r"""Adds the p-Hessian of :math:`w\cdot A(p)u` (constant: Eq. (R1) is quadratic in ``p``) to ``out[3:7, 3:7]``:
    :math:`w\cdot Au = p_0^2\,w\cdot u + 2p_0\,\mathbf p\cdot(u\times w)
    + \mathbf p^T(wu^T + uw^T - (w\cdot u)I)\mathbf p`, so twice
    :math:`[[w\cdot u, (u\times w)^T], [u\times w, wu^T + uw^T - (w\cdot u)I]]`."""
    wu = dot(w, u)
    out[3, 3] += 2.0 * wu
    for i in range(3):
        j1, j2 = (i + 1) % 3, (i + 2) % 3
        cross = u[j1] * w[j2] - u[j2] * w[j1]  # (u x w)_i
        out[3, 4 + i] += 2.0 * cross
        out[4 + i, 3] += 2.0 * cross
        for j in range(3):
            out[4 + i, 4 + j] += 2.0 * (w[i] * u[j] + u[i] * w[j])
        out[4 + i, 4 + i] -= 2.0 * wu


@njit(cache=True)
def marker_frame_hessian(q, point, position_modes, rotation_modes, rotation, offset, weight_point, weight_axes):
    r"""Eq. (FP3): :math:`\sum_c w_c\,\partial^2 p_c/\partial q^2
    + \sum_k\sum_c W_{ck}\,\partial^2 a_{k,c}/\partial q^2`
    (n x n, float64) for the joint point ``p`` and axes ``a_k`` of :func:`marker_frame`; ``weight_point``
    is ``w`` (3), column ``k`` of ``weight_axes`` weighs axis ``k``."""
    n = q.shape[0]
    m = n - 7
    pe = q[3:7]
    a_body, theta, local, turn, tangent = _marker_state(q, point, position_modes, rotation_modes)
    out = np.zeros((n, n))
    coefficients = _exp_so3_coefficients(dot(theta, theta))
    # Every term is linear in the weights: the p-zeta blocks sum to mixed_left T Theta + D_point P, the zeta-zeta
    # block to Theta^T (sum of (FP2)) Theta, so the products with the modes are formed once, not once per vector.
    mixed_left = np.zeros((4, 3))
    d_point = np.zeros((4, 3))
    curvature = np.zeros((3, 3))
    for v in range(4):
        if v == 0:  # the joint point: u = x_bar + P zeta + E o
            w, direction = weight_point, offset
            u = local + mat_vec(turn, offset)
        else:  # axis k = v - 1: u = E R e_k
            w, direction = weight_axes[:, v - 1].copy(), rotation[:, v - 1].copy()
            u = mat_vec(turn, direction)
        _add_rotation_hessian(out, u, w)
        if m == 0:
            continue
        # (R3) is linear in u: column c of d_w is d(w . A e_c)/dp_E, and du/dzeta = -E direction~ T Theta (+ P).
        d_w = transposed_rotation_derivative(pe, w).T
        mixed_left -= mat_mat(d_w, mat_mat(turn, skew(direction)))
        if v == 0:
            d_point = d_w
        curvature += _exp_so3_hessian(coefficients, theta, direction, vec_mat(w, a_body))
    if m > 0:
        mixed = mat_mat(mixed_left, mat_mat(tangent, rotation_modes)) + mat_mat(d_point, position_modes)
        out[3:7, 7:] += mixed
        out[7:, 3:7] += mixed.T
        out[7:, 7:] += mat_mat(rotation_modes.T, mat_mat(curvature, rotation_modes))
    return out
