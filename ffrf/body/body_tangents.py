r"""Exact tangents of a reduced FFRF body's residual, analytic (``docs/formulation.md``, Eqs. (F12)-(F14)).

The residual of Eqs. (F8)-(F11), :math:`f = M(q)\ddot q - Q_v - Q_g + [0; 0; K_r\zeta + D_r\dot\zeta]`, written
with body-frame vectors (:math:`\omega = \bar G\dot p`, :math:`\alpha = \bar G\ddot p`, :math:`s = S_0 + S_1\zeta`):

.. math::
    f_R = m(\ddot R - g) + A v_R,\qquad f_p = \bar G^T v_p,\qquad f_\zeta = \dots\ \text{(Eq. (F12))}

Each block is differentiated by the chain rule through :math:`\omega, \alpha` (linear in ``p``:
:math:`\partial\omega/\partial p = -\bar G(\dot p)`), ``A`` (Eq. (R3)), :math:`\bar G^T v` (linear in ``p``),
``s``, ``J`` (Eqs. (F5)-(F6)), :math:`M_{\omega\zeta}` (Eq. (F7)) and ``N``, ``E`` of Eq. (F9). The
tangents include every term, :math:`\partial(M(q)\ddot q)/\partial q` too, so Newton converges quadratically.
Float64 only: one compiled type, no complex-step copies of the body kernels. Tested against complex-step
derivatives of :func:`ffrf.body.flexible_body.body_residual` in ``tests/test_ffrf_body/test_body_tangents.py``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ffrf.body.body_kernels import _levi_civita, frame_terms, modal_products
from ffrf.body.euler_parameters import g_bar, rotation_derivative, transposed_rotation_derivative
from ffrf.numerics.small_linalg import cross3, dot, mat_mat, mat_vec, skew, vec_mat

__all__ = ["body_tangents"]


@njit(cache=True, inline="always")
def _transposed_products(d: np.ndarray, v: np.ndarray) -> np.ndarray:
    r""":math:`D_{ab}^Tv` for all components ``a, b`` (3, 3, m)."""
    out = np.empty((3, 3, v.shape[0]))
    for a in range(3):
        for b in range(3):
            out[a, b] = vec_mat(v, d[a, b])
    return out


@njit(cache=True, inline="always")
def _g_transpose_derivative(v: np.ndarray) -> np.ndarray:
    r""":math:`\partial(\bar G(p)^Tv)/\partial p` (4 x 4): constant, as :math:`\bar G` is linear in ``p``
    (Eq. (R2))."""
    out = np.empty((4, 4))
    unit = np.zeros(4)
    for k in range(4):
        unit[:] = 0.0
        unit[k] = 1.0
        out[:, k] = vec_mat(v, g_bar(unit))
    return out


@njit(cache=True)
def body_tangents(q, qd, qdd, gravity, mass, s0, s1, x2, c, d, mred, kred, dred, exact_gravity, velocity):
    r"""Eqs. (F13)-(F14): exact ``(df/dq, df/dqd)`` of :func:`ffrf.body.flexible_body.body_residual`, each
    ``(7+m, 7+m)``; ``velocity=False`` leaves ``df/dqd`` zero (statics does not use it). The columns of ``R`` and
    ``Rd`` are zero: the residual depends on neither."""
    n = q.shape[0]
    m = n - 7
    jac_q = np.zeros((n, n))
    jac_qd = np.zeros((n, n))
    p, zeta, pd, zetad = q[3:7], q[7:], qd[3:7], qd[7:]
    rdd, pdd, zetadd = qdd[0:3], qdd[3:7], qdd[7:]
    a_mat, g, omega, alpha, s, s_g, w, d_zeta, inertia, coupling, r_local, g_local, n_mat, v_r, v_p = frame_terms(
        q, qd, qdd, gravity, s0, s1, x2, c, d, exact_gravity
    )
    d_omega = -g_bar(pd)  # d omega / dp, from G(p) pd = -G(pd) p
    d_alpha = -g_bar(pdd)
    dt_zeta = _transposed_products(d, zeta)  # D_ab^T zeta
    dt_zetad = _transposed_products(d, zetad)
    d_zetadd = modal_products(d, zetadd)
    dr_local = transposed_rotation_derivative(p, rdd)
    dg_local = transposed_rotation_derivative(p, gravity)
    trace_n = n_mat[0, 0] + n_mat[1, 1] + n_mat[2, 2]
    omega_t, s_t, w_t = skew(omega), skew(s), skew(w)

    # (F13), rows R: f_R = m (Rdd - g) + A v_R, v_R = alpha x s + S1 zetadd + omega x (omega x s) + 2 omega x w
    dv_r_omega = -skew(cross3(omega, s)) - mat_mat(omega_t, s_t) - 2.0 * w_t
    dv_r_p = mat_mat(dv_r_omega, d_omega) - mat_mat(s_t, d_alpha)  # d(alpha x s)/d alpha = -s~
    jac_q[0:3, 3:7] = rotation_derivative(p, v_r) + mat_mat(a_mat, dv_r_p)
    jac_q[0:3, 7:] = mat_mat(a_mat, mat_mat(skew(alpha) + mat_mat(omega_t, omega_t), s1))

    # (F13), rows p: f_p = G^T v_p, v_p = s x A^T Rdd + J alpha + M_wz zetadd + omega x J omega
    #                                     + 2 (omega tr N - N omega) - s_g x A^T g
    j_omega = mat_vec(inertia, omega)
    dv_p_omega = -skew(j_omega) + mat_mat(omega_t, inertia) + 2.0 * (trace_n * np.eye(3) - n_mat)
    dv_p_p = (
        mat_mat(s_t, dr_local) + mat_mat(inertia, d_alpha) + mat_mat(dv_p_omega, d_omega) - mat_mat(skew(s_g), dg_local)
    )
    jac_q[3:7, 3:7] = _g_transpose_derivative(v_p) + mat_mat(g.T, dv_p_p)
    dv_p_zeta = mat_mat(skew(g_local) if exact_gravity else np.zeros((3, 3)), s1) - mat_mat(skew(r_local), s1)
    dj = np.empty((3, 3))  # dJ/dzeta_j, Eqs. (F5)-(F6); the loops below reuse it and allocate nothing
    dj_omega = np.empty(3)
    for j in range(m):
        trace_du = 2.0 * (c[0, 0, j] + c[1, 1, j] + c[2, 2, j])
        for a in range(3):
            trace_du += d_zeta[a, a, j] + dt_zeta[a, a, j]
        trace_dn = dt_zetad[0, 0, j] + dt_zetad[1, 1, j] + dt_zetad[2, 2, j]
        for a in range(3):
            for b in range(3):
                dj[a, b] = -(c[a, b, j] + c[b, a, j] + d_zeta[a, b, j] + dt_zeta[a, b, j])
            dj[a, a] += trace_du
        for a in range(3):
            dj_omega[a] = dj[a, 0] * omega[0] + dj[a, 1] * omega[1] + dj[a, 2] * omega[2]
        for a in range(3):
            a1, a2 = (a + 1) % 3, (a + 2) % 3
            value = dj[a, 0] * alpha[0] + dj[a, 1] * alpha[1] + dj[a, 2] * alpha[2]
            value += omega[a1] * dj_omega[a2] - omega[a2] * dj_omega[a1]  # omega x dJ omega
            value += 2.0 * trace_dn * omega[a]  # 2 (omega tr dN - dN omega), dN_ab = (D_ab^T zetad)_j
            for b in range(3):
                value -= 2.0 * dt_zetad[a, b, j] * omega[b]
            value += d_zetadd[a1, a2, j] - d_zetadd[a2, a1, j]  # d(M_wz zetadd)/dzeta_j, Eq. (F7)
            dv_p_zeta[a, j] += value
    jac_q[3:7, 7:] = mat_mat(g.T, dv_p_zeta)

    # (F13), rows zeta: f_zeta = S1^T A^T (Rdd - g) + M_wz^T alpha + Mred zetadd + K zeta + D zetad
    #                            + sum_ab omega_a omega_b E_ab - |omega|^2 sum_a E_aa + 2 sum eps_abc omega_b D_ac zetad
    e_sum = np.zeros(m)
    for a in range(3):
        e_sum += c[a, a] + d_zeta[a, a]
    df_omega = np.zeros((m, 3))  # d f_zeta / d omega
    for k in range(3):
        column = -2.0 * omega[k] * e_sum
        for b in range(3):
            column += omega[b] * (c[k, b] + d_zeta[k, b] + c[b, k] + d_zeta[b, k])
        for a in range(3):
            for cc in range(3):
                eps = _levi_civita(a, k, cc)
                if eps != 0.0:
                    column += 2.0 * eps * mat_vec(d[a, cc], zetad)
        df_omega[:, k] = column
    jac_q[7:, 3:7] = mat_mat(s1.T, dr_local - dg_local) + mat_mat(coupling.T, d_alpha) + mat_mat(df_omega, d_omega)
    omega2 = dot(omega, omega)
    for i in range(m):
        for k in range(m):
            total = kred[i, k]
            for a in range(3):
                a1, a2 = (a + 1) % 3, (a + 2) % 3
                total += alpha[a] * (d[a1, a2, k, i] - d[a2, a1, k, i])  # sum_bc eps_abc D_bc^T
                for b in range(3):
                    total += (omega[a] * omega[b] - (omega2 if a == b else 0.0)) * d[a, b, i, k]
            jac_q[7 + i, 7 + k] = total

    if velocity:  # (F14): d f / d qd, through omega (pd) and N, w, the damping (zetad)
        jac_qd[0:3, 3:7] = mat_mat(a_mat, mat_mat(dv_r_omega, g))
        jac_qd[0:3, 7:] = 2.0 * mat_mat(a_mat, mat_mat(omega_t, s1))
        jac_qd[3:7, 3:7] = mat_mat(g.T, mat_mat(dv_p_omega, g))
        dv_p_zetad = np.empty((3, m))
        for j in range(m):  # dN/dzetad_j = (E_ab)_j = C_ab,j + (D_ab zeta)_j
            trace_e = 0.0
            for a in range(3):
                trace_e += c[a, a, j] + d_zeta[a, a, j]
            for a in range(3):
                value = trace_e * omega[a]
                for b in range(3):
                    value -= (c[a, b, j] + d_zeta[a, b, j]) * omega[b]
                dv_p_zetad[a, j] = 2.0 * value
        jac_qd[3:7, 7:] = mat_mat(g.T, dv_p_zetad)
        jac_qd[7:, 3:7] = mat_mat(df_omega, g)
        for i in range(m):
            for k in range(m):
                total = dred[i, k]
                for b in range(3):  # 2 sum_ac eps_abc omega_b D_ac: (a, c) = (b+2, b+1) with +1, (b+1, b+2) with -1
                    b1, b2 = (b + 1) % 3, (b + 2) % 3
                    total += 2.0 * omega[b] * (d[b2, b1, i, k] - d[b1, b2, i, k])
                jac_qd[7 + i, 7 + k] = total
    return jac_q, jac_qd
