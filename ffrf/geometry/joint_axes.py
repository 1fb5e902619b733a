"""Joint axes as lines in space (:class:`Axis`) and the feet of the common normal of two of them (the
joint points of a link)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ffrf.errors import GeometryError

__all__ = ["Axis", "common_normal_feet"]


@dataclass(frozen=True, init=False)
class Axis:
    """A line in space: a point on it and a unit direction (metres, world frame). Built from any
    array-likes; the direction is normalised."""

    point: NDArray[np.float64]
    direction: NDArray[np.float64]

    def __init__(self, point: ArrayLike, direction: ArrayLike) -> None:
        p = np.asarray(point, dtype=float).reshape(3)
        d = np.asarray(direction, dtype=float).reshape(3)
        n = np.linalg.norm(d)
        if not n > 0.0:
            raise GeometryError(f"Axis through {p.tolist()}: direction {d.tolist()} has zero length")
        object.__setattr__(self, "point", p)
        object.__setattr__(self, "direction", d / n)

    @classmethod
    def of(cls, obj) -> Axis:
        """Accept an :class:`Axis`, any object with ``.point`` and ``.direction``, or a (point, direction) pair."""
        if isinstance(obj, Axis):
            return obj
        if hasattr(obj, "point") and hasattr(obj, "direction"):
            return cls(obj.point, obj.direction)
        point, direction = obj
        return cls(point, direction)


def common_normal_feet(axis_a: Axis, axis_b: Axis) -> NDArray[np.float64]:
    """Feet of the common normal of two skew lines, shape (2, 3).

    Closest points p_a + t_a d_a, p_b + t_b d_b from the stationarity of
    ``|(p_a + t_a d_a) - (p_b + t_b d_b)|^2`` (e.g. Eberly, 3D Game Engine Design, sec. 14.1).
    """
    w0 = axis_a.point - axis_b.point
    b = float(axis_a.direction @ axis_b.direction)
    d = float(axis_a.direction @ w0)
    e = float(axis_b.direction @ w0)
    denom = 1.0 - b * b
    if denom < 1e-10:
        raise GeometryError(
            f"link axes through {axis_a.point.tolist()} and {axis_b.point.tolist()} are parallel; "
            "their common normal is not unique, a link between them needs skew axes"
        )
    t_a = (b * e - d) / denom
    t_b = (e - b * d) / denom
    return np.stack([axis_a.point + t_a * axis_a.direction, axis_b.point + t_b * axis_b.direction])
