r"""Numba kernels of a modally reduced FFRF body with Euler parameters.

Coordinates ``q = [R (3), p (4), zeta (m)]``, velocities ``qd = [Rd, pd, zetad]``. Every
kernel costs O(m^2) and is independent of the number of mesh nodes: it only sees the
*modal moments* of the consistent mass matrix (``docs/formulation.md``, Sect. "Modal
moments", Eq. (F4)), with the scalar nodal mass matrix M_s (``M = M_s kron I3``),
reference coordinates ``x^(a)`` and mode rows ``Psi^(a)`` of component ``a``:

=======  ==============================  =============
symbol   definition                      array
=======  ==============================  =============
m        1^T M_s 1                       ``mass``
S0_a     1^T M_s x^(a)                   ``s0[a]``
S1_a     1^T M_s Psi^(a)                 ``s1[a, :]``
X_ab     x^(a)T M_s x^(b)                ``x2[a, b]``
C_ab     Psi^(a)T M_s x^(b)              ``c[a, b, :]``
D_ab     Psi^(a)T M_s Psi^(b)            ``d[a, b, :, :]``
=======  ==============================  =============

The equations (Eqs. (F5)-(F10) of ``docs/formulation.md``) are cited at each kernel. All
arrays passed to one call must share one dtype: float64, or complex128 for the exact
complex-step derivatives that test the analytic tangents (:mod:`ffrf.body.body_tangents`) and give
:func:`ffrf.body.flexible_body.mass_matrix_rate`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ffrf.body.euler_parameters import g_bar, rotation_matrix
from ffrf.numerics.small_linalg import cross3, dot, mat_mat, mat_vec, skew, vec_mat

__all__ = [
    "second_moment",
    "inertia_about_origin",
    "rotation_mode_coupling",
    "mass_matrix",
    "quadratic_velocity",
    "gravity_force",
    "modal_products",
    "frame_terms",
]


@njit(cache=True)
def _levi_civita(a: int, b: int, c: int) -> float:
    return (a - b) * (b - c) * (c - a) / 2.0


@njit(cache=True)
def second_moment(zeta: np.ndarray, x2: np.ndarray, c: np.ndarray, d: np.ndarray) -> np.ndarray:
    r"""Eq. (F5): :math:`U_{ab} = \sum_{ij} m_{ij} u^a_i u^b_j
    = X_{ab} + \zeta\cdot(C_{ab} + C_{ba}) + \zeta^T D_{ab}\zeta`."""
    return _second_moment(zeta, x2, c, modal_products(d, zeta))


@njit(cache=True)
def modal_products(d: np.ndarray, v: np.ndarray) -> np.ndarray:
    r""":math:`D_{ab}v` for all components ``a, b`` (3, 3, m): computed once, shared by Eqs. (F5), (F9)."""
    out = np.empty((3, 3, v.shape[0]), dtype=v.dtype)
    for a in range(3):
        for b in range(3):
            out[a, b] = mat_vec(d[a, b], v)
    return out


@njit(cache=True)
def _second_moment(zeta, x2, c, d_zeta):
    """Eq. (F5) with ``d_zeta = modal_products(d, zeta)``."""
    out = np.empty((3, 3), dtype=zeta.dtype)
    for a in range(3):
        for b in range(3):
            out[a, b] = x2[a, b] + dot(zeta, c[a, b] + c[b, a]) + dot(zeta, d_zeta[a, b])
    return out


@njit(cache=True)
def inertia_about_origin(u: np.ndarray) -> np.ndarray:
    r"""Eq. (F6): inertia tensor of the deformed body about the frame origin, :math:`J = \mathrm{tr}(U)I - U`."""
    return np.trace(u) * np.eye(3) - u


@njit(cache=True)
def rotation_mode_coupling(zeta: np.ndarray, c: np.ndarray, d: np.ndarray) -> np.ndarray:
    r"""Eq. (F7): :math:`\sum_{ij} m_{ij}\tilde u_i\Psi_j`, column ``k`` component ``a`` equal to
    :math:`\epsilon_{abc}(C_{cb,k} + (\zeta^T D_{bc})_k)`."""
    m = zeta.shape[0]
    out = np.zeros((3, m), dtype=zeta.dtype)
    for a in range(3):
        for b in range(3):
            for cc in range(3):
                eps = _levi_civita(a, b, cc)
                if eps != 0.0:
                    out[a] += eps * (c[cc, b] + vec_mat(zeta, d[b, cc]))
    return out


@njit(cache=True)
def mass_matrix(
    p: np.ndarray,
    zeta: np.ndarray,
    mass: float,
    s0: np.ndarray,
    s1: np.ndarray,
    x2: np.ndarray,
    c: np.ndarray,
    d: np.ndarray,
    reduced_mass: np.ndarray,
) -> np.ndarray:
    r"""Eq. (F8): mass matrix in ``qd = [Rd, pd, zetad]``,

    .. math:: M = \begin{bmatrix} mI & -A\tilde s\bar G & A S_1\\ & \bar G^TJ\bar G & \bar G^T M_{\omega\zeta}\\
              \mathrm{sym.} & & \Psi^TM\Psi\end{bmatrix}, \qquad s = S_0 + S_1\zeta.
    """
    a_mat, g, s, d_zeta, j = _kinematics(p, zeta, s0, s1, x2, c, d)
    return _mass_matrix(zeta, mass, s1, c, d, reduced_mass, a_mat, g, s, j)


@njit(cache=True)
def _kinematics(p, zeta, s0, s1, x2, c, d):
    """What Eqs. (F8) and (F9) share: ``A``, ``G``, ``s``, the products ``D_ab zeta`` and ``J``."""
    d_zeta = modal_products(d, zeta)
    return (
        rotation_matrix(p),
        g_bar(p),
        s0 + mat_vec(s1, zeta),
        d_zeta,
        inertia_about_origin(_second_moment(zeta, x2, c, d_zeta)),
    )


@njit(cache=True)
def _mass_matrix(zeta, mass, s1, c, d, reduced_mass, a_mat, g, s, j):
    """Eq. (F8) from the pieces of :func:`_kinematics`."""
    m = zeta.shape[0]
    n = 7 + m
    out = np.zeros((n, n), dtype=zeta.dtype)
    for i in range(3):
        out[i, i] = mass
    m_rp = -mat_mat(mat_mat(a_mat, skew(s)), g)
    m_rz = mat_mat(a_mat, s1)
    m_pp = mat_mat(mat_mat(g.T, j), g)
    m_pz = mat_mat(g.T, rotation_mode_coupling(zeta, c, d))
    out[0:3, 3:7] = m_rp
    out[3:7, 0:3] = m_rp.T
    out[0:3, 7:] = m_rz
    out[7:, 0:3] = m_rz.T
    out[3:7, 3:7] = m_pp
    out[3:7, 7:] = m_pz
    out[7:, 3:7] = m_pz.T
    out[7:, 7:] = reduced_mass
    return out


@njit(cache=True)
def quadratic_velocity(
    p: np.ndarray,
    zeta: np.ndarray,
    pd: np.ndarray,
    zetad: np.ndarray,
    s0: np.ndarray,
    s1: np.ndarray,
    x2: np.ndarray,
    c: np.ndarray,
    d: np.ndarray,
) -> np.ndarray:
    r"""Eq. (F9): quadratic velocity vector (right-hand side), with :math:`\omega = \bar G\dot p`,

    .. math::
        Q_R &= -A(\tilde\omega\tilde\omega s + 2\tilde\omega S_1\dot\zeta),\\
        Q_p &= -\bar G^T\big(\tilde\omega J\omega + 2(\omega\,\mathrm{tr}N - N\omega)\big),
              \quad N_{ab} = \dot\zeta\cdot C_{ab} + \dot\zeta^TD_{ab}\zeta,\\
        Q_\zeta &= -\Big(\sum_{ab}\omega_a\omega_b E_{ab} - |\omega|^2\sum_a E_{aa}
              + 2\sum_{abc}\epsilon_{abc}\,\omega_b D_{ac}\dot\zeta\Big), \quad E_{ab} = C_{ab} + D_{ab}\zeta.
    """
    a_mat, g, s, d_zeta, j = _kinematics(p, zeta, s0, s1, x2, c, d)
    return _quadratic_velocity(pd, zetad, s1, c, d, a_mat, g, s, d_zeta, j)


@njit(cache=True)
def _quadratic_velocity(pd, zetad, s1, c, d, a_mat, g, s, d_zeta, j):
    """Eq. (F9) from the pieces of :func:`_kinematics`."""
    m = zetad.shape[0]
    out = np.zeros(7 + m, dtype=pd.dtype)
    omega = mat_vec(g, pd)
    w = skew(omega)
    out[0:3] = -mat_vec(a_mat, mat_vec(w, mat_vec(w, s)) + 2.0 * mat_vec(w, mat_vec(s1, zetad)))
    n_mat = np.empty((3, 3), dtype=pd.dtype)
    for a in range(3):
        for b in range(3):
            n_mat[a, b] = dot(zetad, c[a, b]) + dot(zetad, d_zeta[a, b])
    torque = mat_vec(w, mat_vec(j, omega)) + 2.0 * (omega * np.trace(n_mat) - mat_vec(n_mat, omega))
    out[3:7] = -vec_mat(torque, g)
    q_zeta = np.zeros(m, dtype=pd.dtype)
    omega2 = dot(omega, omega)
    for a in range(3):
        for b in range(3):
            e_ab = c[a, b] + d_zeta[a, b]
            q_zeta += omega[a] * omega[b] * e_ab
            if a == b:
                q_zeta -= omega2 * e_ab
            for cc in range(3):
                eps = _levi_civita(a, b, cc)
                if eps != 0.0:
                    q_zeta += 2.0 * eps * omega[b] * mat_vec(d[a, cc], zetad)
    out[7:] = -q_zeta
    return out


@njit(cache=True)
def gravity_force(
    p: np.ndarray,
    zeta: np.ndarray,
    gravity: np.ndarray,
    mass: float,
    s0: np.ndarray,
    s1: np.ndarray,
    exact: bool,
) -> np.ndarray:
    r"""Eq. (F10): generalized gravity force :math:`[m g;\ \bar G^T\tilde s A^Tg;\ S_1^TA^Tg]`.

    ``exact=False`` reproduces Exudyn's ``LoadMassProportional`` on ``ObjectFFRFreducedOrder``,
    which uses the undeformed first moment :math:`s = S_0` in the rotational row.
    """
    m = zeta.shape[0]
    out = np.zeros(7 + m, dtype=p.dtype)
    a_mat = rotation_matrix(p)
    local_g = vec_mat(gravity, a_mat)
    s = s0 + mat_vec(s1, zeta) if exact else s0 + 0.0 * mat_vec(s1, zeta)
    out[0:3] = mass * gravity
    out[3:7] = vec_mat(mat_vec(skew(s), local_g), g_bar(p))
    out[7:] = vec_mat(local_g, s1)
    return out


@njit(cache=True)
def frame_terms(q, qd, qdd, gravity, s0, s1, x2, c, d, exact_gravity):
    r"""The body-frame pieces of Eq. (F12), shared by the residual and its tangents (Eqs. (F13)-(F14)):
    ``A``, :math:`\bar G`, :math:`\omega = \bar G\dot p`, :math:`\alpha = \bar G\ddot p`, ``s``, ``s_g`` (``s``, or
    :math:`S_0` for Exudyn's gravity), :math:`w = S_1\dot\zeta`, the products :math:`D_{ab}\zeta`, ``J``,
    :math:`M_{\omega\zeta}`, :math:`A^T\ddot R`, :math:`A^Tg`, ``N`` of Eq. (F9), and

    .. math:: v_R = \alpha\times s + S_1\ddot\zeta + \omega\times(\omega\times s) + 2\omega\times w,\quad
              v_p = s\times A^T\ddot R + J\alpha + M_{\omega\zeta}\ddot\zeta + \omega\times J\omega
              + 2(\omega\,\mathrm{tr}N - N\omega) - s_g\times A^Tg,

    so that :math:`f_R = m(\ddot R - g) + Av_R` and :math:`f_p = \bar G^Tv_p`. One dtype throughout."""
    p, zeta, pd, zetad = q[3:7], q[7:], qd[3:7], qd[7:]
    a_mat, g = rotation_matrix(p), g_bar(p)
    omega, alpha = mat_vec(g, pd), mat_vec(g, qdd[3:7])
    s = s0 + mat_vec(s1, zeta)
    s_g = s if exact_gravity else s0 + 0.0 * s
    w = mat_vec(s1, zetad)
    d_zeta = modal_products(d, zeta)
    inertia = inertia_about_origin(_second_moment(zeta, x2, c, d_zeta))
    coupling = rotation_mode_coupling(zeta, c, d)
    r_local = vec_mat(qdd[0:3], a_mat)
    g_local = vec_mat(gravity, a_mat)
    n_mat = np.empty((3, 3), dtype=q.dtype)
    for a in range(3):
        for b in range(3):
            n_mat[a, b] = dot(zetad, c[a, b]) + dot(zetad, d_zeta[a, b])
    trace_n = n_mat[0, 0] + n_mat[1, 1] + n_mat[2, 2]
    v_r = cross3(alpha, s) + mat_vec(s1, qdd[7:]) + cross3(omega, cross3(omega, s)) + 2.0 * cross3(omega, w)
    v_p = (
        cross3(s, r_local)
        + mat_vec(inertia, alpha)
        + mat_vec(coupling, qdd[7:])
        + cross3(omega, mat_vec(inertia, omega))
        + 2.0 * (trace_n * omega - mat_vec(n_mat, omega))
        - cross3(s_g, g_local)
    )
    return a_mat, g, omega, alpha, s, s_g, w, d_zeta, inertia, coupling, r_local, g_local, n_mat, v_r, v_p
