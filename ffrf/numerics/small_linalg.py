"""Products of small arrays as plain loops, for the numba kernels.

Inside a kernel, ``@`` calls BLAS: about a microsecond of call overhead and, for strided views
such as columns, a copy, on products of 3 x 3 to 3 x 20 arrays that take a few nanoseconds. These
loops do the same arithmetic (sums in index order, any layout, float64 or complex128; all
arguments of one call share one dtype) without the call. Tested against numpy in
``tests/test_ffrf_body/test_small_linalg.py``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["dot", "mat_vec", "vec_mat", "mat_mat", "cross3", "skew"]


@njit(cache=True)
def dot(u: np.ndarray, v: np.ndarray):
    """``u @ v`` of two vectors."""
    total = u.dtype.type(0)
    for i in range(u.shape[0]):
        total += u[i] * v[i]
    return total


@njit(cache=True)
def mat_vec(a: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``a @ v``."""
    out = np.empty(a.shape[0], dtype=a.dtype)
    for i in range(a.shape[0]):
        total = a.dtype.type(0)
        for k in range(a.shape[1]):
            total += a[i, k] * v[k]
        out[i] = total
    return out


@njit(cache=True)
def vec_mat(v: np.ndarray, a: np.ndarray) -> np.ndarray:
    """``v @ a``, i.e. ``a.T @ v``."""
    out = np.zeros(a.shape[1], dtype=a.dtype)
    for k in range(a.shape[0]):
        vk = v[k]
        for j in range(a.shape[1]):
            out[j] += vk * a[k, j]
    return out


@njit(cache=True)
def mat_mat(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a @ b``."""
    out = np.zeros((a.shape[0], b.shape[1]), dtype=a.dtype)
    for i in range(a.shape[0]):
        for k in range(a.shape[1]):
            aik = a[i, k]
            for j in range(b.shape[1]):
                out[i, j] += aik * b[k, j]
    return out


@njit(cache=True)
def cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a x b`` of two 3-vectors (also fast from Python: ``np.cross`` spends ~20 us per call on
    its axis handling).

    >>> cross3(np.array([1.0, 2.0, 3.0]), np.array([4.0, 5.0, 6.0])).tolist()  # (2*6 - 3*5, 3*4 - 1*6, 1*5 - 2*4)
    [-3.0, 6.0, -3.0]
    """
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


@njit(cache=True)
def skew(v: np.ndarray) -> np.ndarray:
    r"""Skew matrix :math:`\tilde v` with :math:`\tilde v w = v \times w`, in ``v``'s dtype.

    A numba kernel; from Python it takes any 1-D array of three floats or complex numbers.

    >>> s = skew(np.array([1.0, 2.0, 3.0]))
    >>> (s @ np.array([4.0, 5.0, 6.0])).tolist(), bool((s == -s.T).all())
    ([-3.0, 6.0, -3.0], True)
    """
    out = np.zeros((3, 3), dtype=v.dtype)
    out[0, 1], out[0, 2] = -v[2], v[1]
    out[1, 0], out[1, 2] = v[2], -v[0]
    out[2, 0], out[2, 1] = -v[1], v[0]
    return out
