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

from ffrf.system.forces import ForceElement, tangent_rates
from ffrf.system.joints import GroundFrame, MarkerJoint, joint_side

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


def _as_rows(gap, rows0, rows1):
    """A scalar gap and its gradients as a one-row gap vector and one-row Jacobians (one form for every contact)."""
    return np.reshape(gap, (1,)), None if rows0 is None else np.reshape(rows0, (1, -1)), np.reshape(rows1, (1, -1))


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
    def separates(self) -> bool:
        return self.radial > 0.0 or self.axial > 0.0

    def _sides(self, blocks: list[NDArray]):
        j = self.joint
        q0 = None if isinstance(j.marker0, GroundFrame) else blocks[0]
        p0, a0, dp0, da0 = joint_side(j.marker0, q0, j.rotation0, j.offset0)
        p1, a1, dp1, da1 = joint_side(j.marker1, blocks[-1], j.rotation1, j.offset1)
        return p0, a0, dp0, da0, p1, a1, dp1, da1

    def _gaps(self, blocks: list[NDArray]):
        """Per contact: name, gap (a scalar penetration when the contact has play, the bilateral vector or signed
        offset when it has none), its rows ``d gap / dq`` per body, whether it is unilateral, and the distance."""
        p0, a0, dp0, da0, p1, a1, dp1, da1 = self._sides(blocks)
        ground = dp0 is None
        z0, z1 = a0[:, 2], a1[:, 2]
        projector = np.eye(3) - np.outer(z0, z0)
        out = []
        for name, s in (("rim -", -0.5 * self.pin_length), ("rim +", 0.5 * self.pin_length)):
            e = p1 + s * z1 - p0
            h = z0 @ e
            perp = e - h * z0
            # d perp = (I - z0 z0^T) de - h dz0 - z0 (e . dz0), with de = dp1 + s dz1 - dp0 (Eq. (P1))
            rows1 = projector @ (dp1 + s * da1[2])
            rows0 = None if ground else -(projector @ dp0) - h * da0[2] - np.outer(z0, e @ da0[2])
            distance = np.sqrt(perp @ perp)
            if self.radial == 0.0:
                out.append((name, perp, rows0, rows1, False, distance))
                continue
            if np.real(distance) <= self.radial:
                out.append((name, None, None, None, True, distance))
                continue
            normal = perp / distance
            gap, rows0, rows1 = distance - self.radial, None if ground else normal @ rows0, normal @ rows1
            out.append((name, *_as_rows(gap, rows0, rows1), True, distance))
        offset = z0 @ (p1 - p0)
        rows1 = z0 @ dp1
        rows0 = None if ground else -(z0 @ dp0) + (p1 - p0) @ da0[2]
        if self.axial == 0.0:
            out.append(("axial", *_as_rows(offset, rows0, rows1), False, offset))
        elif abs(np.real(offset)) <= 0.5 * self.axial:
            out.append(("axial", None, None, None, True, offset))
        else:
            sign = 1.0 if np.real(offset) > 0.0 else -1.0
            signed0 = None if rows0 is None else sign * rows0
            out.append(("axial", *_as_rows(sign * offset - 0.5 * self.axial, signed0, sign * rows1), True, offset))
        return out

    def _contacts(self, blocks: list[NDArray], velocities: list[NDArray]):
        """Per contact: name, penetration, rows, force (Eq. (P3)), distance."""
        rates = [tangent_rates(b, v) for b, v in zip(blocks, velocities, strict=True)]
        ground = len(blocks) == 1
        out = []
        for name, gap, rows0, rows1, unilateral, distance in self._gaps(blocks):
            if gap is None:
                out.append((name, None, None, None, None, distance))
                continue
            rate = rows1 @ rates[-1] + (0.0 if ground else rows0 @ rates[0])
            # Hunt-Crossley: damping grows with the penetration, so the force starts and ends at zero (Eq. (P3))
            force = self.stiffness * gap + self.damping * np.sqrt(gap @ gap) * rate
            if unilateral and np.real(force[0]) <= 0.0:  # a contact pushes, never pulls (Eq. (P3))
                force = 0.0 * force
            out.append((name, gap, rows0, rows1, force, distance))
        return out

    def forces(self, blocks, velocities, t):
        dtype = np.result_type(*blocks, *velocities)
        out = [np.zeros(b.shape[0], dtype=dtype) for b in blocks]
        for _, gap, rows0, rows1, force, _ in self._contacts(blocks, velocities):
            if gap is None:
                continue
            out[-1] = out[-1] - rows1.T @ force
            if len(blocks) == 2:
                out[0] = out[0] - rows0.T @ force
        return out

    def potential_energy(self, blocks, t):
        """Eq. (P4): 1/2 k delta^2 summed over the contacts in touch (J)."""
        total = 0.0
        for _, gap, _, _, _, _ in self._gaps(blocks):
            if gap is not None:
                total += 0.5 * self.stiffness * float(np.real(np.sum(gap * gap)))
        return total

    def contacts(self, blocks: list[NDArray], velocities: list[NDArray] | None = None) -> list[Contact]:
        """The two rims' and the axial contact's distances, penetrations and normal forces at a state (zero
        velocities unless given): what a run reports of the pin in its bore."""
        velocities = [np.zeros_like(b) for b in blocks] if velocities is None else velocities
        out = []
        for name, gap, _, _, force, distance in self._contacts(blocks, velocities):
            play = self.radial if name != "axial" else 0.5 * self.axial
            magnitude = 0.0 if gap is None else float(np.linalg.norm(np.real(np.atleast_1d(force))))
            size = float(np.abs(np.real(distance)))
            out.append(Contact(name, size, size - play, magnitude))
        return out

    def dissipation_rate(self, blocks: list[NDArray], velocities: list[NDArray]) -> float:
        """Power the contacts' dampers take from the motion (W): chi delta delta_dot^2 summed over the contacts pushing
        (a clipped contact, whose spring and damper cancel, takes what its spring gives back)."""
        rates = [tangent_rates(b, v) for b, v in zip(blocks, velocities, strict=True)]
        total = 0.0
        for _, gap, rows0, rows1, force, _ in self._contacts(blocks, velocities):
            if gap is None:
                continue
            rate = rows1 @ rates[-1] + (0.0 if len(blocks) == 1 else rows0 @ rates[0])
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
