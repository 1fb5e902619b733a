"""Joint axes as lines in space (:class:`Axis`), the feet of the common normal of two of them (the
joint points of a link), and the paper's Bennett axes h0..h3: as given in the folded home
configuration (:data:`PAPER_AXES`) and from the DH table with any base-link twist
(:func:`bennett_axes`); link ``k`` carries (h_{k-1}, h_k) (:func:`paper_link_axes`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ffrf.errors import GeometryError

__all__ = ["Axis", "PAPER_AXES", "bennett_axes", "paper_link_axes", "common_normal_feet"]


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


#: The paper's four joint axes h0..h3 in the folded home configuration (metres).
PAPER_AXES: tuple[Axis, ...] = (
    Axis((0.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
    Axis((-0.11, 0.0, 0.0), (0.0, 0.5, -np.sqrt(3.0) / 2.0)),
    Axis((0.11, 0.0, 0.0), (0.0, np.sqrt(3.0) / 2.0, 0.5)),
    Axis((0.22, 0.0, 0.0), (0.0, -1.0, 0.0)),
)


def bennett_axes(alpha3_deg: float = 90.0) -> tuple[Axis, Axis, Axis, Axis]:
    """Joint axes h0..h3 of the paper's linkage (:data:`kinematics.PAPER_A`, ``PAPER_ALPHA``)
    with the base-link twist ``alpha3_deg``.

    The base link (link 0) carries (h3, h0). With alpha_3 != 90 deg the loop does not
    close, so its h3 is where the *base link* puts it: :func:`kinematics.open_loop_axes`
    chains h0..h3 through links 0..2 (nominal) and returns that closing axis, which
    replaces h3 here (the base's bore axis; link 3 keeps the nominal h3).
    """
    from kinematics import PAPER_A, PAPER_ALPHA, open_loop_axes

    if not np.isfinite(alpha3_deg):
        raise GeometryError(
            f"base-link twist alpha3_deg={alpha3_deg!r} is not a finite angle; give it in degrees, "
            "e.g. 90 (paper: 90, 91, 92)"
        )
    alpha = np.array(PAPER_ALPHA)
    alpha[3] = np.radians(alpha3_deg)
    axes, closing_axis = open_loop_axes(PAPER_A, alpha)
    return Axis.of(axes[0]), Axis.of(axes[1]), Axis.of(axes[2]), Axis.of(closing_axis)


def paper_link_axes(link: int, axes=PAPER_AXES) -> tuple[Axis, Axis, tuple[str, str]]:
    """Axes and interface names of link ``link`` (0 = base): it carries (h_{i-1}, h_i)."""
    if link not in (0, 1, 2, 3):
        raise GeometryError(f"link index {link!r} must be 0, 1, 2 or 3 (0 = base)")
    first, second = (link - 1) % 4, link
    return Axis.of(axes[first]), Axis.of(axes[second]), (f"joint{first}", f"joint{second}")


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
            "their common normal is not unique, a Bennett link needs skew axes"
        )
    t_a = (b * e - d) / denom
    t_b = (e - b * d) / denom
    return np.stack([axis_a.point + t_a * axis_a.direction, axis_b.point + t_b * axis_b.direction])
