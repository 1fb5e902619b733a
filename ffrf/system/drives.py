r"""Prescribed joint motions: the paper's cosine ramp, and any function of time.

Paper, Sect. "Simulation Setup": the driven joint's angular velocity rises from rest to
:math:`\omega` along a cosine over :math:`t_r`, then stays constant (``docs/formulation.md``, Eq. (D1)):

.. math:: \dot\varphi(t) = \frac{\omega}{2}\Big(1 - \cos\frac{\pi t}{t_r}\Big)\ (t < t_r),\qquad
          \varphi(t) = \frac{\omega}{2}\Big(t - \frac{t_r}{\pi}\sin\frac{\pi t}{t_r}\Big)\ (t < t_r),

and :math:`\varphi(t) = \omega t_r/2 + \omega(t - t_r)` afterwards. The ramp starts with zero
angle, velocity and acceleration, so it is consistent with a mechanism at rest.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["CosineRamp", "RampedAngle", "rpm"]


def rpm(value: float) -> float:
    """Revolutions per minute in rad/s.

    >>> bool(np.isclose(rpm(60.0), 2 * np.pi))  # one revolution per second
    True
    """
    return 2.0 * np.pi * value / 60.0


@dataclass(frozen=True)
class CosineRamp:
    """Eq. (D1): final rate ``omega`` (rad/s) reached after ``ramp_time`` (s).

    With omega = 2 rad/s over 1 s: half the rate at mid-ramp, omega t_r / 2 = 1 rad turned by the
    end of the ramp, 2 rad/s after it, so 5 rad at t = 3 s:

    >>> drive = CosineRamp(omega=2.0, ramp_time=1.0)
    >>> round(float(drive.rate(0.5)), 12), float(drive.angle(1.0)), float(drive.rate(2.0)), float(drive.angle(3.0))
    (1.0, 1.0, 2.0, 5.0)
    >>> drive.time_for_angle(5.0)
    3.0
    """

    omega: float
    ramp_time: float

    def __post_init__(self):
        if self.ramp_time <= 0:
            raise ValueError(f"ramp_time must be positive, got {self.ramp_time}")

    def __call__(self, t: float) -> float:
        return self.angle(t)

    def angle(self, t):
        t = np.asarray(t, dtype=float)
        tr, w = self.ramp_time, self.omega
        during = 0.5 * w * (t - tr / np.pi * np.sin(np.pi * t / tr))
        after = 0.5 * w * tr + w * (t - tr)
        return np.where(t < tr, during, after)

    def rate(self, t):
        t = np.asarray(t, dtype=float)
        return np.where(t < self.ramp_time, 0.5 * self.omega * (1 - np.cos(np.pi * t / self.ramp_time)), self.omega)

    def acceleration(self, t):
        t = np.asarray(t, dtype=float)
        tr = self.ramp_time
        return np.where(t < tr, 0.5 * self.omega * np.pi / tr * np.sin(np.pi * t / tr), 0.0)

    def time_for_angle(self, angle: float) -> float:
        """When the drive has turned by ``angle`` (rad) in total (e.g. ramp plus one revolution)."""
        ramp_angle = 0.5 * self.omega * self.ramp_time
        if angle >= ramp_angle:
            return self.ramp_time + (angle - ramp_angle) / self.omega
        from scipy.optimize import brentq

        return brentq(lambda t: float(self.angle(t)) - angle, 0.0, self.ramp_time)


@dataclass(frozen=True)
class RampedAngle:
    """A prescribed joint angle ``start + ramp(t)`` (rad): plain data, so that other tools (the
    Exudyn twin's symbolic user function) can rebuild the same law."""

    start: float
    ramp: CosineRamp

    def __call__(self, t: float) -> float:
        return self.start + float(self.ramp(t))
