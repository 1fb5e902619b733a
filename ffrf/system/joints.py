r"""Joints between markers: revolute, fixed, general subsets, and prescribed rotations.

A joint connects a frame on marker 0 (a body marker or the ground) with a frame on marker 1
(``docs/formulation.md``, Sect. "Joints", Eqs. (J1)-(J3)). Each joint frame is the
marker frame (Eq. (K3)) times a constant rotation ``R`` (its columns are the joint axes
x, y, z in marker coordinates), at the marker point plus a constant ``offset`` (marker
coordinates; e.g. the axial offset from a bore centre to the joint point):

.. math:: J_k = A_{M,k} R_k,\qquad p_k = r_{M,k} + A_{M,k}\,o_k .

Equations, as Exudyn's ``GenericJoint`` (so that reactions compare one to one):

* translations (J1): all three locked: :math:`p_1 - p_0 = 0` (world); a subset (or all three with
  ``frame_translations``, for a compliant bushing whose stiffness turns with it): components of
  :math:`J_0^T(p_1 - p_0)`;
* rotations (J2): about x :math:`z_0\cdot y_1 = 0`, about y :math:`z_0\cdot x_1 = 0`, about z
  :math:`x_0'\cdot y_1 = 0`, where :math:`x_0'` is :math:`x_0` turned about :math:`z_0` by the
  prescribed angle :math:`\varphi(t)` (zero for a passive joint) (J3).

A revolute joint locks ``[tx, ty, tz, rx, ry]``; a fixed joint all six; a driven revolute
all six with :math:`\varphi(t)`. The constraint force on body ``k`` is :math:`-C_{q_k}^T\lambda`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ffrf.system.constraints import Constraint
from ffrf.system.marker_kernels import exp_so3_tangent_kernel, marker_frame
from ffrf.system.markers import BodyMarker

__all__ = [
    "GroundFrame",
    "MarkerJoint",
    "joint_side",
    "joint_pose",
    "revolute_joint",
    "fixed_joint",
    "driven_revolute_joint",
    "exp_so3_tangent",
    "frame_from_axis",
    "turned_frame",
]


def exp_so3_tangent(theta: NDArray) -> NDArray:
    r"""Right Jacobian :math:`T(\theta)` of the exponential map,
    :math:`d\exp(\tilde\theta) = \exp(\tilde\theta)\,(T\,d\theta)^\sim`:
    :math:`T = I - \frac{1-\cos\phi}{\phi^2}\tilde\theta + \frac{\phi - \sin\phi}{\phi^3}\tilde\theta^2`."""
    theta = np.asarray(theta)
    return exp_so3_tangent_kernel(theta.astype(np.result_type(theta, float)))


def frame_from_axis(z: ArrayLike, reference_x: ArrayLike | None = None) -> NDArray[np.float64]:
    """Orthonormal joint frame (columns x, y, z) with the given z; x is ``reference_x`` (default the
    world x axis) made normal to z, or the world y axis when ``reference_x`` is along z."""
    z = np.asarray(z, np.float64) / np.linalg.norm(z)
    x = np.array([1.0, 0.0, 0.0]) if reference_x is None else np.asarray(reference_x, np.float64)
    x = x - (x @ z) * z
    if np.linalg.norm(x) < 1e-8:
        x = np.array([0.0, 1.0, 0.0]) - z[1] * z
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def turned_frame(start: NDArray, end: NDArray, fraction: float) -> NDArray[np.float64]:
    """``start`` rotated towards ``end`` by ``fraction`` of their relative rotation (the geodesic)."""
    from scipy.spatial.transform import Rotation

    relative = Rotation.from_matrix(end @ start.T).as_rotvec()
    return Rotation.from_rotvec(fraction * relative).as_matrix() @ start


@dataclass(frozen=True, eq=False)
class GroundFrame:
    """A fixed world frame: ``point`` (world) and ``rotation`` (world axes as columns)."""

    point: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    rotation: NDArray[np.float64] = field(default_factory=lambda: np.eye(3))
    name: str = "ground"


def joint_side(marker, q, rotation, offset):
    """Joint point, axes (columns) and, for a body marker, their derivatives ``dp/dq`` (3 x n) and
    ``d axes/dq`` (3, 3, n) (``None`` on the ground)."""
    if isinstance(marker, GroundFrame):
        return marker.point + marker.rotation @ offset, marker.rotation @ rotation, None, None
    dtype = q.dtype
    return marker_frame(
        q,
        marker.point.astype(dtype),
        marker.position_modes.astype(dtype),
        marker.rotation_modes.astype(dtype),
        rotation.astype(dtype),
        offset.astype(dtype),
    )


def joint_pose(marker, q, rotation, offset):
    """Joint point and axes (columns) of one side of a joint."""
    point, axes, _, _ = joint_side(marker, q, rotation, offset)
    return point, axes


@dataclass(frozen=True, eq=False)
class MarkerJoint(Constraint):
    """Eqs. (J1)-(J3) between ``marker0`` (body marker or :class:`GroundFrame`) and ``marker1``."""

    marker0: BodyMarker | GroundFrame = field(default_factory=GroundFrame)
    marker1: BodyMarker | None = None
    rotation0: NDArray[np.float64] = field(default_factory=lambda: np.eye(3))
    rotation1: NDArray[np.float64] = field(default_factory=lambda: np.eye(3))
    offset0: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    offset1: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    locked: tuple[bool, bool, bool, bool, bool, bool] = (True, True, True, True, True, False)
    angle: Callable[[float], float] | None = None
    frame_translations: bool = False

    def __post_init__(self):
        if self.marker1 is None or isinstance(self.marker1, GroundFrame):
            raise ValueError(f"joint {self.name!r}: marker 1 must be on a body")
        expected = (
            (self.marker1.body,) if isinstance(self.marker0, GroundFrame) else (self.marker0.body, self.marker1.body)
        )
        if tuple(self.bodies) != expected:
            raise ValueError(f"joint {self.name!r}: bodies {self.bodies} do not match its markers {expected}")
        if self.angle is not None and not self.locked[5]:
            raise ValueError(f"joint {self.name!r}: a prescribed angle needs the z rotation locked")

    @property
    def size(self) -> int:
        return int(sum(self.locked))

    def _sides(self, blocks):
        if isinstance(self.marker0, GroundFrame):
            return None, blocks[0]
        return blocks[0], blocks[1]

    def _prescribed_x0(self, axes0, t):
        if self.angle is None:
            return axes0[:, 0]
        phi = self.angle(t)
        return np.cos(phi) * axes0[:, 0] + np.sin(phi) * axes0[:, 1]

    def value(self, blocks, t):
        q0, q1 = self._sides(blocks)
        p0, axes0, _, _ = joint_side(self.marker0, q0, self.rotation0, self.offset0)
        p1, axes1, _, _ = joint_side(self.marker1, q1, self.rotation1, self.offset1)
        return self._equations(p0, axes0, p1, axes1, t)

    def _equations(self, p0, axes0, p1, axes1, t):
        gap = p1 - p0
        world = all(self.locked[:3]) and not self.frame_translations
        out = list(gap) if world else [axes0[:, i] @ gap for i in range(3) if self.locked[i]]
        if self.locked[3]:
            out.append(axes0[:, 2] @ axes1[:, 1])
        if self.locked[4]:
            out.append(axes0[:, 2] @ axes1[:, 0])
        if self.locked[5]:
            out.append(self._prescribed_x0(axes0, t) @ axes1[:, 1])
        return np.array(out)

    def jacobian(self, blocks, t):
        q0, q1 = self._sides(blocks)
        ground = q0 is None
        p0, axes0, dp0, da0 = joint_side(self.marker0, q0, self.rotation0, self.offset0)
        p1, axes1, dp1, da1 = joint_side(self.marker1, q1, self.rotation1, self.offset1)
        dtype = q1.dtype if ground else np.result_type(q0.dtype, q1.dtype)
        rows1 = np.zeros((self.size, q1.shape[0]), dtype=dtype)
        rows0 = None if ground else np.zeros((self.size, q0.shape[0]), dtype=dtype)
        row = 0
        gap = p1 - p0
        if all(self.locked[:3]) and not self.frame_translations:
            rows1[0:3] = dp1
            if not ground:
                rows0[0:3] = -dp0
            row = 3
        else:
            for i in range(3):
                if self.locked[i]:
                    rows1[row] = axes0[:, i] @ dp1
                    if not ground:
                        rows0[row] = -axes0[:, i] @ dp0 + gap @ da0[i]
                    row += 1
        pairs = [(2, 1, False)] * self.locked[3] + [(2, 0, False)] * self.locked[4] + [(0, 1, True)] * self.locked[5]
        for k0, k1, turned in pairs:
            if turned and self.angle is not None:
                phi = self.angle(t)
                a0 = np.cos(phi) * axes0[:, 0] + np.sin(phi) * axes0[:, 1]
                d_a0 = None if ground else np.cos(phi) * da0[0] + np.sin(phi) * da0[1]
            else:
                a0 = axes0[:, k0]
                d_a0 = None if ground else da0[k0]
            rows1[row] = a0 @ da1[k1]
            if not ground:
                rows0[row] = axes1[:, k1] @ d_a0
            row += 1
        return [rows1] if ground else [rows0, rows1]


def _frame_bodies(marker0, marker1) -> tuple[int, ...]:
    return (marker1.body,) if isinstance(marker0, GroundFrame) else (marker0.body, marker1.body)


def revolute_joint(
    marker0, marker1, rotation0=None, rotation1=None, offset0=None, offset1=None, name: str = "revolute"
) -> MarkerJoint:
    """Revolute about the joint z-axis (5 equations)."""
    return MarkerJoint(
        _frame_bodies(marker0, marker1),
        name,
        marker0,
        marker1,
        np.eye(3) if rotation0 is None else np.asarray(rotation0, float),
        np.eye(3) if rotation1 is None else np.asarray(rotation1, float),
        np.zeros(3) if offset0 is None else np.asarray(offset0, float),
        np.zeros(3) if offset1 is None else np.asarray(offset1, float),
        (True, True, True, True, True, False),
    )


def fixed_joint(
    marker0, marker1, rotation0=None, rotation1=None, offset0=None, offset1=None, name: str = "fixed"
) -> MarkerJoint:
    """All six relative motions locked."""
    return replace(revolute_joint(marker0, marker1, rotation0, rotation1, offset0, offset1, name), locked=(True,) * 6)


def driven_revolute_joint(
    marker0,
    marker1,
    angle: Callable[[float], float],
    rotation0=None,
    rotation1=None,
    offset0=None,
    offset1=None,
    name: str = "drive",
) -> MarkerJoint:
    """Revolute whose relative rotation about z is prescribed, :math:`\\varphi(t)` (rad), Eq. (J3)."""
    joint = revolute_joint(marker0, marker1, rotation0, rotation1, offset0, offset1, name)
    return replace(joint, locked=(True,) * 6, angle=angle)
