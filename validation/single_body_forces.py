r"""The force elements and loads of the single-body scenes (:mod:`validation.force_specs`) in their two
translations side by side: our elements (:mod:`ffrf.system.forces`,
``docs/formulation.md`` Eqs. (E1)-(E5)) and Exudyn's items (:mod:`validation.exudyn_items`).

* :class:`CartesianSpring`: Exudyn's ``CartesianSpringDamper`` from a ground point to an interface's weighted
  centre (``MarkerSuperElementPosition``); ours: :func:`~ffrf.system.forces.spring_damper` on a
  :class:`~ffrf.system.joints.MarkerJoint` locking the three translations (world components of p1 - p0), Eq. (E1).
* :class:`InterfaceLoad`: ``LoadForceVector`` / ``LoadTorqueVector`` on an interface's
  ``MarkerSuperElementRigid``, constant or a ``loadVectorUserFunction`` of time, world or ``bodyFixed``; ours:
  :class:`~ffrf.system.forces.MarkerLoad`, Eqs. (E3)-(E4).
* :class:`BushingSpring`: ``RigidBodySpringDamper`` (xyz angles) from ground to the frame interface; ours:
  ``spring_damper`` on a fixed joint (six equations; rotations z0.y1, z0.x1, x0.y1), Eq. (E1). The two agree
  only for small rotations (:mod:`validation.exudyn_force_conventions`).
* :class:`HingeTorque`: ``TorsionalSpringDamper`` on the hinge; ours: :class:`~ffrf.system.forces.JointTorque`,
  Eq. (E5).

With ``exudyn_definitions=True`` our side is built with Exudyn's definitions where they differ from ours
(:mod:`validation.exudyn_force_conventions`), so that the remaining difference is round-off.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from .force_specs import BushingSpring, CartesianSpring, InterfaceLoad

if TYPE_CHECKING:
    from ffrf.system.forces import ForceElement

    from .single_body_scenes import SingleBodyScene

__all__ = [
    "add_exudyn_force_items",
    "ffrf_force_elements",
]


def _interface(scene: SingleBodyScene, interface: str) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    body = scene.body
    return (body.frame_nodes, body.frame_weights) if interface == "frame" else (body.tip_nodes, body.tip_weights)


def _symmetric(matrix: NDArray[np.float64]) -> NDArray[np.float64]:
    """The symmetric part: ``spring_damper`` refuses the round-off asymmetry of R K R^T."""
    return 0.5 * (matrix + matrix.T)


def _ground_frame(scene: SingleBodyScene) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """World point and axes of the frame interface at t = 0 (the bushing's and the hinge's ground side)."""
    rotation = scene.rotation0()
    return np.asarray(scene.position, dtype=float) + rotation @ scene.body.frame_center, rotation


# --------------------------------------------------------------------------------------------
# Ours
# --------------------------------------------------------------------------------------------


def ffrf_force_elements(scene: SingleBodyScene, exudyn_definitions: bool = False) -> tuple[ForceElement, ...]:
    """Our force elements of ``scene.forces`` (body 0); ``exudyn_definitions``: Exudyn's definitions where
    they differ from ours (:mod:`validation.exudyn_force_conventions`)."""
    from ffrf.system.forces import JointTorque, MarkerLoad, spring_damper
    from ffrf.system.joints import GroundFrame, MarkerJoint, fixed_joint, revolute_joint
    from ffrf.system.markers import rigid_interface_marker

    from . import exudyn_force_conventions as conventions

    body = scene.body
    out: list[ForceElement] = []
    for k, spec in enumerate(scene.forces):
        name = f"{type(spec).__name__} {k}"
        if isinstance(spec, CartesianSpring | InterfaceLoad):
            nodes, weights = _interface(scene, spec.interface)
            marker = rigid_interface_marker(0, body.nodes, body.basis, nodes, weights, name=spec.interface)
        else:
            marker = rigid_interface_marker(
                0, body.nodes, body.basis, body.frame_nodes, body.frame_weights, name="frame"
            )
        if isinstance(spec, CartesianSpring):
            joint = MarkerJoint(
                (0,), name, GroundFrame(point=np.asarray(spec.anchor, float)), marker, locked=(True,) * 3 + (False,) * 3
            )
            element = spring_damper(joint, spec.stiffness, spec.damping, spec.offset)
            out.append(element)  # our damper already sees Exudyn's marker velocity (tangent rates)
        elif isinstance(spec, InterfaceLoad):
            vector = np.asarray(spec.vector, dtype=float)
            law = spec.law
            value = vector if law is None else (lambda t, law=law, vector=vector: law(t) * vector)
            load = MarkerLoad((0,), name, marker, frame=spec.frame, **{spec.kind: value})
            out.append(conventions.exudyn_marker_load(load) if exudyn_definitions else load)
        elif isinstance(spec, BushingSpring):
            point, rotation = _ground_frame(scene)
            ground = GroundFrame(point=point, rotation=rotation)
            if exudyn_definitions:
                out.append(conventions.ExudynRigidBodySpringDamper.diagonal(name, ground, marker, spec))
                continue
            # our translation equations are world components of p1 - p0: the ground-frame diagonal turned to world
            turn = np.eye(6)
            turn[:3, :3] = rotation
            stiffness, damping = (_symmetric(turn @ np.diag(v) @ turn.T) for v in (spec.stiffness, spec.damping))
            offset = np.r_[rotation @ np.asarray(spec.offset, dtype=float), np.zeros(3)]
            out.append(spring_damper(fixed_joint(ground, marker, name=name), stiffness, damping, offset))
        else:
            if scene.hinge is None:
                raise ValueError("a HingeTorque needs a scene with a hinge")
            frame = scene.hinge.frame()
            point, _ = _ground_frame(scene)
            joint = revolute_joint(GroundFrame(point=point, rotation=frame), marker, rotation1=frame, name=name)
            out.append(JointTorque((0,), name, joint, spec.law))
    return tuple(out)


# --------------------------------------------------------------------------------------------
# Exudyn
# --------------------------------------------------------------------------------------------


def add_exudyn_force_items(
    mbs, scene: SingleBodyScene, body_object: int, hinge_markers: tuple[int, int] | None
) -> None:
    """Exudyn's items of ``scene.forces`` on FFRF object ``body_object``; ``hinge_markers``: the hinge's
    (ground, body) markers, joint frames with z along the axis."""
    from .exudyn_items import (
        add_cartesian_spring_damper,
        add_ground,
        add_ground_marker,
        add_interface_marker,
        add_interface_position_marker,
        add_rigid_body_spring_damper,
        add_torsional_spring_damper,
        add_vector_load,
    )

    if not scene.forces:
        return
    ground = add_ground(mbs)
    for spec in scene.forces:
        if isinstance(spec, CartesianSpring):
            m0 = add_ground_marker(mbs, ground, np.eye(3), spec.anchor)
            m1 = add_interface_position_marker(mbs, body_object, *_interface(scene, spec.interface))
            add_cartesian_spring_damper(mbs, m0, m1, spec.stiffness, spec.damping, spec.offset)
        elif isinstance(spec, InterfaceLoad):
            marker = add_interface_marker(mbs, body_object, *_interface(scene, spec.interface))
            add_vector_load(mbs, marker, spec.kind, spec.vector, spec.law, body_fixed=spec.frame == "marker")
        elif isinstance(spec, BushingSpring):
            point, rotation = _ground_frame(scene)
            m0 = add_ground_marker(mbs, ground, rotation, point)
            m1 = add_interface_marker(mbs, body_object, scene.body.frame_nodes, scene.body.frame_weights)
            offset = np.r_[spec.offset, np.zeros(3)]
            add_rigid_body_spring_damper(mbs, m0, m1, np.diag(spec.stiffness), np.diag(spec.damping), offset)
        else:
            if hinge_markers is None:
                raise ValueError("a HingeTorque needs a scene with a hinge")
            # Exudyn's torque parameter acts on marker 1 as -torque: ours tau0 is Exudyn's -torque
            add_torsional_spring_damper(mbs, *hinge_markers, spec.stiffness, spec.damping, spec.offset, -spec.torque)
