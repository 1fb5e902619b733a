r"""A conservative proxy of the parametric link: capsules that enclose every part of its solid.

A capsule is a segment :math:`[a, b]` and a radius :math:`r`, the points within :math:`r` of the segment.
The distance between two capsules is the distance between their segments minus both radii, in closed form
(:func:`segment_distances`), so the clearance of two links along a motion costs a few array operations per pose.
Because the capsules enclose the solid (:func:`link_capsules`), two links whose capsules keep a distance
:math:`c` keep at least :math:`c` between their solids (``docs/formulation.md``, "Collision-free links").

The parts of :func:`ffrf.geometry.link_geometry.build_link` and their capsules (half-diagonal
:math:`\rho_a = \tfrac12\sqrt{w^2 + t^2}` of the arm's section :math:`w \times t`, housing radius :math:`R`):

* housing: its axis segment (the housing's length), radius :math:`R`;
* arm: each box along the arm's waypoints, as one capsule per cell of its section (:data:`ARM_CELLS`), each
  about the cell's middle line with the cell's half-diagonal as radius, lengthened by the half width where the
  boxes overlap at a stub. Where a box leaves a housing the capsules start :math:`x_0 = \sqrt{R^2 - \rho_a^2}`
  from the housing centre: nearer, every point of the box lies within :math:`R` of the centre, so it is inside
  the housing or in the region beyond the housing's end faces that ``build_link`` trims away;
* mount block: a segment through its middle along the arm, radius the half-diagonal of its section.

Trimming and bores only remove material, so the proxy of the untrimmed parts encloses the built link too.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ffrf.geometry.joint_axes import Axis
from ffrf.geometry.link_geometry import LinkDesign, arm_frame, arm_waypoints

__all__ = ["ARM", "ARM_CELLS", "MOUNT", "LinkCapsules", "closest_points", "link_capsules", "segment_distances"]

#: ``LinkCapsules.parts`` of the arm's and the mount block's capsules (a housing's part is its side, 0 or 1).
ARM, MOUNT = -1, -2
#: An arm box's section :math:`w \times t` is split into ``ARM_CELLS`` by ``ARM_CELLS`` cells, each enclosed by a
#: capsule about its middle line with the cell's half-diagonal as radius: with two, the proxy stands at most 1 and
#: 2 mm off the faces of the default 16 x 12 mm arm (one capsule about the whole section: 2 and 4 mm), and each
#: cell's capsule lies within that one capsule (its centre half the section's half-diagonal off the axis, and its
#: radius the other half).
ARM_CELLS = 2


@dataclass(frozen=True)
class LinkCapsules:
    """Capsules of one link in the home pose: segment ``starts``/``ends`` ``(k, 3)`` (m), ``radii`` ``(k,)``
    (m) and the part of each (``0``/``1`` the housing on the link's first/second axis, :data:`ARM`, :data:`MOUNT`)."""

    starts: NDArray[np.float64]
    ends: NDArray[np.float64]
    radii: NDArray[np.float64]
    parts: tuple[int, ...]


def link_capsules(
    axis_a, axis_b, joint_points: ArrayLike, design: LinkDesign | None = None, mount: bool = False
) -> LinkCapsules:
    """Capsules enclosing the link :func:`~ffrf.geometry.link_geometry.build_link` builds from the same
    ``axis_a``, ``axis_b``, ``joint_points`` ``(2, 3)``, ``design`` and ``mount`` (module docstring)."""
    design = LinkDesign() if design is None else design
    axes = (Axis.of(axis_a), Axis.of(axis_b))
    points = np.asarray(joint_points, dtype=float).reshape(2, 3)
    s, half_length = design.housing_offset, 0.5 * design.housing_length
    centers = np.stack([points[0] + s * axes[0].direction, points[1] - s * axes[1].direction])
    starts = [c - half_length * a.direction for c, a in zip(centers, axes, strict=True)]
    ends = [c + half_length * a.direction for c, a in zip(centers, axes, strict=True)]
    radii = [design.housing_outer_radius] * 2
    parts = [0, 1]
    arm_radius = 0.5 * float(np.hypot(design.arm_width, design.arm_thickness))
    cell = (design.arm_width / ARM_CELLS, design.arm_thickness / ARM_CELLS)
    cell_radius = 0.5 * float(np.hypot(*cell))
    cell_centres = [
        (-0.5 * design.arm_width + (i + 0.5) * cell[0], -0.5 * design.arm_thickness + (k + 0.5) * cell[1])
        for i in range(ARM_CELLS)
        for k in range(ARM_CELLS)
    ]
    inside = float(np.sqrt(max(design.housing_outer_radius**2 - arm_radius**2, 0.0)))
    path = arm_waypoints(points, axes, design)
    path[0], path[-1] = centers
    stubs = len(path) > 2
    extra = 0.5 * design.arm_width if stubs else 0.0  # boxes after a stub overlap their neighbours (build_link)
    last = len(path) - 2
    for k in range(last + 1):
        start, end = path[k], path[k + 1]
        frame = arm_frame(start, end, axes[0].direction)  # build_link's box: width along e2, thickness along e3
        begin = start + (inside if k == 0 else -extra) * frame[:, 0]
        finish = end - (inside if k == last else -extra) * frame[:, 0]
        for width, thickness in cell_centres:
            across = width * frame[:, 1] + thickness * frame[:, 2]
            starts.append(begin + across)
            ends.append(finish + across)
            radii.append(cell_radius)
            parts.append(ARM)
    if mount:
        middle = len(path) // 2 - 1 if len(path) == 4 else 0
        origin = path[middle]
        frame = arm_frame(origin, path[middle + 1], axes[0].direction)
        span = float(np.linalg.norm(path[middle + 1] - origin))
        depth = design.mount_height + 0.5 * design.arm_thickness  # the block reaches from the arm's middle plane
        x0 = 0.5 * (span - design.mount_length)
        for x in (x0, x0 + design.mount_length):
            (starts if x == x0 else ends).append(origin + frame @ np.array([x, 0.0, -0.5 * depth]))
        radii.append(0.5 * float(np.hypot(design.mount_width, depth)))
        parts.append(MOUNT)
    return LinkCapsules(np.array(starts), np.array(ends), np.array(radii), tuple(parts))


def segment_distances(p0: ArrayLike, p1: ArrayLike, q0: ArrayLike, q1: ArrayLike) -> NDArray[np.float64]:
    """Distances between segments :math:`[p_0, p_1]` and :math:`[q_0, q_1]`, arrays ``(..., 3)`` broadcast
    (:func:`closest_points`)."""
    _, _, gap = closest_points(p0, p1, q0, q1)
    return np.sqrt((gap * gap).sum(-1))


def closest_points(
    p0: ArrayLike, p1: ArrayLike, q0: ArrayLike, q1: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    r"""Closest points of segments :math:`[p_0, p_1]` and :math:`[q_0, q_1]` (arrays ``(..., 3)`` broadcast):
    ``(s, t, gap)`` with :math:`p_0 + s\,u` and :math:`q_0 + t\,v` the closest points and ``gap`` the vector
    from the second to the first.

    They minimise :math:`|w + s u - t v|^2` over :math:`s, t \in [0, 1]` (:math:`u = p_1 - p_0`,
    :math:`v = q_1 - q_0`, :math:`w = p_0 - q_0`): the unconstrained
    :math:`s = (b f - c e)/(a e - b^2)` (:math:`a = u\cdot u, b = u\cdot v, c = u\cdot w, e = v\cdot v,
    f = v\cdot w`) clamped, :math:`t = (b s + f)/e`, and where :math:`t` leaves :math:`[0, 1]` it is clamped
    and :math:`s` recomputed (Ericson, *Real-Time Collision Detection*, 2005, Sect. 5.1.9). Degenerate
    segments (points) and parallel ones are handled (for parallel segments ``s = 0`` to start)."""
    p0, p1, q0, q1 = (np.asarray(x, dtype=float) for x in (p0, p1, q0, q1))
    u, v, w = p1 - p0, q1 - q0, p0 - q0
    a, b, c = (u * u).sum(-1), (u * v).sum(-1), (u * w).sum(-1)
    e, f = (v * v).sum(-1), (v * w).sum(-1)
    tiny = 1e-30
    denominator = a * e - b * b
    safe_a, safe_e = np.where(a > tiny, a, 1.0), np.where(e > tiny, e, 1.0)
    general = denominator > 1e-12 * np.maximum(a * e, tiny)
    s = np.where(general, np.clip((b * f - c * e) / np.where(general, denominator, 1.0), 0.0, 1.0), 0.0)
    s = np.where(e > tiny, s, np.clip(-c / safe_a, 0.0, 1.0))  # q is a point: the nearest point of p's segment
    s = np.where(a > tiny, s, 0.0)
    t = np.where(e > tiny, (b * s + f) / safe_e, 0.0)
    below, above = t < 0.0, t > 1.0
    t = np.clip(t, 0.0, 1.0)
    s = np.where(below, np.clip(-c / safe_a, 0.0, 1.0), s)
    s = np.where(above, np.clip((b - c) / safe_a, 0.0, 1.0), s)
    s = np.where(a > tiny, s, 0.0)
    return s, t, w + s[..., None] * u - t[..., None] * v
