r"""The Exudyn twin of any of our multibody systems of reduced flexible bodies.

Given our bodies (nodes, consistent M and K, interface node sets and weights, reduction) and
a :class:`ffrf.system.multibody.MultibodySystem` of :class:`ffrf.system.joints.MarkerJoint` s, the twin has

Its items are those every twin uses (:mod:`validation.exudyn_items`):

* per body an ``ObjectFFRFreducedOrder`` (``FEMinterface`` with our nodes, M and K and either
  Exudyn's own Craig-Bampton modes on the same interfaces, :func:`validation.twin_bases.twin_bases`,
  or ours), with
  ``positionRef``/``rotationMatrixRef`` and modal initial values from the start state, gravity
  through ``LoadMassProportional`` (our ``exact_gravity=False``, Eq. (F10)) and
  ``stiffnessProportionalDamping``;
* per joint side a ``MarkerSuperElementRigid`` on the interface's nodes with our weights
  (``useAlternativeApproach=True``, exponential map); its ``localHT`` carries our joint
  rotation and the joint point's offset from the interface centre, which Exudyn applies in
  the body frame as our default (``joint_offsets="body"``, :func:`ffrf.system.markers.attach_joint_point`);
  a ground ``MarkerBodyRigid`` for ground frames;
* per joint a ``GenericJoint`` with our locked axes; a prescribed rotation as its
  ``offsetUserFunction``: *symbolic* (C++ speed) for the paper's cosine ramp
  (:class:`ffrf.system.drives.RampedAngle`), our Python function of time otherwise.

Sensors: the rigid and modal nodes of every body, the ``TorqueLocal`` of every driven joint
(``torque:<joint>``); callers add their own (:func:`add_node_sensor`, :func:`add_marker_sensor`).
``exudyn`` is imported lazily.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ffrf.system.drives import RampedAngle

from .exudyn_items import (
    add_coordinates_sensor,
    add_ffrf_body,
    add_generic_joint,
    add_ground,
    add_ground_marker,
    add_interface_marker,
    add_marker_position_sensor,
    add_mesh_node_sensor,
    add_torque_sensor,
)
from .twin_bases import TwinBasis, TwinBody

if TYPE_CHECKING:
    import exudyn as exu


__all__ = [
    "TwinBody",
    "ExudynTwin",
    "build_twin",
    "add_node_sensor",
    "add_marker_sensor",
    "read_twin",
    "joint_key",
    "q_from_twin",
]


@dataclass
class ExudynTwin:
    """An assembled Exudyn system and the item numbers needed to read it back."""

    sc: exu.SystemContainer
    mbs: exu.MainSystem
    objects: list
    rigid_nodes: list
    modal_nodes: list
    reference: list  # per body: reference coordinates of the rigid node (R, ep)
    markers: dict  # joint key -> (marker 0, marker 1)
    joints: dict  # joint key -> object
    sensors: dict
    symbolic: bool
    keep_alive: list = field(default_factory=list)  # user functions Exudyn calls: must live as long as mbs
    notes: list = field(default_factory=list)  # where the twin is not exactly equivalent
    bases: list | None = None  # per body TwinBasis (None: our basis)


def joint_key(name: str) -> str:
    """Exudyn item name of one of our joints: its name up to the first blank (``joint3 (drive)`` -> ``joint3``)."""
    return name.split(" ")[0]


def _drive_function(angle, frozen_time: float | None, symbolic: bool):
    """offsetUserFunction [0, 0, 0, 0, 0, angle(t)]: symbolic (``exudyn.symbolic``) for a
    :class:`ffrf.system.drives.RampedAngle`, else plain Python calling ``angle``."""
    import exudyn as exu

    if frozen_time is not None or not symbolic or not isinstance(angle, RampedAngle):
        fixed = None if frozen_time is None else float(angle(frozen_time))

        def offset(mbs, t, itemNumber, args):
            return [0.0, 0.0, 0.0, 0.0, 0.0, float(angle(t)) if fixed is None else fixed + 0.0 * t]

        return offset
    esym = exu.symbolic
    start, w, tr = float(angle.start), float(angle.ramp.omega), float(angle.ramp.ramp_time)

    def symbolic_offset(mbs, t, itemNumber, args):
        during = 0.5 * w * (t - tr / np.pi * esym.sin(np.pi / tr * t))
        after = 0.5 * w * tr + w * (t - tr)
        return [0.0, 0.0, 0.0, 0.0, 0.0, start + esym.IfThenElse(t < tr, during, after)]

    return symbolic_offset


def _interface_name(body: TwinBody, marker) -> str:
    """The interface of a joint's ``marker`` (a scene may have moved its point, not its name)."""
    for name, candidate in body.markers.items():
        if candidate.name == marker.name:
            return name
    raise ValueError(
        f"marker {marker.name!r} is not one of body {body.name!r}'s interface markers "
        f"({sorted(body.markers)}); the twin supports rigid interface markers only"
    )


def build_twin(
    bodies: list[TwinBody],
    system,
    q0: NDArray,
    beta: float,
    symbolic: bool = True,
    frozen_drive_time: float | None = None,
    bases: list[TwinBasis] | None = None,
) -> ExudynTwin:
    """The twin of ``system`` at ``q0`` (our layout, absolute, at rest; modal part in ``bases``,
    default our basis). ``frozen_drive_time``: drives held at their angle at this time (static solves, whose quasi-time
    would otherwise turn them). Call ``twin.mbs.Assemble()`` after adding sensors."""
    import exudyn as exu

    from ffrf.body.euler_parameters import rotation_matrix
    from ffrf.system.clearance_joint import ClearanceJoint
    from ffrf.system.joints import GroundFrame, MarkerJoint

    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    objects, rigid_nodes, modal_nodes, reference = [], [], [], []
    for k, body in enumerate(bodies):
        block = np.asarray(q0[system.block(k)], dtype=float)
        items = add_ffrf_body(
            mbs,
            body.fe.nodes,
            body.fe.mass,
            body.fe.stiffness,
            np.asarray(body.reduction.basis) if bases is None else bases[k].matrix,
            block[:3],
            rotation_matrix(block[3:7]),
            block[7:],
            system.gravity,
            beta,
            name=body.name,
        )
        objects.append(items.body)
        rigid_nodes.append(items.rigid_node)
        modal_nodes.append(items.modal_node)
        reference.append(np.asarray(mbs.GetNodeParameter(items.rigid_node, "referenceCoordinates"), dtype=float))

    ground = add_ground(mbs)
    markers, joints, keep, notes = {}, {}, [], []

    def add_marker(marker, rotation, offset, label):
        if isinstance(marker, GroundFrame):
            return add_ground_marker(
                mbs, ground, marker.rotation @ rotation, marker.point + marker.rotation @ offset, label
            )
        body = bodies[marker.body]
        name = _interface_name(body, marker)
        itf = body.interfaces[name]
        if np.any(offset != 0.0) and np.any(marker.rotation_modes != 0.0):
            # Our marker-frame offset A exp(theta) o has no Exudyn equivalent; Exudyn applies it as A o.
            notes.append(
                f"{label}: marker-frame offset {np.linalg.norm(offset) * 1e3:.3g} mm applied in the body frame"
            )
        # Exudyn's marker point is the interface's weighted centre plus localHT's translation, in the body frame.
        translation = marker.point - body.markers[name].point + offset
        return add_interface_marker(mbs, objects[marker.body], itf.nodes, itf.weights, rotation, translation, label)

    used_symbolic = False
    sensors = {}
    loose = [f.name for f in system.forces if isinstance(f, ClearanceJoint)]
    if loose:  # Exudyn has no pin-in-bore joint: a twin without the play would compare two other linkages
        raise TypeError(f"joints with play ({', '.join(loose)}) have no Exudyn twin here; validate with ideal joints")
    for c in system.constraints:
        if not isinstance(c, MarkerJoint):
            raise TypeError(f"constraint {c.name!r} ({type(c).__name__}) has no Exudyn twin here")
        key = joint_key(c.name)
        m0 = add_marker(c.marker0, c.rotation0, c.offset0, f"{key}:m0")
        m1 = add_marker(c.marker1, c.rotation1, c.offset1, f"{key}:m1")
        markers[key] = (m0, m1)
        joint = add_generic_joint(mbs, m0, m1, c.locked, key)
        joints[key] = joint
        if c.angle is None:
            continue
        function = None
        if symbolic and frozen_drive_time is None and isinstance(c.angle, RampedAngle):
            from exudyn.utilities import CreateSymbolicUserFunction

            try:
                function = CreateSymbolicUserFunction(
                    mbs, _drive_function(c.angle, None, True), "offsetUserFunction", joint
                )
                used_symbolic = True
            # Any failure of Exudyn's symbolic translation (its own exception types are not
            # documented) falls back to the Python function and is reported in twin.notes.
            except Exception as error:  # noqa: BLE001  # pragma: no cover - reported to the caller
                notes.append(f"{key}: symbolic user function failed ({error!r}); Python function used")
        if function is None:
            function = _drive_function(c.angle, frozen_drive_time, False)
        mbs.SetObjectParameter(joint, "offsetUserFunction", function)
        keep.append(function)
        sensors[f"torque:{key}"] = add_torque_sensor(mbs, joint)
    for k in range(len(bodies)):
        sensors[f"rigid{k}"] = add_coordinates_sensor(mbs, rigid_nodes[k])
        sensors[f"modal{k}"] = add_coordinates_sensor(mbs, modal_nodes[k])
    return ExudynTwin(
        sc,
        mbs,
        objects,
        rigid_nodes,
        modal_nodes,
        reference,
        markers,
        joints,
        sensors,
        used_symbolic,
        keep,
        notes,
        bases,
    )


def add_node_sensor(twin: ExudynTwin, name: str, body: int, node: int) -> None:
    """World position of mesh node ``node`` of body ``body``."""
    twin.sensors[name] = add_mesh_node_sensor(twin.mbs, twin.objects[body], node)


def add_marker_sensor(twin: ExudynTwin, name: str, marker: int) -> None:
    """World position of an Exudyn marker."""
    twin.sensors[name] = add_marker_position_sensor(twin.mbs, marker)


def q_from_twin(twin: ExudynTwin, system, q0: NDArray, rigid: list, modal: list, our_basis: bool = True) -> NDArray:
    """Our-layout absolute coordinates from Exudyn's displacement coordinates (rows = times);
    Euler parameters are given our sign (Exudyn's reference may be -p); modal coordinates in
    our basis (``our_basis``) or the twin's."""
    q = np.empty((rigid[0].shape[0], system.n_coordinates))
    for k in range(len(rigid)):
        block = system.block(k)
        absolute = rigid[k] + twin.reference[k]
        sign = 1.0 if np.dot(twin.reference[k][3:7], q0[block][3:7]) >= 0 else -1.0
        absolute[:, 3:7] *= sign
        q[:, block.start : block.start + 7] = absolute
        to_ours = twin.bases[k].to_ours if (our_basis and twin.bases is not None) else None
        q[:, block.start + 7 : block.stop] = modal[k] if to_ours is None else modal[k] @ to_ours.T
    return q


def read_twin(twin: ExudynTwin, system, q0: NDArray) -> dict[str, NDArray]:
    """Every stored sensor (time column stripped, ``time`` separate), plus ``q`` (our basis) and
    ``twin_q`` (the twin's basis)."""
    mbs = twin.mbs
    data = {name: np.asarray(mbs.GetSensorStoredData(number)) for name, number in twin.sensors.items()}
    n = len(twin.objects)
    rigid = [data[f"rigid{k}"][:, 1:] for k in range(n)]
    modal = [data[f"modal{k}"][:, 1:] for k in range(n)]
    out = {name: values[:, 1:] for name, values in data.items()}
    out["time"] = data["rigid0"][:, 0]
    out["q"] = q_from_twin(twin, system, q0, rigid, modal)
    out["twin_q"] = q_from_twin(twin, system, q0, rigid, modal, our_basis=False)
    return out
