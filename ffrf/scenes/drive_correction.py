r"""The drive's correction along the motion: when the task is a path, not a timing (``docs/formulation.md``,
Eq. (D8); issue #35).

A loaded print's coupler at drive angle :math:`\theta_i` is :math:`c(\theta_i)`, off the ideal point
:math:`c^*(\theta_i)` by :math:`d_i`. No fixed geometry removes the part of the sag that changes with the pose
(Eq. (D4)), but a drive that may run ahead or behind removes its component along the path: the drive angle
:math:`\theta_i + \delta_i` that brings the print's coupler closest to the ideal point is, to first order,

.. math:: \delta_i = -\frac{t_i \cdot d_i}{t_i \cdot t_i}, \qquad t_i = \frac{dc^*}{d\theta}(\theta_i),

with the ideal path's tangent at the nominal angle (the rigid loop's kinematics; the loaded path's tangent differs
by the deviation's own change). Each corrected angle is then solved for the print's equilibrium (Newton from the
nominal one) and the step repeated with the deviation found there and the same tangent (a chord iteration), until
the deviation has no component along the path (:data:`TANGENT_TOLERANCE`) or :data:`MAX_STEPS` are spent. What
remains is the deviation across the path, the coupler's distance to the ideal curve to second order, which no drive
can remove.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import brentq

from ffrf.errors import SceneError
from ffrf.output.sensors import path_sensors
from ffrf.scenes.linkage_scene import LinkageScene
from ffrf.solvers.static_solver import static_equilibrium

__all__ = ["ANGLE_STEP", "MAX_STEPS", "NEGLIGIBLE", "TANGENT_TOLERANCE", "DriveCorrection", "correct_drive"]

#: Step of the ideal path's tangent by central differences in the drive angle (rad): truncation about its square.
ANGLE_STEP = 1e-6
#: The correction is done when the deviation's component along the path is below this fraction of the deviation.
TANGENT_TOLERANCE = 1e-3
#: Most correction steps per pose (each one an equilibrium solve).
MAX_STEPS = 5
#: A deviation below this fraction of the loop's size is round-off: the pose keeps its angle.
NEGLIGIBLE = 1e-12


@dataclass(frozen=True)
class DriveCorrection:
    """At each pose the nominal drive angle and the corrected one (rad), the deviation from the ideal point before and
    after the correction ``(poses, 3)`` (m; after: solved at the corrected angle), and the correction steps each pose
    took; ``clipped`` counts the poses whose corrected angle lay outside the run's motion and was held at its end."""

    drive_angle: NDArray[np.float64]
    corrected_angle: NDArray[np.float64]
    before: NDArray[np.float64]
    after: NDArray[np.float64]
    steps: NDArray[np.int64]
    clipped: int
    seconds: float

    @property
    def before_m(self) -> float:
        return float(np.linalg.norm(self.before, axis=1).max())

    @property
    def after_m(self) -> float:
        return float(np.linalg.norm(self.after, axis=1).max())


def correct_drive(scene: LinkageScene, time_s: NDArray, q: NDArray, multipliers: NDArray) -> DriveCorrection:
    """The drive correction (module docstring) of the linkage ``scene`` at the equilibria ``q`` ``(poses, n)``,
    ``multipliers`` of a quasi-static run at ``time_s``."""
    started = time.perf_counter()
    time_s, q, multipliers = np.asarray(time_s, float), np.asarray(q, float), np.asarray(multipliers, float)
    angles = np.array([scene.drive_angle(float(t)) for t in time_s])
    ideal = scene.ideal_coupler_points(angles)
    coupler = path_sensors(scene, time_s, q, multipliers)["coupler_point"]
    sides = scene.ideal_coupler_points(np.concatenate([angles + ANGLE_STEP, angles - ANGLE_STEP]))
    tangents = (sides[: len(angles)] - sides[len(angles) :]) / (2.0 * ANGLE_STEP)  # dc*/dtheta, m/rad
    ends = (scene.drive_angle(0.0), scene.drive_angle(scene.t_end))
    corrected, after = angles.copy(), coupler - ideal
    steps = np.zeros(len(angles), dtype=np.int64)
    clipped = 0
    for i, (target, tangent) in enumerate(zip(ideal, tangents, strict=True)):
        angle, state, deviation = angles[i], q[i], coupler[i] - target
        for _ in range(MAX_STEPS):
            along = float(tangent @ deviation) / float(tangent @ tangent)
            size = float(np.linalg.norm(deviation))
            if (
                size <= NEGLIGIBLE * scene.loop.scale
                or abs(along) * np.linalg.norm(tangent) <= TANGENT_TOLERANCE * size
            ):
                break
            angle = angle - along
            if not ends[0] <= angle <= ends[1]:
                angle, clipped = float(np.clip(angle, *ends)), clipped + 1
            t = _time_at(scene, angle, ends)
            solved = static_equilibrium(scene.system, state, t=t, tolerance=1e-12)
            state = solved.q
            point = path_sensors(scene, np.array([t]), state[None], solved.multipliers[None])["coupler_point"][0]
            deviation = point - target
            steps[i] += 1
            if angle in ends:
                break
        corrected[i], after[i] = angle, deviation
    return DriveCorrection(angles, corrected, coupler - ideal, after, steps, clipped, time.perf_counter() - started)


def _time_at(scene: LinkageScene, angle: float, ends: tuple[float, float]) -> float:
    """The time at which the drive reaches ``angle`` (its ramp is monotonic: the root is unique)."""
    if angle <= ends[0]:
        return 0.0
    if angle >= ends[1]:
        return float(scene.t_end)
    if not ends[0] < ends[1]:
        raise SceneError("the linkage's drive does not turn: it has no angle to correct")
    return float(brentq(lambda t: scene.drive_angle(t) - angle, 0.0, scene.t_end, xtol=1e-14, rtol=1e-15))
