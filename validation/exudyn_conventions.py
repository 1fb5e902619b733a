r"""Exudyn's modelling conventions, measured on its items and reproduced in our solver, so that
every difference between the two solvers on the Bennett linkage is attributed.

**Offset convention (measured, see ``probe_marker_offset``).** Exudyn applies the translation
of a ``MarkerSuperElementRigid``'s ``localHT`` in the *body* frame:
``p = R + A (o + sum w_i (x_i + u_i))``. Our scenes do the same by default
(``joint_offsets="body"``, :func:`ffrf.system.markers.attach_joint_point`), so the twin's marker
translation is our marker point minus the interface's weighted centre and the models are
equivalent. With ``joint_offsets="marker"`` our joint point is ``r_M + A exp(theta_M) o``,
which Exudyn cannot express; the twin then applies ``o`` in the body frame and records a note
(``ExudynTwin.notes``): the two differ by ``A (exp(theta_M) - I) o`` (``|o|`` = 8.5 mm).
:func:`exudyn_convention_system` also moves any remaining joint offsets into the marker point.

**Marker rotation Jacobian (measured).** Exudyn's joint Jacobian uses the marker angular
velocity ``A (omega_bar + T(theta) theta_dot)``; the exact derivative of its own orientation
``A exp(theta~)`` is ``A (omega_bar + exp(theta~) T(theta) theta_dot)``. So Exudyn's reaction
``C_q^T lambda`` is not the gradient of its constraint equations when a non-frame interface
rotates elastically (O(``|theta|``) relative in the modal columns of the rotation rows; ``|theta|`` up
to 3e-4 here). ``exudyn_convention_system(..., exudyn_jacobian=True)`` reproduces it in our
solver (a :class:`ffrf.system.joints.MarkerJoint` subclass, same equations); then both solvers agree
to round-off.

Measured with :func:`probe_marker_offset`; :func:`exudyn_convention_system` gives one of our
systems both conventions. ``exudyn`` is imported lazily.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

__all__ = ["exudyn_convention_system", "probe_marker_offset"]


def _exudyn_joint_class():
    """:class:`ffrf.system.joints.MarkerJoint` with Exudyn's marker rotation Jacobian (see
    :func:`exudyn_convention_system`)."""
    from ffrf.body.euler_parameters import rotation_matrix
    from ffrf.numerics.small_linalg import skew
    from ffrf.system.joints import MarkerJoint, exp_so3_tangent, joint_side
    from ffrf.system.markers import exp_so3

    def axis_correction(marker, q, rotation):
        """Exudyn's minus the exact d(axis_k)/d zeta, k = 0..2: -A[(E w)~ - E w~] T Theta (3, 3, m)."""
        a_body = rotation_matrix(np.ascontiguousarray(q[3:7]))
        theta = marker.rotation_modes.astype(q.dtype) @ q[7:]
        turn, tangent = exp_so3(theta), exp_so3_tangent(theta)
        out = []
        for k in range(3):
            w = rotation[:, k].astype(q.dtype)
            out.append(-(a_body @ (skew(turn @ w) - turn @ skew(w)) @ tangent) @ marker.rotation_modes)
        return out

    class ExudynMarkerJoint(MarkerJoint):
        """Constraint equations as :class:`MarkerJoint`; in the Jacobian the modal columns of the
        rotation rows use Exudyn's marker angular velocity A(omega_bar + T theta_dot) instead of the
        exact A(omega_bar + exp(theta~) T theta_dot), so C_q^T lambda is Exudyn's reaction."""

        def jacobian(self, blocks, t):
            if not all(self.locked[:3]):
                raise NotImplementedError("Exudyn-Jacobian joints are implemented for locked translations only")
            rows = super().jacobian(blocks, t)
            q0, q1 = self._sides(blocks)
            ground = q0 is None
            _, axes0, _, _ = joint_side(self.marker0, q0, self.rotation0, self.offset0)
            _, axes1, _, _ = joint_side(self.marker1, q1, self.rotation1, self.offset1)
            c1 = axis_correction(self.marker1, q1, self.rotation1) if self.marker1.rotation_modes.shape[1] else None
            c0 = (
                axis_correction(self.marker0, q0, self.rotation0)
                if not ground and self.marker0.rotation_modes.shape[1]
                else None
            )
            rows0, rows1 = (None, rows[0]) if ground else (rows[0], rows[1])
            row = 3
            pairs = (
                [(2, 1, False)] * self.locked[3] + [(2, 0, False)] * self.locked[4] + [(0, 1, True)] * self.locked[5]
            )
            for k0, k1, turned in pairs:
                if turned and self.angle is not None:
                    phi = self.angle(t)
                    a0 = np.cos(phi) * axes0[:, 0] + np.sin(phi) * axes0[:, 1]
                    d0 = None if c0 is None else np.cos(phi) * c0[0] + np.sin(phi) * c0[1]
                else:
                    a0 = axes0[:, k0]
                    d0 = None if c0 is None else c0[k0]
                if c1 is not None:
                    rows1[row, 7:] += a0 @ c1[k1]
                if d0 is not None:
                    rows0[row, 7:] += axes1[:, k1] @ d0
                row += 1
            return rows

    return ExudynMarkerJoint


def exudyn_convention_system(system, exudyn_jacobian: bool = True):
    """``system`` with Exudyn's conventions: every joint offset moved into the marker point (body
    frame), as Exudyn's ``MarkerSuperElementRigid`` offset/``localHT`` translation
    (p = R + A(o + x_bar + P zeta)), and, with ``exudyn_jacobian``, Exudyn's marker rotation
    Jacobian (angular velocity A(omega_bar + T theta_dot), without the factor exp(theta~) in front
    of T that the exact derivative of its orientation A exp(theta~) has) in the joints' C_q.
    The constraint equations are ours either way."""
    from ffrf.system.joints import GroundFrame, MarkerJoint
    from ffrf.system.multibody import MultibodySystem

    joint_class = _exudyn_joint_class() if exudyn_jacobian else None
    constraints = []
    for c in system.constraints:
        if isinstance(c, MarkerJoint):
            changes: dict[str, Any] = {}  # replace()'s keyword arguments: markers and offsets
            for side in (0, 1):
                marker, offset = getattr(c, f"marker{side}"), getattr(c, f"offset{side}")
                if isinstance(marker, GroundFrame):
                    changes[f"marker{side}"] = dataclasses.replace(
                        marker, point=marker.point + marker.rotation @ offset
                    )
                else:
                    changes[f"marker{side}"] = dataclasses.replace(marker, point=marker.point + offset)
                changes[f"offset{side}"] = np.zeros(3)
            c = dataclasses.replace(c, **changes)
            if joint_class is not None:
                c = joint_class(**{f.name: getattr(c, f.name) for f in dataclasses.fields(c)})
        constraints.append(c)
    return MultibodySystem(system.bodies, tuple(constraints), gravity=system.gravity)


def probe_marker_offset(
    scene, link_index: int = 1, interface: str | None = None, zeta_scale: float = 0.03, offset=(0.01, -0.02, 0.005)
) -> dict[str, float]:
    """Where Exudyn puts a ``MarkerSuperElementRigid``'s ``localHT`` translation on a deformed body:
    distances of its marker position from R + A(x_bar + P zeta + o) (body frame) and from
    r_M + A exp(theta) o (marker frame, ours), and its orientation error against A exp(theta) R."""
    import exudyn as exu

    from ffrf.body.euler_parameters import rotation_matrix
    from ffrf.system.markers import exp_so3

    from .exudyn_items import add_ffrf_body, add_interface_marker

    link = scene.links[link_index]
    name = interface or list(link.interfaces)[-1]
    block = scene.q_start[scene.system.block(link_index)]
    a = rotation_matrix(block[3:7])
    m = link.reduction.basis.shape[1]
    zeta = zeta_scale * np.array([(-1.0) ** k * (k + 1) for k in range(m)]) / m
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    items = add_ffrf_body(mbs, link.fe.nodes, link.fe.mass, link.fe.stiffness, link.reduction.basis, block[:3], a, zeta)
    itf = link.interfaces[name]
    turn = rotation_matrix(np.array([np.cos(0.3), np.sin(0.3), 0.0, 0.0]))
    o = np.asarray(offset, float)
    marker = add_interface_marker(mbs, items.body, itf.nodes, itf.weights, turn, o)
    mbs.Assemble()
    out = exu.OutputVariableType
    position = np.asarray(mbs.GetMarkerOutput(marker, out.Position))
    rotation = np.asarray(mbs.GetMarkerOutput(marker, out.RotationMatrix)).reshape(3, 3)
    ours = link.markers[name]
    q = np.r_[block[:7], zeta]
    theta = ours.rotation_vector(q)
    return {
        "theta_norm": float(np.linalg.norm(theta)),
        "body_frame_distance": float(np.linalg.norm(position - (ours.position(q) + a @ o))),
        "marker_frame_distance": float(np.linalg.norm(position - (ours.position(q) + a @ exp_so3(theta) @ o))),
        "orientation_error": float(np.abs(rotation - a @ exp_so3(theta) @ turn).max()),
    }
