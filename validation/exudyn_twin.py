r"""The Exudyn twin of any of our multibody systems of reduced flexible bodies.

Given our bodies (nodes, consistent M and K, interface node sets and weights, reduction) and
a :class:`ffrf.system.multibody.MultibodySystem` of :class:`ffrf.system.joints.MarkerJoint` s, the twin has

* per body an ``ObjectFFRFreducedOrder`` (``FEMinterface`` with our nodes, M and K and either
  Exudyn's own Craig-Bampton modes on the same interfaces, :func:`twin_bases`, or ours), with
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

import time
from dataclasses import dataclass, field
from types import SimpleNamespace

import numpy as np
from numpy.typing import NDArray

from ffrf.system.drives import RampedAngle

__all__ = [
    "TwinBody",
    "TwinBasis",
    "ExudynTwin",
    "twin_bases",
    "to_twin_layout",
    "build_twin",
    "add_node_sensor",
    "add_marker_sensor",
    "read_twin",
    "static_settings",
    "sweep_settings",
    "solve_static",
    "joint_key",
    "exudyn_settings",
    "q_from_twin",
]


@dataclass(frozen=True, eq=False)
class TwinBody:
    """What the twin needs of one of our bodies. ``markers``: our interface markers by interface
    name (their points are the interfaces' weighted centres); ``reduction``: our
    :class:`ffrf.reduction.craig_bampton.CraigBamptonBasis`, interfaces in its order."""

    name: str
    fe: object  # .nodes (N, 3), .mass, .stiffness
    interfaces: dict
    markers: dict
    reduction: object


@dataclass(frozen=True)
class TwinBasis:
    """The mode basis of one body in the twin: Exudyn's own HCB (``source="exudyn"``) or ours."""

    matrix: NDArray[np.float64]  # (3N, m)
    fixed_interface_frequencies_hz: NDArray[np.float64]
    source: str
    setup_s: float
    to_ours: NDArray[np.float64]  # (m, m): our modal coordinates of the same displacement field
    from_ours: NDArray[np.float64]


@dataclass
class ExudynTwin:
    """An assembled Exudyn system and the item numbers needed to read it back."""

    sc: object
    mbs: object
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


def _modal_map(mass, source: NDArray, target: NDArray) -> NDArray[np.float64]:
    """Mass-orthogonal projection of span(source) onto target's coordinates, (target^T M target)^-1 target^T M
    source; exact when both span the same space (our and Exudyn's HCB bases do, to 1e-13)."""
    m_target = target.T @ (mass @ target)
    return np.linalg.solve(m_target, target.T @ (mass @ source))


def twin_bases(bodies: list[TwinBody], source: str = "exudyn") -> list[TwinBasis]:
    """Per body: Exudyn's own HCB modes on our nodes, M, K, interface node sets and weights
    (:func:`validation.modes.exudyn_hcb`), or ``source="ffrf"``: our basis as is."""
    from .modes import exudyn_hcb

    if source not in ("exudyn", "ffrf"):
        raise ValueError(f"basis source must be 'exudyn' or 'ffrf', got {source!r}")
    out = []
    for body in bodies:
        ours = np.asarray(body.reduction.basis)
        frequencies_ours = body.reduction.fixed_interface_frequencies_hz
        if source == "ffrf":
            eye = np.eye(ours.shape[1])
            out.append(TwinBasis(ours, frequencies_ours, "ffrf", 0.0, eye, eye))
            continue
        started = time.perf_counter()
        itfs = list(body.interfaces.values())
        basis, frequencies = exudyn_hcb(
            body.fe, [i.nodes for i in itfs], [i.weights for i in itfs], frequencies_ours.size
        )
        elapsed = time.perf_counter() - started
        out.append(
            TwinBasis(
                basis,
                np.sort(frequencies),
                "exudyn",
                elapsed,
                _modal_map(body.fe.mass, basis, ours),
                _modal_map(body.fe.mass, ours, basis),
            )
        )
    return out


def to_twin_layout(system, q: NDArray, bases: list[TwinBasis] | None) -> NDArray[np.float64]:
    """Our coordinates with each body's modal part in the twin's basis."""
    q = np.array(q, dtype=float)
    if bases is None:
        return q
    for k, basis in enumerate(bases):
        block = system.block(k)
        q[..., block.start + 7 : block.stop] = q[..., block.start + 7 : block.stop] @ basis.from_ours.T
    return q


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

    def offset(mbs, t, itemNumber, args):
        during = 0.5 * w * (t - tr / np.pi * esym.sin(np.pi / tr * t))
        after = 0.5 * w * tr + w * (t - tr)
        return [0.0, 0.0, 0.0, 0.0, 0.0, start + esym.IfThenElse(t < tr, during, after)]

    return offset


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
    import exudyn.itemInterface as eii
    from exudyn.FEM import ObjectFFRFreducedOrderInterface

    from ffrf.body.euler_parameters import rotation_matrix
    from ffrf.system.joints import GroundFrame, MarkerJoint

    from .exudyn_ffrf import _exudyn_fem

    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    objects, rigid_nodes, modal_nodes, reference = [], [], [], []
    for k, body in enumerate(bodies):
        block = np.asarray(q0[system.block(k)], dtype=float)
        basis = np.asarray(body.reduction.basis) if bases is None else bases[k].matrix
        fem = _exudyn_fem(
            SimpleNamespace(
                nodes=np.asarray(body.fe.nodes), mass=body.fe.mass, stiffness=body.fe.stiffness, basis=basis
            )
        )
        info = ObjectFFRFreducedOrderInterface(fem).AddObjectFFRFreducedOrder(
            mbs,
            positionRef=[float(v) for v in block[:3]],
            rotationMatrixRef=rotation_matrix(block[3:7]),
            gravity=[float(v) for v in system.gravity],
            stiffnessProportionalDamping=float(beta),
            name=body.name,
        )
        mbs.SetNodeParameter(info["nGenericODE2"], "initialCoordinates", [float(z) for z in block[7:]])
        objects.append(info["oFFRFreducedOrder"])
        rigid_nodes.append(info["nRigidBody"])
        modal_nodes.append(info["nGenericODE2"])
        reference.append(np.asarray(mbs.GetNodeParameter(info["nRigidBody"], "referenceCoordinates"), dtype=float))

    ground = mbs.AddObject(eii.ObjectGround(referencePosition=[0.0, 0.0, 0.0]))
    markers, joints, keep, notes = {}, {}, [], []

    def add_marker(marker, rotation, offset, label):
        if isinstance(marker, GroundFrame):
            ht = exu.HT(rotation=marker.rotation @ rotation, translation=marker.point + marker.rotation @ offset)
            return mbs.AddMarker(eii.MarkerBodyRigid(bodyNumber=ground, localHT=ht, name=label))
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
        return mbs.AddMarker(
            eii.MarkerSuperElementRigid(
                bodyNumber=objects[marker.body],
                meshNodeNumbers=[int(i) for i in itf.nodes],
                weightingFactors=[float(w) for w in itf.weights],
                useAlternativeApproach=True,
                rotationsExponentialMap=2,
                localHT=exu.HT(rotation=np.asarray(rotation, float), translation=np.asarray(translation, float)),
                name=label,
            )
        )

    used_symbolic = False
    out = exu.OutputVariableType
    sensors = {}
    for c in system.constraints:
        if not isinstance(c, MarkerJoint):
            raise TypeError(f"constraint {c.name!r} ({type(c).__name__}) has no Exudyn twin here")
        key = joint_key(c.name)
        m0 = add_marker(c.marker0, c.rotation0, c.offset0, f"{key}:m0")
        m1 = add_marker(c.marker1, c.rotation1, c.offset1, f"{key}:m1")
        markers[key] = (m0, m1)
        joint = mbs.AddObject(
            eii.GenericJoint(markerNumbers=[m0, m1], constrainedAxes=[int(v) for v in c.locked], name=key)
        )
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
            except Exception as error:  # pragma: no cover - reported to the caller
                notes.append(f"{key}: symbolic user function failed ({error!r}); Python function used")
        if function is None:
            function = _drive_function(c.angle, frozen_drive_time, False)
        mbs.SetObjectParameter(joint, "offsetUserFunction", function)
        keep.append(function)
        sensors[f"torque:{key}"] = mbs.AddSensor(
            eii.SensorObject(
                objectNumber=joint, outputVariableType=out.TorqueLocal, storeInternal=True, writeToFile=False
            )
        )
    for k in range(len(bodies)):
        sensors[f"rigid{k}"] = mbs.AddSensor(
            eii.SensorNode(
                nodeNumber=rigid_nodes[k], outputVariableType=out.Coordinates, storeInternal=True, writeToFile=False
            )
        )
        sensors[f"modal{k}"] = mbs.AddSensor(
            eii.SensorNode(
                nodeNumber=modal_nodes[k], outputVariableType=out.Coordinates, storeInternal=True, writeToFile=False
            )
        )
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
    import exudyn as exu
    import exudyn.itemInterface as eii

    twin.sensors[name] = twin.mbs.AddSensor(
        eii.SensorSuperElement(
            bodyNumber=twin.objects[body],
            meshNodeNumber=int(node),
            outputVariableType=exu.OutputVariableType.Position,
            storeInternal=True,
            writeToFile=False,
        )
    )


def add_marker_sensor(twin: ExudynTwin, name: str, marker: int) -> None:
    """World position of an Exudyn marker."""
    import exudyn as exu
    import exudyn.itemInterface as eii

    twin.sensors[name] = twin.mbs.AddSensor(
        eii.SensorMarker(
            markerNumber=marker,
            outputVariableType=exu.OutputVariableType.Position,
            storeInternal=True,
            writeToFile=False,
        )
    )


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


def exudyn_settings(t_end: float, step: float, rho_inf: float, tolerance: float = 1e-10):
    """:func:`validation.exudyn_ffrf.exudyn_settings`: generalized-alpha index 3, fixed steps, full Newton."""
    from .exudyn_ffrf import exudyn_settings as settings

    plan = SimpleNamespace(n_steps=int(round(t_end / step)), t_end=t_end, rho_inf=rho_inf, step=step)
    return settings(plan, False, tolerance, tolerance)


def static_settings(load_steps: int, tolerance: float, duration: float = 1.0, load_factor: bool = True):
    """``SolveStatic`` settings: fixed load steps over ``duration`` of quasi-time (drives turn with
    it), loads ramped with the steps only if ``load_factor``; dense solver; Newton to ``tolerance``."""
    import exudyn as exu

    s = exu.SimulationSettings()
    s.staticSolver.numberOfLoadSteps = load_steps
    s.staticSolver.loadStepDuration = duration
    s.staticSolver.useLoadFactor = load_factor
    s.staticSolver.adaptiveStep = False
    s.staticSolver.newton.relativeTolerance = tolerance
    s.staticSolver.newton.absoluteTolerance = tolerance
    s.staticSolver.newton.maxIterations = 50
    s.staticSolver.verboseMode = 0
    s.linearSolver.solverType = exu.LinearSolverType.EXUdense
    s.solution.file.write = False
    return s


def sweep_settings(times: NDArray, tolerance: float):
    """``SolveStatic`` settings for equilibria at equally spaced ``times`` from 0: one load step per
    interval, the drives turned by the quasi-time, loads always fully on (``useLoadFactor=False``)."""
    return static_settings(len(times) - 1, tolerance, duration=float(times[-1]), load_factor=False)


def solve_static(twin: ExudynTwin, settings) -> None:
    import exudyn as exu

    solver = exu.MainSolverStatic()
    if not solver.SolveSystem(twin.mbs, settings):
        raise RuntimeError(f"Exudyn SolveStatic failed: {solver.GetErrorString()}")
