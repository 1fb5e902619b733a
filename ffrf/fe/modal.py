"""Clamped modes: the lowest eigenmodes of a body with some DOFs held at zero.

The generalised eigenproblem K phi = omega^2 M phi on the free DOFs is solved with scipy's
``eigsh`` in shift-invert mode about a small negative shift, so that the eigenvalues closest to
it are the lowest ones. Free-free modes (the rigid-body modes left out) are
:func:`ffrf.reduction.free_free.free_free_basis`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ffrf.errors import FEInputError
from ffrf.fe.fe_model import FEModel
from ffrf.numerics.eigen import SHIFT_REL, eigenvalue_scale, fix_signs, shift_invert_eigsh

__all__ = ["Modes", "clamped_modes"]


@dataclass(frozen=True, eq=False)
class Modes:
    """Result of :func:`clamped_modes`.

    Attributes
    ----------
    frequencies : (n,) natural frequencies in Hz, ascending.
    shapes : (3N, n) mass-normalised mode shapes (phi^T M phi = I), zero at the fixed DOFs.
    """

    frequencies: NDArray[np.float64]
    shapes: NDArray[np.float64]


def clamped_modes(fe_model: FEModel, fixed_dofs: ArrayLike, n_modes: int = 10) -> Modes:
    """Lowest ``n_modes`` modes of ``fe_model`` with the DOFs ``fixed_dofs`` held at zero.

    Shapes are returned on all DOFs (zeros at the fixed ones).
    """
    fixed = np.unique(np.asarray(fixed_dofs, dtype=np.int64))
    name = fe_model.mesh.name
    if fixed.size == 0:
        raise FEInputError(
            f"{name}: clamped_modes needs at least one fixed DOF; "
            "use ffrf.reduction.free_free.free_free_basis for an unsupported body"
        )
    if fixed.min() < 0 or fixed.max() >= fe_model.n_dofs:
        raise FEInputError(f"{name}: fixed DOF index out of range [0, {fe_model.n_dofs})")
    if n_modes < 1:
        raise FEInputError(f"n_modes={n_modes!r} must be >= 1")
    free = np.setdiff1d(np.arange(fe_model.n_dofs), fixed)
    if n_modes >= len(free) - 1:
        raise FEInputError(
            f"{n_modes} modes requested but the model has only {len(free)} free DOFs; "
            "refine the mesh or ask for fewer modes"
        )
    k_ff = fe_model.stiffness[free][:, free]
    m_ff = fe_model.mass[free][:, free]
    sigma = -SHIFT_REL * eigenvalue_scale(fe_model.mass, fe_model.stiffness)
    values, vectors = shift_invert_eigsh(k_ff.tocsc(), m_ff.tocsc(), n_modes, sigma)
    shapes = np.zeros((fe_model.n_dofs, n_modes))
    shapes[free] = fix_signs(vectors)
    return Modes(np.sqrt(np.clip(values, 0.0, None)) / (2 * np.pi), shapes)
