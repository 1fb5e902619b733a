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

from .bennett import bennett_violations
from .dh import _loop_arrays, dh_matrix, home_configuration, loop_closure_residual
from .single_loop import SingleLoop

__all__ = ["LoopMobility", "MobilityReport", "explain_mobility", "rigid_mobility"]


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


@dataclass(frozen=True)
class LoopMobility:
    """Why a loop of revolute joints moves or not (:func:`explain_mobility`).

    ``first_order``: ``n - rank`` of the closure Jacobian at the start (Eq. (L3));
    ``singular_values``: the Jacobian's, lengths scaled by the loop's size; ``turn``: the driver's
    trial rotation (rad); ``gap_translation`` (m) and ``gap_rotation`` (rad): the closest rigid closure
    with the driver turned by ``turn`` (zero for a mobile loop); ``conditions``: for a 4R with
    ``d = 0``, the violated Bennett conditions (empty when none).
    """

    n: int
    driver: int
    first_order: int
    singular_values: NDArray[np.float64]
    turn: float
    gap_translation: float
    gap_rotation: float
    scale: float
    conditions: tuple[str, ...]

    @property
    def mobile(self) -> bool:
        """A finite motion: the loop closes, to 1e-9 of its size and 1e-9 rad, with the driver turned."""
        return self.gap_translation <= 1e-9 * self.scale and self.gap_rotation <= 1e-9

    def summary(self) -> str:
        head = f"{self.n}R loop, joint {self.driver} driven: "
        if self.mobile:
            kind = "overconstrained" if self.n < 7 else "generic"
            return head + f"mobile ({kind}; first-order mobility {self.first_order})"
        why = (
            f"rigid: its closure Jacobian has full rank (smallest singular value "
            f"{self.singular_values[-1] / self.singular_values[0]:.3g} of the largest)"
            if self.first_order == 0
            else f"only infinitesimally mobile (first-order mobility {self.first_order}, no finite motion)"
        )
        text = (
            head
            + f"NOT mobile, {why}; turning joint {self.driver} by {np.degrees(self.turn):.3g} deg leaves a closure "
            f"gap of {1e3 * self.gap_translation:.4g} mm and {np.degrees(self.gap_rotation):.4g} deg"
        )
        if self.conditions:
            text += "; violated: " + "; ".join(self.conditions)
        return text


def _bennett_violations(loop: SingleLoop, rtol: float = 1e-9) -> tuple[str, ...]:
    """The Bennett conditions (:func:`kinematics.bennett.bennett_violations`) a 4R loop with zero offsets violates;
    none for the other mobile 4R families, planar (parallel axes) and spherical (axes through one point)."""
    dh = loop.dh()
    if loop.n != 4 or np.any(np.abs(dh.d) > rtol * loop.scale):
        return ()
    planar = np.all(np.abs(np.sin(dh.alpha)) <= rtol)
    spherical = np.all(np.abs(dh.a) <= rtol * loop.scale)
    return () if planar or spherical else bennett_violations(dh.a, dh.alpha, rtol)


def explain_mobility(
    loop: SingleLoop, driver: int = 0, turn: float = np.radians(1.0), start: ArrayLike | None = None
) -> LoopMobility:
    """Does the loop move when joint ``driver`` turns by ``turn`` from ``start`` (closing joint rotations,
    default home), and if not, by how much does it miss? The closest rigid closure with the driver held (least
    squares over the other joints from ``start``, translation scaled by the loop's size) measures the gap; for
    a 4R the violated Bennett conditions are named. Give a regular ``start`` where home is singular (a loop
    folded flat): there the least squares may stop at a spurious local minimum. A loop that closes with the
    driver turned the other way (a start near the driver's dead point) is mobile."""
    if not 0 <= driver < loop.n:
        raise ValueError(f"driver must be a joint index 0..{loop.n - 1}, got {driver}")
    origin = np.zeros(loop.n) if start is None else np.asarray(start, dtype=float)
    free = [i for i in range(loop.n) if i != driver]
    weights = loop.residual_weights

    def closest(signed_turn: float) -> LoopMobility:
        def residual(x: NDArray) -> NDArray:
            phi = origin.copy()
            phi[free] = x
            phi[driver] = origin[driver] + signed_turn
            return weights * loop.closure_residual(phi)

        gap = least_squares(residual, origin[free], xtol=1e-15, ftol=1e-15, gtol=1e-15).fun / weights
        return LoopMobility(
            n=loop.n,
            driver=driver,
            first_order=loop.mobility(origin),
            singular_values=loop.singular_values(origin),
            turn=float(signed_turn),
            gap_translation=float(np.linalg.norm(gap[:3])),
            gap_rotation=float(np.linalg.norm(gap[3:])),
            scale=loop.scale,
            conditions=_bennett_violations(loop),
        )

    forward = closest(turn)
    if forward.mobile:
        return forward
    # The start may lie within ``turn`` of a dead point of the driver: the other way it moves.
    backward = closest(-turn)
    return backward if backward.mobile else forward
