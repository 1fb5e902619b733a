r"""Joint axes of a single loop, branch by branch (paper, Sect. "Kinematic Parameters Identification").

The loop is split into two branches that start at the grounded base and meet at the
coupler. Along a branch, the first link turns about a fixed axis, so its tracked points
move on circles: :func:`fit_link_axis`. The next link's path is not circular, but it is
in the *moving frame of the previous joint*: with :math:`T_{i,j}` the frame with origin
at the circle centre :math:`c_i`, z-axis :math:`\vec a_i` and x-axis :math:`\vec x_{i,j}`
towards the previous link's point at frame ``j``, and :math:`T_i = T_{i,0}` (paper, Eq.
projection)

.. math:: p^*_{i+1,j} = T_i\, T_{i,j}^{-1}\, p_{i+1,j}

undoes the motion of link ``i`` and leaves a circular path about the next axis, seen in
the configuration of frame 0. Longer branches extend the product from the left, one pair
:math:`T_{i-1} T_{i-1,j}^{-1}` per joint. All axes come out in the configuration of the
first frame, so together they are one consistent configuration of the loop.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from kinematics import Line

from .circle_fit import CircleFit, IdentificationError, fit_circle

__all__ = ["LinkAxisFit", "fit_link_axis", "moving_frames", "project_into_previous_frame", "identify_branch"]

#: Paths that sweep less than this about their axis are refused (a link that barely moves).
MIN_SWEPT_ANGLE = np.radians(10.0)
#: Paths whose RMS distance from the fitted circle exceeds this fraction of its radius are refused.
MAX_CIRCLE_RMS = 0.2


@dataclass(frozen=True)
class LinkAxisFit:
    """Axis of one link's rotation: the ``axis`` line, per-point circle ``fits``, and the
    link's rotation angle ``angles[j]`` at frame ``j`` relative to frame 0 (rad)."""

    axis: Line
    centre: NDArray[np.float64]
    fits: tuple[CircleFit, ...]
    angles: NDArray[np.float64]
    swept: float


def _as_frames_points(points: NDArray, name: str) -> NDArray[np.float64]:
    points = np.asarray(points, dtype=float)
    if points.ndim == 2:
        points = points[:, None, :]
    if points.ndim != 3 or points.shape[2] != 3:
        raise IdentificationError(f"{name}: expected (frames, 3) or (frames, k, 3) positions, got {points.shape}")
    return points


def fit_link_axis(points: NDArray, name: str = "link") -> LinkAxisFit:
    """Axis of a link turning about a fixed line, from one or several tracked points.

    Each point gets its own PCA/circle fit; the axis direction is the radius-weighted mean
    of their normals (signs aligned), its point the weighted mean of the centres, and the
    rotation angle per frame the weighted circular mean of the points' angle changes.
    """
    points = _as_frames_points(points, name)
    fits = [fit_circle(points[:, k], f"{name}, point {k}") for k in range(points.shape[1])]
    radii = np.array([f.radius for f in fits])
    worst = max(fits, key=lambda f: f.circle_rms / f.radius)
    if worst.circle_rms > MAX_CIRCLE_RMS * worst.radius:
        raise IdentificationError(
            f"{name}: the tracked path is not a circle (RMS deviation {1e3 * worst.circle_rms:.3g} mm on a "
            f"radius of {1e3 * worst.radius:.3g} mm): the link barely moves, or does not turn about a fixed axis"
        )
    usable = radii > 1e-3 * radii.max()  # points on the axis carry no direction information
    reference = fits[int(np.argmax(radii))].normal
    normals = np.array([f.normal * np.sign(f.normal @ reference) for f in fits])
    weights = radii * usable
    direction = (weights[:, None] * normals).sum(axis=0)
    direction /= np.linalg.norm(direction)
    centre = (weights[:, None] * np.array([f.centre for f in fits])).sum(axis=0) / weights.sum()
    # Angle of each point about the common axis, relative to frame 0.
    e_x = fits[int(np.argmax(radii))].e_x
    e_x = e_x - (e_x @ direction) * direction
    e_x /= np.linalg.norm(e_x)
    e_y = np.cross(direction, e_x)
    rel = points - centre
    phase = np.arctan2(rel @ e_y, rel @ e_x)  # (frames, k)
    change = np.unwrap(phase - phase[:1], axis=0)
    angles = np.arctan2((weights * np.sin(change)).sum(axis=1), (weights * np.cos(change)).sum(axis=1))
    angles = np.unwrap(angles)
    swept = float(np.ptp(angles))
    if swept < MIN_SWEPT_ANGLE:
        raise IdentificationError(
            f"{name} turns only {np.degrees(swept):.2f} deg about its axis; at least "
            f"{np.degrees(MIN_SWEPT_ANGLE):.0f} deg are needed to fit a joint axis (record a longer motion)"
        )
    return LinkAxisFit(Line.from_point_direction(centre, direction), centre, tuple(fits), angles, swept)


def moving_frames(centre: NDArray, direction: NDArray, x_directions: NDArray) -> NDArray[np.float64]:
    r"""Frames :math:`T_{i,j}` (``(frames, 4, 4)``): origin ``centre``, z = ``direction``, x = ``x_directions[j]``."""
    z = direction / np.linalg.norm(direction)
    x = x_directions - (x_directions @ z)[:, None] * z
    x /= np.linalg.norm(x, axis=1, keepdims=True)
    y = np.cross(z, x)
    frames = np.zeros((x.shape[0], 4, 4))
    frames[:, :3, 0], frames[:, :3, 1], frames[:, :3, 2], frames[:, :3, 3] = x, y, z, centre
    frames[:, 3, 3] = 1.0
    return frames


def project_into_previous_frame(link_fit: LinkAxisFit, points: NDArray) -> NDArray[np.float64]:
    r"""Paper's Eq. projection :math:`p^* = T_i T_{i,j}^{-1} p` for points ``(frames, k, 3)``."""
    direction = link_fit.axis.direction
    e_x = link_fit.fits[0].e_x - (link_fit.fits[0].e_x @ direction) * direction
    e_x /= np.linalg.norm(e_x)
    e_y = np.cross(direction, e_x)
    x_directions = np.cos(link_fit.angles)[:, None] * e_x + np.sin(link_fit.angles)[:, None] * e_y
    frames = moving_frames(link_fit.centre, direction, x_directions)
    undo = frames[0] @ np.linalg.inv(frames)  # T_i T_{i,j}^{-1}
    return np.einsum("jab,jkb->jka", undo[:, :3, :3], points) + undo[:, None, :3, 3]


def identify_branch(link_points: list[NDArray], names: list[str]) -> list[LinkAxisFit]:
    """Axes along one branch, from the base outwards: ``link_points[i]`` are the tracked
    positions ``(frames, k, 3)`` of the ``i``-th link after the base."""
    if len(link_points) != len(names):
        raise ValueError("one name per link is needed")
    remaining = [_as_frames_points(p, n) for p, n in zip(link_points, names, strict=True)]
    frames = {p.shape[0] for p in remaining}
    if len(frames) != 1:
        raise IdentificationError(f"all links must have the same number of frames, got {sorted(frames)}")
    fits = []
    for i, name in enumerate(names):
        fit = fit_link_axis(remaining[i], name)
        fits.append(fit)
        remaining = [project_into_previous_frame(fit, p) if k > i else p for k, p in enumerate(remaining)]
    return fits
