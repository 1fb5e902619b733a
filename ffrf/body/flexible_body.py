r"""A modally reduced flexible body in the floating frame of reference (FFRF).

Its residual (``docs/formulation.md``, Eqs. (F8)-(F11))

.. math:: f(q, \dot q, \ddot q) = M(q)\ddot q - Q_v(q, \dot q) - Q_g(q) + K_r\zeta + D_r\dot\zeta

and its exact Jacobians :math:`\partial f/\partial q` and :math:`\partial f/\partial\dot q`, analytic
(:func:`ffrf.body.body_tangents.body_tangents`, Eqs. (F12)-(F14)). They include the terms Exudyn's solver leaves
out, such as :math:`\partial(M(q)\ddot q)/\partial q`, so Newton converges quadratically.
:func:`body_residual` takes one dtype throughout, complex128 too: its complex-step derivatives (Squire and Trapp
1998; every term of ``f`` is a polynomial in ``(p, zeta, pd, zetad)``, so
:math:`\partial f/\partial q_k = \mathrm{Im}\,f(q + ih e_k)/h` to round-off) are the tests' truth for the tangents.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

from ffrf.body.body_kernels import (
    _levi_civita,
    frame_terms,
    inertia_about_origin,
    mass_matrix,
    rotation_mode_coupling,
    second_moment,
)
from ffrf.body.body_tangents import body_tangents
from ffrf.body.euler_parameters import g_bar, rotation_derivative, rotation_matrix
from ffrf.body.modal_moments import ModalMoments
from ffrf.numerics.small_linalg import dot, mat_vec, vec_mat

__all__ = [
    "FlexibleBody",
    "node_positions",
    "body_residual",
    "kinetic_energy_gradient",
    "mass_matrix_rate",
]

_COMPLEX_STEP = 1e-30  # any tiny step: complex-step derivatives have no cancellation error


#: The body's constant arrays, in the order the kernels take them:
#: (s0, s1, x2, c, d, reduced mass, reduced stiffness, reduced damping).
_Packed = tuple[NDArray, NDArray, NDArray, NDArray, NDArray, NDArray, NDArray, NDArray]


@dataclass(frozen=True, eq=False)
class FlexibleBody:
    """Constant data of one reduced FFRF body (SI units).

    ``moments`` are the modal moments of the consistent mass matrix, ``stiffness`` and
    ``damping`` the reduced ``K_r`` and ``D_r`` (m x m). ``exact_gravity=False`` reproduces
    Exudyn's simplified gravity load (Eq. (F10)).
    """

    name: str
    moments: ModalMoments
    stiffness: NDArray[np.float64]
    damping: NDArray[np.float64]
    exact_gravity: bool = True
    _packed: _Packed = field(init=False, repr=False)
    _packed_complex: _Packed = field(init=False, repr=False)

    def __post_init__(self):
        m = self.moments.n_modes
        for label, matrix in (("stiffness", self.stiffness), ("damping", self.damping)):
            if np.shape(matrix) != (m, m):
                raise ValueError(
                    f"body {self.name!r}: reduced {label} has shape {np.shape(matrix)}, expected ({m}, {m})"
                )
            if not np.all(np.isfinite(matrix)):
                raise ValueError(f"body {self.name!r}: reduced {label} contains NaN or inf")
        mm = self.moments
        arrays = (mm.s0, mm.s1, mm.x2, mm.c, mm.d, mm.reduced_mass, self.stiffness, self.damping)
        packed = tuple(np.ascontiguousarray(a, dtype=np.float64) for a in arrays)
        object.__setattr__(self, "_packed", packed)
        object.__setattr__(self, "_packed_complex", tuple(a.astype(np.complex128) for a in packed))

    @property
    def n_modes(self) -> int:
        return self.moments.n_modes

    def scaled(self, stiffness: float = 1.0, density: float = 1.0) -> FlexibleBody:
        """The same body of a material ``stiffness`` times as stiff (``K_r`` and ``D_r``) and ``density`` times as
        dense (every modal moment): its modes are unchanged, as scaling ``K`` or ``M`` leaves the eigenvectors of the
        pair ``(K, M)`` and the Craig-Bampton basis alone."""
        m = self.moments
        moments = ModalMoments(
            density * m.mass, density * m.s0, density * m.s1, density * m.x2, density * m.c, density * m.d
        )
        return FlexibleBody(
            self.name, moments, stiffness * self.stiffness, stiffness * self.damping, self.exact_gravity
        )

    @property
    def n_coordinates(self) -> int:
        """7 + m: position (3), Euler parameters (4), modal coordinates (m)."""
        return 7 + self.moments.n_modes

    def residual(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike, gravity: ArrayLike) -> NDArray[np.float64]:
        return body_residual(*_floats(q, qd, qdd, gravity), self.moments.mass, *self._packed, self.exact_gravity)

    def jacobians(self, q, qd, qdd, gravity) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Exact ``(df/dq, df/dqd)``, each ``(7+m, 7+m)`` (Eqs. (F13)-(F14))."""
        return body_tangents(*_floats(q, qd, qdd, gravity), self.moments.mass, *self._packed, self.exact_gravity, True)

    def mass_matrix(self, q: ArrayLike) -> NDArray[np.float64]:
        q = np.asarray(q, float)
        s0, s1, x2, c, d, mred, _, _ = self._packed
        return mass_matrix(q[3:7], q[7:], self.moments.mass, s0, s1, x2, c, d, mred)

    def kinetic_energy(self, q: ArrayLike, qd: ArrayLike) -> float:
        qd = np.asarray(qd, float)
        return 0.5 * float(qd @ self.mass_matrix(q) @ qd)

    def kinetic_energy_gradient(self, q: ArrayLike, qd: ArrayLike) -> NDArray[np.float64]:
        r""":math:`\partial T/\partial q` at fixed velocities (Eq. (V6))."""
        return kinetic_energy_gradient(
            np.asarray(q, float), np.asarray(qd, float), self.moments.mass, *self._packed[:6]
        )

    def mass_matrix_rate(self, q: ArrayLike, qd: ArrayLike) -> NDArray[np.float64]:
        r""":math:`\dot M = \sum_k (\partial M/\partial q_k)\dot q_k` (Eq. (V5)), exact by complex step."""
        return mass_matrix_rate(
            np.asarray(q, float), np.asarray(qd, float), self.moments.mass, *self._packed_complex[:6]
        )

    def strain_energy(self, q: ArrayLike) -> float:
        zeta = np.asarray(q, float)[7:]
        return 0.5 * float(zeta @ self.stiffness @ zeta)

    def potential_energy(self, q: ArrayLike, gravity: ArrayLike) -> float:
        """Gravity potential -g . (m R + A s), Eq. (F10) (exact first moment)."""
        q = np.asarray(q, float)
        mm = self.moments
        s = mm.s0 + mm.s1 @ q[7:]
        return -float(np.asarray(gravity, float) @ (mm.mass * q[:3] + rotation_matrix(q[3:7]) @ s))


def _floats(
    q: ArrayLike, qd: ArrayLike, qdd: ArrayLike, gravity: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The state and gravity as float64 arrays, the dtype the body kernels are compiled for (a
    fixed-length tuple: type checkers match a star-unpacked tuple against the kernel's parameters)."""
    return np.asarray(q, float), np.asarray(qd, float), np.asarray(qdd, float), np.asarray(gravity, float)


def node_positions(q: ArrayLike, nodes: ArrayLike, basis: ArrayLike, indices: ArrayLike) -> NDArray[np.float64]:
    r"""World positions of the mesh nodes ``indices`` of one body (``docs/formulation.md``, Eq. (F1)):

    .. math:: r_i = R + A(\theta)\,(x_i + \Psi_i \zeta),

    ``q``: the body's coordinate block ``[R, theta (Euler parameters), zeta]``, or rows of blocks;
    ``nodes``: (N, 3) undeformed positions x; ``basis``: (3N, m) mode basis Psi. Returns
    (len(indices), 3), or (rows, len(indices), 3) for rows of blocks."""
    q = np.asarray(q, dtype=float)
    rows = np.atleast_2d(q)
    indices = np.asarray(indices, dtype=np.int64)
    basis = np.asarray(basis, dtype=float)
    local = np.asarray(nodes, dtype=float)[indices]  # (k, 3)
    psi = basis.reshape(-1, 3, basis.shape[1])[indices]  # (k, 3, m): the 3 rows of each node
    out = np.empty((rows.shape[0], indices.size, 3))
    for r, block in enumerate(rows):
        deformed = local + psi @ block[7:]
        out[r] = block[:3] + deformed @ rotation_matrix(block[3:7]).T
    return out if q.ndim == 2 else out[0]


@njit(cache=True)
def body_residual(q, qd, qdd, gravity, mass, s0, s1, x2, c, d, mred, kred, dred, exact_gravity):
    r"""Eqs. (F8)-(F11), ``M(q) qdd - Q_v - Q_g + K_r zeta + D_r zetad``, in the form of Eq. (F12) (no mass matrix
    formed): :math:`f_R = m(\ddot R - g) + Av_R`, :math:`f_p = \bar G^Tv_p` with the vectors of
    :func:`ffrf.body.body_kernels.frame_terms`, and

    .. math:: f_\zeta = S_1^TA^T(\ddot R - g) + M_{\omega\zeta}^T\alpha + M_{red}\ddot\zeta + K_r\zeta
              + D_r\dot\zeta + \sum_{ab}\omega_a\omega_bE_{ab} - |\omega|^2\sum_aE_{aa}
              + 2\sum_{abc}\epsilon_{abc}\omega_bD_{ac}\dot\zeta.

    One dtype throughout (complex128 for the complex-step derivatives that test the tangents)."""
    zeta, zetad, zetadd = q[7:], qd[7:], qdd[7:]
    a_mat, g, omega, alpha, _, _, _, d_zeta, _, coupling, r_local, g_local, _, v_r, v_p = frame_terms(
        q, qd, qdd, gravity, s0, s1, x2, c, d, exact_gravity
    )
    out = np.empty(q.shape[0], dtype=q.dtype)
    out[0:3] = mass * (qdd[0:3] - gravity) + mat_vec(a_mat, v_r)
    out[3:7] = vec_mat(v_p, g)
    f_zeta = vec_mat(r_local - g_local, s1) + vec_mat(alpha, coupling)
    f_zeta += mat_vec(mred, zetadd) + mat_vec(kred, zeta) + mat_vec(dred, zetad)
    omega2 = dot(omega, omega)
    for a in range(3):
        a1, a2 = (a + 1) % 3, (a + 2) % 3
        for b in range(3):
            weight = omega[a] * omega[b] - (omega2 if a == b else 0.0)
            f_zeta += weight * (c[a, b] + d_zeta[a, b])
        # 2 sum_bc eps_abc omega_b D_ac zetad: (b, c) = (a+1, a+2) with +1, (a+2, a+1) with -1
        f_zeta += 2.0 * (omega[a1] * mat_vec(d[a, a2], zetad) - omega[a2] * mat_vec(d[a, a1], zetad))
    out[7:] = f_zeta
    return out


@njit(cache=True)
def _kinetic_terms(q, qd, s0, s1, x2, c, d):
    """What Eqs. (V6) and (F8) as a scalar share: ``omega_bar = G(p) pd``, the first moment
    ``s``, its body-frame rate ``w = omega_bar x s + S1 zetad`` and the inertia ``J`` (Eq. (F6))."""
    zeta = q[7:]
    omega = g_bar(q[3:7]) @ qd[3:7]
    s = s0 + s1 @ zeta
    return omega, s, np.cross(omega, s) + s1 @ qd[7:], inertia_about_origin(second_moment(zeta, x2, c, d))


@njit(cache=True)
def kinetic_energy_of(q, qd, mass, s0, s1, x2, c, d, mred):
    r"""Eq. (F8) as a scalar without forming ``M``: with :math:`\bar\omega = \bar G\dot p` and
    :math:`w = \bar\omega\times s + S_1\dot\zeta` (body-frame rate of the first moment),
    :math:`T = \tfrac12 m|\dot R|^2 + \dot R\cdot Aw + \tfrac12\bar\omega\cdot J\bar\omega
    + \bar\omega\cdot M_{\omega\zeta}\dot\zeta + \tfrac12\dot\zeta\cdot\Psi^TM\Psi\dot\zeta`.
    All arrays share one dtype (complex128 for :func:`kinetic_energy_gradient`)."""
    p, zeta, rd, zetad = q[3:7], q[7:], qd[0:3], qd[7:]
    omega, s, w, inertia = _kinetic_terms(q, qd, s0, s1, x2, c, d)
    return (
        0.5 * mass * (rd @ rd)
        + rd @ (rotation_matrix(p) @ w)
        + 0.5 * (omega @ (inertia @ omega))
        + omega @ (rotation_mode_coupling(zeta, c, d) @ zetad)
        + 0.5 * (zetad @ (mred @ zetad))
    )


@njit(cache=True)
def kinetic_energy_gradient(q, qd, mass, s0, s1, x2, c, d, mred):
    r""":math:`\partial T/\partial q` of :func:`kinetic_energy_of` at fixed ``qd`` (Eq. (V6)), float64:

    .. math::
        T_R = 0,\qquad T_p = \Big(\frac{\partial(Aw)}{\partial p}\Big)^T\dot R - \bar G(\dot p)^T\tau,
        \quad \tau = s\times A^T\dot R + J\bar\omega + M_{\omega\zeta}\dot\zeta,\\
        T_\zeta = S_1^T(A^T\dot R\times\bar\omega) + \sum_{ab}W_{ab}(C_{ab} + D_{ab}\zeta)
        + \sum_{abc}\epsilon_{abc}\bar\omega_aD_{bc}\dot\zeta,\quad W = |\bar\omega|^2I - \bar\omega\bar\omega^T

    (:math:`\bar\omega = \bar G(p)\dot p = -\bar G(\dot p)p` is linear in each). Needed apart from
    :func:`body_residual`, whose quadratic velocity vector (Eq. (F9)) equals
    :math:`\partial T/\partial q - \dot M\dot q` only up to a multiple of ``p``: the normalisation
    absorbs that in the DAE, but not in Eq. (V2) at the midpoint, where ``p`` is not a unit vector."""
    p, zeta = q[3:7], q[7:]
    rd, pd, zetad = qd[0:3], qd[3:7], qd[7:]
    omega, s, w, inertia = _kinetic_terms(q, qd, s0, s1, x2, c, d)
    a_rd = rotation_matrix(p).T @ rd
    tau = np.cross(s, a_rd) + inertia @ omega + rotation_mode_coupling(zeta, c, d) @ zetad
    out = np.zeros(q.shape[0])
    out[3:7] = rotation_derivative(p, w).T @ rd - g_bar(pd).T @ tau
    t_zeta = s1.T @ np.cross(a_rd, omega)
    w2 = omega @ omega
    for i in range(3):
        for j in range(3):
            weight = (w2 if i == j else 0.0) - omega[i] * omega[j]
            t_zeta += weight * (c[i, j] + d[i, j] @ zeta)
    for i in range(3):
        for j in range(3):
            for k in range(3):
                eps = _levi_civita(i, j, k)
                if eps != 0.0:
                    t_zeta += eps * omega[i] * (d[j, k] @ zetad)
    out[7:] = t_zeta
    return out


@njit(cache=True)
def mass_matrix_rate(q, qd, mass, s0, s1, x2, c, d, mred):
    r""":math:`\dot M` of Eq. (F8): one complex-step evaluation of ``M`` along ``qd`` (the arrays
    after ``mass`` complex128)."""
    qc = q.astype(np.complex128) + 1j * _COMPLEX_STEP * qd.astype(np.complex128)
    return mass_matrix(qc[3:7], qc[7:], mass, s0, s1, x2, c, d, mred).imag / _COMPLEX_STEP
