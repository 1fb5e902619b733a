r"""Exudyn's definitions of force elements and loads where they differ from ours
(``docs/formulation.md`` Eqs. (E1)-(E4)), read in its C++ (``CObjectConnector*SpringDamper.cpp``,
``CMarkerSuperElementRigid.cpp``, ``CSystem::ComputeODE2SingleLoad``) and reproduced in our solver, so that
the single-body twins (:mod:`validation.single_body_forces`) agree to round-off once aligned and every
difference is attributed:

**Marker velocity (damping of spring-dampers).** Exudyn's marker velocities use the frame's angular
velocity :math:`\bar\omega = \bar G\dot p`; the derivative of :math:`g(q)` with the quadratic form :math:`A(p)`
(Eq. (R1)) has the extra term :math:`2(p\cdot\dot p)Au`, which index-3 integration does not keep at zero. Our
dampers (Eq. (E1), :func:`ffrf.system.forces.tangent_rates`) project :math:`\dot p` onto the tangent of
:math:`p\cdot p = 1` as Exudyn does, so the two agree without alignment.

**Rotation Jacobian of ``MarkerSuperElementRigid`` (torque loads).** Exudyn's ``LoadTorqueVector`` uses
:math:`Q = J_\omega^TM` with :math:`J_\omega = A[\bar G_{2}, T(\theta)\Theta]` (``TExpSO3``, our right
Jacobian :math:`T`, ``experimental.markerSuperElementRigidTexpSO3 = 1``); the marker frame
:math:`A\exp(\tilde\theta)` turns at :math:`A(\bar\omega + \exp(\tilde\theta)T\dot\theta)`, which is our
:math:`G_\omega` of Eq. (E4). Exudyn's torque on an elastically rotating interface thus misses a factor
:math:`\exp(\tilde\theta)` (O(:math:`|\theta|`) relative in the modal forces); on the frame interface
(:math:`\theta \equiv 0`) both agree. :class:`ExudynMarkerLoad` uses Exudyn's :math:`J_\omega`.

**RigidBodySpringDamper vs our six-equation spring-damper.** Exudyn (not intrinsic): displacement
:math:`A_0^T(p_1 - p_0)` and the xyz (Tait-Bryan) angles of :math:`A_0^TA_1`, force and torque
:math:`A_0 f`, :math:`f = K(u - u_0) + D\,[A_0^T(v_1 - v_0); A_0^T(\omega_1 - \omega_0)]`, the torque applied
through :math:`J_\omega` (not the gradient of a potential). Ours: :math:`g = (p_1 - p_0, z_0\cdot y_1,
z_0\cdot x_1, x_0\cdot y_1)` with :math:`Q = -C_q^Tf` (Eqs. (E1)-(E2)): the rotation equations are
:math:`(\varphi_x, -\varphi_y, -\varphi_z) + O(\varphi^2)` of the relative rotation vector, the xyz angles
:math:`\varphi + O(\varphi^2)`, so for diagonal stiffness the torques agree to first order and differ by
O(:math:`k\varphi^2`). :class:`ExudynRigidBodySpringDamper` is Exudyn's element in our solver.

Read in the C++ of Exudyn 1.11 (the mirrored source) and confirmed on the installed 1.13.6 by the twins
(``tests/test_validation/test_force_elements_vs_exudyn.py``: round-off once aligned). ``exudyn`` is not
needed here.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ffrf.body.euler_parameters import rotation_matrix
from ffrf.system.forces import ForceElement, MarkerLoad, marker_jacobians, tangent_rates
from ffrf.system.joints import GroundFrame, exp_so3_tangent
from ffrf.system.markers import BodyMarker

from .force_specs import BushingSpring

__all__ = [
    "ExudynMarkerLoad",
    "ExudynRigidBodySpringDamper",
    "exudyn_marker_jacobians",
    "exudyn_marker_load",
    "xyz_angles",
]


def exudyn_marker_jacobians(marker: BodyMarker, q: NDArray) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    r"""Point, axes, :math:`G_p` and Exudyn's rotation Jacobian of a ``MarkerSuperElementRigid``:
    our :math:`G_\omega` of Eq. (E4) with the modal columns :math:`A\,T(\theta)\Theta` instead of
    :math:`A\exp(\tilde\theta)T(\theta)\Theta`."""
    point, axes, g_point, g_omega = marker_jacobians(marker, q)
    theta = marker.rotation_vector(q)
    if marker.rotation_modes.shape[1]:
        modes = marker.rotation_modes.astype(q.dtype)
        g_omega = g_omega.copy()
        g_omega[:, 7:] = rotation_matrix(np.ascontiguousarray(q[3:7])) @ exp_so3_tangent(theta) @ modes
    return point, axes, g_point, g_omega


@dataclass(frozen=True, eq=False)
class ExudynMarkerLoad(MarkerLoad):
    """Eq. (E3) with Exudyn's rotation Jacobian (:func:`exudyn_marker_jacobians`) for the torque."""

    def forces(self, blocks, velocities, t):
        _, axes, g_point, g_omega = exudyn_marker_jacobians(self.marker, blocks[0])
        force, torque = (
            np.zeros(3) if v is None else np.asarray(v(t) if callable(v) else v, dtype=float)
            for v in (self.force, self.torque)
        )
        if self.frame == "marker":
            force, torque = axes @ force, axes @ torque
        return [g_point.T @ force + g_omega.T @ torque]


def _copy_as(cls: type, element: Any) -> Any:
    return cls(**{f.name: getattr(element, f.name) for f in dataclasses.fields(element)})


def exudyn_marker_load(load: MarkerLoad) -> ExudynMarkerLoad:
    """``load`` with Exudyn's rotation Jacobian."""
    return _copy_as(ExudynMarkerLoad, load)


def xyz_angles(rotation: NDArray) -> NDArray:
    r"""Exudyn's ``RotationMatrix2RotXYZ``: angles :math:`(\alpha, \beta, \gamma)` with
    :math:`R = R_x(\alpha)R_y(\beta)R_z(\gamma)`, for :math:`|\alpha|, |\beta|, |\gamma| < \pi/2`
    (``atan2(y, x) = atan(y / x)`` for x > 0, so that complex steps pass)."""
    r = rotation
    if np.real(r[2, 2]) <= 0.0 or np.real(r[0, 0]) <= 0.0:
        raise ValueError("xyz angles beyond pi/2: the small-rotation spring-damper does not apply")
    c1 = np.sqrt(r[1, 2] ** 2 + r[2, 2] ** 2)
    return np.array([np.arctan(-r[1, 2] / r[2, 2]), np.arctan(r[0, 2] / c1), np.arctan(-r[0, 1] / r[0, 0])])


@dataclass(frozen=True, eq=False)
class ExudynRigidBodySpringDamper(ForceElement):
    r"""Exudyn's ``RigidBodySpringDamper`` (not intrinsic) from the ground frame ``marker0`` (axes :math:`A_0`) to
    ``marker1`` (axes :math:`A_1`): :math:`u = [A_0^T(p_1 - p_0); \mathrm{xyz}(A_0^TA_1)]`,
    :math:`f = K(u - u_0) + D[A_0^Tv_1; A_0^T\omega_1]` with Exudyn's marker velocity and angular velocity
    :math:`\omega_1 = A_1(\bar\omega + T\dot\theta)` (its C++ multiplies the marker orientation with the body-frame
    angular velocity; checked only on the frame interface, where :math:`\theta \equiv 0`);
    :math:`Q = -(G_p^TA_0f_t + J_\omega^TA_0f_r)`. Marker 0 is the ground."""

    marker0: GroundFrame
    marker1: BodyMarker
    stiffness: NDArray[np.float64]
    damping: NDArray[np.float64]
    offset: NDArray[np.float64]

    @classmethod
    def diagonal(
        cls, name: str, marker0: GroundFrame, marker1: BodyMarker, spec: BushingSpring
    ) -> ExudynRigidBodySpringDamper:
        """The element of a :class:`validation.force_specs.BushingSpring` (diagonal, offset in translation)."""
        offset = np.r_[np.asarray(spec.offset, dtype=float), np.zeros(3)]
        return cls((marker1.body,), name, marker0, marker1, np.diag(spec.stiffness), np.diag(spec.damping), offset)

    def forces(self, blocks, velocities, t):
        q = blocks[0]
        qd = tangent_rates(q, velocities[0])
        point, axes, g_point, g_omega = exudyn_marker_jacobians(self.marker1, q)
        a0 = self.marker0.rotation
        body_rotation = rotation_matrix(np.ascontiguousarray(q[3:7]))
        omega = axes @ (body_rotation.T @ (g_omega @ qd))  # A_1 * angularVelocityLocal, as Exudyn
        u = np.r_[a0.T @ (point - self.marker0.point), xyz_angles(a0.T @ axes)]
        rate = np.r_[a0.T @ (g_point @ qd), a0.T @ omega]
        f = self.stiffness @ (u - self.offset) + self.damping @ rate
        return [-(g_point.T @ (a0 @ f[:3]) + g_omega.T @ (a0 @ f[3:]))]
