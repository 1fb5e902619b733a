"""Branch identification, including the paper's extension to three joints per branch."""

import numpy as np

from identification import identify_branch
from kinematics import DualQuaternion, Line


def _rotation(axis: Line, angle):
    """cos(angle/2) + sin(angle/2) h for an array of angles."""
    angle = np.asarray(angle, dtype=float)[..., None]
    return DualQuaternion(np.cos(angle / 2) * np.eye(8)[0] + np.sin(angle / 2) * axis.to_dual_quaternion().coeffs)


def test_three_joint_serial_branch(rng):
    """A 3R serial branch with unrelated joint motions: every axis is recovered in the
    configuration of the first frame (projection extended from the left, paper Eq. projection)."""
    axes = [Line.from_point_direction(rng.normal(size=3) * 0.1, rng.normal(size=3)) for _ in range(3)]
    frames = np.linspace(0.3, 1.3, 400)  # frame 0 is not the home configuration
    angles = [2.0 * np.pi * frames, 1.3 * np.sin(5 * frames) + 3 * frames, -4.0 * frames + 0.5 * frames**2]
    first = _rotation(axes[0], angles[0])
    second = first * _rotation(axes[1], angles[1])
    third = second * _rotation(axes[2], angles[2])
    points = [np.stack([pose.act(p) for p in 0.1 * rng.normal(size=(2, 3))], axis=1) for pose in (first, second, third)]
    fits = identify_branch(points, ["a", "b", "c"])
    for fit, axis, pose in zip(fits, axes, (None, first[0], second[0]), strict=True):
        expected = axis if pose is None else axis.transformed(pose)
        assert fit.axis.is_close(expected, 1e-8) or fit.axis.is_close(expected.reversed(), 1e-8)
