r"""Joints of a scene description: each side's body, interface, axis and point, and the constraint built from them.

A joint's two sides may carry different axes and points (as built, :mod:`ffrf.scenes.builder`); the joint frames
are :math:`J_1 = F(z_1)`, :math:`J_0 = F(z_0, x_{J_1})` with :func:`~ffrf.system.joints.frame_from_axis`, side 0
turned ``fraction`` of the way from side 1's frame and point to its own. Force elements on joints
(:mod:`ffrf.scenes.scene_forces`) use the same geometry.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from ffrf.errors import SceneError
from ffrf.system.clearance_joint import ClearanceJoint, PinFit, clearance_joint, line_contact_stiffness
from ffrf.system.drives import CosineRamp, RampedAngle, rpm
from ffrf.system.joints import (
    GroundFrame,
    MarkerJoint,
    driven_revolute_joint,
    fixed_joint,
    frame_from_axis,
    revolute_joint,
    turned_frame,
)
from ffrf.system.markers import BodyMarker, attach_joint_point

__all__ = [
    "HasMarkers",
    "JointGeometry",
    "drive_from_spec",
    "joint_constraint",
    "joint_geometry",
    "loose_joint",
    "pin_fit",
]


class HasMarkers(Protocol):
    """A built body of a scene: one rigid marker per interface (:class:`ffrf.scenes.builder.SceneBody`)."""

    @property
    def markers(self) -> dict[str, BodyMarker]: ...


@dataclass(frozen=True)
class JointGeometry:
    """A joint as described: type, sides (body index and interface; side 0 may be the ground,
    ``(None, None)``, side 1 is always a body), each side's axis and point (mesh coordinates) and
    the prescribed angle of a driven joint."""

    name: str
    kind: str
    bodies: tuple[int | None, int]
    interfaces: tuple[str | None, str]
    axes: tuple[NDArray[np.float64], NDArray[np.float64]]
    points: tuple[NDArray[np.float64], NDArray[np.float64]]
    angle: RampedAngle | None = None
    fit: PinFit | None = None

    @property
    def misfit_degrees(self) -> float:
        """Angle between the two sides' axes (deg)."""
        a, b = (axis / np.linalg.norm(axis) for axis in self.axes)
        return math.degrees(math.atan2(float(np.linalg.norm(np.cross(a, b))), float(a @ b)))

    @property
    def misfit(self) -> bool:
        return self.misfit_degrees > 0.0 or bool(np.any(self.points[0] != self.points[1]))


def drive_from_spec(spec: dict) -> RampedAngle:
    omega = float(spec["omega"]) if "omega" in spec else rpm(float(spec["rpm"]))
    start = (
        float(spec["start_angle"]) if "start_angle" in spec else math.radians(float(spec.get("start_angle_deg", 0.0)))
    )
    return RampedAngle(float(start), CosineRamp(omega, float(spec.get("ramp_time", 1.0))))


def pin_fit(spec: dict) -> PinFit:
    """A ``clearance = {radial_mm, axial_mm, pin_length_mm, stiffness, damping}`` table in SI units."""
    return PinFit(
        1e-3 * float(spec["radial_mm"]),
        1e-3 * float(spec.get("axial_mm", 0.0)),
        1e-3 * float(spec["pin_length_mm"]),
        float(spec["stiffness"]) if "stiffness" in spec else None,
        float(spec.get("damping", 0.0)),
    )


def joint_geometry(
    spec: dict, index: dict[str, int], bodies: Sequence[HasMarkers], clearance: dict | None = None
) -> JointGeometry:
    """The sides of a joint as described; body 1 is always a body (the ground goes to side 0). A passive revolute
    joint has its own ``clearance`` table, else the scene's (``clearance``, ``None``: every joint ideal)."""
    sides = [
        (None, None) if spec[f"body{s}"] == "ground" else (index[spec[f"body{s}"]], spec[f"interface{s}"])
        for s in ("0", "1")
    ]
    keys = ("0", "1")
    if sides[1][0] is None:
        sides, keys = sides[::-1], keys[::-1]
    axis = spec.get("axis", [0.0, 0.0, 1.0])
    body1, interface1 = sides[1]
    if body1 is None or interface1 is None:  # check_scene rejects it first
        raise SceneError(f"joint {spec.get('name', 'joint')!r}: at least one side must be a body, both are 'ground'")
    point = spec.get("point", bodies[body1].markers[interface1].point)
    axis0, axis1 = (np.asarray(spec.get(f"axis{s}", axis), dtype=np.float64) for s in keys)
    point0, point1 = (np.asarray(spec.get(f"point{s}", point), dtype=np.float64) for s in keys)
    return JointGeometry(
        spec.get("name", "joint"),
        spec.get("type", "revolute"),
        (sides[0][0], body1),
        (sides[0][1], interface1),
        (axis0, axis1),
        (point0, point1),
        drive_from_spec(spec["drive"]) if "drive" in spec else None,
        _fit(spec, clearance),
    )


def _fit(spec: dict, clearance: dict | None) -> PinFit | None:
    if spec.get("type", "revolute") != "revolute":
        return None
    own = spec.get("clearance", clearance)
    return None if own is None else pin_fit(own)


def _material(body: HasMarkers) -> tuple[float, float] | None:
    material = getattr(getattr(body, "fe", None), "material", None)
    return None if material is None else (float(material.E), float(material.nu))


def loose_joint(
    joint: JointGeometry, bodies: Sequence[HasMarkers], joint_offsets: str, fraction: float
) -> ClearanceJoint:
    """The revolute ``joint`` with its play (Eqs. (P1)-(P5)): side 0 the bore, side 1 the pin; the contact stiffness,
    unless given, from the two bodies' materials (the pin's for both on the ground)."""
    if joint.fit is None:
        raise SceneError(f"joint {joint.name!r} has no clearance")
    fit = joint.fit
    stiffness = fit.stiffness
    if stiffness is None:
        pin = _material(bodies[joint.bodies[1]])
        bore = pin if joint.bodies[0] is None else _material(bodies[joint.bodies[0]])
        if pin is None or bore is None:
            raise SceneError(
                f"joint {joint.name!r}: a body given by its matrices has no material for the contact stiffness; give "
                "clearance.stiffness (N/m per contact)"
            )
        stiffness = line_contact_stiffness(*pin, *bore, fit.pin_length)
    rigid = joint_constraint(joint, bodies, joint_offsets, fraction)
    return clearance_joint(rigid, fit.radial, fit.axial, fit.pin_length, stiffness, fit.damping)


def joint_constraint(
    joint: JointGeometry, bodies: Sequence[HasMarkers], joint_offsets: str, fraction: float
) -> MarkerJoint:
    """Eqs. (J1)-(J3) for ``joint`` with side 0 at ``fraction`` of its misfit (module docstring)."""
    frame1 = frame_from_axis(joint.axes[1])
    point1 = joint.points[1]
    if joint.misfit:
        own = frame_from_axis(joint.axes[0], frame1[:, 0])
        frame0 = turned_frame(frame1, own, fraction)
        point0 = point1 + fraction * (joint.points[0] - point1)
    else:
        frame0, point0 = frame1, joint.points[0]
    body1, interface1 = joint.bodies[1], joint.interfaces[1]
    side1, offset1 = attach_joint_point(bodies[body1].markers[interface1], point1, joint_offsets)
    body0, interface0 = joint.bodies[0], joint.interfaces[0]
    side0: GroundFrame | BodyMarker
    if body0 is None:
        side0, offset0 = GroundFrame(point0, np.eye(3)), np.zeros(3)
    elif interface0 is None:
        raise SceneError(f"joint {joint.name!r}: side 0 is body {body0} but names no interface")
    else:
        side0, offset0 = attach_joint_point(bodies[body0].markers[interface0], point0, joint_offsets)
    if joint.kind == "revolute":
        return revolute_joint(side0, side1, frame0, frame1, offset0, offset1, name=joint.name)
    if joint.kind == "fixed":
        return fixed_joint(side0, side1, frame0, frame1, offset0, offset1, name=joint.name)
    if joint.angle is None:  # check_scene rejects it first
        raise SceneError(f"joint {joint.name!r}: a {joint.kind} joint needs a drive (its prescribed angle)")
    return driven_revolute_joint(side0, side1, joint.angle, frame0, frame1, offset0, offset1, name=joint.name)
