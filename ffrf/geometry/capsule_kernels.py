r"""Numba kernel: the clearances of many capsule pairs at many poses, in one pass.

The same closest points as :func:`ffrf.geometry.link_capsules.closest_points` (Ericson, *Real-Time Collision
Detection*, 2005, Sect. 5.1.9; ``docs/formulation.md``, (CF2)), per pair without numpy's temporaries: the design of
collision-free links (:mod:`ffrf.scenes.collision_free`) evaluates some :math:`10^4` pairs at each of :math:`10^2`
poses for each of :math:`10^4` candidate stackings.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["capsule_clearances"]

_TINY = 1e-30


@njit(cache=True)
def _segment_distance(starts: np.ndarray, ends: np.ndarray, k: int, i: int, j: int) -> float:
    """Distance at pose ``k`` between segments ``i`` and ``j`` of ``starts``/``ends`` ``(m, K, 3)``, as
    ``closest_points`` (indices rather than views: no array is made per pair)."""
    u0, u1, u2 = ends[k, i, 0] - starts[k, i, 0], ends[k, i, 1] - starts[k, i, 1], ends[k, i, 2] - starts[k, i, 2]
    v0, v1, v2 = ends[k, j, 0] - starts[k, j, 0], ends[k, j, 1] - starts[k, j, 1], ends[k, j, 2] - starts[k, j, 2]
    w0 = starts[k, i, 0] - starts[k, j, 0]
    w1 = starts[k, i, 1] - starts[k, j, 1]
    w2 = starts[k, i, 2] - starts[k, j, 2]
    a = u0 * u0 + u1 * u1 + u2 * u2
    b = u0 * v0 + u1 * v1 + u2 * v2
    c = u0 * w0 + u1 * w1 + u2 * w2
    e = v0 * v0 + v1 * v1 + v2 * v2
    f = v0 * w0 + v1 * w1 + v2 * w2
    denominator = a * e - b * b
    s = 0.0
    if e > _TINY:
        if denominator > 1e-12 * max(a * e, _TINY):
            s = min(max((b * f - c * e) / denominator, 0.0), 1.0)
    elif a > _TINY:
        s = min(max(-c / a, 0.0), 1.0)  # q is a point: the nearest point of p's segment
    if a <= _TINY:
        s = 0.0
    t = (b * s + f) / e if e > _TINY else 0.0
    if t < 0.0:
        t = 0.0
        s = min(max(-c / a, 0.0), 1.0) if a > _TINY else 0.0
    elif t > 1.0:
        t = 1.0
        s = min(max((b - c) / a, 0.0), 1.0) if a > _TINY else 0.0
    g0, g1, g2 = w0 + s * u0 - t * v0, w1 + s * u1 - t * v1, w2 + s * u2 - t * v2
    return np.sqrt(g0 * g0 + g1 * g1 + g2 * g2)


@njit(cache=True)
def capsule_clearances(
    starts: np.ndarray, ends: np.ndarray, radii: np.ndarray, first: np.ndarray, second: np.ndarray
) -> np.ndarray:
    """Clearances ``(m, P)`` of capsule pairs ``(first[p], second[p])`` at every pose: segment ends ``starts``,
    ``ends`` ``(m, K, 3)``, radii ``(K,)``; distance of the segments less both radii."""
    m, pairs = starts.shape[0], first.shape[0]
    out = np.empty((m, pairs))
    for k in range(m):
        for p in range(pairs):
            i, j = first[p], second[p]
            out[k, p] = _segment_distance(starts, ends, k, i, j) - radii[i] - radii[j]
    return out
