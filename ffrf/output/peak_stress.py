r"""A link's peak von Mises stress as a function of its modal coordinates, with its exact gradient
(``docs/formulation.md``, Eq. (D9)).

The strain at the corners of every element is linear in the link's elastic displacement :math:`u = \Psi\zeta`, so
it is a sum of *strain modes*, :math:`\varepsilon = \sum_j \zeta_j\,\varepsilon_j` (each mode's corner strains,
:meth:`ffrf.fe.fe_model.FEModel.vertex_strains`; their extremes in a P1 or P2 element are at its corners). The von
Mises stress :math:`v = \sqrt{3/2\; s:s}` of :math:`s = 2\mu\,\mathrm{dev}\,\varepsilon` then has the gradient

.. math:: \frac{\partial v}{\partial \zeta_j} = \frac{3\mu}{v}\; s : \varepsilon_j

at the corner where it is largest (the peak's derivative where that corner is the only one at the peak: a
maximum is differentiable only there, and elsewhere this is the derivative of the branch that holds it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ffrf.fe.fe_model import FEModel
from ffrf.reduction.component_modes_post import von_mises_stress

__all__ = ["PeakStress", "corner_stress", "peak_stress", "strain_modes"]


def strain_modes(fe: FEModel, basis: ArrayLike) -> NDArray[np.float64]:
    """The corner strains of each mode (column of ``basis``, ``(3N, m)``): ``(n_tets, 4, 3, 3, m)``."""
    basis = np.asarray(basis, dtype=float)
    return np.stack([fe.vertex_strains(basis[:, j]) for j in range(basis.shape[1])], axis=-1)


@dataclass(frozen=True)
class PeakStress:
    """The largest von Mises stress ``value`` (Pa) over a link's element corners, where (``element``, ``corner``),
    and its gradient by the link's modal coordinates (Pa per unit coordinate)."""

    value: float
    element: int
    corner: int
    gradient: NDArray[np.float64]


def peak_stress(modes: NDArray, zeta: ArrayLike, E: float, nu: float) -> PeakStress:
    """:class:`PeakStress` of the link whose strain modes are ``modes`` (:func:`strain_modes`) at the modal
    coordinates ``zeta``, of Young's modulus ``E`` and Poisson's ratio ``nu`` (module docstring)."""
    strain = modes @ np.asarray(zeta, dtype=float)
    stress = von_mises_stress(strain, E, nu)
    element, corner = np.unravel_index(int(np.argmax(stress)), stress.shape)
    value = float(stress[element, corner])
    mu = E / (2.0 * (1.0 + nu))
    local = strain[element, corner]
    deviator = 2.0 * mu * (local - np.trace(local) / 3.0 * np.eye(3))
    gradient = (
        3.0 * mu / value * np.einsum("ab,abj->j", deviator, modes[element, corner])
        if value > 0.0
        else np.zeros(modes.shape[-1])
    )
    return PeakStress(value, int(element), int(corner), gradient)


def corner_stress(fe: FEModel, basis: ArrayLike, zeta: ArrayLike, element: int, corner: int) -> float:
    """The von Mises stress (Pa) at one element's corner of the link ``fe`` with mode ``basis`` at coordinates
    ``zeta``."""
    strain = fe.vertex_strains(np.asarray(basis, dtype=float) @ np.asarray(zeta, dtype=float))[element, corner]
    return float(von_mises_stress(strain, fe.material.E, fe.material.nu))
