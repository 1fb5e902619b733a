r"""``superElementRigidJointTest.py``: two rotors in a row, clamped to ground and to each other by
``GenericJoint`` on ``MarkerSuperElementRigid`` interfaces, sagging under gravity.

The model: ``rotorDiscTest`` with its stiffness scaled by 1e-3 and 0.1 kg at node 9, 20 free-free modes
(sparse eigensolver), twice: body 1 at the origin, body 2 at z = 0.5 m, both through Python user
functions for the FFRF terms (``AddObjectFFRFreducedOrderWithUserFunctions``, whose gravity is
Exudyn's simplified one, as ``exact_gravity=False``), gravity -9.81 m/s^2 along y. Joints locking all six
motions: body 1's face z = 0 to ground at the origin, body 1's face z = 0.5 to body 2's face z = 0 (rigid
interface markers, equal weights, ``useAlternativeApproach=True``). Generalized-alpha, rho_inf = 0.5,
h = 1e-3 s to 0.005 s; result: sum of ``|Displacement|`` of body 1's node at (0, 0, 0.25), time column
included.

Ours: :func:`ffrf.reduction.free_free.free_free_basis`, :func:`ffrf.system.joints.fixed_joint` on
:func:`ffrf.system.markers.rigid_interface_marker` (Exudyn's marker with the alternative approach); the
ground joint with the ground as marker 0 (Exudyn's has it second; a joint locking all six motions is the
same constraint either way).
"""

from __future__ import annotations

import time

import numpy as np

from ffrf.body.flexible_body import FlexibleBody
from ffrf.body.modal_moments import modal_moments
from ffrf.fe.node_selection import node_at_point, nodes_in_plane
from ffrf.reduction.free_free import free_free_basis
from ffrf.solvers.generalized_alpha import generalized_alpha
from ffrf.system.joints import GroundFrame, fixed_joint
from ffrf.system.markers import rigid_interface_marker
from ffrf.system.multibody import MultibodySystem

from .fe_data import DATA, rotor_model
from .sensors import node_displacement
from .spec import ModelRun, add_with_user_functions, exudyn_label, solve

__all__ = ["ours", "exudyn"]

STIFFNESS_FACTOR = 1e-3
UNBALANCE_NODE = 9
UNBALANCE_MASS = 0.1
N_MODES = 20
GRAVITY = (0.0, -9.81, 0.0)
SECOND_BODY = (0.0, 0.0, 0.5)
SENSOR_POINT = (0.0, 0.0, 0.25)
STEP, T_END, RHO_INF = 1e-3, 0.005, 0.5


def ours(tolerance: float) -> ModelRun:
    """Our solver on the two clamped rotors; the script's result."""
    started = time.perf_counter()
    model = rotor_model().with_scaled_stiffness(STIFFNESS_FACTOR).with_node_mass(UNBALANCE_NODE, UNBALANCE_MASS)
    modes = free_free_basis(model, N_MODES)
    basis = modes.basis
    moments = modal_moments(model.nodes, model.mass, basis)
    damping = np.zeros((N_MODES, N_MODES))
    bodies = tuple(
        FlexibleBody(name, moments, modes.reduced_stiffness, damping, False) for name in ("rotor 1", "rotor 2")
    )
    left, right = (nodes_in_plane(model.nodes, (0.0, 0.0, z), (0.0, 0.0, 1.0)) for z in (0.0, 0.5))
    left_1 = rigid_interface_marker(0, model.nodes, basis, left, name="rotor 1 left")
    right_1 = rigid_interface_marker(0, model.nodes, basis, right, name="rotor 1 right")
    left_2 = rigid_interface_marker(1, model.nodes, basis, left, name="rotor 2 left")
    joints = (fixed_joint(GroundFrame(), left_1, name="ground"), fixed_joint(right_1, left_2, name="rotor 1 - rotor 2"))
    system = MultibodySystem(bodies, joints, np.array(GRAVITY))
    q0 = system.initial_state(positions=[(0.0, 0.0, 0.0), SECOND_BODY])
    run = generalized_alpha(system, q0, np.zeros_like(q0), T_END, STEP, rho_inf=RHO_INF, tolerance=tolerance)
    node = node_at_point(model.nodes, SENSOR_POINT)
    sensor = np.column_stack([run.time, node_displacement(run.q[:, system.block(0)], model.nodes, basis, node)])
    settings = f"ffrf generalized-alpha, modified Newton, tolerance {tolerance:g}, {N_MODES} modes per body"
    return ModelRun(float(np.abs(sensor).sum()), sensor, time.perf_counter() - started, settings)


def exudyn(tight: bool) -> ModelRun:
    """The script with Exudyn's items, graphics off; ``tight``: tightened Newton tolerances."""
    import exudyn as exu
    import exudyn.itemInterface as eii
    from exudyn.FEM import FEMinterface, ObjectFFRFreducedOrderInterface

    started = time.perf_counter()
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    fem = FEMinterface()
    fem.ImportFromAbaqusInputFile(str(DATA / "rotorDiscTest.inp"), typeName="Instance", name="rotor-1")
    fem.ReadMassMatrixFromAbaqus(str(DATA / "rotorDiscTestMASS1.mtx.xz"))  # numpy.loadtxt reads .xz
    fem.ReadStiffnessMatrixFromAbaqus(str(DATA / "rotorDiscTestSTIF1.mtx.xz"))
    fem.ScaleStiffnessMatrix(STIFFNESS_FACTOR)
    fem.AddNodeMass(UNBALANCE_NODE, UNBALANCE_MASS)
    fem.ComputeEigenmodes(N_MODES, excludeRigidBodyModes=6, useSparseSolver=True)
    bodies = []
    for position in ((0.0, 0.0, 0.0), SECOND_BODY):
        cms = ObjectFFRFreducedOrderInterface(fem)

        def force(mbs, t, item, q, q_t, cms=cms):
            return cms.UFforceFFRFreducedOrder(exu, mbs, t, q, q_t)

        def mass(mbs, t, item, q, q_t, cms=cms):
            return cms.UFmassFFRFreducedOrder(exu, mbs, t, q, q_t)

        items = add_with_user_functions(
            cms,
            exu,
            mbs,
            positionRef=list(position),
            eulerParametersRef=[1, 0, 0, 0],
            gravity=list(GRAVITY),
            UFforce=force,
            UFmassMatrix=mass,
        )
        bodies.append(items["oFFRFreducedOrder"])
    ground = mbs.AddObject(eii.ObjectGround(referencePosition=[0, 0, 0]))
    on_ground = mbs.AddMarker(eii.MarkerBodyRigid(bodyNumber=ground, localPosition=[0, 0, 0]))
    left, right = (fem.GetNodesInPlane([0, 0, z], [0, 0, 1]) for z in (0.0, 0.5))

    def interface(body: int, nodes) -> int:
        return mbs.AddMarker(
            eii.MarkerSuperElementRigid(
                bodyNumber=body,
                useAlternativeApproach=True,
                meshNodeNumbers=np.array(nodes),
                weightingFactors=np.full(len(nodes), 1.0 / len(nodes)),
            )
        )

    left_1, right_1, left_2 = interface(bodies[0], left), interface(bodies[0], right), interface(bodies[1], left)
    mbs.AddObject(eii.GenericJoint(markerNumbers=[left_1, on_ground], constrainedAxes=[1] * 6))
    mbs.AddObject(eii.GenericJoint(markerNumbers=[right_1, left_2], constrainedAxes=[1] * 6))
    sensor = mbs.AddSensor(
        eii.SensorSuperElement(
            bodyNumber=bodies[0],
            meshNodeNumber=fem.GetNodeAtPoint(list(SENSOR_POINT)),
            storeInternal=True,
            outputVariableType=exu.OutputVariableType.Displacement,
        )
    )
    mbs.Assemble()
    used = solve(mbs, STEP, T_END, RHO_INF, tight)  # the script's useIndex2Constraints = useNewmark = False: defaults
    data = np.asarray(mbs.GetSensorStoredData(sensor), dtype=float)
    return ModelRun(float(np.abs(data).sum()), data, time.perf_counter() - started, exudyn_label(used))
