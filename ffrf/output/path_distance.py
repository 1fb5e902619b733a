r"""Distance of points to a closed curve given exactly, not by a fixed sampling.

The ideal coupler curve of a linkage is a function :math:`p(\theta)` of the drive angle over one period (the motion
polynomial of a Bennett linkage, or the rigid loop closed at that angle, ``docs/formulation.md`` (L4)). Its
samples :math:`p_j = p(\theta_j)` only bound the distance from above; between two samples the chord is off the
curve by up to the sagitta, about :math:`|p_{j+1} - 2p_j + p_{j-1}|/8`, which is millimetres where the coupler
moves fast (issue #32: 1.7 mm for a run that follows the curve to 1e-15 m). The distance here is exact to a
tolerance (Eq. (C1) of ``docs/formulation.md``):

.. math:: d(x) = \min_\theta |p(\theta) - x| ,

found in two steps. (1) Candidates: the nearest sample gives the upper bound :math:`U = \min_j |p_j - x|`; every
arc whose chord lies closer than :math:`U` plus the arc's own deviation bound :math:`e_j` (four times the sagitta
estimate, so a safety factor of 4) may hold the minimum. (2) On each candidate arc
:math:`\theta \in [\theta_j, \theta_{j+1}]`, from the chord's closest point, Newton's method on
:math:`f(\theta) = \tfrac12 |p(\theta) - x|^2`: :math:`f' = (p - x)\cdot p'`, :math:`f'' = |p'|^2 + (p - x)\cdot p''`
with :math:`p', p''` from central differences of the exact :math:`p` (an error of the derivatives moves the
stationary point only to second order in the distance, and not at all when the point is on the curve), each step
clipped to the arc, until the step moves the curve point by less than the tolerance. The distance is that of the
last exact curve point, so it is never below the true one by more than the tolerance; the smallest over the
candidates (and the nearest sample) is the result. All points and arcs are refined together (vectorised).
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

__all__ = ["ExactCurve", "PathDistance", "distance_to_curve"]

log = logging.getLogger(__name__)

#: Central-difference step of the curve's derivatives (rad): the truncation error ``h^2 p'''`` and the round-off
#: ``eps |p| / h`` of ``p'`` are both near 1e-10 of ``|p'|`` for a curve of about unit angular scale.
DERIVATIVE_STEP = 1e-5
#: Newton iterations per arc; from the chord's closest point it converges in 3 to 5.
MAX_ITERATIONS = 30


@dataclass(frozen=True)
class ExactCurve:
    r"""A closed curve :math:`p(\theta)` of period ``period`` (rad): ``angles`` ``(m,)`` increasing over one period
    and the curve's ``points`` ``(m, 3)`` there (m), and ``exact(angles, arcs) -> (k, 3)``, the curve at any angles,
    each within (or a derivative step beyond) arc ``arcs[i]`` (between samples ``arcs[i]`` and ``arcs[i] + 1``,
    the last arc closing the period); a function that continues from a sample uses ``arcs`` as its start."""

    angles: NDArray[np.float64]
    points: NDArray[np.float64]
    period: float
    exact: Callable[[NDArray[np.float64], NDArray[np.int64]], NDArray[np.float64]]

    @property
    def arc_ends(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Start and end angles of the ``m`` arcs (the last one ends at ``angles[0] + period``)."""
        return self.angles, np.append(self.angles[1:], self.angles[0] + self.period)

    def arc_deviation_bound(self) -> NDArray[np.float64]:
        """Bound ``e_j`` on how far arc ``j`` strays from its chord (m): half the larger second difference of the
        samples at its ends, four times the circle's sagitta ``|p_{j+1} - 2 p_j + p_{j-1}| / 8``."""
        p = self.points
        second = np.linalg.norm(np.roll(p, -1, axis=0) - 2.0 * p + np.roll(p, 1, axis=0), axis=1)
        return 0.5 * np.maximum(second, np.roll(second, -1))


@dataclass(frozen=True)
class PathDistance:
    """Per point: the distance to the curve (m), the angle of the closest curve point (rad) and whether Newton's
    method converged there (when not, the distance is still an upper bound: that of an exact curve point)."""

    distance: NDArray[np.float64]
    angle: NDArray[np.float64]
    converged: NDArray[np.bool_]


def distance_to_curve(points: NDArray, curve: ExactCurve, tolerance: float = 1e-12) -> PathDistance:
    """Distance of each of ``points`` ``(k, 3)`` to ``curve`` (Eq. (C1), module docstring), to ``tolerance`` (m)."""
    points = np.asarray(points, dtype=float)
    samples, (start, end) = curve.points, curve.arc_ends
    following = np.roll(samples, -1, axis=0)
    chord = following - samples
    chord2 = np.maximum(np.einsum("ij,ij->i", chord, chord), np.finfo(float).tiny)
    bound = curve.arc_deviation_bound()
    tree = cKDTree(samples)
    upper, nearest = tree.query(points)
    # A chord within U + e_j of x has its first sample within U + e_j + |chord_j| of x.
    reach = upper + float(np.max(bound + np.sqrt(chord2))) * (1.0 + 1e-12)
    owners, arcs = [], []
    for k, near in enumerate(tree.query_ball_point(points, reach)):
        candidates = np.unique(np.concatenate([near, np.asarray(near, dtype=int) - 1]) % len(samples))
        owners.append(np.full(len(candidates), k))
        arcs.append(candidates)
    owner, arc = np.concatenate(owners), np.concatenate(arcs).astype(np.int64)
    rel = points[owner] - samples[arc]
    s = np.clip(np.einsum("ij,ij->i", rel, chord[arc]) / chord2[arc], 0.0, 1.0)
    gap = np.linalg.norm(rel - s[:, None] * chord[arc], axis=1)
    keep = gap <= upper[owner] + bound[arc]
    owner, arc, s = owner[keep], arc[keep], s[keep]
    low, high = start[arc], end[arc]
    theta, distance, converged = _newton_on_arcs(
        curve, points[owner], arc, low + s * (high - low), low, high, tolerance
    )
    best = np.array(upper)
    angle = np.array(curve.angles[nearest])
    done = np.ones(len(points), dtype=bool)
    order = np.lexsort((distance, owner))  # per point, its candidates by distance, the smallest first
    first = order[np.unique(owner[order], return_index=True)[1]]
    better = distance[first] < best[owner[first]]
    best[owner[first][better]] = distance[first][better]
    angle[owner[first][better]] = theta[first][better]
    done[owner[first]] = converged[first]
    if not np.all(done):
        log.warning("distance to the ideal path: Newton's method did not converge at %d points", int(np.sum(~done)))
    return PathDistance(best, angle, done)


def _newton_on_arcs(
    curve: ExactCurve,
    targets: NDArray,
    arcs: NDArray[np.int64],
    theta: NDArray,
    low: NDArray,
    high: NDArray,
    tolerance: float,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
    """Minimise ``|p(theta) - target|`` on each arc ``[low, high]`` by clipped Newton steps (module docstring);
    returns the angles, the distances of their exact curve points and which converged."""
    h = DERIVATIVE_STEP
    theta = np.array(theta, dtype=float)
    distance = np.full(len(theta), np.inf)
    converged = np.zeros(len(theta), dtype=bool)
    active = np.arange(len(theta))
    for _ in range(MAX_ITERATIONS):
        if active.size == 0:
            break
        t, a = theta[active], arcs[active]
        p = curve.exact(np.concatenate([t - h, t, t + h]), np.concatenate([a, a, a])).reshape(3, len(t), 3)
        behind, here, ahead = p
        offset = here - targets[active]
        distance[active] = np.linalg.norm(offset, axis=1)
        d1 = (ahead - behind) / (2.0 * h)
        d2 = (ahead - 2.0 * here + behind) / (h * h)
        speed2 = np.einsum("ij,ij->i", d1, d1)
        slope = np.einsum("ij,ij->i", offset, d1)
        curvature = speed2 + np.einsum("ij,ij->i", offset, d2)
        # Where f'' <= 0 (far from the curve, beyond a centre of curvature) Gauss-Newton's step still descends.
        step = -slope / np.where(curvature > 0.0, curvature, np.maximum(speed2, np.finfo(float).tiny))
        moved = np.clip(t + step, low[active], high[active]) - t
        theta[active] = t + moved
        # The curve point moves by about |p'| |step|; below the tolerance the distance is final.
        small = np.abs(moved) * np.sqrt(speed2) <= tolerance
        converged[active[small]] = True
        active = active[~small]
    # The last steps' curve points: within the tolerance of the minimum (Newton's next step would be far smaller).
    final = curve.exact(theta, arcs)
    return theta, np.minimum(distance, np.linalg.norm(final - targets, axis=1)), converged
