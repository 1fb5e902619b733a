r"""A modally reduced flexible body in the floating frame of reference (FFRF).

Its residual (``docs/formulation.md``, Eqs. (F8)-(F11))

.. math:: f(q, \dot q, \ddot q) = M(q)\ddot q - Q_v(q, \dot q) - Q_g(q) + K_r\zeta + D_r\dot\zeta

and its exact Jacobians :math:`\partial f/\partial q` and :math:`\partial f/\partial\dot q`.
The Jacobians come from complex-step differentiation (Squire and Trapp 1998): every term
of ``f`` is a polynomial in ``(p, zeta, pd, zetad)``, so
:math:`\partial f/\partial q_k = \mathrm{Im}\,f(q + ih e_k)/h` holds to round-off for any
small ``h`` (no subtractive cancellation). They include the terms Exudyn's solver leaves
out, such as :math:`\partial(M(q)\ddot q)/\partial q`, so Newton converges quadratically.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

from .body_kernels import gravity_force, mass_and_quadratic_velocity, mass_matrix
from .modal_moments import ModalMoments
from .small_linalg import mat_vec

__all__ = ["FlexibleBody", "body_residual", "body_jacobians"]

_COMPLEX_STEP = 1e-30  # any tiny step: complex-step derivatives have no cancellation error


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
    _packed: tuple = field(init=False, repr=False)
    _packed_complex: tuple = field(init=False, repr=False)

    def __post_init__(self):
        m = self.moments.n_modes
        for label, matrix in (("stiffness", self.stiffness), ("damping", self.damping)):
            if np.shape(matrix) != (m, m):
                raise ValueError(f"body {self.name!r}: reduced {label} has shape {np.shape(matrix)}, expected ({m}, {m})")
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

    @property
    def n_coordinates(self) -> int:
        """7 + m: position (3), Euler parameters (4), modal coordinates (m)."""
        return 7 + self.moments.n_modes

    def residual(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike, gravity: ArrayLike) -> NDArray[np.float64]:
        return body_residual(np.asarray(q, float), np.asarray(qd, float), np.asarray(qdd, float),
                             np.asarray(gravity, float), self.moments.mass, *self._packed, self.exact_gravity)

    def jacobians(self, q, qd, qdd, gravity) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Exact ``(df/dq, df/dqd)``, each ``(7+m, 7+m)``."""
        return body_jacobians(np.asarray(q, float), np.asarray(qd, float), np.asarray(qdd, float),
                              np.asarray(gravity, float), self.moments.mass, *self._packed_complex, self.exact_gravity)

    def mass_matrix(self, q: ArrayLike) -> NDArray[np.float64]:
        q = np.asarray(q, float)
        s0, s1, x2, c, d, mred, _, _ = self._packed
        return mass_matrix(q[3:7], q[7:], self.moments.mass, s0, s1, x2, c, d, mred)

    def kinetic_energy(self, q: ArrayLike, qd: ArrayLike) -> float:
        qd = np.asarray(qd, float)
        return 0.5 * float(qd @ self.mass_matrix(q) @ qd)

    def strain_energy(self, q: ArrayLike) -> float:
        zeta = np.asarray(q, float)[7:]
        return 0.5 * float(zeta @ self.stiffness @ zeta)

    def potential_energy(self, q: ArrayLike, gravity: ArrayLike) -> float:
        """Gravity potential -g . (m R + A s), Eq. (F10) (exact first moment)."""
        from .euler_parameters import rotation_matrix

        q = np.asarray(q, float)
        mm = self.moments
        s = mm.s0 + mm.s1 @ q[7:]
        return -float(np.asarray(gravity, float) @ (mm.mass * q[:3] + rotation_matrix(q[3:7]) @ s))


@njit(cache=True)
def body_residual(q, qd, qdd, gravity, mass, s0, s1, x2, c, d, mred, kred, dred, exact_gravity):
    """Eqs. (F8)-(F11): ``M(q) qdd - Q_v - Q_g + K_r zeta + D_r zetad`` (one dtype throughout)."""
    p, zeta = q[3:7], q[7:]
    pd, zetad = qd[3:7], qd[7:]
    out = np.zeros(q.shape[0], dtype=q.dtype)
    if np.any(qd != 0) or np.any(qdd != 0):  # at rest (statics) M qdd and Q_v vanish exactly
        mass_q, velocity_q = mass_and_quadratic_velocity(p, zeta, pd, zetad, mass, s0, s1, x2, c, d, mred)
        out += mat_vec(mass_q, qdd)
        out -= velocity_q
    out -= gravity_force(p, zeta, gravity.astype(q.dtype), mass, s0, s1, exact_gravity)
    out[7:] += mat_vec(kred, zeta) + mat_vec(dred, zetad)
    return out


@njit(cache=True)
def body_jacobians(q, qd, qdd, gravity, mass, s0, s1, x2, c, d, mred, kred, dred, exact_gravity):
    """Complex-step Jacobians of :func:`body_residual`; the constant arrays must be complex128."""
    n = q.shape[0]
    jac_q = np.empty((n, n))
    jac_qd = np.empty((n, n))
    qc = q.astype(np.complex128)
    qdc = qd.astype(np.complex128)
    qddc = qdd.astype(np.complex128)
    for k in range(n):
        qc[k] += 1j * _COMPLEX_STEP
        jac_q[:, k] = body_residual(qc, qdc, qddc, gravity, mass, s0, s1, x2, c, d, mred, kred, dred,
                                    exact_gravity).imag / _COMPLEX_STEP
        qc[k] = q[k]
        qdc[k] += 1j * _COMPLEX_STEP
        jac_qd[:, k] = body_residual(qc, qdc, qddc, gravity, mass, s0, s1, x2, c, d, mred, kred, dred,
                                     exact_gravity).imag / _COMPLEX_STEP
        qdc[k] = qd[k]
    return jac_q, jac_qd
