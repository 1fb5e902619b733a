r"""``abaqusImportTest.py``: a 4 x 1 x 1 m block, meshed with five Abaqus element types, clamped at one
end and sagging under gravity.

For each of C3D4, C3D10, C3D8, C3D20 and C3D20R (Abaqus matrices; C3D4 and C3D8 lumped mass): the face
x = 0 is the interface (its nodes weighted by their surface areas, ``GetNodeWeightsFromSurfaceAreas``),
5 Hurty/Craig-Bampton modes (RBE2, the interface's rigid motions left out, dense eigensolver), the
interface clamped to ground at its centre (0, 0.5, 0.5) m by a ``GenericJoint`` locking all six motions,
gravity -9.81 m/s^2 along y (``LoadMassProportional``), generalized-alpha, rho_inf = 0.5, h = 1e-4 s to
5e-3 s. Result: the sum over the five blocks of ``|DisplacementLocal|`` of the node at (4, 0, 0) at the
last step. The script also round-trips the FE data and the reduced body through files
(``SaveToFile``/``LoadFromFile``); the rebuild here leaves that out (it writes files, the data are the
same), and its Exudyn run reproduces the stored value.

Ours: :func:`ffrf.reduction.craig_bampton.craig_bampton` (RBE2 interface, ``reference="interface"``),
:func:`ffrf.fe.node_selection.surface_area_weights` on :func:`ffrf.fe.node_selection.surface_triangles`,
:func:`ffrf.system.joints.fixed_joint` to ground on :func:`ffrf.system.markers.rigid_interface_marker`.
"""

from __future__ import annotations

import time
from functools import cache

import numpy as np

from ffrf.body.flexible_body import FlexibleBody
from ffrf.body.modal_moments import modal_moments
from ffrf.fe.node_selection import node_at_point, nodes_in_plane, surface_area_weights, surface_triangles
from ffrf.reduction.craig_bampton import craig_bampton
from ffrf.solvers.generalized_alpha import generalized_alpha
from ffrf.system.joints import GroundFrame, fixed_joint
from ffrf.system.markers import rigid_interface_marker
from ffrf.system.multibody import MultibodySystem

from .fe_data import BLOCKS, DATA, block_model
from .sensors import node_local_displacement
from .spec import ModelRun, exudyn_label, solve

__all__ = ["ours", "exudyn"]

N_MODES = 5
FACE_POINT, FACE_NORMAL = (0.0, 0.0, 0.0), (-1.0, 0.0, 0.0)
CLAMP = (0.0, 0.5, 0.5)
TIP = (4.0, 0.0, 0.0)
GRAVITY = (0.0, -9.81, 0.0)
STEP, T_END, RHO_INF = 1e-4, 5e-3, 0.5


def _result(sensor: np.ndarray) -> float:
    """Sum over the blocks of ``|last row|`` (time column left out); ``sensor`` stacks the blocks' rows."""
    rows = sensor.reshape(len(BLOCKS), -1, sensor.shape[1])
    return float(np.abs(rows[:, -1, 1:]).sum())


def ours(tolerance: float) -> ModelRun:
    """Our solver on the five blocks; the script's result, the sensor rows of all blocks stacked."""
    started = time.perf_counter()
    sensors = []
    for element in BLOCKS:
        model = block_model(element)
        face = nodes_in_plane(model.nodes, FACE_POINT, FACE_NORMAL)
        weights = surface_area_weights(model.nodes, surface_triangles(model.elements), face)
        modes = craig_bampton(model, [face], N_MODES, [weights])
        moments = modal_moments(model.nodes, model.mass, modes.basis)
        body = FlexibleBody("block", moments, modes.reduced_stiffness, np.zeros((N_MODES, N_MODES)), False)
        marker = rigid_interface_marker(0, model.nodes, modes.basis, face, weights, name="clamped face")
        clamp = fixed_joint(GroundFrame(point=np.array(CLAMP)), marker, name="clamp")
        system = MultibodySystem((body,), (clamp,), np.array(GRAVITY))
        q0 = system.initial_state(positions=[(0.0, 0.0, 0.0)])
        run = generalized_alpha(system, q0, np.zeros_like(q0), T_END, STEP, rho_inf=RHO_INF, tolerance=tolerance)
        tip = node_at_point(model.nodes, TIP)
        sensors.append(np.column_stack([run.time, node_local_displacement(run.q, modes.basis, tip)]))
    sensor = np.vstack(sensors)
    settings = f"ffrf generalized-alpha, modified Newton, tolerance {tolerance:g}, {N_MODES} modes"
    return ModelRun(_result(sensor), sensor, time.perf_counter() - started, settings)


@cache
def _exudyn_fem(element: str):
    """Exudyn's FE data of one block with its HCB modes (computed once: the dense eigensolver takes seconds)."""
    from exudyn.FEM import FEMinterface, HCBstaticModeSelection

    fem = FEMinterface()
    stem = DATA / "abaqus" / f"block{element}"
    fem.ImportFromAbaqusInputFile(str(stem.with_suffix(".inp")), typeName="Instance", name="rotor-1")  # as the script
    fem.ReadMassMatrixFromAbaqus(str(stem.with_name(stem.name + "_MASS1.mtx.xz")))  # numpy.loadtxt reads .xz
    fem.ReadStiffnessMatrixFromAbaqus(str(stem.with_name(stem.name + "_STIF1.mtx.xz")))
    face = fem.GetNodesInPlane(list(FACE_POINT), list(FACE_NORMAL))
    weights = fem.GetNodeWeightsFromSurfaceAreas(face)
    fem.ComputeHurtyCraigBamptonModes(
        boundaryNodesList=[face],
        nEigenModes=N_MODES,
        useSparseSolver=False,
        computationMode=HCBstaticModeSelection.RBE2,
    )
    return fem, face, weights


def exudyn(tight: bool) -> ModelRun:
    """The script with Exudyn's items, graphics off; ``tight``: tightened Newton tolerances. The HCB
    modes are computed by the first call and kept (the wall time of a later call leaves them out)."""
    import exudyn as exu
    import exudyn.itemInterface as eii
    from exudyn.FEM import ObjectFFRFreducedOrderInterface

    started = time.perf_counter()
    sensors: list[np.ndarray] = []
    used: list[float | None] = []
    for element in BLOCKS:
        fem, face, weights = _exudyn_fem(element)
        sc = exu.SystemContainer()
        mbs = sc.AddSystem()
        cms = ObjectFFRFreducedOrderInterface(fem)
        items = cms.AddObjectFFRFreducedOrder(mbs, positionRef=[0, 0, 0], gravity=list(GRAVITY))
        body = items["oFFRFreducedOrder"]
        ground = mbs.AddObject(eii.ObjectGround(referencePosition=[0, 0, 0]))
        on_ground = mbs.AddMarker(eii.MarkerBodyRigid(bodyNumber=ground, localPosition=list(CLAMP)))
        on_body = mbs.AddMarker(
            eii.MarkerSuperElementRigid(bodyNumber=body, meshNodeNumbers=np.array(face), weightingFactors=weights)
        )
        mbs.AddObject(eii.GenericJoint(markerNumbers=[on_ground, on_body], constrainedAxes=[1] * 6))
        sensor = mbs.AddSensor(
            eii.SensorSuperElement(
                bodyNumber=body,
                meshNodeNumber=fem.GetNodeAtPoint(list(TIP)),
                storeInternal=True,
                outputVariableType=exu.OutputVariableType.DisplacementLocal,
            )
        )
        mbs.Assemble()
        used.append(solve(mbs, STEP, T_END, RHO_INF, tight))
        sensors.append(np.asarray(mbs.GetSensorStoredData(sensor), dtype=float))
    sensor = np.vstack(sensors)
    loosest = None if None in used else max(t for t in used if t is not None)
    return ModelRun(_result(sensor), sensor, time.perf_counter() - started, exudyn_label(loosest))
