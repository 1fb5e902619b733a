r"""A link's peak von Mises stress as a function of its modal coordinates, with its exact gradient
(``docs/formulation.md``, Eq. (D9)).

The strain at the corners of every element is linear in the link's elastic displacement :math:`u = \Psi\zeta`, so
it is a sum of *strain modes*, :math:`\varepsilon = \sum_j \zeta_j\,\varepsilon_j` (each mode's corner strains,
:meth:`ffrf.fe.fe_model.FEModel.vertex_strains`; their extremes in a P1 or P2 element are at its corners). The von
Mises stress :math:`v = \sqrt{3/2\; s:s}` of :math:`s = 2\mu\,\mathrm{dev}\,\varepsilon` then has the gradient

.. math:: \frac{\partial v}{\partial \zeta_j} = \frac{3\mu}{v}\; s : \varepsilon_j

at the corner where it is largest (the peak's derivative where that corner is the only one at the peak: a
maximum is differentiable only there, and elsewhere this is the derivative of the branch that holds it).

A bound on the peak is a bound on a maximum over corners, whose gradient jumps where another corner takes the peak
over; a design bounds instead the p-norm of the corner stresses (Eq. (D10)),

.. math:: \|v\|_p = \Big(\sum_i v_i^p\Big)^{1/p},\qquad
          \frac{\partial \|v\|_p}{\partial \zeta_j} = \sum_i \Big(\frac{v_i}{\|v\|_p}\Big)^{p-1}
          \frac{\partial v_i}{\partial \zeta_j},

smooth wherever the stress is not zero everywhere, never below the peak and at most :math:`N^{1/p}` times it for
:math:`N` corners (measured on the PLA Bennett's links with p = 32: 3e-5 to 2 % above the peak).

Where the elastic stress is singular (re-entrant edges) the corner values grow as the mesh is refined; with an
``average`` (:class:`~ffrf.output.stress_average.BallAverage`, Eq. (D14)) the same functions take the strain
averaged over a ball of material around each vertex instead, one 'corner' per vertex: finite, converging, and
linear in the modal coordinates as the corner strains are.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ffrf.fe.fe_model import FEModel
from ffrf.output.stress_average import BallAverage
from ffrf.reduction.component_modes_post import von_mises_stress

__all__ = [
    "STRESS_NORM_POWER",
    "PeakStress",
    "StressNorm",
    "corner_stress",
    "peak_stress",
    "p_norm",
    "strain_modes",
    "stress_norm",
    "stress_norm_at",
]

#: The power p of the stress norm of Eq. (D10): a design's stress bound holds the norm, 3e-5 to 2 % above the peak on
#: the PLA Bennett's links (their peaks sit at one or two corners), 0.2 to 5 % with p = 16, 0.2 to 24 % with p = 8.
STRESS_NORM_POWER = 32


def strain_modes(fe: FEModel, basis: ArrayLike, average: BallAverage | None = None) -> NDArray[np.float64]:
    """The corner strains of each mode (column of ``basis``, ``(3N, m)``): ``(n_tets, 4, 3, 3, m)``; with an
    ``average``, the averaged strains of Eq. (D14), ``(vertices, 1, 3, 3, m)``."""
    basis = np.asarray(basis, dtype=float)
    modes = np.stack([fe.vertex_strains(basis[:, j]) for j in range(basis.shape[1])], axis=-1)
    return modes if average is None else average.strains(fe, modes)


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


def corner_stress(
    fe: FEModel, basis: ArrayLike, zeta: ArrayLike, element: int, corner: int, average: BallAverage | None = None
) -> float:
    """The von Mises stress (Pa) at one element's corner of the link ``fe`` with mode ``basis`` at coordinates
    ``zeta``; with an ``average``, the averaged stress at its centre ``element`` (``corner`` 0)."""
    strain = _strains(fe, np.asarray(basis, dtype=float) @ np.asarray(zeta, dtype=float), average)[element, corner]
    return float(von_mises_stress(strain, fe.material.E, fe.material.nu))


def _strains(fe: FEModel, displacement: NDArray, average: BallAverage | None) -> NDArray[np.float64]:
    """The corner strains of ``displacement``, or their averages of Eq. (D14)."""
    corners = fe.vertex_strains(displacement)
    return corners if average is None else average.strains(fe, corners)


def p_norm(values: NDArray, power: float = STRESS_NORM_POWER) -> float:
    """``(sum values^power)^(1/power)`` of non-negative ``values``, scaled by their largest so that no power
    overflows; 0 for all zero."""
    peak = float(np.max(values))
    if not peak > 0.0:
        return 0.0
    return peak * float(np.sum((np.asarray(values) / peak) ** power)) ** (1.0 / power)


@dataclass(frozen=True)
class StressNorm:
    """The p-norm ``value`` of a link's corner stresses (Pa, Eq. (D10)) and its gradient by the link's modal
    coordinates (Pa per unit coordinate)."""

    value: float
    gradient: NDArray[np.float64]


def stress_norm(modes: NDArray, zeta: ArrayLike, E: float, nu: float, power: float = STRESS_NORM_POWER) -> StressNorm:
    """:class:`StressNorm` of the link whose strain modes are ``modes`` (:func:`strain_modes`) at the modal
    coordinates ``zeta`` (module docstring)."""
    strain = modes @ np.asarray(zeta, dtype=float)
    stress = von_mises_stress(strain, E, nu)
    value = p_norm(stress, power)
    if not value > 0.0:
        return StressNorm(0.0, np.zeros(modes.shape[-1]))
    mu = E / (2.0 * (1.0 + nu))
    deviator = 2.0 * mu * (strain - np.einsum("ecaa->ec", strain)[..., None, None] / 3.0 * np.eye(3))
    positive = stress > 0.0
    # (v_i / |v|_p)^(p-1) times dv_i/dzeta's factor 3 mu / v_i; zero where v_i = 0 (the product goes as v_i^(p-2))
    weight = np.where(positive, (stress / value) ** (power - 1.0) * 3.0 * mu / np.where(positive, stress, 1.0), 0.0)
    return StressNorm(value, np.einsum("ec,ecab,ecabj->j", weight, deviator, modes))


def stress_norm_at(
    fe: FEModel,
    basis: ArrayLike,
    zeta: ArrayLike,
    power: float = STRESS_NORM_POWER,
    average: BallAverage | None = None,
) -> float:
    """The p-norm of Eq. (D10) (Pa) of the corner stresses of the link ``fe`` with mode ``basis`` at coordinates
    ``zeta`` (with an ``average``, of its averaged stresses, Eq. (D14))."""
    strain = _strains(fe, np.asarray(basis, dtype=float) @ np.asarray(zeta, dtype=float), average)
    return p_norm(von_mises_stress(strain, fe.material.E, fe.material.nu), power)
