r"""Joint reactions as physical forces and torques, in each joint's own frame.

The constraint force of a joint on its bodies is :math:`-C_q^T\lambda` (``docs/formulation.md``,
Eq. (J4)). Its physical content follows from how each equation (J1)-(J3) varies under a
virtual displacement :math:`\delta p_1` and rotation :math:`\delta\varphi_1` of side 1's frame:

* all translations locked, :math:`g = p_1 - p_0`: :math:`\delta g = \delta p_1`, so side 1 feels
  the force :math:`F_1 = -\lambda_{0..2}` (world) at its joint point; a subset,
  :math:`g_i = J_{0,i}^T(p_1 - p_0)`: :math:`F_1 = -\sum_i \lambda_i J_{0,i}`;
* a rotation equation :math:`a\cdot b_1 = 0` (``a`` on side 0, ``b_1`` on side 1) varies by
  :math:`a\cdot(\delta\varphi_1\times b_1) = \delta\varphi_1\cdot(b_1\times a)`, so side 1 feels
  the torque :math:`-\lambda\,(b_1\times a)`: pairs :math:`(z_0, y_1)`, :math:`(z_0, x_1)`,
  :math:`(x_0', y_1)`.

Side 0 feels the opposite wrench at the same point (actio = reactio; the joint point is
common to both sides when the constraints hold). For a driven revolute the torque about
:math:`z_0` is :math:`-\lambda_5\,z_0\cdot(y_1\times x_0') = \lambda_5` when the frames are
aligned: the driving torque applied to side 1. It is also the derivative of the equilibrium's potential energy by
the prescribed angle (``docs/formulation.md``, Eq. (S8)).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ffrf.numerics.small_linalg import cross3
from ffrf.system.joints import MarkerJoint, joint_pose
from ffrf.system.multibody import MultibodySystem

__all__ = ["JointReaction", "driving_torques", "joint_poses", "joint_reaction", "joint_reactions", "relative_angle"]


@dataclass(frozen=True)
class JointReaction:
    """Wrench on side 1 (marker 1's body) at the joint point: world and joint-frame-0 components."""

    point: NDArray[np.float64]  # joint point of side 1 (world)
    force: NDArray[np.float64]  # world
    torque: NDArray[np.float64]  # world
    frame: NDArray[np.float64]  # joint frame 0 (columns x0, y0, z0; x0 turned by the prescribed angle)

    @property
    def force_local(self) -> NDArray[np.float64]:
        return self.frame.T @ self.force

    @property
    def torque_local(self) -> NDArray[np.float64]:
        return self.frame.T @ self.torque


def joint_poses(joint: MarkerJoint, blocks: list[NDArray]) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """Joint point and axes of side 0 and of side 1 (``blocks`` as for ``joint.value``)."""
    q0, q1 = (None, blocks[0]) if len(blocks) == 1 else blocks
    p0, axes0 = joint_pose(joint.marker0, q0, joint.rotation0, joint.offset0)
    p1, axes1 = joint_pose(joint.marker1, q1, joint.rotation1, joint.offset1)
    return p0, axes0, p1, axes1


def relative_angle(poses: tuple) -> float:
    """Rotation of side 1 against side 0 about z0 (rad), from :func:`joint_poses`."""
    _, axes0, _, axes1 = poses
    return float(np.arctan2(cross3(axes0[:, 0], axes1[:, 0]) @ axes0[:, 2], axes0[:, 0] @ axes1[:, 0]))


def joint_reaction(
    joint: MarkerJoint, blocks: list[NDArray], multipliers: NDArray, t: float, poses: tuple | None = None
) -> JointReaction:
    """The wrench of the module docstring for one joint; ``blocks`` as for ``joint.value``;
    ``poses``: :func:`joint_poses` of these blocks if the caller has them already."""
    _, axes0, p1, axes1 = joint_poses(joint, blocks) if poses is None else poses
    if joint.angle is not None:
        phi = joint.angle(t)
        x0 = np.cos(phi) * axes0[:, 0] + np.sin(phi) * axes0[:, 1]
        axes0 = np.column_stack([x0, cross3(axes0[:, 2], x0), axes0[:, 2]])
    lam = np.asarray(multipliers, dtype=float)
    row = 0
    if all(joint.locked[:3]):
        force = -lam[:3].copy()
        row = 3
    else:
        force = np.zeros(3)
        for i in range(3):
            if joint.locked[i]:
                force -= lam[row] * axes0[:, i]
                row += 1
    torque = np.zeros(3)
    pairs = [(2, 1)] * joint.locked[3] + [(2, 0)] * joint.locked[4] + [(0, 1)] * joint.locked[5]
    for k0, k1 in pairs:
        torque -= lam[row] * cross3(axes1[:, k1], axes0[:, k0])
        row += 1
    return JointReaction(p1, force, torque, axes0)


def joint_reactions(
    system: MultibodySystem, q: NDArray, multipliers: NDArray, t: float, poses: dict[str, tuple] | None = None
) -> dict[str, JointReaction]:
    """Every :class:`~ffrf.system.joints.MarkerJoint` of ``system`` at one state, by joint name; ``poses``:
    :func:`joint_poses` by joint name, for the joints the caller has them for."""
    out = {}
    for k, c in enumerate(system.all_constraints):
        if isinstance(c, MarkerJoint):
            lam = multipliers[int(system.rows[k]) : int(system.rows[k + 1])]
            known = None if poses is None else poses.get(c.name)
            out[c.name] = joint_reaction(c, [q[system.block(i)] for i in c.bodies], lam, t, known)
    return out


def driving_torques(system: MultibodySystem, multipliers: NDArray) -> dict[str, float]:
    """Per joint with a prescribed angle (Eq. (J3)), by name: the multiplier of its angle equation, its last row, which
    is the torque about z0 applied to side 1 (module docstring) and dV/d(angle) of the equilibrium (Eq. (S8))."""
    return {
        c.name: float(multipliers[int(system.rows[k + 1]) - 1])
        for k, c in enumerate(system.all_constraints)
        if isinstance(c, MarkerJoint) and c.angle is not None
    }
