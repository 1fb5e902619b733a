r"""A joint axis from the circular path of a point: PCA plane and linear least-squares circle.

Paper, Sect. "Kinematic Parameters Identification": with the ``n`` recorded positions
:math:`X \in \mathbb R^{n\times 3}` and their centroid :math:`x_c = \frac1n\sum x_i`, the
centred matrix is decomposed as :math:`\tilde X = U S V^T` (Eq. SVD). The first two
columns of ``V`` span the best-fit plane, the last is the direction of least variance:
the axis direction :math:`\vec a`. In the plane, the circle centre :math:`(c_x, c_y)`
solves the linear least-squares problem (Kasa's algebraic fit)

.. math:: u^2 + v^2 = 2 c_x u + 2 c_y v + k, \qquad k = r^2 - c_x^2 - c_y^2,

and the 3-D centre is :math:`c = x_c + c_x \vec e_x + c_y \vec e_y` (paper, Eq. centre).
The axis is the line through ``c`` along :math:`\vec a`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from kinematics import Line

__all__ = ["CircleFit", "IdentificationError", "fit_circle", "swept_angle"]


class IdentificationError(ValueError):
    """Trajectories that cannot identify an axis; the message names the link and the remedy."""


@dataclass(frozen=True)
class CircleFit:
    """Best-fit circle of a 3-D path: ``centre``, unit ``normal`` (axis), ``radius`` (m),
    in-plane basis ``e_x, e_y``, and the RMS distances of the points from the plane and
    from the circle (m)."""

    centre: NDArray[np.float64]
    normal: NDArray[np.float64]
    radius: float
    e_x: NDArray[np.float64]
    e_y: NDArray[np.float64]
    plane_rms: float
    circle_rms: float

    @property
    def axis(self) -> Line:
        return Line.from_point_direction(self.centre, self.normal)

    def angles(self, points: ArrayLike) -> NDArray[np.float64]:
        """Angular position of points about the axis (right-hand about ``normal``, from ``e_x``)."""
        rel = np.asarray(points, dtype=float) - self.centre
        return np.arctan2(rel @ self.e_y, rel @ self.e_x)


def fit_circle(points: ArrayLike, name: str = "path") -> CircleFit:
    """PCA plane and algebraic circle fit of ``points`` ``(n, 3)``; see the module docstring."""
    points = np.asarray(points, dtype=float)
    if points.ndim != 2 or points.shape[1] != 3:
        raise IdentificationError(f"{name}: expected points of shape (n, 3), got {points.shape}")
    if points.shape[0] < 5:
        raise IdentificationError(f"{name}: {points.shape[0]} points are too few to fit a circle (need >= 5)")
    if not np.all(np.isfinite(points)):
        raise IdentificationError(f"{name}: points contain NaN; clean the record first (identification.preprocess)")
    centroid = points.mean(axis=0)
    _, singular_values, vt = np.linalg.svd(points - centroid, full_matrices=False)
    e_x, e_y, normal = vt
    spread = singular_values[0] / np.sqrt(points.shape[0])
    if spread == 0.0 or singular_values[1] < 1e-6 * singular_values[0]:
        raise IdentificationError(
            f"{name}: the path is a point or a straight line (singular values {singular_values}); "
            "the link barely moves or moves along a line, so no rotation axis can be fitted"
        )
    u, v = (points - centroid) @ e_x, (points - centroid) @ e_y
    design = np.column_stack([2 * u, 2 * v, np.ones_like(u)])
    (cx, cy, k), *_ = np.linalg.lstsq(design, u**2 + v**2, rcond=None)
    radius = float(np.sqrt(k + cx**2 + cy**2))
    centre = centroid + cx * e_x + cy * e_y
    in_plane = np.hypot(u - cx, v - cy)
    return CircleFit(
        centre=centre,
        normal=normal,
        radius=radius,
        e_x=e_x,
        e_y=e_y,
        plane_rms=float(singular_values[2] / np.sqrt(points.shape[0])),
        circle_rms=float(np.sqrt(np.mean((in_plane - radius) ** 2))),
    )


def swept_angle(fit: CircleFit, points: ArrayLike) -> float:
    """Angle range (rad) that consecutive points sweep about the axis (unwrapped max - min)."""
    angles = np.unwrap(fit.angles(points))
    return float(np.ptp(angles)) if angles.size else 0.0
