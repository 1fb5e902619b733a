r"""Minimum-energy paths by the simplified string method (``docs/formulation.md``, Eq. (S9)).

Weinan E, W. Ren and E. Vanden-Eijnden, "Simplified and improved string method for computing the minimum
energy paths in barrier-crossing events", J. Chem. Phys. 126, 164103 (2007). A string of images
:math:`\varphi_0 .. \varphi_m` joins two states; each iteration

1. moves every free image down the energy, :math:`\varphi_i^* = \varphi_i - \Delta t\,\nabla V(\varphi_i)`
   (plain descent; a component masked out of ``free_start`` is held, and a fixed end image stays);
2. re-parametrises the string to equal arc length: the normalised arc lengths :math:`\alpha_i` of the
   :math:`\varphi_i^*` are computed and the images are put at :math:`\alpha = i/m` on the linear or
   cubic-spline interpolant through them.

The string converges to a minimum-energy path: :math:`\nabla V` normal to it vanishes. At the fixed point the
descent moves the images only along the string, which the re-parametrisation undoes, so the largest move of an
image in one iteration over :math:`\Delta t` is the largest normal gradient left (the residual); the iteration
stops when it falls below ``tolerance``. Forward Euler is stable for :math:`\Delta t < 2/\lambda_{max}` (the
largest curvature of V across the string); beyond it an image's move turns back each iteration without
shrinking, and the step is halved when one does.

Symbols: ``images`` :math:`\varphi_i` (rows), ``energies`` :math:`V(\varphi_i)`, ``gradients``
:math:`\nabla V(\varphi_i)`, ``step`` :math:`\Delta t`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import CubicSpline

__all__ = ["StringPath", "hermite_peak", "reparametrized", "string_method"]

EnergyAndGradient = Callable[[NDArray[np.float64]], tuple[float, NDArray[np.float64]]]
#: Re-parametrisations of step 2.
INTERPOLATIONS = ("linear", "cubic")


@dataclass(frozen=True)
class StringPath:
    """A string of images (rows of ``images``) with their energies and gradients; ``iterations`` done,
    ``converged`` (the residual fell below the tolerance), ``residual``: the largest move of an image in the last
    iteration over the step (units of V / phi, the normal gradient left), ``step``: the last time step."""

    images: NDArray[np.float64]
    energies: NDArray[np.float64]
    gradients: NDArray[np.float64]
    iterations: int
    converged: bool
    residual: float
    step: float

    @property
    def arclength(self) -> NDArray[np.float64]:
        """Cumulative arc length of the polyline through the images, from image 0."""
        return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(self.images, axis=0), axis=1))])

    @property
    def peak_index(self) -> int:
        """The image of highest energy."""
        return int(np.argmax(self.energies))

    def peak(self) -> tuple[float, float]:
        """Arc length and energy of the highest point of the path: :func:`hermite_peak` on the two segments
        around the image of highest energy."""
        return hermite_peak(self.images, self.energies, self.gradients, self.peak_index)


def _tangent_slopes(images: NDArray, gradients: NDArray) -> NDArray[np.float64]:
    """dV/ds at each image along the string (central differences of the images for the direction)."""
    direction = np.gradient(images, axis=0)
    norm = np.linalg.norm(direction, axis=1)
    return np.einsum("ij,ij->i", gradients, direction) / np.where(norm > 0.0, norm, 1.0)


def hermite_peak(images: NDArray, energies: NDArray, gradients: NDArray, k: int) -> tuple[float, float]:
    r"""The largest V on the cubic Hermite interpolants of V(s) over the segments next to image ``k``, from the
    values and the slopes :math:`dV/ds = \nabla V\cdot\tau` at their ends (error O(h^4) in the spacing h).
    Returns the arc length (from image 0) and the energy there."""
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(images, axis=0), axis=1))])
    slopes = _tangent_slopes(images, gradients)
    best = (float(s[k]), float(energies[k]))
    for a in (k - 1, k):
        if a < 0 or a + 1 >= len(s):
            continue
        h = s[a + 1] - s[a]
        x = np.linspace(0.0, 1.0, 201)
        h00, h10, h01, h11 = 2 * x**3 - 3 * x**2 + 1, x**3 - 2 * x**2 + x, -2 * x**3 + 3 * x**2, x**3 - x**2
        values = h00 * energies[a] + h10 * h * slopes[a] + h01 * energies[a + 1] + h11 * h * slopes[a + 1]
        j = int(np.argmax(values))
        if values[j] > best[1]:
            best = (float(s[a] + x[j] * h), float(values[j]))
    return best


def reparametrized(images: NDArray, interpolation: str = "linear") -> NDArray[np.float64]:
    """``images`` moved to equal arc length along the linear or cubic-spline interpolant through them (step 2)."""
    if interpolation not in INTERPOLATIONS:
        raise ValueError(f"interpolation must be one of {INTERPOLATIONS}, got {interpolation!r}")
    lengths = np.linalg.norm(np.diff(images, axis=0), axis=1)
    alpha = np.concatenate([[0.0], np.cumsum(lengths)])
    if alpha[-1] == 0.0:
        return images.copy()
    alpha /= alpha[-1]
    keep = np.concatenate([[True], lengths > 1e-14 * alpha.size])  # coincident images carry no direction
    targets = np.linspace(0.0, 1.0, images.shape[0])
    if interpolation == "cubic" and np.count_nonzero(keep) > 3:
        return np.asarray(CubicSpline(alpha[keep], images[keep], axis=0)(targets))
    return np.column_stack([np.interp(targets, alpha[keep], column) for column in images[keep].T])


def string_method(
    energy_and_gradient: EnergyAndGradient,
    initial: ArrayLike,
    step: float,
    tolerance: float,
    max_iterations: int = 2000,
    free_start: ArrayLike | bool = False,
    free_end: bool = False,
    interpolation: str = "linear",
    progress: Callable[[int, float], None] | None = None,
) -> StringPath:
    r"""The minimum-energy path from the string ``initial`` (``(m + 1, n)`` images, usually equally spaced on a
    straight line between two states), by the simplified string method of the module docstring.

    ``energy_and_gradient(phi) -> (V, dV/dphi)``; ``step``: the descent's time step :math:`\Delta t` (units of
    phi^2 / V; halved when an image's move turns back without shrinking); ``tolerance``: the residual (the largest
    move of an image in one iteration over the step, units of V / phi) at which the string has converged;
    ``free_start``: whether image 0 descends (``True``), stays (``False``) or descends in the components where a
    mask of length n is true (the others held); ``free_end`` likewise for image m (all components);
    ``progress(iteration, residual)`` is called after every iteration.
    """
    images = np.array(initial, dtype=float)
    if images.ndim != 2 or images.shape[0] < 3:
        raise ValueError(f"initial must be (m + 1, n) images with m >= 2, got shape {images.shape}")
    if not (np.isfinite(step) and step > 0.0 and np.isfinite(tolerance) and tolerance > 0.0):
        raise ValueError(f"step and tolerance must be positive and finite, got {step} and {tolerance}")
    mask = np.ones_like(images)
    mask[0] = np.broadcast_to(np.asarray(free_start, dtype=float), images.shape[1])
    mask[-1] = 1.0 if free_end else 0.0
    evaluated = [energy_and_gradient(phi) for phi in images]
    energies = np.array([e for e, _ in evaluated], dtype=float)
    gradients = np.array([g for _, g in evaluated], dtype=float)
    residual, previous, iteration = np.inf, np.zeros_like(images), 0
    for iteration in range(1, max_iterations + 1):
        descended = images - step * mask * gradients
        moved = reparametrized(descended, interpolation)
        moved[[0, -1]] = descended[[0, -1]]  # the ends stay where the descent put them, to the bit
        moves = moved - images
        residual = float(np.max(np.linalg.norm(moves, axis=1))) / step
        images = moved
        if _oscillates(moves, previous, tolerance * step):
            step, moves = 0.5 * step, np.zeros_like(moves)  # judge the new step on its own moves
        previous = moves
        evaluated = [energy_and_gradient(phi) for phi in images]
        energies = np.array([e for e, _ in evaluated], dtype=float)
        gradients = np.array([g for _, g in evaluated], dtype=float)
        if progress is not None:
            progress(iteration, residual)
        if residual < tolerance:
            return StringPath(images, energies, gradients, iteration, True, residual, step)
    return StringPath(images, energies, gradients, iteration, False, residual, step)


def _oscillates(moves: NDArray, previous: NDArray, floor: float) -> bool:
    """Whether an image's move turned back (cosine below -1/2) without shrinking by a tenth, above ``floor``: forward
    Euler beyond its stability limit in the stiffest direction (a stable step reverses only while shrinking)."""
    size, before = np.linalg.norm(moves, axis=1), np.linalg.norm(previous, axis=1)
    turned = np.einsum("ij,ij->i", moves, previous) < -0.5 * size * before
    return bool(np.any(turned & (size > 0.9 * before) & (size > floor)))
