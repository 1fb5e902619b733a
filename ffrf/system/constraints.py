r"""Holonomic constraints g(q, t) = 0 with analytic Jacobians.

Each constraint acts on one or two bodies' coordinate blocks ``q_b = [R, p, zeta]`` and
provides its value ``g``, the Jacobian rows ``C_q`` on those blocks, and (through
complex-step differentiation of the analytic :math:`C_q^T\lambda`, see
:func:`constraint_hessian_term`) the exact term :math:`\partial(C_q^T\lambda)/\partial q`
of the Newton iteration matrix. Positions on a body are *body points*
:math:`u = \bar x + \bar\Psi\zeta` (a fixed point of the frame when :math:`\bar\Psi = 0`;
the weighted mean of an interface when it is the interface's ``3 x m`` mode average).

Conventions: world-frame constraint equations; the Euler parameter block is ``q_b[3:7]``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ffrf.body.euler_parameters import rotation_derivative, rotation_matrix

__all__ = [
    "Constraint",
    "EulerNormalization",
    "GroundPoint",
    "GroundPerpendicular",
    "constraint_hessian_term",
    "constraint_velocity_derivative",
]


@dataclass(frozen=True, eq=False)
class Constraint:
    """Base: ``bodies`` are the indices of the bodies whose coordinates the constraint reads."""

    bodies: tuple[int, ...]
    name: str

    @property
    def size(self) -> int:  # pragma: no cover - abstract
        raise NotImplementedError

    def value(self, blocks: list[NDArray], t: float) -> NDArray:  # pragma: no cover - abstract
        raise NotImplementedError

    def jacobian(self, blocks: list[NDArray], t: float) -> list[NDArray]:  # pragma: no cover - abstract
        """One ``(size, n_b)`` matrix per body in ``bodies``."""
        raise NotImplementedError


@dataclass(frozen=True, eq=False)
class EulerNormalization(Constraint):
    r""":math:`g = p^Tp - 1` (the normalisation of the Euler parameters, Eq. (R2) of the docs)."""

    @property
    def size(self) -> int:
        return 1

    def value(self, blocks, t):
        p = blocks[0][3:7]
        return np.array([p @ p - 1.0])

    def jacobian(self, blocks, t):
        q = blocks[0]
        rows = np.zeros((1, q.shape[0]), dtype=q.dtype)
        rows[0, 3:7] = 2.0 * q[3:7]
        return [rows]


def _body_point(q: NDArray, local: NDArray, modes: NDArray) -> NDArray:
    return local + modes @ q[7:] if modes.shape[1] else local.astype(q.dtype)


@dataclass(frozen=True, eq=False)
class GroundPoint(Constraint):
    r"""A body point held at a world point: :math:`g = R + A(p)(\bar x + \bar\Psi\zeta) - r_0` (3 equations)."""

    local: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    modes: NDArray[np.float64] = field(default_factory=lambda: np.zeros((3, 0)))
    target: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))

    @property
    def size(self) -> int:
        return 3

    def value(self, blocks, t):
        q = blocks[0]
        return q[:3] + rotation_matrix(q[3:7]) @ _body_point(q, self.local, self.modes) - self.target

    def jacobian(self, blocks, t):
        q = blocks[0]
        u = _body_point(q, self.local, self.modes)
        rows = np.zeros((3, q.shape[0]), dtype=q.dtype)
        rows[:, :3] = np.eye(3)
        rows[:, 3:7] = rotation_derivative(q[3:7], u)
        if self.modes.shape[1]:
            rows[:, 7:] = rotation_matrix(q[3:7]) @ self.modes.astype(q.dtype)
        return [rows]


@dataclass(frozen=True, eq=False)
class GroundPerpendicular(Constraint):
    r"""A body vector :math:`v` (body frame) kept perpendicular to world vectors :math:`e_k`:
    :math:`g_k = e_k\cdot A(p)v`. Two of them with :math:`e_1, e_2 \perp` the hinge axis and
    :math:`v` along it make a revolute joint with :class:`GroundPoint`."""

    vector: NDArray[np.float64] = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    normals: NDArray[np.float64] = field(default_factory=lambda: np.eye(3)[:2])

    @property
    def size(self) -> int:
        return self.normals.shape[0]

    def value(self, blocks, t):
        q = blocks[0]
        return self.normals @ (rotation_matrix(q[3:7]) @ self.vector.astype(q.dtype))

    def jacobian(self, blocks, t):
        q = blocks[0]
        rows = np.zeros((self.size, q.shape[0]), dtype=q.dtype)
        rows[:, 3:7] = self.normals @ rotation_derivative(q[3:7], self.vector.astype(q.dtype))
        return [rows]


_STEP = 1e-30


def constraint_hessian_term(
    constraint: Constraint, blocks: list[NDArray], multipliers: NDArray, t: float
) -> list[list[NDArray]]:
    r"""Exact :math:`\partial(C_q^T\lambda)/\partial q` as blocks ``[i][j]`` (body i rows, body j columns),
    by complex-step differentiation of the analytic ``jacobian`` (polynomial in ``q``)."""
    out = []
    for i in range(len(blocks)):
        out.append([np.zeros((blocks[i].shape[0], blocks[j].shape[0])) for j in range(len(blocks))])
    for j, block in enumerate(blocks):
        for k in range(block.shape[0]):
            shifted = [b.astype(np.complex128) for b in blocks]
            shifted[j][k] += 1j * _STEP
            rows = constraint.jacobian(shifted, t)
            for i in range(len(blocks)):
                out[i][j][:, k] = (rows[i].T @ multipliers).imag / _STEP
    return out


def constraint_velocity_derivative(
    constraint: Constraint, blocks: list[NDArray], velocities: list[NDArray], t: float
) -> NDArray:
    r""":math:`(\partial(C_q\dot q)/\partial q)\,\dot q`, the quadratic term of the acceleration-level
    constraint :math:`C_q\ddot q + (C_q\dot q)_q\dot q = 0`, as one complex-step directional derivative."""
    shifted = [b.astype(np.complex128) + 1j * _STEP * v for b, v in zip(blocks, velocities, strict=True)]
    rows = constraint.jacobian(shifted, t)
    return sum(r @ v for r, v in zip(rows, velocities, strict=True)).imag / _STEP
