r"""How the clearance of two links changes with their shape (``docs/formulation.md``, Eq. (CL5)).

A design parameter moves the points of a link's mesh along its design velocity (Eq. (D5)), and with them the link's
surface, while the rigid motion of the loop stays (the bores do not move). The clearance of two links at one relative
pose is then differentiated as the section's other outputs are: central differences of the solids morphed by
:math:`\pm h` along the velocities, at that pose, with the same joint zone (Eq. (CL3)). Where one pose holds a pair's
smallest clearance over the motion, that smallest clearance changes as the clearance at that pose (Danskin's
theorem). The witness-point formula :math:`n \cdot (V_b - V_a)` would give the same where the closest points are
unique and away from a joint zone's boundary; at that boundary (the zone is fixed in space while the surface moves
through it) it does not, and the links' faces, often parallel, hold their clearance over whole regions.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ffrf.output.solid_distance import JointZone, LinkSolid, SolidPair

__all__ = ["clearance_slopes"]


def clearance_slopes(
    a: LinkSolid,
    b: LinkSolid,
    relative: ArrayLike,
    velocities_a: NDArray,
    velocities_b: NDArray,
    steps: ArrayLike,
    zone: JointZone | None = None,
) -> tuple[float, NDArray[np.float64]]:
    """The clearance of ``a`` and ``b`` (``b`` moved by ``relative`` ``(4, 4)`` into ``a``'s frame) and its
    derivatives ``(k,)`` by the ``k`` parameters whose velocities at the solids' vertices are ``velocities_a``
    ``(m_a, 3, k)`` and ``velocities_b`` ``(m_b, 3, k)`` (home coordinates, per unit of the parameter): central
    differences over ``steps`` ``(k,)`` of each (module docstring)."""
    relative = np.asarray(relative, dtype=float)
    steps = np.asarray(steps, dtype=float)
    value = SolidPair(a, b, zone).clearance(relative)
    slopes = np.zeros(len(steps))
    for j, step in enumerate(steps):
        if not (np.any(velocities_a[..., j]) or np.any(velocities_b[..., j])):
            continue  # neither solid moves with this parameter
        sides = [
            SolidPair(
                _moved(a, sign * step * velocities_a[..., j]), _moved(b, sign * step * velocities_b[..., j]), zone
            )
            for sign in (1.0, -1.0)
        ]
        slopes[j] = (sides[0].clearance(relative) - sides[1].clearance(relative)) / (2.0 * step)
    return float(value), slopes


def _moved(solid: LinkSolid, displacement: NDArray) -> LinkSolid:
    return LinkSolid(solid.vertices + displacement, solid.triangles, solid.name)
