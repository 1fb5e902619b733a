r"""``NGsolveModalAnalysis.py`` (an Exudyn example): a steel crane on four feet, its modal body held in
a fixed frame, shaken at its arm tip.

The model (:data:`.netgen_meshes.CRANE`, 4544 nodes): five rigid (RBE2) interfaces, the bottom faces of
the four feet (nodes in a box 0.4 m around each foot's corner, 1 mm thick) and the arm's end face (nodes
in its plane), weighted by surface area; Hurty/Craig-Bampton with all 5 x 6 static modes kept
(``excludeRigidBodyMotion=False``) and 8 fixed-interface modes, 38 in all; the body's frame locked to
ground (the script's ``RotationRxyz`` node with its six coordinates constrained), stiffness-proportional
damping 0.01 K, gravity -9.81 m/s^2 along z. Each foot interface is held at its centre by a joint
locking the three translations (``GenericJoint`` with the rotations free: spherical). From t > 10 s a
force ``sin(2 pi 1.8 t) (10000, 0, -20000)`` N acts on the arm-tip interface. Generalized-alpha
(rho_inf = Exudyn's default 0.9), h = 5 ms, modified Newton, to 20 s as the script does. Sensor: the
script's ``Displacement`` of the arm-tip marker; result: its largest component over all rows.

The script's fixed-interface eigenfrequencies, with the tip interface among the fixed ones as it runs:
:func:`frequencies` (ours and Exudyn's on the same mesh). Its comment "if tip is not fixed, gives:
1.8202 1.8223 11.3098 11.3469 31.2923 31.3375 46.6563 53.1684 Hz" is the variant with the four feet
alone (``boundaryNodesList[:-1]``): :data:`STATED_HZ`, compared with ours for the feet alone.
Left out: the stress modes and the file round trip (they do not enter the motion), graphics.

Ours: :func:`ffrf.reduction.craig_bampton.craig_bampton` (``reference="none"``), the frame held by
:func:`ffrf.system.joints.fixed_joint` on :func:`ffrf.system.markers.frame_marker`, the feet by
:class:`ffrf.system.joints.MarkerJoint` locking the translations, the tip force a
:class:`ffrf.system.forces.MarkerLoad` with a time function.
"""

from __future__ import annotations

import time
from functools import cache

import numpy as np
from numpy.typing import NDArray

from ffrf.body.flexible_body import FlexibleBody
from ffrf.body.modal_moments import modal_moments
from ffrf.fe.node_selection import nodes_in_box, nodes_in_plane, surface_area_weights
from ffrf.reduction.craig_bampton import craig_bampton
from ffrf.solvers.generalized_alpha import generalized_alpha
from ffrf.system.forces import MarkerLoad
from ffrf.system.joints import GroundFrame, MarkerJoint, fixed_joint
from ffrf.system.markers import frame_marker, rigid_interface_marker
from ffrf.system.multibody import MultibodySystem

from .netgen_meshes import CRANE, crane_fem, external_model
from .spec import ModelRun, exudyn_label, solve

__all__ = ["ours", "exudyn", "frequencies", "STATED_HZ"]

N_MODES = 8
DAMPING = 0.01  # stiffness-proportional: D = 0.01 K
GRAVITY = (0.0, 0.0, -9.81)
TIP_FORCE = np.array([10000.0, 0.0, -20000.0])
LOAD_FREQUENCY, LOAD_START = 1.8, 10.0
STEP, T_END, RHO_INF = 5e-3, 20.0, 0.9
#: The script's comment: fixed-interface frequencies (Hz) with the tip interface free, rounded to 4 decimals.
STATED_HZ = np.array([1.8202, 1.8223, 11.3098, 11.3469, 31.2923, 31.3375, 46.6563, 53.1684])


def tip_force(t: float, vector: NDArray[np.float64] = TIP_FORCE) -> NDArray[np.float64]:
    """The script's ``UFload``: nothing up to 10 s (the start transient decays), then ``vector`` times a
    1.8 Hz sine."""
    return np.zeros(3) if t <= LOAD_START else np.sin(2.0 * np.pi * LOAD_FREQUENCY * t) * np.asarray(vector)


def interface_sets(nodes: NDArray) -> list[NDArray[np.int64]]:
    """The script's five node sets: the feet's bottom faces (``GetNodesInCube``), the arm's end face
    (``GetNodesInPlane``)."""
    margin = np.array([CRANE.foot_width, CRANE.foot_width, 1e-3])
    feet = [nodes_in_box(nodes, corner - margin, corner + margin) for corner in CRANE.feet()]
    return feet + [nodes_in_plane(nodes, CRANE.tip(), CRANE.arm_direction())]


def foot_centres() -> NDArray[np.float64]:
    """(4, 3) where the feet are held: the middle of each foot's bottom face."""
    return CRANE.feet() + [0.5 * CRANE.foot_width, 0.5 * CRANE.foot_width, 0.0]


@cache
def _our_modes(with_tip: bool = True):
    model, triangles = external_model(crane_fem(), "crane")
    sets = interface_sets(model.nodes)[: None if with_tip else -1]
    weights = [surface_area_weights(model.nodes, triangles, s) for s in sets]
    return model, sets, weights, craig_bampton(model, sets, N_MODES, weights, reference="none")


def ours(tolerance: float) -> ModelRun:
    """Our solver on the crane; sensor rows and the largest tip displacement."""
    started = time.perf_counter()
    model, sets, weights, modes = _our_modes()
    m = modes.n_modes
    moments = modal_moments(model.nodes, model.mass, modes.basis)
    body = FlexibleBody("crane", moments, modes.reduced_stiffness, DAMPING * modes.reduced_stiffness, False)
    markers = [
        rigid_interface_marker(0, model.nodes, modes.basis, s, w, name=f"interface {k}")
        for k, (s, w) in enumerate(zip(sets, weights, strict=True))
    ]
    joints = [fixed_joint(GroundFrame(), frame_marker(0, m), name="frame locked")]
    joints += [
        MarkerJoint(
            (0,), f"foot {k}", GroundFrame(point=centre), markers[k], locked=(True, True, True, False, False, False)
        )
        for k, centre in enumerate(foot_centres())
    ]
    load = MarkerLoad((0,), "tip force", markers[-1], force=tip_force)
    system = MultibodySystem((body,), tuple(joints), np.array(GRAVITY), (load,))
    q0 = system.initial_state(positions=[(0.0, 0.0, 0.0)])
    run = generalized_alpha(system, q0, np.zeros_like(q0), T_END, STEP, rho_inf=RHO_INF, tolerance=tolerance)
    tip = markers[-1]
    displacement = np.array([tip.position(q) for q in run.q[:, system.block(0)]]) - tip.position(q0)
    sensor = np.column_stack([run.time, displacement])
    settings = f"ffrf generalized-alpha, modified Newton, tolerance {tolerance:g}, {m} modes"
    return ModelRun(float(np.abs(sensor[:, 1:]).max()), sensor, time.perf_counter() - started, settings)


@cache
def _exudyn_fem(with_tip: bool = True):
    """Exudyn's crane with its HCB modes (computed once per process) and the script's node sets."""
    from exudyn.FEM import FEMinterface, HCBstaticModeSelection

    fem = FEMinterface()
    fem.SetWithDictionary(crane_fem().GetDictionary())  # a copy: the modes are stored in the interface
    sets = []
    for corner in CRANE.feet():
        margin = np.array([CRANE.foot_width, CRANE.foot_width, 1e-3])
        sets.append(fem.GetNodesInCube(corner - margin, corner + margin))
    if with_tip:
        sets.append(fem.GetNodesInPlane(list(CRANE.tip()), list(CRANE.arm_direction())))
    weights = [fem.GetNodeWeightsFromSurfaceAreas(s) for s in sets]
    fem.ComputeHurtyCraigBamptonModes(
        boundaryNodesList=sets,
        nEigenModes=N_MODES,
        useSparseSolver=True,
        excludeRigidBodyMotion=False,
        computationMode=HCBstaticModeSelection.RBE2,
    )
    return fem, sets, weights


def frequencies() -> dict[str, NDArray[np.float64]]:
    """Fixed-interface eigenfrequencies (Hz): ours and Exudyn's with all five interfaces fixed (as the
    script runs) and with the feet alone, and the script's comment for the latter (``"stated"``)."""
    return {
        "ours": _our_modes(True)[3].fixed_interface_frequencies_hz,
        "exudyn": np.sort(_exudyn_fem(True)[0].GetEigenFrequenciesHz()),
        "ours_feet_only": _our_modes(False)[3].fixed_interface_frequencies_hz,
        "exudyn_feet_only": np.sort(_exudyn_fem(False)[0].GetEigenFrequenciesHz()),
        "stated": STATED_HZ,
    }


def exudyn(tight: bool) -> ModelRun:
    """The script with Exudyn's items, graphics off (no renderer, no files); ``tight``: tightened Newton."""
    import exudyn as exu
    import exudyn.itemInterface as eii
    from exudyn.FEM import ObjectFFRFreducedOrderInterface

    started = time.perf_counter()
    fem, sets, weights = _exudyn_fem()
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    cms = ObjectFFRFreducedOrderInterface(fem, rigidBodyNodeType=exu.NodeType.RotationRxyz)
    items = cms.AddObjectFFRFreducedOrder(
        mbs, positionRef=[0, 0, 0], gravity=list(GRAVITY), stiffnessProportionalDamping=DAMPING
    )
    body, frame = items["oFFRFreducedOrder"], items["nRigidBody"]
    ground_node = mbs.AddNode(eii.NodePointGround())
    on_ground_node = mbs.AddMarker(eii.MarkerNodeCoordinate(nodeNumber=ground_node, coordinate=0))
    for i in range(len(mbs.GetNode(frame)["referenceCoordinates"])):
        coordinate = mbs.AddMarker(eii.MarkerNodeCoordinate(nodeNumber=frame, coordinate=i))
        mbs.AddObject(eii.ObjectConnectorCoordinate(markerNumbers=[on_ground_node, coordinate]))
    ground = mbs.AddObject(eii.ObjectGround(referencePosition=[0, 0, 0]))
    for k, centre in enumerate(foot_centres()):
        on_ground = mbs.AddMarker(eii.MarkerBodyRigid(bodyNumber=ground, localPosition=list(centre)))
        foot = mbs.AddMarker(
            eii.MarkerSuperElementRigid(bodyNumber=body, meshNodeNumbers=np.array(sets[k]), weightingFactors=weights[k])
        )
        mbs.AddObject(eii.GenericJoint(markerNumbers=[on_ground, foot], constrainedAxes=[1, 1, 1, 0, 0, 0]))
    tip = mbs.AddMarker(
        eii.MarkerSuperElementRigid(bodyNumber=body, meshNodeNumbers=np.array(sets[-1]), weightingFactors=weights[-1])
    )
    mbs.AddLoad(
        eii.LoadForceVector(
            markerNumber=tip,
            loadVector=list(TIP_FORCE),
            loadVectorUserFunction=lambda mbs, t, load: list(tip_force(t, np.asarray(load))),
        )
    )
    sensor = mbs.AddSensor(
        eii.SensorMarker(
            markerNumber=tip,
            storeInternal=True,
            writeToFile=False,
            outputVariableType=exu.OutputVariableType.Displacement,
        )
    )
    mbs.Assemble()
    used = solve(mbs, STEP, T_END, RHO_INF, tight)
    data = np.asarray(mbs.GetSensorStoredData(sensor), dtype=float)
    return ModelRun(float(np.abs(data[:, 1:]).max()), data, time.perf_counter() - started, exudyn_label(used))
