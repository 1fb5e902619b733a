r"""A revolute joint with play: a pin that sits loose in its bore (``docs/formulation.md``, Sect. "Joints with
play", Eqs. (P1)-(P5)).

The joint's frames are those of a :class:`~ffrf.system.joints.MarkerJoint`: frame 0 is the bore (its z axis the
bore's axis, its point the bore's centre), frame 1 the pin (its z axis the pin's axis, its point the pin's centre).
Instead of the revolute joint's five equations, contact forces hold the pin:

* radial (P1): at each of the pin's two rims, :math:`x_\pm = p_1 \pm \tfrac L2 z_1`, the distance from the bore's
  axis :math:`d_\pm = |e_\perp|`, :math:`e_\perp = (I - z_0z_0^T)(x_\pm - p_0)`, may not exceed the radial clearance
  :math:`c` (bore radius minus pin radius); two rims give the tilt a pin of length :math:`L` has in its bore;
* axial (P2): the pin's axial offset :math:`a = z_0\cdot(p_1 - p_0)` may not exceed half the axial play;
* each contact is a penalty with Hunt-Crossley damping, :math:`f = \max(0,\ k\,\delta + \chi\,\delta\dot\delta)` on
  its penetration :math:`\delta` (P3), the generalized force :math:`Q = -(\partial\delta/\partial q)^T f`; the
  spring part is the gradient of :math:`\tfrac12 k\,\delta^2`, so the joint stores energy and its tangent is
  symmetric (P4).

Rotation about the bore's axis stays free. With zero clearance a contact is bilateral (a bushing:
:math:`\tfrac12 k |e_\perp|^2`), so the joint tends to the ideal revolute joint as :math:`k` grows. Forces are
analytic in ``q`` and ``qd`` away from contact switches, so the complex-step tangents
(:func:`~ffrf.system.forces.element_tangents`) are exact there and Newton converges quadratically.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ffrf.system.forces import ForceElement, element_tangents, tangent_rates
from ffrf.system.joints import GroundFrame, MarkerJoint, joint_side
from ffrf.system.marker_kernels import marker_frame_hessian

__all__ = ["ClearanceJoint", "Contact", "PinFit", "clearance_joint", "line_contact_stiffness"]


def line_contact_stiffness(young0: float, poisson0: float, young1: float, poisson1: float, length: float) -> float:
    r"""Eq. (P5): penalty stiffness (N/m) of one rim of a pin of contact length ``length`` (m) in a bore, the pin of
    one material and the bore of the other: :math:`k = E^*\,L/2` with the plane-strain contact modulus
    :math:`1/E^* = (1 - \nu_0^2)/E_0 + (1 - \nu_1^2)/E_1`, the order of a line contact's linearised stiffness per unit
    length (Johnson, Contact Mechanics, Sect. 5.2, without its logarithmic factor) times the rim's share of the
    length."""
    for young, poisson in ((young0, poisson0), (young1, poisson1)):
        if not young > 0.0 or not 0.0 <= poisson < 0.5:
            raise ValueError(
                f"line contact stiffness: needs E > 0 and 0 <= nu < 0.5 for pin and bore, got E={young}, nu={poisson}"
            )
    if not length > 0.0:
        raise ValueError(f"line contact stiffness: needs a contact length > 0 m, got {length}")
    modulus = 1.0 / ((1.0 - poisson0**2) / young0 + (1.0 - poisson1**2) / young1)
    return modulus * 0.5 * length


@dataclass(frozen=True)
class PinFit:
    """How a pin sits in its bore (SI): radial clearance (bore radius minus pin radius, m), axial play (m, in all),
    contact length (m), penalty stiffness per contact (N/m; ``None``: from the materials, Eq. (P5)) and
    Hunt-Crossley damping (N s/m^2)."""

    radial: float
    axial: float
    pin_length: float
    stiffness: float | None = None
    damping: float = 0.0


@dataclass(frozen=True)
class Contact:
    """One contact of a :class:`ClearanceJoint` at a state: which (``"rim -"``, ``"rim +"``, ``"axial"``), its
    distance (radial: the rim's distance from the bore axis; axial: the pin's axial offset, m), its penetration
    (m, positive in contact) and normal force (N, at least zero)."""

    name: str
    distance: float
    penetration: float
    force: float


@dataclass(frozen=True, eq=False)
class ClearanceJoint(ForceElement):
    """Eqs. (P1)-(P4): the pin (frame 1 of ``joint``) in the bore (frame 0) with radial clearance ``radial`` (m),
    axial play ``axial`` (m, in all: the pin slides by half of it either way), contact length ``pin_length`` (m),
    penalty ``stiffness`` (N/m per contact) and Hunt-Crossley ``damping`` chi (N s/m^2 per contact)."""

    joint: MarkerJoint
    radial: float
    axial: float
    pin_length: float
    stiffness: float
    damping: float

    @property
    def reads_velocities(self) -> bool:
        return self.damping != 0.0

    @property
    def conservative(self) -> bool:
        return not self.reads_velocities

    @property
    def separates(self) -> bool:
        return self.radial > 0.0 or self.axial > 0.0

    def _frames(self, blocks: list[NDArray]) -> tuple[NDArray, list[NDArray]]:
        """The joint's frame coordinates ``y = (p0, z0, p1, z1)`` (12) and, per body, ``G = dy/dq`` (12 x n): every
        contact is a function of ``y`` (Eqs. (P1)-(P2)), its ``q``-derivatives follow by the chain rule."""
        j = self.joint
        ground = isinstance(j.marker0, GroundFrame)
        p0, a0, dp0, da0 = joint_side(j.marker0, None if ground else blocks[0], j.rotation0, j.offset0)
        p1, a1, dp1, da1 = joint_side(j.marker1, blocks[-1], j.rotation1, j.offset1)
        y = np.concatenate([p0, a0[:, 2], p1, a1[:, 2]])
        dtype = np.result_type(*blocks)
        out = []
        for side, (dp, da) in enumerate(((dp0, da0), (dp1, da1))[1 if ground else 0 :], start=1 if ground else 0):
            rows = np.zeros((12, dp.shape[1]), dtype=dtype)
            rows[6 * side : 6 * side + 3] = dp
            rows[6 * side + 3 : 6 * side + 6] = da[2]
            out.append(rows)
        return y, out

    def _gaps(self, y: NDArray, curvature: bool = False):
        """Per contact of the frames ``y``: name, gap (a scalar penetration when the contact has play, the bilateral
        vector or signed offset when it has none; ``None`` when apart), its rows ``d gap / dy``, whether it is
        unilateral, the distance, and with ``curvature`` the ``y``-Hessian of 1/2 |gap|^2 (Eq. (P7)). Written for
        any ``z0`` (not only unit ones), so that its ``y``-derivatives are those of the chain rule."""
        p0, z0, p1, z1 = y[:3], y[3:6], y[6:9], y[9:]
        dtype = y.dtype
        eye = np.eye(3)
        out: list[tuple] = []
        for name, s in (("rim -", -0.5 * self.pin_length), ("rim +", 0.5 * self.pin_length)):
            e = p1 + s * z1 - p0
            h = z0 @ e
            perp = e - h * z0
            distance = np.sqrt(perp @ perp)
            if self.radial > 0.0 and np.real(distance) <= self.radial:
                out.append((name, None, None, True, distance, None))
                continue
            # d perp = (I - z0 z0^T) de - (z0 e^T + h I) dz0, de = dp1 + s dz1 - dp0 (Eq. (P1))
            along = np.eye(3, dtype=dtype) - np.outer(z0, z0)
            rows = np.concatenate([-along, -(np.outer(z0, e) + h * eye), along, s * along], axis=1)
            if self.radial == 0.0:
                hessian = rows.T @ rows + _perp_curvature(z0, e, s, perp) if curvature else None
                out.append((name, perp, rows, False, distance, hessian))
                continue
            normal = perp / distance
            gap = distance - self.radial
            hessian = None
            if curvature:  # d2 d = rows^T (I - n n^T) rows / d + d2 (n . perp) at fixed n
                radial_rows = normal @ rows
                bend = rows.T @ (eye - np.outer(normal, normal)) @ rows / distance
                hessian = np.outer(radial_rows, radial_rows) + gap * (bend + _perp_curvature(z0, e, s, normal))
            out.append((name, np.reshape(gap, (1,)), (normal @ rows)[None], True, distance, hessian))
        offset = z0 @ (p1 - p0)
        rows = np.concatenate([-z0, p1 - p0, z0, np.zeros(3, dtype=dtype)])[None]
        if self.axial == 0.0:
            sign, gap = 1.0, offset
        elif abs(np.real(offset)) <= 0.5 * self.axial:
            out.append(("axial", None, None, True, offset, None))
            return out
        else:
            sign = 1.0 if np.real(offset) > 0.0 else -1.0
            gap = sign * offset - 0.5 * self.axial
        hessian = None
        if curvature:  # the offset's only second derivatives: d2 / dz0 dp1 = I, d2 / dz0 dp0 = -I
            hessian = rows.T @ rows
            mixed = np.zeros((12, 12))
            mixed[3:6, 6:9], mixed[3:6, 0:3] = eye, -eye
            hessian = hessian + sign * gap * (mixed + mixed.T)
        out.append(("axial", np.reshape(gap, (1,)), sign * rows, self.axial != 0.0, offset, hessian))
        return out

    def _contacts(self, blocks: list[NDArray], velocities: list[NDArray]):
        """Per contact: name, penetration, rows ``d gap / dy``, force (Eq. (P3)), distance, rate of penetration; and
        the rows ``dy/dq`` per body."""
        y, frames = self._frames(blocks)
        rates = sum(g @ tangent_rates(b, v) for g, b, v in zip(frames, blocks, velocities, strict=True))
        out = []
        for name, gap, rows, unilateral, distance, _ in self._gaps(y):
            if gap is None:
                out.append((name, None, None, None, distance, None))
                continue
            rate = rows @ rates
            # Hunt-Crossley: damping grows with the penetration, so the force starts and ends at zero (Eq. (P3))
            force = self.stiffness * gap + self.damping * np.sqrt(gap @ gap) * rate
            if unilateral and np.real(force[0]) <= 0.0:  # a contact pushes, never pulls (Eq. (P3))
                force = 0.0 * force
            out.append((name, gap, rows, force, distance, rate))
        return out, frames

    def forces(self, blocks, velocities, t):
        contacts, frames = self._contacts(blocks, velocities)
        pull = sum((rows.T @ force for _, gap, rows, force, _, _ in contacts if gap is not None), np.zeros(12))
        return [-(g.T @ pull) for g in frames]

    def tangents(self, blocks, velocities, t):
        r"""Without damping, Eq. (P7): :math:`\partial Q/\partial q = -(G^T V_{yy} G + \sum_b V_y\cdot\partial^2
        y_b/\partial q_b^2)` with the frames' second derivatives of Eq. (FP3), all analytic. With damping, complex
        steps of the forces (:func:`~ffrf.system.forces.element_tangents`)."""
        if self.damping != 0.0:
            return element_tangents(self, blocks, velocities, t)
        y, frames = self._frames(blocks)
        gradient, curvature = np.zeros(12), np.zeros((12, 12))
        for _, gap, rows, _, _, hessian in self._gaps(y, curvature=True):
            if gap is not None:
                gradient += self.stiffness * (rows.T @ gap)
                curvature += self.stiffness * hessian
        j = self.joint
        sides = ((j.marker0, j.rotation0, j.offset0), (j.marker1, j.rotation1, j.offset1))[2 - len(blocks) :]
        d_q = [[-(ga.T @ curvature @ gb) for gb in frames] for ga in frames]
        for b, ((marker, rotation, offset), q) in enumerate(zip(sides, blocks, strict=True)):
            side = 6 * (b + 2 - len(blocks))
            weight_axes = np.zeros((3, 3))
            weight_axes[:, 2] = gradient[side + 3 : side + 6]
            d_q[b][b] -= marker_frame_hessian(
                np.ascontiguousarray(q, dtype=float),
                np.ascontiguousarray(marker.point, dtype=float),
                np.ascontiguousarray(marker.position_modes, dtype=float),
                np.ascontiguousarray(marker.rotation_modes, dtype=float),
                np.ascontiguousarray(rotation, dtype=float),
                np.ascontiguousarray(offset, dtype=float),
                np.ascontiguousarray(gradient[side : side + 3]),
                weight_axes,
            )
        return d_q, [[np.zeros_like(block) for block in row] for row in d_q]

    def potential_energy(self, blocks, t):
        """Eq. (P4): 1/2 k delta^2 summed over the contacts in touch (J)."""
        total = 0.0
        for _, gap, _, _, _, _ in self._gaps(self._frames(blocks)[0]):
            if gap is not None:
                total += 0.5 * self.stiffness * float(np.real(np.sum(gap * gap)))
        return total

    def contacts(self, blocks: list[NDArray], velocities: list[NDArray] | None = None) -> list[Contact]:
        """The two rims' and the axial contact's distances, penetrations and normal forces at a state (zero
        velocities unless given): what a run reports of the pin in its bore."""
        velocities = [np.zeros_like(b) for b in blocks] if velocities is None else velocities
        out = []
        for name, gap, _, force, distance, _ in self._contacts(blocks, velocities)[0]:
            play = self.radial if name != "axial" else 0.5 * self.axial
            magnitude = 0.0 if gap is None else float(np.linalg.norm(np.real(np.atleast_1d(force))))
            size = float(np.abs(np.real(distance)))
            out.append(Contact(name, size, size - play, magnitude))
        return out

    def dissipation_rate(self, blocks: list[NDArray], velocities: list[NDArray]) -> float:
        """Power the contacts' dampers take from the motion (W): chi delta delta_dot^2 summed over the contacts pushing
        (a clipped contact, whose spring and damper cancel, takes what its spring gives back)."""
        total = 0.0
        for _, gap, _, force, _, rate in self._contacts(blocks, velocities)[0]:
            if gap is None:
                continue
            spring = self.stiffness * gap
            total += float(np.real(np.sum((force - spring) * rate)))
        return total


def clearance_joint(
    joint: MarkerJoint,
    radial: float,
    axial: float,
    pin_length: float,
    stiffness: float,
    damping: float = 0.0,
) -> ClearanceJoint:
    """``joint`` (a revolute joint: frame 0 the bore, frame 1 the pin) with play (Eqs. (P1)-(P4)); lengths in m."""
    if joint.angle is not None or joint.locked != (True, True, True, True, True, False):
        raise ValueError(
            f"clearance joint {joint.name!r}: needs a passive revolute joint (five locked directions, no prescribed "
            "angle); drive a loose joint with a separate driven joint or a JointTorque"
        )
    values = {"radial": radial, "axial": axial, "pin_length": pin_length, "stiffness": stiffness, "damping": damping}
    bad = {k: v for k, v in values.items() if not np.isfinite(v) or v < 0.0}
    if bad or pin_length <= 0.0 or stiffness <= 0.0:
        raise ValueError(
            f"clearance joint {joint.name!r}: clearances and damping must be >= 0 and the pin length and stiffness "
            f"> 0 (m, N/m, N s/m), got {values}"
        )
    return ClearanceJoint(joint.bodies, joint.name, joint, radial, axial, pin_length, stiffness, damping)


def _perp_curvature(z0: NDArray, e: NDArray, s: float, weight: NDArray) -> NDArray:
    r"""Eq. (P7): the ``y``-Hessian of :math:`w\cdot e_\perp` at fixed ``w``, :math:`e_\perp = e - (z_0\cdot e) z_0`,
    :math:`e = p_1 + s z_1 - p_0`: :math:`\partial^2/\partial e\,\partial z_0 = -(z_0 w^T + (w\cdot z_0) I)`,
    :math:`\partial^2/\partial z_0^2 = -(w e^T + e w^T)`, ``e`` linear in ``y``."""
    eye = np.eye(3)
    along = np.concatenate([-eye, np.zeros((3, 3)), eye, s * eye], axis=1)  # de/dy
    mixed = along.T @ -(np.outer(z0, weight) + (weight @ z0) * eye)  # (12, 3): columns z0
    out = np.zeros((12, 12), dtype=np.result_type(z0, e, weight))
    out[:, 3:6] += mixed
    out[3:6, :] += mixed.T
    out[3:6, 3:6] -= np.outer(weight, e) + np.outer(e, weight)
    return out
