"""Generalized symmetric eigenproblems K x = lambda M x that give the same answer on every run.

ARPACK's ``eigsh`` starts Lanczos from a random vector unless given one, so two identical runs
differed (Craig-Bampton bases by 1.4e-11, a near-rigid loop's driving torque by 1.5e-6 N m).
Here Lanczos always starts from :func:`lanczos_start`, and every mode's sign follows
:func:`fix_signs`, so a rerun on the same machine reproduces every bit.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.sparse.linalg import eigsh

__all__ = ["fix_signs", "lanczos_start", "shift_invert_eigsh"]

_START_SEED = 20261124
_SIGN_BAND = 1e-6  # entries this close (relative) to the largest magnitude compete for deciding the sign


def lanczos_start(size: int) -> NDArray[np.float64]:
    """A fixed start vector: seeded normal entries, so that no mode is missed by symmetry (a
    constant vector is orthogonal to the antisymmetric modes of a symmetric mesh)."""
    return np.random.default_rng(_START_SEED).standard_normal(size)


def fix_signs(vectors: NDArray) -> NDArray[np.float64]:
    """Each column turned so that its first entry of (nearly) largest magnitude is positive.

    "First within 1e-6 of the largest" rather than "the largest": symmetric meshes have mode
    shapes whose extreme entries come in mirrored pairs of opposite sign that round-off orders at
    random."""
    vectors = np.array(vectors, dtype=float)
    magnitude = np.abs(vectors)
    if vectors.size == 0:
        return vectors
    deciding = np.argmax(magnitude >= (1.0 - _SIGN_BAND) * magnitude.max(axis=0), axis=0)
    signs = np.sign(vectors[deciding, np.arange(vectors.shape[1])])
    return vectors * np.where(signs < 0.0, -1.0, 1.0)


def shift_invert_eigsh(stiffness: Any, mass: Any, k: int, sigma: float, opinv: Any = None):
    """The ``k`` eigenpairs nearest ``sigma`` (ARPACK shift-invert, deterministic start), ascending."""
    values, vectors = eigsh(
        stiffness, k=k, M=mass, sigma=sigma, which="LM", OPinv=opinv, v0=lanczos_start(stiffness.shape[0])
    )
    order = np.argsort(values)
    return values[order], vectors[:, order]
