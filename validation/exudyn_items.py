r"""The Exudyn items of our models, one function per kind: every twin (the single-body scenes of
:mod:`validation.exudyn_ffrf`, whole systems in :mod:`validation.exudyn_twin`, the marker probe of
:mod:`validation.exudyn_conventions`) builds its bodies, markers, joints and sensors here.

* a body: ``FEMinterface`` filled with our nodes, consistent M, K and a mode basis
  (``modeBasis = {'matrix': Psi, 'type': 'HCBmodes'}``), then
  ``ObjectFFRFreducedOrderInterface(fem).AddObjectFFRFreducedOrder`` (Euler-parameter frame node,
  C++ FFRF terms, no user functions), gravity through ``LoadMassProportional`` (our
  ``exact_gravity=False``) and ``stiffnessProportionalDamping`` (D = beta K_red);
* an interface marker: ``MarkerSuperElementRigid`` on the interface's nodes with our weights
  (``useAlternativeApproach=True``, exponential map), its ``localHT`` applied in the body frame;
  a ground frame: ``MarkerBodyRigid`` on an ``ObjectGround``;
* a joint: ``GenericJoint`` with our locked axes;
* force elements and loads (:mod:`validation.single_body_forces`): ``MarkerSuperElementPosition`` (the
  weighted centre of an interface), ``CartesianSpringDamper``, ``RigidBodySpringDamper``,
  ``TorsionalSpringDamper``, ``LoadForceVector`` and ``LoadTorqueVector`` (constant or a user function of time);
* sensors stored in memory (no files): node coordinates, mesh-node and marker positions, joint
  torques.

Exudyn's ODE2 coordinates are displacements from the reference; ``AddObjectFFRFreducedOrder``
expects the *global* angular velocity. ``exudyn`` is imported lazily.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike

__all__ = [
    "FFRFItems",
    "exudyn_fem",
    "add_ffrf_body",
    "add_ground",
    "add_ground_marker",
    "add_interface_marker",
    "add_generic_joint",
    "add_interface_position_marker",
    "add_cartesian_spring_damper",
    "add_rigid_body_spring_damper",
    "add_torsional_spring_damper",
    "add_vector_load",
    "add_stored_sensor",
    "add_coordinates_sensor",
    "add_mesh_node_sensor",
    "add_marker_position_sensor",
    "add_torque_sensor",
]


class FFRFItems(NamedTuple):
    """Item numbers of one ``ObjectFFRFreducedOrder``: the object, its rigid and its modal node."""

    body: int
    rigid_node: int
    modal_node: int


def exudyn_fem(nodes: ArrayLike, mass, stiffness, basis: ArrayLike):
    """``FEMinterface`` with our nodes (N, 3), M, K (3N, 3N, DOFs [x0, y0, z0, x1, ...]) and mode basis
    (3N, m); no surface (only needed for weights and graphics)."""
    from exudyn.FEM import FEMinterface

    fem = FEMinterface()
    fem.nodes = {"Position": np.array(nodes, dtype=float)}
    fem.massMatrix = sp.csr_matrix(mass)
    fem.stiffnessMatrix = sp.csr_matrix(stiffness)
    fem.modeBasis = {"matrix": np.array(basis, dtype=float), "type": "HCBmodes"}
    return fem


def _floats(values: ArrayLike) -> list[float]:
    return [float(v) for v in np.asarray(values, dtype=float).ravel()]


def add_ffrf_body(
    mbs,
    nodes: ArrayLike,
    mass,
    stiffness,
    basis: ArrayLike,
    position: ArrayLike,
    rotation: ArrayLike,
    zeta0: ArrayLike,
    gravity: ArrayLike = (0.0, 0.0, 0.0),
    beta: float = 0.0,
    velocity: ArrayLike = (0.0, 0.0, 0.0),
    angular_velocity: ArrayLike = (0.0, 0.0, 0.0),
    name: str = "",
    alpha: float = 0.0,
) -> FFRFItems:
    """An ``ObjectFFRFreducedOrder`` of our FE data: reference ``position`` and ``rotation`` (body to
    world) of its frame, modal initial values ``zeta0``, initial ``velocity`` (of the frame origin) and
    *global* ``angular_velocity``, ``gravity`` and Rayleigh damping D = alpha M_red + beta K_red of the modal
    coordinates (``massProportionalDamping`` alpha in 1/s, ``stiffnessProportionalDamping`` beta in s; ours:
    ``docs/formulation.md`` Eq. (HCB-8))."""
    from exudyn.FEM import ObjectFFRFreducedOrderInterface

    cms = ObjectFFRFreducedOrderInterface(exudyn_fem(nodes, mass, stiffness, basis))  # Euler parameters
    info = cms.AddObjectFFRFreducedOrder(
        mbs,
        positionRef=_floats(position),
        initialVelocity=_floats(velocity),
        rotationMatrixRef=np.asarray(rotation, dtype=float),
        initialAngularVelocity=_floats(angular_velocity),
        gravity=_floats(gravity),
        massProportionalDamping=float(alpha),
        stiffnessProportionalDamping=float(beta),
        name=name,
    )
    mbs.SetNodeParameter(info["nGenericODE2"], "initialCoordinates", _floats(zeta0))
    return FFRFItems(info["oFFRFreducedOrder"], info["nRigidBody"], info["nGenericODE2"])


def add_ground(mbs) -> int:
    """An ``ObjectGround`` at the origin."""
    import exudyn.itemInterface as eii

    return mbs.AddObject(eii.ObjectGround(referencePosition=[0.0, 0.0, 0.0]))


def _ht(rotation: ArrayLike, translation: ArrayLike):
    import exudyn as exu

    return exu.HT(rotation=np.asarray(rotation, dtype=float), translation=np.asarray(translation, dtype=float))


def add_ground_marker(mbs, ground: int, rotation: ArrayLike, point: ArrayLike, name: str = "") -> int:
    """A fixed frame: ``MarkerBodyRigid`` on ``ground`` at ``point`` with axes ``rotation`` (columns)."""
    import exudyn.itemInterface as eii

    return mbs.AddMarker(eii.MarkerBodyRigid(bodyNumber=ground, localHT=_ht(rotation, point), name=name))


def add_interface_marker(
    mbs,
    body: int,
    nodes: ArrayLike,
    weights: ArrayLike,
    rotation: ArrayLike | None = None,
    translation: ArrayLike = (0.0, 0.0, 0.0),
    name: str = "",
) -> int:
    """``MarkerSuperElementRigid`` on mesh ``nodes`` of FFRF object ``body`` with our ``weights``:
    its point is the weighted centre plus ``translation``, its axes ``rotation`` (default the body
    axes), both in the body frame (``localHT``)."""
    import exudyn.itemInterface as eii

    return mbs.AddMarker(
        eii.MarkerSuperElementRigid(
            bodyNumber=body,
            meshNodeNumbers=[int(i) for i in np.asarray(nodes)],
            weightingFactors=[float(w) for w in np.asarray(weights)],
            useAlternativeApproach=True,
            rotationsExponentialMap=2,
            localHT=_ht(np.eye(3) if rotation is None else rotation, translation),
            name=name,
        )
    )


def add_generic_joint(mbs, marker0: int, marker1: int, locked: ArrayLike, name: str = "") -> int:
    """``GenericJoint`` between two rigid markers; ``locked``: the six constrained axes (x, y, z,
    rx, ry, rz of the joint frame), as our :class:`ffrf.system.joints.MarkerJoint`."""
    import exudyn.itemInterface as eii

    return mbs.AddObject(
        eii.GenericJoint(
            markerNumbers=[marker0, marker1], constrainedAxes=[int(v) for v in np.asarray(locked)], name=name
        )
    )


def add_interface_position_marker(mbs, body: int, nodes: ArrayLike, weights: ArrayLike, name: str = "") -> int:
    """``MarkerSuperElementPosition``: the weighted centre ``sum w_i r_i`` of mesh ``nodes`` of FFRF object
    ``body`` (velocity ``sum w_i v_i``), our rigid interface marker's point (Eq. (K1))."""
    import exudyn.itemInterface as eii

    return mbs.AddMarker(
        eii.MarkerSuperElementPosition(
            bodyNumber=body,
            meshNodeNumbers=[int(i) for i in np.asarray(nodes)],
            weightingFactors=_floats(weights),
            name=name,
        )
    )


def add_cartesian_spring_damper(
    mbs, marker0: int, marker1: int, stiffness: ArrayLike, damping: ArrayLike, offset: ArrayLike, name: str = ""
) -> int:
    """``CartesianSpringDamper``: f = k o (p1 - p0 - offset) + d o (v1 - v0) per world axis, -f on marker 1 and
    +f on marker 0 (its ``ComputeODE2LHS`` adds J1^T f and -J0^T f to the left-hand side)."""
    import exudyn.itemInterface as eii

    return mbs.AddObject(
        eii.ObjectConnectorCartesianSpringDamper(
            markerNumbers=[marker0, marker1],
            stiffness=_floats(stiffness),
            damping=_floats(damping),
            offset=_floats(offset),
            name=name,
        )
    )


def add_rigid_body_spring_damper(
    mbs, marker0: int, marker1: int, stiffness: ArrayLike, damping: ArrayLike, offset: ArrayLike, name: str = ""
) -> int:
    """``RigidBodySpringDamper`` (not intrinsic): 6 x 6 ``stiffness`` and ``damping`` on the displacement
    A0^T (p1 - p0) and the xyz (Tait-Bryan) angles of A0^T A1 in marker 0's frame, minus ``offset`` (6)."""
    import exudyn.itemInterface as eii

    return mbs.AddObject(
        eii.ObjectConnectorRigidBodySpringDamper(
            markerNumbers=[marker0, marker1],
            stiffness=np.asarray(stiffness, dtype=float),
            damping=np.asarray(damping, dtype=float),
            offset=_floats(offset),
            useIntrinsicFormulation=False,
            name=name,
        )
    )


def add_torsional_spring_damper(
    mbs,
    marker0: int,
    marker1: int,
    stiffness: float,
    damping: float,
    offset: float = 0.0,
    torque: float = 0.0,
    name: str = "",
) -> int:
    """``TorsionalSpringDamper`` about marker 0's z axis: T = stiffness (phi - offset) + damping phi_dot + torque,
    with phi the z angle of the xyz angles of A0^T A1; it adds J_w1^T T z0 to marker 1's left-hand side, so the
    torque *acting* on marker 1 is -T z0 (and +T z0 on marker 0)."""
    import exudyn.itemInterface as eii

    return mbs.AddObject(
        eii.ObjectConnectorTorsionalSpringDamper(
            markerNumbers=[marker0, marker1],
            stiffness=float(stiffness),
            damping=float(damping),
            offset=float(offset),
            torque=float(torque),
            name=name,
        )
    )


def add_vector_load(
    mbs,
    marker: int,
    kind: str,
    vector: ArrayLike,
    law: Callable[[float], float] | None = None,
    body_fixed: bool = False,
    name: str = "",
) -> int:
    """``LoadForceVector`` (``kind="force"``, Q = J_p^T F) or ``LoadTorqueVector`` (``"torque"``, Q = J_w^T M) on
    ``marker``: ``vector`` times ``law(t)`` (a ``loadVectorUserFunction``; constant without), in world axes or,
    with ``body_fixed``, in the marker's (turned by its orientation)."""
    import exudyn.itemInterface as eii

    item = {"force": eii.LoadForceVector, "torque": eii.LoadTorqueVector}[kind]
    options = {}
    if law is not None:

        def user_function(mbs, t, load_vector):
            return list(law(t) * np.asarray(load_vector, dtype=float))

        options["loadVectorUserFunction"] = user_function
    return mbs.AddLoad(
        item(markerNumber=marker, loadVector=_floats(vector), bodyFixed=bool(body_fixed), name=name, **options)
    )


def add_stored_sensor(mbs, kind: str, output: str, **item) -> int:
    """A sensor item ``kind`` (``SensorNode``, ``SensorSuperElement``, ...) of the output variable
    ``output`` (an ``exudyn.OutputVariableType`` name), stored in memory, never written to a file."""
    import exudyn as exu
    import exudyn.itemInterface as eii

    sensor = getattr(eii, kind)(
        outputVariableType=getattr(exu.OutputVariableType, output), storeInternal=True, writeToFile=False, **item
    )
    return mbs.AddSensor(sensor)


def add_coordinates_sensor(mbs, node: int) -> int:
    """The coordinates of ``node`` (displacements from its reference)."""
    return add_stored_sensor(mbs, "SensorNode", "Coordinates", nodeNumber=node)


def add_mesh_node_sensor(mbs, body: int, node: int) -> int:
    """World position of mesh node ``node`` of FFRF object ``body``."""
    return add_stored_sensor(mbs, "SensorSuperElement", "Position", bodyNumber=body, meshNodeNumber=int(node))


def add_marker_position_sensor(mbs, marker: int) -> int:
    """World position of a marker."""
    return add_stored_sensor(mbs, "SensorMarker", "Position", markerNumber=marker)


def add_torque_sensor(mbs, joint: int) -> int:
    """The torque of ``joint`` in its own frame (``TorqueLocal``)."""
    return add_stored_sensor(mbs, "SensorObject", "TorqueLocal", objectNumber=joint)
