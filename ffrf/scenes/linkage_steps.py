r"""Steps of a linkage run from how fast its rigid loop moves: the fastest joint, not the drive alone.

Near a near-dead pose of the driver one joint of the loop turns many times faster than the driver (the
``interp_4poses_6r`` of Rational Linkages: joint 5 about 42 times, ``docs/hard_cases.md``); a step that turns the
drive by a fixed angle then turns that joint by 42 times as much. The rigid loop's joint rates
:math:`r_k = |d\varphi_k / d\varphi_{\mathrm{drive}}|` along the run (Eq. (L9), :func:`kinematics.rate_profile`)
bound the steps (``docs/formulation.md``):

* (G7) dynamic: a step from :math:`t_0` to :math:`t_1` is done in parts no longer than
  :math:`\Delta\varphi_J / (\max|\dot\varphi_{\mathrm{drive}}|\,\max_k r_k)`, the maxima over the step, so that the
  fastest joint turns at most :data:`JOINT_ANGLE_PER_STEP` per part;
* (S10) quasi-static: the path's own step from t turns the drive by at most
  :data:`~ffrf.scenes.assembly.MAX_DRIVE_STEP` and the fastest joint by at most :data:`MAX_JOINT_PATH_STEP`.

* (G8) dynamic, from the solution: a part whose local error estimate (every coordinate in metres) exceeds
  :func:`dynamic_error_tolerance` is redone in twice as many parts (the elastic vibration and whatever the rigid
  loop's rates do not see).

Both leave a loop whose joints turn at most twice as fast as its driver (the paper's Bennett: :math:`\sqrt3`) on
the drive's own steps. A run that stops where the ratio is large names the near-dead point
(:func:`near_dead_point`).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ffrf.output.verification import STEP_ERROR_RTOL, scene_length
from ffrf.scenes.assembly import DRIVE_ANGLE_PER_STEP, MAX_DRIVE_STEP
from ffrf.scenes.linkage_description import drive_sign
from ffrf.scenes.linkage_scene import LinkageScene, _loop_content
from ffrf.scenes.scene_cache import content_key
from kinematics import RateProfile, rate_profile

__all__ = [
    "JOINT_ANGLE_PER_STEP",
    "MAX_JOINT_PATH_STEP",
    "NEAR_DEAD_RATIO",
    "STEP_ERROR_FLOOR",
    "dynamic_error_tolerance",
    "dynamic_step_limit",
    "joint_rate_profile",
    "near_dead_point",
    "near_dead_poses",
    "quasi_static_path_step",
]

#: Largest turn of the rigid loop's fastest joint per dynamic step (rad, Eq. (G7)): twice the drive's
#: :data:`~ffrf.scenes.assembly.DRIVE_ANGLE_PER_STEP`, so that the paper's Bennett (joints at most sqrt(3) times as
#: fast as the driver) keeps the drive's steps.
JOINT_ANGLE_PER_STEP = 2.0 * DRIVE_ANGLE_PER_STEP
#: Largest turn of the rigid loop's fastest joint per quasi-static path step (rad, Eq. (S10)), twice
#: :data:`~ffrf.scenes.assembly.MAX_DRIVE_STEP` for the same reason.
MAX_JOINT_PATH_STEP = 2.0 * MAX_DRIVE_STEP
#: A joint this many times faster than the driver makes a pose near-dead (:func:`near_dead_point`).
NEAR_DEAD_RATIO = 10.0
#: Smallest local error tolerance of a dynamic step (m, Eq. (G8)): a thousand times the Newton tolerance 1e-10 (m
#: for a scene of at most 1 m), which bounds how well the accelerations that Eq. (G5) differences are known.
STEP_ERROR_FLOOR = 1e-9
#: Sampling of :func:`joint_rate_profile`: the fastest joint turns at most this much between samples (rad) ...
PROFILE_JOINT_STEP = math.radians(2.0)
#: ... and the driver at most this much (rad).
PROFILE_DRIVER_STEP = math.radians(4.0)


def joint_rate_profile(scene: LinkageScene) -> RateProfile:
    """The rigid nominal loop's joint rates (Eq. (L9)) over the scene's run, from its start pose; kept by content in
    the scene's cache (one trace per loop, driver, start and turn)."""
    sign = drive_sign(scene.driver, scene.loop.n)
    turn = sign * float(scene.drive(scene.t_end))
    key = content_key(
        "joint rate profile", _loop_content(scene.loop), scene.driver, scene.start_phi, turn, PROFILE_JOINT_STEP
    )
    return scene.cache.rigid_motions.get_or_compute(
        key,
        lambda: rate_profile(scene.loop, scene.driver, scene.start_phi, turn, PROFILE_JOINT_STEP, PROFILE_DRIVER_STEP),
    )


def _driver_angle(scene: LinkageScene, t: float) -> float:
    """The driver's rotation phi of Eq. (L1) at time t (rad from home)."""
    return drive_sign(scene.driver, scene.loop.n) * scene.drive_angle(t)


def _limit(scene: LinkageScene, profile: RateProfile, t0: float, t1: float, angle: float) -> float:
    """The longest step (s) in which the fastest joint turns ``angle`` at the largest drive rate and joint-rate ratio
    between t0 and t1 (Eqs. (G7), (S10)); infinite while the drive rests."""
    rate = max(abs(float(scene.drive.rate(t0))), abs(float(scene.drive.rate(t1))))
    ratio = profile.largest(_driver_angle(scene, t0), _driver_angle(scene, t1))[0]
    return math.inf if rate == 0.0 else angle / (rate * ratio)


def dynamic_step_limit(scene: LinkageScene) -> Callable[[float, float], float]:
    """Eq. (G7): ``limit(t0, t1)``, the longest generalized-alpha step between t0 and t1 (s)."""
    profile = joint_rate_profile(scene)
    return lambda t0, t1: _limit(scene, profile, t0, t1, JOINT_ANGLE_PER_STEP)


def dynamic_error_tolerance(scene: LinkageScene) -> float:
    """Eq. (G8): the local error estimate a dynamic step may make (m), :data:`~ffrf.output.verification.STEP_ERROR_RTOL`
    of the longest link (what the run's ``step_error`` self-check judges the median estimate against), at least
    :data:`STEP_ERROR_FLOOR`."""
    return max(STEP_ERROR_RTOL * scene_length(scene), STEP_ERROR_FLOOR)


def quasi_static_path_step(scene: LinkageScene) -> Callable[[float], float]:
    """Eq. (S10): ``step(t)``, the quasi-static path's own step from t (s): the drive turns at most
    :data:`~ffrf.scenes.assembly.MAX_DRIVE_STEP` at full speed and the fastest joint at most
    :data:`MAX_JOINT_PATH_STEP` over the step."""
    profile = joint_rate_profile(scene)
    longest = MAX_DRIVE_STEP / abs(float(scene.drive.omega))

    def step(t: float) -> float:
        return min(longest, _limit(scene, profile, t, t + longest, MAX_JOINT_PATH_STEP))

    return step


def near_dead_point(scene: LinkageScene, t: float, window: float = math.radians(2.0)) -> str | None:
    """Where a run stopped at time t is a near-dead pose of the rigid loop (a joint at least :data:`NEAR_DEAD_RATIO`
    times faster than the driver within ``window`` of drive angle of t): the sentence that says so, else ``None``."""
    angle = _driver_angle(scene, t)
    ratio, joint, at = joint_rate_profile(scene).largest(angle - window, angle + window)
    if ratio < NEAR_DEAD_RATIO:
        return None
    sign = drive_sign(scene.driver, scene.loop.n)
    return (
        f"near-dead point of the rigid loop at drive angle {np.degrees(sign * at):.4g} deg: joint {joint} turns "
        f"{ratio:.3g} times faster than the driver (joint {scene.driver}) there"
    )


def near_dead_poses(scene: LinkageScene, drive_angles: np.ndarray, deviation: np.ndarray) -> list[dict]:
    """The near-dead poses the run passed (peaks of the rigid loop's joint-rate ratio of at least
    :data:`NEAR_DEAD_RATIO`, Eq. (L9)) and how far the coupler left the rigid motion near each (within 2 deg of drive)
    and elsewhere: ``deviation`` (m) at the outputs' ``drive_angles`` (rad, the driven joint's prescribed angle).
    There the rigid motion is ill-conditioned (a joint turns many times faster than the driver, the loop is near a
    bifurcation) and a built model may leave it by far more than its strain elsewhere."""
    profile = joint_rate_profile(scene)
    sign = drive_sign(scene.driver, scene.loop.n)
    ratios = profile.ratios
    peaks = [
        k
        for k in range(1, len(ratios) - 1)
        if ratios[k] >= NEAR_DEAD_RATIO and ratios[k] >= ratios[k - 1] and ratios[k] > ratios[k + 1]
    ]
    reached = sign * np.asarray(drive_angles, dtype=float)
    out = []
    for k in peaks:
        angle = float(profile.driver_angles[k])
        if not min(reached) - 1e-9 <= angle <= max(reached) + 1e-9:
            continue
        near = np.abs(reached - angle) <= math.radians(2.0)
        out.append(
            {
                "drive_angle_deg": float(np.degrees(sign * angle)),
                "joint": int(profile.fastest[k]),
                "ratio": float(ratios[k]),
                "max_coupler_deviation_near_m": float(np.max(deviation[near], initial=0.0)),
                "max_coupler_deviation_elsewhere_m": float(np.max(deviation[~near], initial=0.0)),
            }
        )
    return out
