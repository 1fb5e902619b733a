r"""A single loop's rigid motion as the links' poses and twists at any drive angle, for the clearance's bound
between poses (:class:`ffrf.output.clearance.RigidMotion`, ``docs/formulation.md`` Eq. (CL4)).

The motion is traced once (Eq. (L4)); at any other drive angle the loop is closed from the nearest sample
(:func:`kinematics.close_near`). Link ``k``'s twist per rad of drive is the sum of its joints' twists along the
chain from the base (Eqs. (L1), (L3)),

.. math:: \xi_k = \sum_{i<k} \frac{d\varphi_i}{d\theta}\, (l_i,\; p_i \times l_i),

with :math:`(l_i, p_i)` the direction and a point of axis ``i`` in its current pose and
:math:`d\varphi/d\theta` the motion's tangent (:func:`kinematics.motion_tangents`, times the drive's sign).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from kinematics import LoopMotion, SingleLoop, close_near, motion_tangents, trace_motion

__all__ = ["LoopPoses"]


@dataclass(frozen=True)
class LoopPoses:
    """The rigid ``loop`` driven at joint ``driver``: the traced ``samples`` and ``sign``, the drive angle's sense
    relative to the joint's rotation (:func:`ffrf.scenes.linkage_description.drive_sign`)."""

    loop: SingleLoop
    driver: int
    sign: float
    samples: LoopMotion

    @classmethod
    def revolution(
        cls, loop: SingleLoop, driver: int, n_poses: int, start: ArrayLike | None = None, sign: float = 1.0
    ) -> LoopPoses:
        """One revolution of the drive from ``start`` (closing joint rotations, default home) in ``n_poses`` equal
        steps, the end pose included (``n_poses + 1`` samples), turning the way ``sign`` says."""
        samples = trace_motion(loop, driver, n_poses + 1, sign * 2 * np.pi, start=start, endpoint=True)
        return cls(loop, driver, float(sign), samples)

    @property
    def drive_angles(self) -> NDArray[np.float64]:
        """The sampled drive angles (rad), in the motion's order."""
        return self.sign * self.samples.driver_angles

    def joint_angles(self, angles: ArrayLike) -> NDArray[np.float64]:
        """The closing joint rotations ``(m, n)`` at drive ``angles`` (rad), each closed from the nearest sample."""
        angles = np.asarray(angles, dtype=float)
        nearest = np.argmin(np.abs(angles[:, None] - self.drive_angles[None, :]), axis=1)
        phi = self.samples.phi[nearest].copy()
        moved = angles != self.drive_angles[nearest]
        if moved.any():
            phi[moved] = close_near(self.loop, self.driver, phi[moved], self.sign * angles[moved])
        return phi

    def poses(self, angles: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The links' displacements from home ``(m, n, 4, 4)`` (Eq. (L1)) and twists ``(m, n, 6)`` (angular, then
        linear velocity at the origin, per rad of drive) at drive ``angles``."""
        phi = self.joint_angles(angles)
        n = self.loop.n
        rates = self.sign * motion_tangents(self.loop, self.driver, phi)
        points = np.array([axis.point for axis in self.loop.axes])
        directions = np.array([axis.direction for axis in self.loop.axes])
        transforms = np.array([self.loop.link_transforms(p) for p in phi])  # (m, n + 1, 4, 4)
        rotations, shifts = transforms[:, :n, :3, :3], transforms[:, :n, :3, 3]
        direction = (rotations @ directions[None, :, :, None])[..., 0]
        point = (rotations @ points[None, :, :, None])[..., 0] + shifts
        joint_twists = rates[:, :, None] * np.concatenate([direction, np.cross(point, direction)], axis=2)
        twists = np.concatenate([np.zeros((len(phi), 1, 6)), np.cumsum(joint_twists, axis=1)[:, : n - 1]], axis=1)
        return transforms[:, :n], twists
