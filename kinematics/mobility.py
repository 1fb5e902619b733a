r"""Is a rigid single loop mobile? The closure misfit of loops that are not Bennett linkages.

A 4R loop has 4 joint angles and 6 closure equations (:func:`kinematics.dh.loop_closure_residual`):
rigid links can assemble and move only under special conditions (Bennett's). For a loop
such as the paper's misaligned base (:math:`\alpha_3 = 91^\circ`) we turn the driven joint
through one revolution and, at each angle, find the other joint angles that bring the
loop *closest* to closing (least squares on the translation, scaled by the mean link
length, and the rotation vector of the loop product). The largest of these minimal
residuals over the revolution says how far rigid links are from following the drive;
elastic links must take up that misfit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

from .dh import _loop_arrays, dh_matrix, home_configuration, loop_closure_residual

__all__ = ["MobilityReport", "rigid_mobility"]


@dataclass(frozen=True)
class MobilityReport:
    """Closest rigid closure along one revolution of the driven joint.

    ``driver_angles`` (rad, ``(n,)``), best-fit ``joint_angles`` (``(n, 4)``) and the
    remaining ``translation_residual`` (m) and ``rotation_residual`` (rad) at each.
    """

    driver_joint: int
    driver_angles: NDArray[np.float64]
    joint_angles: NDArray[np.float64]
    translation_residual: NDArray[np.float64]
    rotation_residual: NDArray[np.float64]
    translation_tolerance: float
    rotation_tolerance: float

    @property
    def max_translation_residual(self) -> float:
        return float(np.max(self.translation_residual))

    @property
    def max_rotation_residual(self) -> float:
        return float(np.max(self.rotation_residual))

    @property
    def mobile(self) -> bool:
        """True when the rigid loop closes (to ``tolerance``) at every driver angle."""
        return (
            self.max_translation_residual <= self.translation_tolerance
            and self.max_rotation_residual <= self.rotation_tolerance
        )

    def summary(self) -> str:
        if self.mobile:
            return "rigid loop is mobile: it closes over the whole revolution of the driver"
        worst = int(np.argmax(self.translation_residual))
        return (
            "rigid loop is NOT mobile: with rigid links it cannot follow the drive; closest closure "
            f"misses by up to {1e3 * self.max_translation_residual:.4f} mm and "
            f"{np.degrees(self.max_rotation_residual):.4f} deg (worst at driver angle "
            f"{np.degrees(self.driver_angles[worst]):.1f} deg)"
        )


def _loop_product(a, alpha, d, theta) -> NDArray[np.float64]:
    n = a.shape[0]
    product = dh_matrix(a[n - 1], alpha[n - 1], d[0], theta[0])
    for i in range(1, n):
        product = product @ dh_matrix(a[i - 1], alpha[i - 1], d[i], theta[i])
    return product


def rigid_mobility(
    a: ArrayLike,
    alpha: ArrayLike,
    d: ArrayLike | None = None,
    driver_joint: int = 3,
    n_angles: int = 360,
    start: ArrayLike | None = None,
    tolerance: float = 1e-9,
) -> MobilityReport:
    """Closest rigid closure of a 4R (or nR) loop along one revolution of ``driver_joint``.

    ``start`` are joint angles to begin the continuation from (default: the folded home
    configuration, exact for Bennett linkages and close for small misalignments).
    ``tolerance`` is relative to the mean link length (translation) and in radians.
    """
    a, alpha, d = _loop_arrays(a, alpha, d)
    n = a.shape[0]
    if not 0 <= driver_joint < n:
        raise ValueError(f"driver_joint must be in 0..{n - 1}, got {driver_joint}")
    length = float(np.mean(a)) if np.any(a > 0) else 1.0
    theta = home_configuration(n) if start is None else np.asarray(start, dtype=float).copy()
    free = [i for i in range(n) if i != driver_joint]

    def residual(x: NDArray, driver: float) -> NDArray:
        full = theta.copy()
        full[free] = x
        full[driver_joint] = driver
        product = _loop_product(a, alpha, d, full)
        rotvec = Rotation.from_matrix(product[:3, :3]).as_rotvec()
        return np.concatenate([product[:3, 3] / length, rotvec])

    driver_angles = theta[driver_joint] + np.linspace(0.0, 2.0 * np.pi, n_angles, endpoint=False)
    solutions = np.zeros((n_angles, n))
    for k, driver in enumerate(driver_angles):
        fit = least_squares(residual, theta[free], args=(driver,), xtol=1e-14, ftol=1e-14, gtol=1e-14)
        theta[free] = fit.x
        theta[driver_joint] = driver
        solutions[k] = theta
    closure = loop_closure_residual(a, alpha, d, solutions)
    return MobilityReport(
        driver_joint=driver_joint,
        driver_angles=driver_angles,
        joint_angles=solutions,
        translation_residual=closure.translation,
        rotation_residual=closure.rotation,
        translation_tolerance=tolerance * length,
        rotation_tolerance=tolerance,
    )
