r"""Oriented lines in Pluecker coordinates, and their dual quaternion embedding.

Convention: a line through the point ``p`` with unit direction ``l`` has the Pluecker
coordinates ``(l, m)`` with the *moment* :math:`m = p \times l` (Pottmann and Wallner,
Computational Line Geometry, p. 133). The moment does not depend on which point of the
line is used, and ``l . m = 0``. The point of the line closest to the origin is
:math:`l \times m`.

The paper writes joint axes as *vectorial dual quaternions* (Sect. "Recovery of Motion
Polynomials", equation for h_0..h_3, following the Rational Linkages package):

.. math:: h = l_1\mathbf i + l_2\mathbf j + l_3\mathbf k
          - \varepsilon\,(m_1\mathbf i + m_2\mathbf j + m_3\mathbf k),

i.e. the dual part holds :math:`-m = l \times p`. With this embedding a displacement
:math:`\sigma` (see :mod:`kinematics.dual_quaternion`) moves a line by
:math:`h \mapsto \sigma h \tilde\sigma / (\sigma\tilde\sigma)`, and the rotation by the angle
``phi`` about the line is the dual quaternion :math:`\cos\frac{\phi}{2} + \sin\frac{\phi}{2}\,h`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .dual_quaternion import DualQuaternion

__all__ = ["Line", "CommonNormal", "common_normal", "distance", "angle"]

_PARALLEL_TOL = 1e-12


def _vector(x: ArrayLike, name: str) -> NDArray[np.float64]:
    array = np.asarray(x, dtype=float)
    if array.shape != (3,):
        raise ValueError(f"{name} must be a 3-vector, got shape {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} contains NaN or infinity: {array}")
    return array


@dataclass(frozen=True, eq=False)
class Line:
    r"""An oriented line: unit ``direction`` ``l`` and ``moment`` ``m = p x l`` (metres).

    The line through (0, 1, 0) along z has the moment (0, 1, 0) x (0, 0, 1) = (1, 0, 0), and
    (3, 1, 5) lies 3 from it:

    >>> line = Line.from_point_direction([0, 1, 0], [0, 0, 2])
    >>> line.direction.tolist(), line.moment.tolist(), line.point.tolist()
    ([0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    >>> float(line.distance_to_point([3, 1, 5]))
    3.0

    The half turn about it, :math:`\cos\frac\pi2 + \sin\frac\pi2 h` (module docstring), takes the
    origin to (0, 2, 0):

    >>> (line.to_dual_quaternion().act([0, 0, 0]) + 0.0).tolist()
    [0.0, 2.0, 0.0]
    """

    direction: NDArray[np.float64]
    moment: NDArray[np.float64]

    def __post_init__(self):
        direction = _vector(self.direction, "line direction")
        moment = _vector(self.moment, "line moment")
        norm = np.linalg.norm(direction)
        if norm == 0.0:
            raise ValueError("line direction has zero length")
        direction, moment = direction / norm, moment / norm
        if abs(direction @ moment) > 1e-9 * max(1.0, np.linalg.norm(moment)):
            raise ValueError(
                f"not a line: direction . moment = {direction @ moment:.3e} must vanish "
                "(Pluecker condition); build it with Line.from_point_direction"
            )
        # Remove the round-off component of m along l so that l.m = 0 holds exactly.
        moment = moment - (direction @ moment) * direction
        direction.flags.writeable = False
        moment.flags.writeable = False
        object.__setattr__(self, "direction", direction)
        object.__setattr__(self, "moment", moment)

    @classmethod
    def from_point_direction(cls, point: ArrayLike, direction: ArrayLike) -> Line:
        point = _vector(point, "point")
        direction = _vector(direction, "direction")
        norm = np.linalg.norm(direction)
        if norm == 0.0:
            raise ValueError("line direction has zero length")
        direction = direction / norm
        return cls(direction, np.cross(point, direction))

    @classmethod
    def from_dual_quaternion(cls, h: DualQuaternion | ArrayLike) -> Line:
        """From the vectorial embedding ``[0, l, 0, -m]`` (scalars must vanish)."""
        coeffs = h.coeffs if isinstance(h, DualQuaternion) else np.asarray(h, dtype=float)
        if coeffs.shape != (8,):
            raise ValueError(f"expected one dual quaternion (8 coefficients), got {coeffs.shape}")
        scale = np.linalg.norm(coeffs[1:4])
        if scale == 0.0 or abs(coeffs[0]) > 1e-9 * scale or abs(coeffs[4]) > 1e-9 * scale:
            raise ValueError(
                "not a vectorial dual quaternion (scalar parts must vanish and the primal "
                f"vector must be non-zero): {coeffs}"
            )
        return cls(coeffs[1:4], -coeffs[5:8])

    def to_dual_quaternion(self) -> DualQuaternion:
        """The paper's embedding ``l - eps m`` as a :class:`DualQuaternion`."""
        return DualQuaternion(np.concatenate([[0.0], self.direction, [0.0], -self.moment]))

    @property
    def point(self) -> NDArray[np.float64]:
        """The point of the line closest to the origin, ``l x m``."""
        return np.cross(self.direction, self.moment)

    def point_at(self, s: ArrayLike) -> NDArray[np.float64]:
        """Points ``point + s l`` for arc-length parameters ``s``."""
        s = np.asarray(s, dtype=float)
        return self.point + s[..., None] * self.direction

    def project(self, x: ArrayLike) -> NDArray[np.float64]:
        """Orthogonal projection of points ``(..., 3)`` onto the line."""
        x = np.asarray(x, dtype=float)
        return self.point_at((x - self.point) @ self.direction)

    def distance_to_point(self, x: ArrayLike) -> NDArray[np.float64]:
        """Distance of points ``(..., 3)`` from the line, ``|x x l - m|``."""
        x = np.asarray(x, dtype=float)
        return np.linalg.norm(np.cross(x, self.direction) - self.moment, axis=-1)

    def transformed(self, sigma: DualQuaternion) -> Line:
        r"""Image under the displacement ``sigma``: :math:`\sigma h\tilde\sigma / (\sigma\tilde\sigma)`."""
        image = sigma * self.to_dual_quaternion() * sigma.conjugate()
        return Line.from_dual_quaternion(image.coeffs / sigma.norm()[0])

    def reversed(self) -> Line:
        """Same line, opposite orientation."""
        return Line(-self.direction, -self.moment)

    def is_close(self, other: Line, tol: float = 1e-12) -> bool:
        """Same oriented line up to ``tol`` in direction and moment (metres)."""
        return bool(
            np.allclose(self.direction, other.direction, atol=tol, rtol=0)
            and np.allclose(self.moment, other.moment, atol=tol, rtol=0)
        )

    def __repr__(self) -> str:
        direction = ", ".join(f"{c:.6g}" for c in self.direction)
        moment = ", ".join(f"{c:.6g}" for c in self.moment)
        return f"Line(direction=[{direction}], moment=[{moment}])"


class CommonNormal(NamedTuple):
    """Common normal of two lines: feet ``foot0`` on the first, ``foot1`` on the second.

    ``distance = |foot1 - foot0|`` and ``unit`` points from ``foot0`` to ``foot1``
    (for intersecting lines it is ``l0 x l1`` normalised; for parallel lines the normal
    is not unique and the feet are taken through ``reference`` or the first line's
    closest point to the origin). ``kind`` is ``"skew"``, ``"intersecting"``,
    ``"parallel"`` or ``"coincident"``.
    """

    foot0: NDArray[np.float64]
    foot1: NDArray[np.float64]
    distance: float
    unit: NDArray[np.float64] | None
    kind: str


def common_normal(
    line0: Line,
    line1: Line,
    reference: ArrayLike | None = None,
    tol: float = 1e-12,
) -> CommonNormal:
    r"""Feet of the common normal of two lines.

    For non-parallel lines with directions ``l0, l1`` and ``n = l0 x l1``, the feet are
    (Pottmann and Wallner, Sect. 2.1)

    .. math:: f_0 = \frac{-m_0\times(l_1\times n) + (m_1\cdot n)\,l_0}{|n|^2},\qquad
              f_1 = \frac{m_1\times(l_0\times n) - (m_0\cdot n)\,l_1}{|n|^2}.

    ``reference`` (a point) fixes the feet of parallel lines: the normal through the
    projection of ``reference`` onto ``line0``.

    The z-axis and the line through (0, 2, 5) along x are 2 apart, at height 5:

    >>> z_axis = Line.from_point_direction([0, 0, 0], [0, 0, 1])
    >>> normal = common_normal(z_axis, Line.from_point_direction([0, 2, 5], [1, 0, 0]))
    >>> (normal.foot0 + 0.0).tolist(), (normal.foot1 + 0.0).tolist(), normal.distance, normal.kind
    ([0.0, 0.0, 5.0], [0.0, 2.0, 5.0], 2.0, 'skew')
    """
    l0, m0 = line0.direction, line0.moment
    l1, m1 = line1.direction, line1.moment
    n = np.cross(l0, l1)
    n2 = n @ n
    if n2 > tol**2:
        foot0 = (-np.cross(m0, np.cross(l1, n)) + (m1 @ n) * l0) / n2
        foot1 = (np.cross(m1, np.cross(l0, n)) - (m0 @ n) * l1) / n2
        gap = foot1 - foot0
        dist = float(np.linalg.norm(gap))
        if dist > tol:
            return CommonNormal(foot0, foot1, dist, gap / dist, "skew")
        return CommonNormal(foot0, foot0.copy(), 0.0, n / np.sqrt(n2), "intersecting")
    start = line0.point if reference is None else line0.project(reference)
    foot1 = line1.project(start)
    gap = foot1 - start
    dist = float(np.linalg.norm(gap))
    if dist > tol:
        return CommonNormal(start, foot1, dist, gap / dist, "parallel")
    return CommonNormal(start, foot1, 0.0, None, "coincident")


def distance(line0: Line, line1: Line) -> float:
    """Shortest distance between two lines (metres)."""
    return common_normal(line0, line1).distance


def angle(line0: Line, line1: Line) -> float:
    """Angle between the oriented directions, in ``[0, pi]`` (radians)."""
    cross = np.linalg.norm(np.cross(line0.direction, line1.direction))
    return float(np.arctan2(cross, line0.direction @ line1.direction))
