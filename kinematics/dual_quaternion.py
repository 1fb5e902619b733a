r"""Dual quaternions for rigid-body displacements, in the paper's convention.

A dual quaternion is :math:`\sigma = p + \varepsilon d` with quaternions ``p`` (primal)
and ``d`` (dual) and the dual unit :math:`\varepsilon^2 = 0`. It is stored as 8 reals,
scalar first: ``[p0, p1, p2, p3, d0, d1, d2, d3]``, vectorised as ``(..., 8)``.

Convention (the paper's, Sect. "Recovery of Motion Polynomials from DH parameters",
and that of the Rational Linkages package it cites):

* A point ``x`` is embedded as :math:`1 + \varepsilon x` and moved by
  :math:`1 + \varepsilon x' \propto \sigma_\varepsilon (1 + \varepsilon x) \tilde\sigma`,
  where :math:`\sigma_\varepsilon = p - \varepsilon d` and
  :math:`\tilde\sigma = \tilde p + \varepsilon \tilde d`. Expanding gives

  .. math:: x' = \frac{p\,x\,\tilde p + p\tilde d - d\tilde p}{p\tilde p}, \qquad (1)

  so :math:`\sigma = p - \tfrac{\varepsilon}{2}\, t\, p` rotates by ``p`` and then
  translates by ``t``; the paper's :math:`t_x(a) = 1 - \varepsilon\frac{a}{2}\mathbf i`
  translates by ``+a`` along ``x``.
* Products compose like 4x4 matrices: :math:`\sigma_1\sigma_2` applies
  :math:`\sigma_2` first. Hence ``to_matrix(s1 * s2) == to_matrix(s1) @ to_matrix(s2)``.
* A displacement is a dual quaternion with :math:`p\ne 0` and the Study condition
  :math:`p\tilde d + d\tilde p = 0`, i.e. ``dot(p, d) = 0``. ``sigma`` and ``lambda*sigma``
  (``lambda`` real, non-zero) are the same displacement.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .quaternion import (
    matrix_to_quaternion,
    quaternion_conjugate,
    quaternion_product,
    quaternion_to_matrix,
)

__all__ = ["DualQuaternion"]


@dataclass(frozen=True, eq=False)
class DualQuaternion:
    """Dual quaternion(s) ``p + eps d``, coefficients ``(..., 8)`` scalar first.

    A translation moves the origin by ``t``; products apply the right factor first, so a
    translation by x followed by a quarter turn about z takes the origin to y:

    >>> DualQuaternion.translation([1.0, 2.0, 3.0]).act([0.0, 0.0, 0.0]).tolist()
    [1.0, 2.0, 3.0]
    >>> quarter_turn = DualQuaternion.from_rotation_translation([[0, -1, 0], [1, 0, 0], [0, 0, 1]], [0, 0, 0])
    >>> ((quarter_turn * DualQuaternion.translation([1.0, 0.0, 0.0])).act([0.0, 0.0, 0.0]).round(12) + 0.0).tolist()
    [0.0, 1.0, 0.0]

    A displacement satisfies the Study condition ``p . d = 0``:

    >>> DualQuaternion([1, 0, 0, 0, 0, 0, 0, 1]).is_displacement()
    True
    >>> DualQuaternion([1, 0, 0, 0, 1, 0, 0, 0]).is_displacement()
    False
    """

    coeffs: NDArray[np.float64]

    def __init__(self, coeffs: ArrayLike = (1, 0, 0, 0, 0, 0, 0, 0)):
        array = np.array(coeffs, dtype=float)
        if array.shape[-1:] != (8,):
            raise ValueError(f"a dual quaternion needs 8 coefficients [p0..p3, d0..d3], got shape {array.shape}")
        array.flags.writeable = False
        object.__setattr__(self, "coeffs", array)

    # -- construction ---------------------------------------------------------------
    @classmethod
    def from_parts(cls, primal: ArrayLike, dual: ArrayLike) -> DualQuaternion:
        """Assemble from primal and dual quaternions (``(..., 4)`` each)."""
        primal, dual = np.broadcast_arrays(np.asarray(primal, float), np.asarray(dual, float))
        return cls(np.concatenate([primal, dual], axis=-1))

    @classmethod
    def identity(cls) -> DualQuaternion:
        return cls()

    @classmethod
    def from_rotation_translation(cls, rotation: ArrayLike, translation: ArrayLike) -> DualQuaternion:
        r"""Displacement ``x -> R x + t`` as :math:`p - \tfrac{\varepsilon}{2} t p` (inverse of Eq. 1)."""
        p = matrix_to_quaternion(rotation)
        t = np.asarray(translation, dtype=float)
        t_quat = np.concatenate([np.zeros(t.shape[:-1] + (1,)), t], axis=-1)
        return cls.from_parts(p, -0.5 * quaternion_product(t_quat, p))

    @classmethod
    def from_matrix(cls, matrix: ArrayLike) -> DualQuaternion:
        """From homogeneous 4x4 matrices ``[[R, t], [0, 1]]`` (``(..., 4, 4)``)."""
        matrix = np.asarray(matrix, dtype=float)
        if matrix.shape[-2:] != (4, 4):
            raise ValueError(f"expected homogeneous 4x4 matrices, got shape {matrix.shape}")
        return cls.from_rotation_translation(matrix[..., :3, :3], matrix[..., :3, 3])

    @classmethod
    def translation(cls, t: ArrayLike) -> DualQuaternion:
        r"""Pure translation :math:`1 - \tfrac{\varepsilon}{2} t`."""
        t = np.asarray(t, dtype=float)
        ones = np.ones(t.shape[:-1] + (1,))
        zeros = np.zeros(t.shape[:-1] + (1,))
        return cls(np.concatenate([ones, zeros, zeros, zeros, zeros, -0.5 * t], axis=-1))

    # -- parts and shape ------------------------------------------------------------------
    @property
    def primal(self) -> NDArray[np.float64]:
        return self.coeffs[..., :4]

    @property
    def dual(self) -> NDArray[np.float64]:
        return self.coeffs[..., 4:]

    @property
    def shape(self) -> tuple[int, ...]:
        """Batch shape (the coefficient array's shape without its last axis)."""
        return self.coeffs.shape[:-1]

    def __getitem__(self, index) -> DualQuaternion:
        if self.coeffs.ndim == 1:
            raise IndexError("a single dual quaternion cannot be indexed; use .coeffs")
        return DualQuaternion(self.coeffs[index])

    def __len__(self) -> int:
        if self.coeffs.ndim == 1:
            raise TypeError("a single dual quaternion has no length")
        return self.coeffs.shape[0]

    # -- algebra --------------------------------------------------------------------------
    def __mul__(self, other: DualQuaternion | float) -> DualQuaternion:
        r""":math:`(p_1 + \varepsilon d_1)(p_2 + \varepsilon d_2) = p_1p_2 + \varepsilon(p_1d_2 + d_1p_2)`."""
        if isinstance(other, DualQuaternion):
            p = quaternion_product(self.primal, other.primal)
            d = quaternion_product(self.primal, other.dual) + quaternion_product(self.dual, other.primal)
            return DualQuaternion.from_parts(p, d)
        scalar = np.asarray(other, dtype=float)
        return DualQuaternion(self.coeffs * scalar[..., None])

    def __rmul__(self, other: float) -> DualQuaternion:
        scalar = np.asarray(other, dtype=float)
        return DualQuaternion(self.coeffs * scalar[..., None])

    def __add__(self, other: DualQuaternion) -> DualQuaternion:
        return DualQuaternion(self.coeffs + other.coeffs)

    def __sub__(self, other: DualQuaternion) -> DualQuaternion:
        return DualQuaternion(self.coeffs - other.coeffs)

    def __neg__(self) -> DualQuaternion:
        return DualQuaternion(-self.coeffs)

    def conjugate(self) -> DualQuaternion:
        r"""Quaternion conjugate :math:`\tilde\sigma = \tilde p + \varepsilon\tilde d`."""
        return DualQuaternion.from_parts(quaternion_conjugate(self.primal), quaternion_conjugate(self.dual))

    def eps_conjugate(self) -> DualQuaternion:
        r"""Dual conjugate :math:`\sigma_\varepsilon = p - \varepsilon d`."""
        return DualQuaternion.from_parts(self.primal, -self.dual)

    def norm(self) -> NDArray[np.float64]:
        r"""Dual-number norm :math:`\sigma\tilde\sigma = p\tilde p + \varepsilon(p\tilde d + d\tilde p)`.

        Returned as ``(..., 2)``: ``[|p|^2, 2 p.d]``. The second entry is the Study
        condition residual; it vanishes for displacements.
        """
        p, d = self.primal, self.dual
        return np.stack([np.sum(p * p, axis=-1), 2.0 * np.sum(p * d, axis=-1)], axis=-1)

    def inverse(self) -> DualQuaternion:
        r""":math:`\sigma^{-1} = \tilde\sigma/(\sigma\tilde\sigma)`, with the dual-number division
        :math:`1/(n_0 + \varepsilon n_1) = 1/n_0 - \varepsilon n_1/n_0^2`.

        >>> sigma = DualQuaternion([2, 0, 0, 0, 0, -1, 0, 0])  # a translation by x, scaled by 2
        >>> (sigma * sigma.inverse()).coeffs.tolist()
        [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        """
        n = self.norm()
        if np.any(n[..., 0] == 0.0):
            raise ZeroDivisionError("dual quaternion with zero primal part has no inverse")
        inv0 = 1.0 / n[..., 0]
        inv1 = -n[..., 1] * inv0**2
        c = self.conjugate()
        return DualQuaternion.from_parts(
            c.primal * inv0[..., None], c.dual * inv0[..., None] + c.primal * inv1[..., None]
        )

    def normalized(self) -> DualQuaternion:
        """Scale so that ``|p| = 1`` and ``p0 >= 0`` (same displacement, canonical sign)."""
        p = self.primal
        norm = np.linalg.norm(p, axis=-1)
        if np.any(norm == 0.0):
            raise ZeroDivisionError("dual quaternion with zero primal part cannot be normalised")
        sign = np.where(p[..., 0] < 0.0, -1.0, 1.0)
        return self * (sign / norm)

    def study_residual(self) -> NDArray[np.float64]:
        """``dot(p, d) / |p|^2``: zero exactly for rigid displacements."""
        n = self.norm()
        return 0.5 * n[..., 1] / n[..., 0]

    # -- as a displacement -----------------------------------------------------------------
    def rotation_matrix(self) -> NDArray[np.float64]:
        """Rotation part ``R`` of the displacement (``(..., 3, 3)``)."""
        return quaternion_to_matrix(self.primal)

    def translation_vector(self) -> NDArray[np.float64]:
        r"""Translation part of Eq. (1): :math:`t = (p\tilde d - d\tilde p)/(p\tilde p)` (vector part)."""
        p, d = self.primal, self.dual
        numerator = quaternion_product(p, quaternion_conjugate(d)) - quaternion_product(d, quaternion_conjugate(p))
        return numerator[..., 1:] / np.sum(p * p, axis=-1)[..., None]

    def to_matrix(self) -> NDArray[np.float64]:
        """Homogeneous 4x4 matrices ``[[R, t], [0, 1]]``."""
        matrix = np.zeros(self.shape + (4, 4))
        matrix[..., :3, :3] = self.rotation_matrix()
        matrix[..., :3, 3] = self.translation_vector()
        matrix[..., 3, 3] = 1.0
        return matrix

    def act(self, points: ArrayLike) -> NDArray[np.float64]:
        """Move points ``(..., 3)`` by the displacement, Eq. (1): ``R x + t``.

        Broadcasting follows numpy: a single dual quaternion moves many points, an array
        of dual quaternions moves one point each or one point along a whole motion.
        """
        points = np.asarray(points, dtype=float)
        rotation = self.rotation_matrix()
        return np.einsum("...ij,...j->...i", rotation, points) + self.translation_vector()

    def is_displacement(self, tol: float = 1e-12) -> bool:
        """Primal part non-zero and Study condition satisfied to ``tol`` (relative)."""
        n = self.norm()
        return bool(np.all(n[..., 0] > 0.0) and np.all(np.abs(n[..., 1]) <= tol * n[..., 0]))

    def __repr__(self) -> str:
        if self.coeffs.ndim == 1:
            p = ", ".join(f"{c:.6g}" for c in self.primal)
            d = ", ".join(f"{c:.6g}" for c in self.dual)
            return f"DualQuaternion(primal=[{p}], dual=[{d}])"
        return f"DualQuaternion(shape={self.shape})"
