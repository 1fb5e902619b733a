r"""Quaternion algebra on plain arrays, scalar first.

A quaternion is stored as ``q = [q0, q1, q2, q3]`` meaning ``q0 + q1 i + q2 j + q3 k``
with :math:`i^2 = j^2 = k^2 = ijk = -1`. Every function works on arrays of shape
``(..., 4)`` and broadcasts over the leading axes.

Rotations are *active*: the unit quaternion ``p`` acts on a vector ``x`` (embedded
as the pure quaternion ``0 + x``) by :math:`x \mapsto p\,x\,\tilde p`, where
:math:`\tilde p` is the conjugate. ``cos(phi/2) + sin(phi/2) n`` rotates by ``phi``
about the unit axis ``n`` (right-hand rule).

Conversions between quaternions and rotation matrices use
:class:`scipy.spatial.transform.Rotation` (with ``scalar_first=True``).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

__all__ = [
    "quaternion_product",
    "quaternion_conjugate",
    "quaternion_to_matrix",
    "matrix_to_quaternion",
    "axis_angle_quaternion",
    "rotation_vector",
]


def quaternion_product(p: ArrayLike, q: ArrayLike) -> NDArray[np.float64]:
    r"""Hamilton product :math:`pq = (p_0 q_0 - \mathbf p\cdot\mathbf q,\;
    p_0\mathbf q + q_0\mathbf p + \mathbf p\times\mathbf q)`.

    Hamilton's rules :math:`ij = k = -ji`:

    >>> quaternion_product([0, 1, 0, 0], [0, 0, 1, 0]).tolist()
    [0.0, 0.0, 0.0, 1.0]
    >>> quaternion_product([0, 0, 1, 0], [0, 1, 0, 0]).tolist()
    [0.0, 0.0, 0.0, -1.0]
    """
    p = np.asarray(p, dtype=float)
    q = np.asarray(q, dtype=float)
    p0, pv = p[..., :1], p[..., 1:]
    q0, qv = q[..., :1], q[..., 1:]
    scalar = p0 * q0 - np.sum(pv * qv, axis=-1, keepdims=True)
    vector = p0 * qv + q0 * pv + np.cross(pv, qv)
    return np.concatenate([scalar, vector], axis=-1)


def quaternion_conjugate(q: ArrayLike) -> NDArray[np.float64]:
    r"""Conjugate :math:`\tilde q = q_0 - q_1 i - q_2 j - q_3 k`."""
    q = np.array(q, dtype=float)
    q[..., 1:] *= -1.0
    return q


def quaternion_to_matrix(p: ArrayLike) -> NDArray[np.float64]:
    r"""Rotation matrix ``R`` with :math:`R x = p x \tilde p / (p \tilde p)`.

    ``p`` need not be normalised; its norm is divided out. A quarter turn about z takes x to y:

    >>> quaternion_to_matrix(axis_angle_quaternion([0, 0, 1], np.pi / 2)).round(12).tolist()
    [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    """
    p = np.asarray(p, dtype=float)
    flat = p.reshape(-1, 4)
    if np.any(np.linalg.norm(flat, axis=1) == 0.0):
        raise ValueError("the zero quaternion is not a rotation; check the primal part")
    matrices = Rotation.from_quat(flat, scalar_first=True).as_matrix()
    return matrices.reshape(p.shape[:-1] + (3, 3))


def matrix_to_quaternion(rotation: ArrayLike) -> NDArray[np.float64]:
    """Unit quaternion (scalar first, sign chosen with ``q0 >= 0``) of a rotation matrix."""
    rotation = np.asarray(rotation, dtype=float)
    flat = rotation.reshape(-1, 3, 3)
    q = Rotation.from_matrix(flat).as_quat(canonical=True, scalar_first=True)
    return q.reshape(rotation.shape[:-2] + (4,))


def rotation_vector(matrix: NDArray[np.float64]) -> NDArray[np.float64]:
    """The rotation vector (axis times angle in [0, pi]) of a rotation matrix, through its unit quaternion by
    Shepperd's choice of the largest of w, x, y, z (Shepperd, J. Guidance Control 1(3), 1978): what scipy's
    ``Rotation.from_matrix(...).as_rotvec()`` gives, without its checks and conversions, which took a third of the
    time of tracing a rigid loop's motion (:func:`kinematics.single_loop.follow_driver`)."""
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = matrix.tolist()
    trace = r00 + r11 + r22
    largest = max(trace, r00, r11, r22)
    if largest == trace:
        w = 0.5 * math.sqrt(1.0 + trace)
        x, y, z = (r21 - r12) / (4.0 * w), (r02 - r20) / (4.0 * w), (r10 - r01) / (4.0 * w)
    elif largest == r00:
        x = 0.5 * math.sqrt(1.0 + r00 - r11 - r22)
        w, y, z = (r21 - r12) / (4.0 * x), (r01 + r10) / (4.0 * x), (r02 + r20) / (4.0 * x)
    elif largest == r11:
        y = 0.5 * math.sqrt(1.0 - r00 + r11 - r22)
        w, x, z = (r02 - r20) / (4.0 * y), (r01 + r10) / (4.0 * y), (r12 + r21) / (4.0 * y)
    else:
        z = 0.5 * math.sqrt(1.0 - r00 - r11 + r22)
        w, x, y = (r10 - r01) / (4.0 * z), (r02 + r20) / (4.0 * z), (r12 + r21) / (4.0 * z)
    if w < 0.0:
        w, x, y, z = -w, -x, -y, -z
    sine = math.sqrt(x * x + y * y + z * z)
    if sine == 0.0:
        return np.zeros(3)
    scale = 2.0 * math.atan2(sine, w) / sine
    return np.array([scale * x, scale * y, scale * z])


def axis_angle_quaternion(axis: ArrayLike, angle: ArrayLike) -> NDArray[np.float64]:
    r"""``cos(angle/2) + sin(angle/2) n`` for the unit vector ``n`` along ``axis``."""
    axis = np.asarray(axis, dtype=float)
    norm = np.linalg.norm(axis, axis=-1, keepdims=True)
    if np.any(norm == 0.0):
        raise ValueError("rotation axis has zero length")
    half = 0.5 * np.asarray(angle, dtype=float)[..., None]
    return np.concatenate([np.cos(half), np.sin(half) * axis / norm], axis=-1)
