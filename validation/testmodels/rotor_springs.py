r"""The spinning rotor on two spring-dampers: ``objectFFRFreducedOrderTest.py``,
``objectFFRFreducedOrderAccelerations.py`` and ``objectFFRFTest2.py`` (in its reduced form).

The model (all three scripts): ``rotorDiscTest`` (Abaqus, lumped mass) with its stiffness scaled
(``ScaleStiffnessMatrix``), 0.1 kg added at the disc node nearest (0, 0.19598444, 0.15) m
(``AddNodeMass``), free-free modes (``ComputeEigenmodes(nModes, excludeRigidBodyModes=6)``), spinning at
50 rev/s about z, no gravity, held at its end faces z = 0 and z = 0.5 m (mean of the face nodes, equal
weights: ``MarkerSuperElementPosition``) by ``CartesianSpringDamper`` to ground with k = 2e8 N/m in x, y, z
(left) and x, y (right), d = 0.01 k in all three; generalized-alpha with rho_inf = 0.5, h = 1e-4 s. The
scripts differ in the body and the sensor:

=========================================  ========  =====  ===================  ======================
script                                     K factor  modes  body                 sensor, t_end
=========================================  ========  =====  ===================  ======================
objectFFRFreducedOrderTest                 1e-2      8      C++ FFRF terms       Displacement, 0.01 s
objectFFRFreducedOrderAccelerations        6e-4      8 [1]  Python user funcs    Acceleration, 0.001 s
objectFFRFTest2                            1e-2      all    ``ObjectFFRF`` [2]   Displacement, 0.0025 s
=========================================  ========  =====  ===================  ======================

[1] dense eigensolver. [2] The full FFRF body: every node's displacements as coordinates, held by the
linearised Tisserand conditions :math:`\Phi_t^TMu = 0`, :math:`\tilde x^TMu = 0` (``CoordinateVectorConstraint``).
Its reduced form is our body with a basis of the null space of those six rows (3N - 6 = 339 columns):
the constraints are linear, so the constrained motion is the Galerkin projection onto that space, and
generalized-alpha keeps :math:`q, \dot q, \ddot q` in it; the two discrete solutions are the same.

Ours: :func:`ffrf.reduction.free_free.free_free_basis` (the same span as Exudyn's modes),
:class:`~ffrf.body.flexible_body.FlexibleBody`, :func:`ffrf.system.forces.spring_damper` on a joint locking
the three translations of the face's mean (world components: ``CartesianSpringDamper``; its damper sees
the tangent Euler-parameter rates, as Exudyn's marker velocity), the sensors as Exudyn defines them
(:mod:`validation.testmodels.sensors`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.linalg
from numpy.typing import NDArray

from ffrf.body.flexible_body import FlexibleBody
from ffrf.body.modal_moments import modal_moments
from ffrf.fe.external_model import ExternalFEModel
from ffrf.fe.node_selection import node_at_point, nodes_in_plane
from ffrf.reduction.free_free import free_free_basis
from ffrf.solvers.generalized_alpha import generalized_alpha
from ffrf.system.forces import spring_damper
from ffrf.system.joints import GroundFrame, MarkerJoint
from ffrf.system.markers import rigid_interface_marker
from ffrf.system.multibody import MultibodySystem

from .fe_data import DATA, rotor_model
from .sensors import node_acceleration, node_displacement
from .spec import ModelRun, add_with_user_functions, exudyn_label, solve

__all__ = ["RotorOnSprings", "REDUCED_ORDER_TEST", "ACCELERATIONS", "FFRF_TEST2", "tisserand_basis"]

UNBALANCE_POINT = (0.0, 0.19598444, 0.15)
UNBALANCE_MASS = 0.1
OMEGA = (0.0, 0.0, 50.0 * 2.0 * np.pi)
ENDS = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.5))
SPRING = 2e8


@dataclass(frozen=True)
class RotorOnSprings:
    """One of the three scripts (table of the module docstring); ``n_modes = 0``: the full FFRF body."""

    script: str
    stiffness_factor: float
    n_modes: int
    sensor: str  # "Displacement" or "Acceleration"
    sensor_point: tuple[float, float, float]
    t_end: float
    step: float = 1e-4
    rho_inf: float = 0.5
    exudyn_body: str = "cpp"  # "cpp", "user_functions" or "full"
    sparse_eigensolver: bool = True
    unbalance_node: int | None = None  # the script's node number, or None: the node at UNBALANCE_POINT

    def fe_model(self) -> ExternalFEModel:
        """The scaled rotor with the unbalance mass."""
        model = rotor_model().with_scaled_stiffness(self.stiffness_factor)
        node = node_at_point(model.nodes, UNBALANCE_POINT) if self.unbalance_node is None else self.unbalance_node
        return model.with_node_mass(node, UNBALANCE_MASS)

    def ours(self, tolerance: float) -> ModelRun:
        """Our solver: the body, the two spring-dampers, 50 rev/s about z; the script's result."""
        started = time.perf_counter()
        model = self.fe_model()
        basis = tisserand_basis(model) if self.n_modes == 0 else free_free_basis(model, self.n_modes).basis
        reduced_stiffness = basis.T @ (model.stiffness @ basis)
        m = basis.shape[1]
        body = FlexibleBody(
            "rotor",
            modal_moments(model.nodes, model.mass, basis),
            0.5 * (reduced_stiffness + reduced_stiffness.T),
            np.zeros((m, m)),
            exact_gravity=False,
        )
        springs = []
        for end, stiffness_z, name in zip(ENDS, (SPRING, 0.0), ("left", "right"), strict=True):
            face = nodes_in_plane(model.nodes, end, (0.0, 0.0, 1.0))
            marker = rigid_interface_marker(0, model.nodes, basis, face, name=name)
            joint = MarkerJoint(
                (0,), f"{name} support", GroundFrame(point=np.array(end)), marker, locked=(True,) * 3 + (False,) * 3
            )
            springs.append(spring_damper(joint, (SPRING, SPRING, stiffness_z), 0.01 * SPRING))
        system = MultibodySystem((body,), (), np.zeros(3), tuple(springs))
        q0 = system.initial_state(positions=[(0.0, 0.0, 0.0)])
        qd0 = system.rigid_velocity(q0, 0, angular_velocity=OMEGA)
        run = generalized_alpha(system, q0, qd0, self.t_end, self.step, rho_inf=self.rho_inf, tolerance=tolerance)
        node = node_at_point(model.nodes, self.sensor_point)
        if self.sensor == "Displacement":
            values = node_displacement(run.q, model.nodes, basis, node)
        else:
            values = node_acceleration(run.q, run.qd, run.qdd, model.nodes, basis, node)
        sensor = np.column_stack([run.time, values])
        settings = f"ffrf generalized-alpha, modified Newton, tolerance {tolerance:g}, {m} modes"
        return ModelRun(float(np.abs(sensor).sum()), sensor, time.perf_counter() - started, settings)

    def exudyn(self, tight: bool) -> ModelRun:
        """The script with Exudyn's items, graphics off; ``tight``: tightened Newton tolerances."""
        import exudyn as exu
        import exudyn.itemInterface as eii
        from exudyn.FEM import FEMinterface, ObjectFFRFinterface, ObjectFFRFreducedOrderInterface

        started = time.perf_counter()
        sc = exu.SystemContainer()
        mbs = sc.AddSystem()
        fem = FEMinterface()
        stem = DATA / "rotorDiscTest"
        fem.ImportFromAbaqusInputFile(str(stem.with_suffix(".inp")), typeName="Instance", name="rotor-1")
        fem.ReadMassMatrixFromAbaqus(str(DATA / "rotorDiscTestMASS1.mtx.xz"))  # numpy.loadtxt reads .xz
        fem.ReadStiffnessMatrixFromAbaqus(str(DATA / "rotorDiscTestSTIF1.mtx.xz"))
        fem.ScaleStiffnessMatrix(self.stiffness_factor)
        node = fem.GetNodeAtPoint(point=list(UNBALANCE_POINT)) if self.unbalance_node is None else self.unbalance_node
        fem.AddNodeMass(node, UNBALANCE_MASS)
        fem.ComputeEigenmodes(max(self.n_modes, 8), excludeRigidBodyModes=6, useSparseSolver=self.sparse_eigensolver)
        omega = list(OMEGA)
        if self.exudyn_body == "full":
            ffrf = ObjectFFRFinterface(fem)
            items = ffrf.AddObjectFFRF(exu, mbs, positionRef=[0, 0, 0], initialAngularVelocity=omega)
            body = items["oFFRF"]
        else:
            cms = ObjectFFRFreducedOrderInterface(fem)
            if self.exudyn_body == "user_functions":

                def force(mbs, t, item, q, q_t):
                    return cms.UFforceFFRFreducedOrder(exu, mbs, t, q, q_t)

                def mass(mbs, t, item, q, q_t):
                    return cms.UFmassFFRFreducedOrder(exu, mbs, t, q, q_t)

                items = add_with_user_functions(
                    cms,
                    exu,
                    mbs,
                    positionRef=[0, 0, 0],
                    eulerParametersRef=[1, 0, 0, 0],
                    initialAngularVelocity=omega,
                    UFforce=force,
                    UFmassMatrix=mass,
                )
            else:
                items = cms.AddObjectFFRFreducedOrder(mbs, positionRef=[0, 0, 0], initialAngularVelocity=omega)
            body = items["oFFRFreducedOrder"]
        ground = mbs.AddObject(eii.ObjectGround(referencePosition=[0, 0, 0]))
        for end, stiffness_z in zip(ENDS, (SPRING, 0.0), strict=True):
            on_ground = mbs.AddMarker(eii.MarkerBodyPosition(bodyNumber=ground, localPosition=list(end)))
            face = fem.GetNodesInPlane(list(end), [0, 0, 1])
            on_body = mbs.AddMarker(
                eii.MarkerSuperElementPosition(
                    bodyNumber=body, meshNodeNumbers=np.array(face), weightingFactors=np.full(len(face), 1 / len(face))
                )
            )
            d = SPRING * 0.01
            mbs.AddObject(
                eii.CartesianSpringDamper(
                    markerNumbers=[on_body, on_ground], stiffness=[SPRING, SPRING, stiffness_z], damping=[d, d, d]
                )
            )
        sensor = mbs.AddSensor(
            eii.SensorSuperElement(
                bodyNumber=body,
                meshNodeNumber=fem.GetNodeAtPoint(list(self.sensor_point)),
                storeInternal=True,
                outputVariableType=getattr(exu.OutputVariableType, self.sensor),
            )
        )
        mbs.Assemble()
        used = solve(mbs, self.step, self.t_end, self.rho_inf, tight)
        data = np.asarray(mbs.GetSensorStoredData(sensor), dtype=float)
        return ModelRun(float(np.abs(data).sum()), data, time.perf_counter() - started, exudyn_label(used))


def tisserand_basis(model: ExternalFEModel) -> NDArray[np.float64]:
    r"""Orthonormal basis (3N, 3N - 6) of the displacements that satisfy the linearised Tisserand
    conditions of ``ObjectFFRF``: :math:`\Phi_t^TMu = 0` and :math:`\tilde x^TMu = 0` (Exudyn's ``X1``)."""
    nodes, mass = model.nodes, model.mass
    n = len(nodes)
    translations = np.kron(np.ones((n, 1)), np.eye(3))  # Phi_t (3N, 3)
    skew = np.zeros((3 * n, 3))  # the nodes' skew matrices stacked (Exudyn's ComputeSkewMatrix(xRef))
    for i, (x, y, z) in enumerate(nodes):
        skew[3 * i : 3 * i + 3] = [[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]]
    rows = np.vstack([(mass @ translations).T, (mass @ skew).T])
    return np.asarray(scipy.linalg.null_space(rows))


REDUCED_ORDER_TEST = RotorOnSprings("objectFFRFreducedOrderTest", 1e-2, 8, "Displacement", (0.0, 0.0, 0.25), t_end=0.01)
ACCELERATIONS = RotorOnSprings(
    "objectFFRFreducedOrderAccelerations",
    6e-4,
    8,
    "Acceleration",
    (0.0, 0.05, 0.25),
    t_end=0.001,
    exudyn_body="user_functions",
    sparse_eigensolver=False,
)
FFRF_TEST2 = RotorOnSprings(
    "objectFFRFTest2", 1e-2, 0, "Displacement", (0.0, 0.0, 0.25), t_end=0.0025, exudyn_body="full", unbalance_node=9
)
