r"""``NGsolveFFRF.py`` (an Exudyn example): a frame with a filled drum, two materials, swinging about
the vertical axis of its two pins under a torque pulse, gravity along x.

The model (:data:`.netgen_meshes.FRAME`, 5303 nodes): the four pin end faces (Netgen's named boundaries,
Exudyn's node sets) are rigid (RBE2) interfaces weighted by surface area, the first one carrying the
body frame (``excludeRigidBodyMotion=True``): 3 x 6 static and 16 fixed-interface modes, 34 in all;
stiffness-proportional damping 0.01 K, gravity 9.81 m/s^2 along x. Each interface is held at its
reference position by a ``GenericJoint`` with the rotations free: the first locks x, y and z, the
others x and y, so the frame turns about the pins' axis (x = 0.12 m, y = 0). A torque about z,
``7000 sin(pi (t - 1) / 4)`` N m for 1 s <= t < 5 s, acts on the first interface (the script sets it
in a ``PreStepUserFunction``, which Exudyn calls with the step's end time; ours is a time function
evaluated there too). Generalized-alpha (rho_inf = Exudyn's default 0.9), h = 4 ms, modified Newton,
to :data:`T_END`. The script has no sensor: ours is the ``Displacement`` of the mesh node nearest to
:data:`SENSOR_POINT`, on the outer face of the beam farthest from the pins (the interfaces lie on the
axis and see only elastic motion); result: its largest component over all rows. Left out: the stress
modes, graphics and the solution file.

Ours: the node sets' own nodes, :func:`ffrf.fe.node_selection.surface_area_weights` on the mesh surface,
:func:`ffrf.reduction.craig_bampton.craig_bampton` (``reference="interface"``),
:class:`ffrf.system.joints.MarkerJoint` locking translations, the torque a
:class:`ffrf.system.forces.MarkerLoad` with a time function.
"""

from __future__ import annotations

import time
from functools import cache

import numpy as np
from numpy.typing import NDArray

from ffrf.body.flexible_body import FlexibleBody
from ffrf.body.modal_moments import modal_moments
from ffrf.fe.node_selection import surface_area_weights
from ffrf.reduction.craig_bampton import craig_bampton
from ffrf.solvers.generalized_alpha import generalized_alpha
from ffrf.system.forces import MarkerLoad
from ffrf.system.joints import GroundFrame, MarkerJoint
from ffrf.system.markers import rigid_interface_marker
from ffrf.system.multibody import MultibodySystem

from .netgen_meshes import FRAME, external_model, frame_fem
from .sensors import node_displacement
from .spec import ModelRun, exudyn_label, solve

__all__ = ["ours", "exudyn", "T_END", "SENSOR_POINT"]

N_MODES = 16
DAMPING = 1e-2
GRAVITY = (9.81, 0.0, 0.0)
TORQUE, TORQUE_START, TORQUE_END = 7000.0, 1.0, 5.0
#: The script runs 10 s (2500 steps); the report runs the torque pulse, 0 to 5 s (1250 steps; cost).
STEP, T_END, RHO_INF = 4e-3, 5.0, 0.9
#: Outer face of the vertical beam at x = L + b/2, mid height.
SENSOR_POINT = (FRAME.length + 0.5 * FRAME.width, 0.0, 0.5 * FRAME.length)
#: Which translations each interface's joint locks: all three on the first, x and y on the others.
LOCKED = ((True, True, True, False, False, False),) + ((True, True, False, False, False, False),) * 3


def torque_z(t: float) -> float:
    """The script's torque pulse (N m) about z: one half sine from 1 s to 5 s."""
    return TORQUE * np.sin(np.pi * (t - TORQUE_START) / 4.0) if TORQUE_START <= t < TORQUE_END else 0.0


def sensor_node(nodes: NDArray) -> int:
    """The mesh node nearest to :data:`SENSOR_POINT`."""
    return int(np.argmin(np.linalg.norm(nodes - np.array(SENSOR_POINT), axis=1)))


def node_sets(fem) -> list[NDArray[np.int64]]:
    """The nodes of the four named pin faces, as ``ImportMeshFromNGsolve`` collected them."""
    named = {s["Name"]: np.asarray(s["NodeNumbers"], dtype=np.int64) for s in fem.nodeSets}
    return [named[name] for name in FRAME.boundaries]


def ours(tolerance: float) -> ModelRun:
    """Our solver on the frame; sensor rows and the largest displacement component."""
    started = time.perf_counter()
    fem = frame_fem()
    model, triangles = external_model(fem, "frame")
    sets = node_sets(fem)
    weights = [surface_area_weights(model.nodes, triangles, s) for s in sets]
    modes = craig_bampton(model, sets, N_MODES, weights)
    moments = modal_moments(model.nodes, model.mass, modes.basis)
    body = FlexibleBody("frame", moments, modes.reduced_stiffness, DAMPING * modes.reduced_stiffness, False)
    markers = [
        rigid_interface_marker(0, model.nodes, modes.basis, s, w, name=name)
        for s, w, name in zip(sets, weights, FRAME.boundaries, strict=True)
    ]
    joints = tuple(
        MarkerJoint((0,), f"pin {m.name}", GroundFrame(point=m.point.copy()), m, locked=locked)
        for m, locked in zip(markers, LOCKED, strict=True)
    )
    torque = MarkerLoad((0,), "torque pulse", markers[0], torque=lambda t: (0.0, 0.0, torque_z(t)))
    system = MultibodySystem((body,), joints, np.array(GRAVITY), (torque,))
    q0 = system.initial_state(positions=[(0.0, 0.0, 0.0)])
    run = generalized_alpha(system, q0, np.zeros_like(q0), T_END, STEP, rho_inf=RHO_INF, tolerance=tolerance)
    node = sensor_node(model.nodes)
    sensor = np.column_stack([run.time, node_displacement(run.q, model.nodes, modes.basis, node)])
    settings = f"ffrf generalized-alpha, modified Newton, tolerance {tolerance:g}, {modes.n_modes} modes"
    return ModelRun(float(np.abs(sensor[:, 1:]).max()), sensor, time.perf_counter() - started, settings)


@cache
def _exudyn_fem():
    """Exudyn's frame with its HCB modes (computed once per process), node sets and weights."""
    from exudyn.FEM import FEMinterface, HCBstaticModeSelection

    fem = FEMinterface()
    fem.SetWithDictionary(frame_fem().GetDictionary())  # a copy: the modes are stored in the interface
    sets = [list(s) for s in node_sets(fem)]
    weights = [np.asarray(s["NodeWeights"]) for s in fem.nodeSets]
    fem.ComputeHurtyCraigBamptonModes(
        boundaryNodesList=sets, nEigenModes=N_MODES, useSparseSolver=True, computationMode=HCBstaticModeSelection.RBE2
    )
    return fem, sets, weights


def exudyn(tight: bool) -> ModelRun:
    """The script with Exudyn's items, graphics off (no renderer, no files); ``tight``: tightened Newton."""
    import exudyn as exu
    import exudyn.itemInterface as eii
    from exudyn.basicUtilities import GetOtherMarker
    from exudyn.FEM import ObjectFFRFreducedOrderInterface

    started = time.perf_counter()
    fem, sets, weights = _exudyn_fem()
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    cms = ObjectFFRFreducedOrderInterface(fem)
    items = cms.AddObjectFFRFreducedOrder(
        mbs, positionRef=[0, 0, 0], gravity=list(GRAVITY), stiffnessProportionalDamping=DAMPING
    )
    body = items["oFFRFreducedOrder"]
    markers = [
        mbs.AddMarker(eii.MarkerSuperElementRigid(bodyNumber=body, meshNodeNumbers=np.array(s), weightingFactors=w))
        for s, w in zip(sets, weights, strict=True)
    ]
    ground = mbs.AddObject(eii.ObjectGround(referencePosition=[0, 0, 0]))
    for marker, locked in zip(markers, LOCKED, strict=True):
        on_ground = GetOtherMarker(mbs, bodyNumber=ground, existingMarker=marker, show=False)
        mbs.AddObject(eii.GenericJoint(markerNumbers=[on_ground, marker], constrainedAxes=[int(x) for x in locked]))
    torque = mbs.AddLoad(eii.Torque(markerNumber=markers[0], loadVector=[0, 0, 0]))

    def pre_step(mbs, t):  # the script's PreStepUserFunction
        mbs.SetLoadParameter(torque, "loadVector", [0, 0, torque_z(t)])
        return True

    mbs.SetPreStepUserFunction(pre_step)
    sensor = mbs.AddSensor(
        eii.SensorSuperElement(
            bodyNumber=body,
            meshNodeNumber=sensor_node(fem.GetNodePositionsAsArray()),
            storeInternal=True,
            writeToFile=False,
            outputVariableType=exu.OutputVariableType.Displacement,
        )
    )
    mbs.Assemble()
    used = solve(mbs, STEP, T_END, RHO_INF, tight)
    data = np.asarray(mbs.GetSensorStoredData(sensor), dtype=float)
    return ModelRun(float(np.abs(data[:, 1:]).max()), data, time.perf_counter() - started, exudyn_label(used))
