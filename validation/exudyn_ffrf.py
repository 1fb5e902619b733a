r"""The Exudyn twin of small FFRF scenes, and the same scenes in our solver.

A :class:`ReducedBody` holds one body's FE data (nodes, consistent M, K, the mode basis
and the frame-interface weights). A :class:`Scene` adds gravity, damping, the initial
state and an optional revolute joint to ground at the frame interface. Both solvers get
*identical* input:

* Exudyn: ``FEMinterface`` filled with our nodes, M, K and **our** basis
  (``modeBasis = {'matrix': Psi, 'type': 'HCBmodes'}``), then
  ``ObjectFFRFreducedOrderInterface(fem)`` (Euler-parameter frame node, the default) and
  ``AddObjectFFRFreducedOrder`` (C++ FFRF terms, no user functions). The hinge is a
  ``MarkerSuperElementRigid`` on the frame-interface nodes with our weights and a ground
  ``MarkerBodyRigid``, joined by ``GenericJoint(constrainedAxes=[1,1,1,1,1,0])``; the joint
  frames are rotated by the markers' ``localHT`` so that their z-axis is the hinge axis.
* Ours: :class:`ffrf.body.flexible_body.FlexibleBody` with ``exact_gravity=False`` (Exudyn's
  ``LoadMassProportional`` on ``ObjectFFRFreducedOrder`` uses the undeformed centre of mass in
  the rotational row), ``GroundPoint`` at the weighted frame-interface centre and
  ``GroundPerpendicular`` for the axis.

Conventions matched (see the report in ``docs`` / the tests):

* DOF order [x0, y0, z0, x1, ...] in both; the frame origin is the mesh origin.
* Exudyn's ODE2 coordinates are displacements from the reference; the results here are
  absolute (reference added back).
* ``AddObjectFFRFreducedOrder(initialAngularVelocity=...)`` expects the **global** angular
  velocity (``GetRigidBodyNode`` -> ``AngularVelocity2EulerParameters_t``); we give the
  body-frame one and convert with the reference rotation.
* Damping: both use D = beta K_red (``stiffnessProportionalDamping``).
* Newton: full Newton, fixed steps, no adaptive step, consistent initial accelerations.

``exudyn`` is imported lazily, so that this module can be imported (for the scenes and our
solver) where Exudyn is missing.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "ReducedBody",
    "Hinge",
    "Scene",
    "TrajectoryResult",
    "bar_body",
    "pendulum_scene",
    "free_body_scene",
    "run_exudyn",
    "run_ffrf",
    "hinge_frame",
    "static_deflection",
    "tip_node",
    "ffrf_system",
    "node_positions",
]


# --------------------------------------------------------------------------------------------
# Scene description (solver neutral)
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class ReducedBody:
    """FE data of one modally reduced body, shared verbatim by both solvers.

    Attributes
    ----------
    nodes : (N, 3) reference node positions in the body frame (m).
    mass, stiffness : (3N, 3N) consistent mass and stiffness (CSR), DOFs [x0, y0, z0, x1, ...].
    basis : (3N, m) mode basis Psi (vanishes on the frame interface).
    frame_nodes, frame_weights : node indices and weights (sum 1) of the frame interface (bore 0).
    tip_nodes, tip_weights : node indices and weights of the second interface (bore 1).
    length : characteristic length (m) used to scale tolerances.
    """

    nodes: NDArray[np.float64]
    mass: sp.csr_matrix
    stiffness: sp.csr_matrix
    basis: NDArray[np.float64]
    frame_nodes: NDArray[np.int64]
    frame_weights: NDArray[np.float64]
    tip_nodes: NDArray[np.int64]
    tip_weights: NDArray[np.float64]
    length: float
    reduced_mass: NDArray[np.float64] = field(init=False, repr=False)
    reduced_stiffness: NDArray[np.float64] = field(init=False, repr=False)

    def __post_init__(self):
        n = len(self.nodes)
        if self.basis.shape[0] != 3 * n:
            raise ValueError(f"basis has {self.basis.shape[0]} rows, expected 3 x {n} nodes")
        for label, w in (("frame", self.frame_weights), ("tip", self.tip_weights)):
            if abs(float(np.sum(w)) - 1.0) > 1e-12:
                raise ValueError(f"{label} interface weights must sum to 1, got {np.sum(w)!r}")
        reduced_mass = self.basis.T @ (self.mass @ self.basis)
        reduced_stiffness = self.basis.T @ (self.stiffness @ self.basis)
        object.__setattr__(self, "reduced_mass", 0.5 * (reduced_mass + reduced_mass.T))
        object.__setattr__(self, "reduced_stiffness", 0.5 * (reduced_stiffness + reduced_stiffness.T))

    @property
    def n_modes(self) -> int:
        return self.basis.shape[1]

    @property
    def frame_center(self) -> NDArray[np.float64]:
        """Weighted mean of the frame-interface reference positions (body frame)."""
        return self.frame_weights @ self.nodes[self.frame_nodes]

    def max_mode_on_frame_interface(self) -> float:
        """Largest |Psi| entry on the frame-interface DOFs (0 for the RBE2 reference condition)."""
        dofs = (3 * self.frame_nodes[:, None] + np.arange(3)).ravel()
        return float(np.abs(self.basis[dofs]).max())


@dataclass(frozen=True)
class Hinge:
    """Revolute joint to ground at the frame-interface centre, about the world ``axis``."""

    axis: tuple[float, float, float] = (0.0, 1.0, 0.0)


@dataclass(frozen=True, eq=False)
class Scene:
    """One body, its initial state, loads and an optional hinge; all in SI units.

    ``euler0`` is the initial (= Exudyn reference) rotation of the frame as unit Euler
    parameters; a hinged scene needs the identity. ``omega_bar`` is the body-frame angular
    velocity.
    """

    body: ReducedBody
    tracked_nodes: tuple[int, ...]
    gravity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    beta: float = 0.0  # stiffness-proportional damping D = beta K_red (s)
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    omega_bar: tuple[float, float, float] = (0.0, 0.0, 0.0)
    euler0: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)
    zeta0: NDArray[np.float64] | None = None
    hinge: Hinge | None = None
    t_end: float = 1.0
    step: float = 1e-3
    rho_inf: float = 0.8

    def __post_init__(self):
        p = np.asarray(self.euler0, dtype=float)
        if p.shape != (4,) or abs(np.linalg.norm(p) - 1.0) > 1e-12:
            raise ValueError(f"euler0 must be 4 unit Euler parameters, got {self.euler0!r}")
        if self.hinge is not None and np.abs(p - np.array([1.0, 0.0, 0.0, 0.0])).max() > 0:
            raise ValueError("a hinged scene starts from the identity rotation (euler0 = (1, 0, 0, 0))")

    def rotation0(self) -> NDArray[np.float64]:
        """Initial rotation matrix A(euler0) (body to world)."""
        from ffrf.body.euler_parameters import rotation_matrix

        return rotation_matrix(np.asarray(self.euler0, dtype=float))

    def initial_zeta(self) -> NDArray[np.float64]:
        if self.zeta0 is None:
            return np.zeros(self.body.n_modes)
        zeta0 = np.asarray(self.zeta0, dtype=float)
        if zeta0.shape != (self.body.n_modes,):
            raise ValueError(f"zeta0 has shape {zeta0.shape}, expected ({self.body.n_modes},)")
        return zeta0

    @property
    def n_steps(self) -> int:
        n = int(round(self.t_end / self.step))
        if n < 1 or abs(n * self.step - self.t_end) > 1e-9 * self.t_end:
            raise ValueError(f"t_end={self.t_end} is not a whole number of steps h={self.step}")
        return n

    def with_step(self, step: float) -> "Scene":
        return replace(self, step=step)


@dataclass
class TrajectoryResult:
    """Time histories (rows = output times, including t = 0) of one solver run.

    Attributes
    ----------
    time : (n,) s.
    position : (n, 3) frame origin R (world).
    euler : (n, 4) Euler parameters of the frame (scalar first).
    zeta : (n, m) modal coordinates.
    tracked : (n, k, 3) world positions of ``Scene.tracked_nodes``.
    setup_time, integration_time : wall times (s).
    newton_iterations : total Newton iterations (or -1 if unknown).
    solver : text label, with the Exudyn version for Exudyn runs.
    """

    time: NDArray[np.float64]
    position: NDArray[np.float64]
    euler: NDArray[np.float64]
    zeta: NDArray[np.float64]
    tracked: NDArray[np.float64]
    setup_time: float
    integration_time: float
    newton_iterations: int
    solver: str
    version: str = ""

    @property
    def time_per_step(self) -> float:
        return self.integration_time / max(len(self.time) - 1, 1)


def hinge_frame(axis: ArrayLike) -> NDArray[np.float64]:
    """Rotation matrix whose third column is the unit ``axis`` (the joint z-axis).

    Its first two columns are the unit normals used by our ``GroundPerpendicular``.
    """
    z = np.asarray(axis, dtype=float)
    norm = np.linalg.norm(z)
    if not norm > 0:
        raise ValueError(f"hinge axis must be non-zero, got {axis!r}")
    z = z / norm
    helper = np.eye(3)[int(np.argmin(np.abs(z)))]
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


# --------------------------------------------------------------------------------------------
# The test bar
# --------------------------------------------------------------------------------------------


def bar_body(
    divisions: tuple[int, int, int] = (8, 2, 2),
    size: tuple[float, float, float] = (0.2, 0.02, 0.01),
    E: float = 1.2e9,
    nu: float = 0.33,
    rho: float = 450.0,
    n_modes: int = 4,
    weights: str = "uniform",
) -> ReducedBody:
    """Prismatic bar along x, centred in y and z, bore 0 = face x = 0 (frame interface).

    Parameters
    ----------
    divisions : elements (boxes of 6 tetrahedra) along x, y, z; at least 2 across.
    size : bar dimensions (m).
    n_modes : fixed-interface modes (the basis has 6 + n_modes columns).
    weights : "uniform" (1/n) or "area" (tributary face areas of the structured end-face grid,
        trapezoidal rule) for both interfaces. Either way both solvers get the same weights.
    """
    import skfem

    from ffrf import FEModel
    from ffrf.mesh.tet_mesh import orient_positive
    from ffrf.reduction.craig_bampton import craig_bampton

    nx, ny, nz = divisions
    if ny < 2 or nz < 2:
        raise ValueError(f"use at least 2 elements across the section, got {divisions}")
    lx, ly, lz = size
    mesh = skfem.MeshTet.init_tensor(
        np.linspace(0.0, lx, nx + 1), np.linspace(-ly / 2, ly / 2, ny + 1), np.linspace(-lz / 2, lz / 2, nz + 1)
    )
    points = mesh.p.T
    tets = orient_positive(points, mesh.t.T)
    model = FEModel.from_mesh(points, tets, E=E, nu=nu, rho=rho, order=1)
    nodes = np.asarray(model.nodes)
    tol = 1e-9 * lx
    bores = [np.flatnonzero(np.abs(nodes[:, 0]) < tol), np.flatnonzero(np.abs(nodes[:, 0] - lx) < tol)]
    if weights == "uniform":
        w = [np.full(len(b), 1.0 / len(b)) for b in bores]
    elif weights == "area":
        w = [_face_area_weights(nodes[b][:, 1:], ny, nz) for b in bores]
    else:
        raise ValueError(f"weights={weights!r}: use 'uniform' or 'area'")
    cb = craig_bampton(model, bores, n_modes, w)
    return ReducedBody(
        nodes,
        sp.csr_matrix(model.mass),
        sp.csr_matrix(model.stiffness),
        np.asarray(cb.basis),
        bores[0],
        w[0],
        bores[1],
        w[1],
        float(lx),
    )


def _face_area_weights(yz: NDArray[np.float64], ny: int, nz: int) -> NDArray[np.float64]:
    """Tributary areas of a structured rectangular face grid (trapezoidal rule), normalised."""
    ys, zs = np.unique(np.round(yz[:, 0], 12)), np.unique(np.round(yz[:, 1], 12))
    if len(ys) != ny + 1 or len(zs) != nz + 1:
        raise ValueError("face nodes do not form the expected structured grid")
    wy = np.diff(ys, prepend=ys[0]) / 2 + np.diff(ys, append=ys[-1]) / 2
    wz = np.diff(zs, prepend=zs[0]) / 2 + np.diff(zs, append=zs[-1]) / 2
    iy = np.searchsorted(ys, np.round(yz[:, 0], 12))
    iz = np.searchsorted(zs, np.round(yz[:, 1], 12))
    w = wy[iy] * wz[iz]
    return w / w.sum()


def tip_node(body: ReducedBody) -> int:
    """The tip node closest to the tip-interface centre."""
    centre = body.tip_weights @ body.nodes[body.tip_nodes]
    return int(body.tip_nodes[np.argmin(np.linalg.norm(body.nodes[body.tip_nodes] - centre, axis=1))])


def pendulum_scene(
    body: ReducedBody,
    step: float = 1e-3,
    t_end: float = 1.0,
    beta: float = 0.0,
    rho_inf: float = 0.8,
    axis: tuple[float, float, float] = (0.0, 1.0, 0.0),
) -> Scene:
    """Scene 1: hinged at bore 0 about ``axis``, released from horizontal at rest, g = -9.81 e_z."""
    corner = int(np.argmax(body.nodes @ np.array([1.0, 1e-3, 1e-6])))  # an outer tip corner
    return Scene(
        body,
        (tip_node(body), corner),
        gravity=(0.0, 0.0, -9.81),
        beta=beta,
        hinge=Hinge(axis),
        t_end=t_end,
        step=step,
        rho_inf=rho_inf,
    )


def static_deflection(body: ReducedBody, tip_force: ArrayLike) -> NDArray[np.float64]:
    """Modal coordinates of the static deflection under ``tip_force`` (N, body frame), spread over
    the tip interface with its weights, with the frame interface clamped: K_red zeta = Psi^T f."""
    f = np.zeros(3 * len(body.nodes))
    for i, w in zip(body.tip_nodes, body.tip_weights):
        f[3 * i : 3 * i + 3] = w * np.asarray(tip_force, dtype=float)
    return np.linalg.solve(body.reduced_stiffness, body.basis.T @ f)


def free_body_scene(
    body: ReducedBody,
    step: float = 1e-3,
    t_end: float = 0.2,
    rho_inf: float = 0.8,
    tip_force: tuple[float, float, float] = (0.0, 1e-2, 1e-2),
    tilted: bool = False,
) -> Scene:
    """Scene 2: no gravity, no constraints, omega_bar = (1, 2, 30) rad/s, v = (0.1, 0, 0) m/s.

    The elastic excitation zeta0 is the static deflection under a small ``tip_force`` (10 mN:
    zeta0 ~ 1e-5, tip deflection ~ 1.5 um for the default bar). A smooth shape is needed:
    zeta0 = 1e-6 (1, -1, ...) excites the stiffest modes (up to 16 kHz, omega h ~ 100; about
    1e-4 m at up to 1e6 m/s^2) and Newton diverges in the first step at h = 1e-3 in *both*
    solvers (ours: NewtonDivergence after 12 iterations, full or modified Newton; Exudyn:
    "Newton has been stopped"); it runs at h = 1e-4. So does 100x the default tip force.
    ``tilted=True`` starts from a rotation of 40 deg about (1, 2, 3)/sqrt(14), so that body and
    world angular velocities differ (this checks the angular-velocity frame convention).
    """
    euler0 = (1.0, 0.0, 0.0, 0.0)
    if tilted:
        half, axis = np.radians(40.0) / 2.0, np.array([1.0, 2.0, 3.0]) / np.sqrt(14.0)
        euler0 = tuple(float(v) for v in np.r_[np.cos(half), np.sin(half) * axis])
    corner = int(np.argmax(body.nodes @ np.array([1.0, 1e-3, 1e-6])))
    return Scene(
        body,
        (tip_node(body), corner),
        velocity=(0.1, 0.0, 0.0),
        omega_bar=(1.0, 2.0, 30.0),
        zeta0=static_deflection(body, tip_force),
        euler0=euler0,
        t_end=t_end,
        step=step,
        rho_inf=rho_inf,
    )


# --------------------------------------------------------------------------------------------
# Exudyn twin
# --------------------------------------------------------------------------------------------


def _exudyn_fem(body: ReducedBody):
    """FEMinterface with our nodes, M, K and basis (no surface: only needed for weights/graphics)."""
    from exudyn.FEM import FEMinterface

    fem = FEMinterface()
    fem.nodes = {"Position": np.array(body.nodes, dtype=float)}
    fem.massMatrix = sp.csr_matrix(body.mass)
    fem.stiffnessMatrix = sp.csr_matrix(body.stiffness)
    fem.modeBasis = {"matrix": np.array(body.basis, dtype=float), "type": "HCBmodes"}
    return fem


def _add_exudyn_body(mbs, scene: Scene):
    """Add the FFRF body; returns (object, rigid node, modal node) indices."""
    from exudyn.FEM import ObjectFFRFreducedOrderInterface

    body = scene.body
    cms = ObjectFFRFreducedOrderInterface(_exudyn_fem(body))  # Euler parameters (default)
    rotation_ref = scene.rotation0()
    omega_global = rotation_ref @ np.asarray(scene.omega_bar, dtype=float)  # Exudyn expects the global omega
    info = cms.AddObjectFFRFreducedOrder(
        mbs,
        positionRef=list(scene.position),
        initialVelocity=list(scene.velocity),
        rotationMatrixRef=rotation_ref,
        initialAngularVelocity=list(omega_global),
        gravity=list(scene.gravity),
        stiffnessProportionalDamping=scene.beta,
    )
    mbs.SetNodeParameter(info["nGenericODE2"], "initialCoordinates", [float(z) for z in scene.initial_zeta()])
    return info["oFFRFreducedOrder"], info["nRigidBody"], info["nGenericODE2"]


def _add_exudyn_hinge(mbs, scene: Scene, body_object) -> None:
    """MarkerSuperElementRigid on bore 0 (our weights) + ground marker + GenericJoint (free rz)."""
    import exudyn as exu
    import exudyn.itemInterface as eii

    body = scene.body
    frame = hinge_frame(scene.hinge.axis)  # world = body axes at t = 0 (identity reference rotation)
    centre_world = np.asarray(scene.position, dtype=float) + body.frame_center
    ground = mbs.AddObject(eii.ObjectGround(referencePosition=[0.0, 0.0, 0.0]))
    m_ground = mbs.AddMarker(
        eii.MarkerBodyRigid(bodyNumber=ground, localHT=exu.HT(rotation=frame, translation=centre_world))
    )
    m_body = mbs.AddMarker(
        eii.MarkerSuperElementRigid(
            bodyNumber=body_object,
            meshNodeNumbers=[int(i) for i in body.frame_nodes],
            weightingFactors=[float(w) for w in body.frame_weights],
            useAlternativeApproach=True,
            localHT=exu.HT(rotation=frame, translation=[0.0, 0.0, 0.0]),
        )
    )
    mbs.AddObject(eii.GenericJoint(markerNumbers=[m_ground, m_body], constrainedAxes=[1, 1, 1, 1, 1, 0]))


def _add_exudyn_sensors(mbs, scene: Scene, body_object, rigid_node, modal_node) -> dict[str, object]:
    import exudyn as exu
    import exudyn.itemInterface as eii

    out = exu.OutputVariableType
    sensors = {
        "rigid": mbs.AddSensor(
            eii.SensorNode(
                nodeNumber=rigid_node, outputVariableType=out.Coordinates, storeInternal=True, writeToFile=False
            )
        ),
        "modal": mbs.AddSensor(
            eii.SensorNode(
                nodeNumber=modal_node, outputVariableType=out.Coordinates, storeInternal=True, writeToFile=False
            )
        ),
    }
    for k, node in enumerate(scene.tracked_nodes):
        sensors[f"node{k}"] = mbs.AddSensor(
            eii.SensorSuperElement(
                bodyNumber=body_object,
                meshNodeNumber=int(node),
                outputVariableType=out.Position,
                storeInternal=True,
                writeToFile=False,
            )
        )
    return sensors


def exudyn_settings(
    scene: Scene, modified_newton: bool = False, relative_tolerance: float = 1e-12, absolute_tolerance: float = 1e-12
):
    """Generalized-alpha (index 3, no Newmark), fixed step, full Newton, tight tolerances."""
    import exudyn as exu

    s = exu.SimulationSettings()
    ti = s.timeIntegration
    ti.numberOfSteps = scene.n_steps
    ti.endTime = scene.t_end
    ti.adaptiveStep = False
    ti.automaticStepSize = False
    ti.verboseMode = 0
    ti.generalizedAlpha.spectralRadius = scene.rho_inf
    ti.generalizedAlpha.useIndex2Constraints = False
    ti.generalizedAlpha.useNewmark = False
    ti.generalizedAlpha.computeInitialAccelerations = True
    ti.newton.useModifiedNewton = modified_newton
    ti.newton.relativeTolerance = relative_tolerance
    ti.newton.absoluteTolerance = absolute_tolerance
    ti.newton.maxIterations = 25
    s.solution.file.write = False
    s.solution.sensors.writePeriod = 0.5 * scene.step  # every step
    s.show.statistics = False
    s.show.computationTime = False
    s.linearSolver.solverType = exu.LinearSolverType.EXUdense
    s.parallel.numberOfThreads = 1
    return s


def run_exudyn(
    scene: Scene, modified_newton: bool = False, relative_tolerance: float = 1e-12, absolute_tolerance: float = 1e-12
) -> TrajectoryResult:
    """Build the Exudyn twin of ``scene``, integrate it and return plain arrays.

    ``relative_tolerance``/``absolute_tolerance`` are Exudyn's Newton criteria (residual norm
    relative to the first residual of the step / absolute, mixed units).
    """
    import exudyn as exu

    started = time.perf_counter()
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    body_object, rigid_node, modal_node = _add_exudyn_body(mbs, scene)
    if scene.hinge is not None:
        _add_exudyn_hinge(mbs, scene, body_object)
    sensors = _add_exudyn_sensors(mbs, scene, body_object, rigid_node, modal_node)
    mbs.Assemble()
    settings = exudyn_settings(scene, modified_newton, relative_tolerance, absolute_tolerance)
    setup = time.perf_counter() - started

    started = time.perf_counter()
    solver = exu.MainSolverImplicitSecondOrder()
    success = solver.SolveSystem(mbs, settings)
    integration = time.perf_counter() - started
    if not success:
        raise RuntimeError(f"Exudyn did not finish the run (h={scene.step}): {solver.GetErrorString()}")
    iterations = int(solver.it.newtonStepsCount) if hasattr(solver, "it") else -1

    rigid = np.asarray(mbs.GetSensorStoredData(sensors["rigid"]))
    modal = np.asarray(mbs.GetSensorStoredData(sensors["modal"]))
    reference = np.asarray(mbs.GetNodeParameter(rigid_node, "referenceCoordinates"), dtype=float)
    tracked = np.stack(
        [np.asarray(mbs.GetSensorStoredData(sensors[f"node{k}"]))[:, 1:] for k in range(len(scene.tracked_nodes))],
        axis=1,
    )
    t = rigid[:, 0]
    _check_output_times(t, scene)
    q_rigid = rigid[:, 1:] + reference  # Exudyn stores displacements from the reference
    return TrajectoryResult(
        t,
        q_rigid[:, :3],
        q_rigid[:, 3:7],
        modal[:, 1:],
        tracked,
        setup,
        integration,
        iterations,
        f"exudyn {exu.__version__}",
        exu.__version__,
    )


def _check_output_times(t: NDArray[np.float64], scene: Scene) -> None:
    expected = scene.step * np.arange(scene.n_steps + 1)
    if t.shape != expected.shape or np.abs(t - expected).max() > 1e-9 * scene.t_end:
        raise RuntimeError(
            f"Exudyn sensor output has {len(t)} rows at unexpected times; expected one per step "
            f"({len(expected)} rows); check solution.sensors.writePeriod"
        )


# --------------------------------------------------------------------------------------------
# Our solver on the same scene
# --------------------------------------------------------------------------------------------


def ffrf_system(scene: Scene, exact_gravity: bool = False):
    """Our :class:`ffrf.system.multibody.MultibodySystem` of ``scene`` and its initial state (q0, qd0).

    ``exact_gravity=False`` (default) is Exudyn's simplified gravity moment; True keeps the
    deformation-dependent term (only for sensitivity studies).
    """
    from ffrf.body.euler_parameters import g_bar
    from ffrf.body.flexible_body import FlexibleBody
    from ffrf.body.modal_moments import modal_moments
    from ffrf.system.constraints import GroundPerpendicular, GroundPoint
    from ffrf.system.multibody import MultibodySystem

    body = scene.body
    moments = modal_moments(body.nodes, body.mass, body.basis)
    flexible = FlexibleBody(
        "bar",
        moments,
        stiffness=body.reduced_stiffness,
        damping=scene.beta * body.reduced_stiffness,
        exact_gravity=exact_gravity,
    )
    constraints = ()
    if scene.hinge is not None:
        frame = hinge_frame(scene.hinge.axis)
        centre = body.frame_center
        constraints = (
            GroundPoint(
                bodies=(0,), name="hinge", local=centre, target=np.asarray(scene.position, dtype=float) + centre
            ),
            GroundPerpendicular(
                bodies=(0,), name="hinge axis", vector=frame[:, 2].copy(), normals=np.ascontiguousarray(frame[:, :2].T)
            ),
        )
    system = MultibodySystem(bodies=(flexible,), constraints=constraints, gravity=np.asarray(scene.gravity, float))
    q0 = system.initial_state(positions=[scene.position], rotations=[scene.euler0])
    q0[7:] = scene.initial_zeta()
    qd0 = np.zeros_like(q0)
    qd0[:3] = scene.velocity
    qd0[3:7] = g_bar(q0[3:7]).T @ np.asarray(scene.omega_bar, dtype=float) / 4.0  # G G^T = 4 I
    return system, q0, qd0


def node_positions(body: ReducedBody, nodes: tuple[int, ...], q: NDArray[np.float64]) -> NDArray[np.float64]:
    """World positions (n_times, k, 3) of mesh ``nodes``: R + A(p)(x_i + Psi_i zeta)."""
    from ffrf.body.euler_parameters import rotation_matrix

    q = np.atleast_2d(q)
    out = np.empty((q.shape[0], len(nodes), 3))
    rows = [body.basis[3 * i : 3 * i + 3] for i in nodes]
    for k, qk in enumerate(q):
        a = rotation_matrix(np.ascontiguousarray(qk[3:7]))
        for j, i in enumerate(nodes):
            out[k, j] = qk[:3] + a @ (body.nodes[i] + rows[j] @ qk[7:])
    return out


def run_ffrf(
    scene: Scene, tolerance: float = 1e-12, exact_gravity: bool = False, modified_newton: bool | None = None
) -> TrajectoryResult:
    """Integrate ``scene`` with our generalized-alpha solver (Newton ``tolerance``, see
    :func:`ffrf.solvers.generalized_alpha.generalized_alpha`); ``modified_newton=None`` keeps the
    solver's default."""
    from ffrf.solvers.generalized_alpha import generalized_alpha

    started = time.perf_counter()
    system, q0, qd0 = ffrf_system(scene, exact_gravity)
    setup = time.perf_counter() - started
    options = {} if modified_newton is None else {"modified_newton": modified_newton}
    result = generalized_alpha(
        system, q0, qd0, scene.t_end, scene.step, rho_inf=scene.rho_inf, tolerance=tolerance, **options
    )
    q = result.q
    return TrajectoryResult(
        result.time,
        q[:, :3],
        q[:, 3:7],
        q[:, 7:],
        node_positions(scene.body, scene.tracked_nodes, q),
        setup,
        result.wall_time,
        int(result.newton_iterations.sum()),
        "ffrf" if modified_newton is None else f"ffrf (modified_newton={modified_newton})",
    )
