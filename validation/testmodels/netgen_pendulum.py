r"""``NGsolveCMStest.py``: a coarse Netgen beam as a flexible pendulum on a revolute joint.

The model: the 1 x 0.2 x 0.2 m beam of ``netgenTestMesh.pkl`` (29 nodes, 4-node tetrahedra, rho = 1000
kg/m^3, E = 1e6 Pa; the script meshes it with Netgen but then loads this file, which replaces the mesh),
its face x = 0 the interface (nodes weighted by surface area), 4 Hurty/Craig-Bampton modes (RBE2, the
interface's rigid motions left out), the interface on a ``GenericJoint`` to ground at the origin free
about z, gravity -9.81 m/s^2 along y, generalized-alpha, rho_inf = 0.8, h = 1e-3 s to 0.1 s. Result: the
norm of the Displacement of the node at (1, -0.1, -0.1) m at the end. The script's stress modes and
file round trips do not enter the motion and are left out.

Ours: the file read by :func:`.fe_data.netgen_model` (allow-listed unpickling),
:func:`ffrf.reduction.craig_bampton.craig_bampton`, :func:`ffrf.system.joints.revolute_joint` to ground on
:func:`ffrf.system.markers.rigid_interface_marker`.
"""

from __future__ import annotations

import time

import numpy as np

from ffrf.body.flexible_body import FlexibleBody
from ffrf.body.modal_moments import modal_moments
from ffrf.fe.node_selection import node_at_point, nodes_in_plane, surface_area_weights
from ffrf.reduction.craig_bampton import craig_bampton
from ffrf.solvers.generalized_alpha import generalized_alpha
from ffrf.system.joints import GroundFrame, revolute_joint
from ffrf.system.markers import rigid_interface_marker
from ffrf.system.multibody import MultibodySystem

from .fe_data import DATA, NETGEN_PICKLE_BLOB, git_blob_id, netgen_model
from .sensors import node_displacement
from .spec import ModelRun, exudyn_label, solve

__all__ = ["ours", "exudyn"]

HALF_WIDTH = 0.1
N_MODES = 4
FACE_POINT, FACE_NORMAL = (0.0, -HALF_WIDTH, -HALF_WIDTH), (-1.0, 0.0, 0.0)
TIP = (1.0, -HALF_WIDTH, -HALF_WIDTH)
GRAVITY = (0.0, -9.81, 0.0)
STEP, T_END, RHO_INF = 1e-3, 0.1, 0.8


def ours(tolerance: float) -> ModelRun:
    """Our solver on the pendulum; the script's result."""
    started = time.perf_counter()
    model, triangles = netgen_model()
    face = nodes_in_plane(model.nodes, FACE_POINT, FACE_NORMAL)
    weights = surface_area_weights(model.nodes, triangles, face)
    modes = craig_bampton(model, [face], N_MODES, [weights])
    moments = modal_moments(model.nodes, model.mass, modes.basis)
    body = FlexibleBody("beam", moments, modes.reduced_stiffness, np.zeros((N_MODES, N_MODES)), False)
    marker = rigid_interface_marker(0, model.nodes, modes.basis, face, weights, name="hinged face")
    system = MultibodySystem((body,), (revolute_joint(GroundFrame(), marker, name="hinge"),), np.array(GRAVITY))
    q0 = system.initial_state(positions=[(0.0, 0.0, 0.0)])
    run = generalized_alpha(system, q0, np.zeros_like(q0), T_END, STEP, rho_inf=RHO_INF, tolerance=tolerance)
    tip = node_at_point(model.nodes, TIP)
    sensor = np.column_stack([run.time, node_displacement(run.q, model.nodes, modes.basis, tip)])
    settings = f"ffrf generalized-alpha, modified Newton, tolerance {tolerance:g}, {N_MODES} modes"
    return ModelRun(float(np.linalg.norm(sensor[-1, 1:])), sensor, time.perf_counter() - started, settings)


def exudyn(tight: bool) -> ModelRun:
    """The script with Exudyn's items, graphics off; ``tight``: tightened Newton tolerances."""
    import exudyn as exu
    import exudyn.itemInterface as eii
    from exudyn.FEM import FEMinterface, HCBstaticModeSelection, ObjectFFRFreducedOrderInterface

    started = time.perf_counter()
    path = DATA / "netgenTestMesh.pkl"
    if git_blob_id(path.read_bytes()) != NETGEN_PICKLE_BLOB:  # Exudyn unpickles it without an allow-list
        raise ValueError(f"{path} is not the vendored file (git blob id); not unpickled")
    fem = FEMinterface()
    fem.LoadFromFile(str(path.with_suffix("")), mode="PKL")
    face = fem.GetNodesInPlane(list(FACE_POINT), list(FACE_NORMAL))
    weights = fem.GetNodeWeightsFromSurfaceAreas(face)
    fem.ComputeHurtyCraigBamptonModes(
        boundaryNodesList=[face], nEigenModes=N_MODES, useSparseSolver=True, computationMode=HCBstaticModeSelection.RBE2
    )
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    cms = ObjectFFRFreducedOrderInterface(fem)
    body = cms.AddObjectFFRFreducedOrder(mbs, positionRef=[0, 0, 0], gravity=list(GRAVITY))["oFFRFreducedOrder"]
    ground = mbs.AddObject(eii.ObjectGround(referencePosition=[0, 0, 0]))
    on_ground = mbs.AddMarker(eii.MarkerBodyRigid(bodyNumber=ground, localPosition=[0, 0, 0]))
    on_body = mbs.AddMarker(
        eii.MarkerSuperElementRigid(bodyNumber=body, meshNodeNumbers=np.array(face), weightingFactors=weights)
    )
    mbs.AddObject(eii.GenericJoint(markerNumbers=[on_ground, on_body], constrainedAxes=[1, 1, 1, 1, 1, 0]))
    sensor = mbs.AddSensor(
        eii.SensorSuperElement(
            bodyNumber=body,
            meshNodeNumber=fem.GetNodeAtPoint(list(TIP)),
            storeInternal=True,
            outputVariableType=exu.OutputVariableType.Displacement,
        )
    )
    mbs.Assemble()
    used = solve(mbs, STEP, T_END, RHO_INF, tight)
    data = np.asarray(mbs.GetSensorStoredData(sensor), dtype=float)
    return ModelRun(float(np.linalg.norm(data[-1, 1:])), data, time.perf_counter() - started, exudyn_label(used))
