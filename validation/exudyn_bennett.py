r"""The Exudyn twin of the flexible Bennett scene, its runner, and the comparison with our solver.

The twin is built from a :class:`ffrf.scenes.bennett_scene.BennettScene` only (identical input in both
solvers):

* four ``ObjectFFRFreducedOrder`` bodies (``FEMinterface`` with our nodes, consistent M, K and
  **our** Craig-Bampton basis, via :func:`validation.exudyn_ffrf._exudyn_fem`), each with
  ``positionRef``/``rotationMatrixRef`` from the start state ``q0`` (absolute, our layout) and
  its modal coordinates as initial values; gravity through ``LoadMassProportional`` (our
  ``exact_gravity=False``) and ``stiffnessProportionalDamping = beta``;
* one ``MarkerSuperElementRigid`` per joint side on the interface's nodes with our weights
  (``useAlternativeApproach=True``, exponential map), ``localHT`` = (our ``rotation0/1``,
  our ``offset0/1``); a ground ``MarkerBodyRigid`` for the clamp;
* the clamp as ``GenericJoint`` (all six axes), joints 0..2 as ``GenericJoint([1,1,1,1,1,0])``,
  joint 3 as ``GenericJoint`` (all six) whose ``offsetUserFunction`` turns J0 about its z-axis by
  the prescribed angle ``scene.drive_angle(t)`` (a *symbolic* user function; the joint frames
  are defined in the FE reference pose, so the offset at t = 0 is the start angle).

**Offset convention (measured, see ``probe_marker_offset``).** Exudyn applies the translation
of a ``MarkerSuperElementRigid``'s ``localHT`` in the *body* frame:
``p = R + A (o + sum w_i (x_i + u_i))``. Our scenes do the same by default
(``joint_offsets="body"``, :func:`ffrf.system.markers.attach_joint_point`), so the twin's marker
translation is our marker point minus the interface's weighted centre and the models are
equivalent. With ``joint_offsets="marker"`` our joint point is ``r_M + A exp(theta_M) o``,
which Exudyn cannot express; the twin then applies ``o`` in the body frame and records a note
(``ExudynTwin.notes``): the two differ by ``A (exp(theta_M) - I) o`` (``|o|`` = 8.5 mm).
:func:`exudyn_convention_system` also moves any remaining joint offsets into the marker point.

**Marker rotation Jacobian (measured).** Exudyn's joint Jacobian uses the marker angular
velocity ``A (omega_bar + T(theta) theta_dot)``; the exact derivative of its own orientation
``A exp(theta~)`` is ``A (omega_bar + exp(theta~) T(theta) theta_dot)``. So Exudyn's reaction
``C_q^T lambda`` is not the gradient of its constraint equations when a non-frame interface
rotates elastically (O(|theta|) relative in the modal columns of the rotation rows; |theta| up
to 3e-4 here). ``exudyn_convention_system(..., exudyn_jacobian=True)`` reproduces it in our
solver (a :class:`ffrf.system.joints.MarkerJoint` subclass, same equations); then both solvers agree
to round-off.

Measured on the coarse PLA scene (h = 6 mm, 2 modes, from ``q_start``, h = 1e-3, 0.2 s):
with Exudyn's Jacobian: coupler 1e-16 m, torque 1e-9 relative; production system (our exact
Jacobian): coupler 2e-9 m (4e-5 of its motion), torque 2.4e-6 relative; marker-frame offsets:
coupler 1.2e-6 m (3 %), torque 4 % (``bench/bench_bennett_vs_exudyn.py`` and the tests).

``exudyn`` is imported lazily.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass, field
from types import SimpleNamespace

import numpy as np
from numpy.typing import NDArray

from .exudyn_twin import (
    ExudynTwin,
    TwinBasis,
    exudyn_settings,
    q_from_twin,
    solve_static,
    static_settings,
    sweep_settings,
    to_twin_layout,
)

__all__ = [
    "BennettTrajectory",
    "bennett_bodies",
    "exudyn_convention_system",
    "build_exudyn_twin",
    "run_exudyn_bennett",
    "run_ffrf_bennett",
    "static_exudyn_bennett",
    "assemble_exudyn_bennett",
    "quasi_static_exudyn_bennett",
    "static_ffrf_bennett",
    "compare",
    "probe_marker_offset",
    "exudyn_settings",
    "system_points",
]


# --------------------------------------------------------------------------------------------
# Results
# --------------------------------------------------------------------------------------------


@dataclass
class BennettTrajectory:
    """Time histories (rows = output times, t = 0 included) of one solver on the Bennett scene.

    ``q``: coordinates in our layout (absolute; Euler parameters with our sign); ``coupler``:
    (n, 3) mean of link 2's two joint points; ``tracked``: (n, 9, 3) links 1..3, three nodes
    each; ``torque``: (n,) multiplier of the drive's x0'.y1 equation (dynamic sign: the
    constraint force is -C_q^T lambda); ``zeta``: list of (n, m_k) per link.
    """

    time: NDArray[np.float64]
    q: NDArray[np.float64]
    coupler: NDArray[np.float64]
    tracked: NDArray[np.float64]
    torque: NDArray[np.float64]
    zeta: list
    setup_time: float
    integration_time: float
    newton_iterations: int
    solver: str
    extra: dict = field(default_factory=dict)


# --------------------------------------------------------------------------------------------
# Our system with Exudyn's offset convention
# --------------------------------------------------------------------------------------------


def _exudyn_joint_class():
    """:class:`ffrf.system.joints.MarkerJoint` with Exudyn's marker rotation Jacobian (see :func:`exudyn_convention_system`)."""
    from ffrf.body.euler_parameters import rotation_matrix
    from ffrf.system.joints import MarkerJoint, exp_so3_tangent, joint_side
    from ffrf.system.markers import _skew, exp_so3

    def axis_correction(marker, q, rotation):
        """Exudyn's minus the exact d(axis_k)/d zeta, k = 0..2: -A[(E w)~ - E w~] T Theta (3, 3, m)."""
        a_body = rotation_matrix(np.ascontiguousarray(q[3:7]))
        theta = marker.rotation_modes.astype(q.dtype) @ q[7:]
        turn, tangent = exp_so3(theta), exp_so3_tangent(theta)
        out = []
        for k in range(3):
            w = rotation[:, k].astype(q.dtype)
            out.append(-(a_body @ (_skew(turn @ w) - turn @ _skew(w)) @ tangent) @ marker.rotation_modes)
        return out

    class ExudynMarkerJoint(MarkerJoint):
        """Constraint equations as :class:`MarkerJoint`; in the Jacobian the modal columns of the
        rotation rows use Exudyn's marker angular velocity A(omega_bar + T theta_dot) instead of the
        exact A(omega_bar + exp(theta~) T theta_dot), so C_q^T lambda is Exudyn's reaction."""

        def jacobian(self, blocks, t):
            if not all(self.locked[:3]):
                raise NotImplementedError("Exudyn-Jacobian joints are implemented for locked translations only")
            rows = super().jacobian(blocks, t)
            q0, q1 = self._sides(blocks)
            ground = q0 is None
            _, axes0, _, _ = joint_side(self.marker0, q0, self.rotation0, self.offset0)
            _, axes1, _, _ = joint_side(self.marker1, q1, self.rotation1, self.offset1)
            c1 = axis_correction(self.marker1, q1, self.rotation1) if self.marker1.rotation_modes.shape[1] else None
            c0 = (
                axis_correction(self.marker0, q0, self.rotation0)
                if not ground and self.marker0.rotation_modes.shape[1]
                else None
            )
            rows0, rows1 = (None, rows[0]) if ground else (rows[0], rows[1])
            row = 3
            pairs = (
                [(2, 1, False)] * self.locked[3] + [(2, 0, False)] * self.locked[4] + [(0, 1, True)] * self.locked[5]
            )
            for k0, k1, turned in pairs:
                if turned and self.angle is not None:
                    phi = self.angle(t)
                    a0 = np.cos(phi) * axes0[:, 0] + np.sin(phi) * axes0[:, 1]
                    d0 = None if c0 is None else np.cos(phi) * c0[0] + np.sin(phi) * c0[1]
                else:
                    a0 = axes0[:, k0]
                    d0 = None if c0 is None else c0[k0]
                if c1 is not None:
                    rows1[row, 7:] += a0 @ c1[k1]
                if d0 is not None:
                    rows0[row, 7:] += axes1[:, k1] @ d0
                row += 1
            return rows

    return ExudynMarkerJoint


def exudyn_convention_system(system, exudyn_jacobian: bool = True):
    """``system`` with Exudyn's conventions: every joint offset moved into the marker point (body
    frame), as Exudyn's ``MarkerSuperElementRigid`` offset/``localHT`` translation
    (p = R + A(o + x_bar + P zeta)), and, with ``exudyn_jacobian``, Exudyn's marker rotation
    Jacobian (angular velocity A(omega_bar + T theta_dot), without the factor exp(theta~) in front
    of T that the exact derivative of its orientation A exp(theta~) has) in the joints' C_q.
    The constraint equations are ours either way."""
    from ffrf.system.joints import GroundFrame, MarkerJoint
    from ffrf.system.multibody import MultibodySystem

    joint_class = _exudyn_joint_class() if exudyn_jacobian else None
    constraints = []
    for c in system.constraints:
        if isinstance(c, MarkerJoint):
            changes = {}
            for side in (0, 1):
                marker, offset = getattr(c, f"marker{side}"), getattr(c, f"offset{side}")
                if isinstance(marker, GroundFrame):
                    changes[f"marker{side}"] = dataclasses.replace(
                        marker, point=marker.point + marker.rotation @ offset
                    )
                else:
                    changes[f"marker{side}"] = dataclasses.replace(marker, point=marker.point + offset)
                changes[f"offset{side}"] = np.zeros(3)
            c = dataclasses.replace(c, **changes)
            if joint_class is not None:
                c = joint_class(**{f.name: getattr(c, f.name) for f in dataclasses.fields(c)})
        constraints.append(c)
    return MultibodySystem(system.bodies, tuple(constraints), gravity=system.gravity)


def _joints(system):
    from ffrf.system.joints import MarkerJoint

    return {c.name: c for c in system.constraints if isinstance(c, MarkerJoint)}


def system_points(scene, system, q: NDArray) -> tuple[NDArray, NDArray]:
    """Coupler point (mean of link 2's joint points, as :func:`ffrf.scenes.bennett_run.evaluate_sensors`)
    and the tracked nodes of links 1..3 for coordinate rows ``q``, using ``system``'s joints."""
    from ffrf.body.flexible_body import node_positions
    from ffrf.system.joints import joint_pose

    joints = _joints(system)
    j1, j2 = joints["joint1"], joints["joint2"]
    q = np.atleast_2d(q)
    coupler = np.empty((len(q), 3))
    tracked = np.empty((len(q), 9, 3))
    for row, qq in enumerate(q):
        p_far, _ = joint_pose(j1.marker1, qq[system.block(j1.bodies[1])], j1.rotation1, j1.offset1)
        p_near, _ = joint_pose(j2.marker0, qq[system.block(j2.bodies[0])], j2.rotation0, j2.offset0)
        coupler[row] = 0.5 * (p_far + p_near)
        for a, link in enumerate(scene.links[1:]):
            nodes = scene.tracked_nodes[link.index]
            tracked[row, 3 * a : 3 * a + len(nodes)] = node_positions(
                qq[system.block(link.index)], link.fe.nodes, link.reduction.basis, nodes
            )
    return coupler, tracked


def _zeta(system, q) -> list:
    return [q[:, system.block(k)][:, 7:] for k in range(len(system.bodies))]


# --------------------------------------------------------------------------------------------
# Exudyn twin
# --------------------------------------------------------------------------------------------


def bennett_bodies(scene) -> list:
    """The scene's links as :class:`validation.exudyn_twin.TwinBody` s."""
    from .exudyn_twin import TwinBody

    return [
        TwinBody(f"link{link.index}", link.fe, link.interfaces, link.markers, link.reduction) for link in scene.links
    ]


def build_exudyn_twin(
    scene,
    q0: NDArray,
    symbolic: bool = True,
    frozen_drive_time: float | None = None,
    system=None,
    bases: list[TwinBasis] | None = None,
) -> ExudynTwin:
    """The Exudyn twin (:func:`validation.exudyn_twin.build_twin`) of ``system`` (default
    ``scene.system``) starting at ``q0``, with the Bennett sensors: the nine tracked nodes
    (``node0..8``), link 2's two joint points (``coupler_a/b``) and the drive's ``TorqueLocal``."""
    from .exudyn_twin import add_marker_sensor, add_node_sensor, build_twin

    system = scene.system if system is None else system
    twin = build_twin(
        bennett_bodies(scene), system, q0, float(scene.settings["beta"]), symbolic, frozen_drive_time, bases
    )
    for a, link in enumerate(scene.links[1:]):
        for j, node in enumerate(scene.tracked_nodes[link.index]):
            add_node_sensor(twin, f"node{3 * a + j}", link.index, node)
    # link 2 is marker 1 of joint1 and marker 0 of joint2
    add_marker_sensor(twin, "coupler_a", twin.markers["joint1"][1])
    add_marker_sensor(twin, "coupler_b", twin.markers["joint2"][0])
    twin.sensors["torque"] = twin.sensors["torque:joint3"]
    twin.mbs.Assemble()
    return twin


def _read_twin(twin: ExudynTwin, scene, q0: NDArray) -> dict:
    """Rows of every Bennett sensor: q (our basis), twin q, coupler, tracked nodes, drive multiplier (dynamic sign)."""
    from .exudyn_twin import read_twin

    data = read_twin(twin, scene.system, q0)
    return {
        "time": data["time"],
        "q": data["q"],
        "twin_q": data["twin_q"],
        "tracked": np.stack([data[f"node{i}"] for i in range(9)], axis=1),
        "coupler": 0.5 * (data["coupler_a"] + data["coupler_b"]),
        "torque": data["torque"][:, 2],
    }


def _check_times(times: NDArray, expected: NDArray, what: str) -> None:
    if times.shape != expected.shape or np.abs(times - expected).max() > 1e-9 * max(1.0, expected[-1]):
        raise RuntimeError(f"Exudyn {what} output has {len(times)} rows, expected one per step ({len(expected)})")


def _label(twin: ExudynTwin) -> str:
    import exudyn as exu

    return f"exudyn {exu.__version__}" + (" (symbolic drive)" if twin.symbolic else " (Python drive)")


def run_exudyn_bennett(
    scene,
    q0: NDArray,
    t_end: float,
    step: float = 1e-3,
    rho_inf: float = 0.9,
    tolerance: float = 1e-10,
    symbolic: bool = True,
    bases: list[TwinBasis] | None = None,
) -> BennettTrajectory:
    """Build the twin at ``q0`` (at rest; modal part in ``bases``), integrate to ``t_end`` with
    generalized-alpha and read every step back (``q`` in our basis)."""
    import exudyn as exu

    started = time.perf_counter()
    twin = build_exudyn_twin(scene, q0, symbolic=symbolic, bases=bases)
    settings = exudyn_settings(t_end, step, rho_inf, tolerance)
    setup = time.perf_counter() - started
    started = time.perf_counter()
    solver = exu.MainSolverImplicitSecondOrder()
    success = solver.SolveSystem(twin.mbs, settings)
    integration = time.perf_counter() - started
    if not success:
        raise RuntimeError(f"Exudyn did not finish the Bennett run: {solver.GetErrorString()}")
    out = _read_twin(twin, scene, q0)
    _check_times(out["time"], step * np.arange(int(round(t_end / step)) + 1), "dynamic")
    iterations = int(solver.it.newtonStepsCount) if hasattr(solver, "it") else -1
    return BennettTrajectory(
        out["time"],
        out["q"],
        out["coupler"],
        out["tracked"],
        out["torque"],
        _zeta(scene.system, out["q"]),
        setup,
        integration,
        iterations,
        _label(twin),
        {"symbolic": twin.symbolic, "twin_q": out["twin_q"], "notes": twin.notes},
    )


def run_ffrf_bennett(
    scene,
    system,
    q0: NDArray,
    t_end: float,
    step: float = 1e-3,
    rho_inf: float = 0.9,
    tolerance: float = 1e-12,
    label: str = "ffrf",
) -> BennettTrajectory:
    """Our generalized-alpha on ``system`` (``scene.system`` or :func:`exudyn_convention_system`) from ``q0`` at rest."""
    from ffrf.solvers.generalized_alpha import generalized_alpha

    result = generalized_alpha(
        system, np.asarray(q0, float), np.zeros_like(q0), t_end, step, rho_inf=rho_inf, tolerance=tolerance
    )
    coupler, tracked = system_points(scene, system, result.q)
    return BennettTrajectory(
        result.time,
        result.q,
        coupler,
        tracked,
        result.multipliers[:, -1],
        _zeta(system, result.q),
        0.0,
        result.wall_time,
        int(result.newton_iterations.sum()),
        label,
    )


# --------------------------------------------------------------------------------------------
# Statics
# --------------------------------------------------------------------------------------------


def static_exudyn_bennett(
    scene,
    q0: NDArray,
    t: float = 0.0,
    load_steps: int = 2,
    tolerance: float = 1e-10,
    system=None,
    bases: list[TwinBasis] | None = None,
):
    """Exudyn ``SolveStatic`` of the twin of ``system`` from ``q0`` with the drive frozen at ``t``
    (gravity in ``load_steps``). Returns (q (our basis), drive multiplier with *our* sign (Exudyn's
    static lambda is flipped), coupler, tracked, q in the twin's basis)."""
    import exudyn as exu

    twin = build_exudyn_twin(scene, q0, symbolic=False, frozen_drive_time=t, system=system, bases=bases)
    solve_static(twin, static_settings(load_steps, tolerance))
    mbs = twin.mbs
    out = exu.OutputVariableType
    n = len(scene.links)
    rigid = [np.atleast_2d(mbs.GetNodeOutput(twin.rigid_nodes[k], out.Coordinates)) for k in range(n)]
    modal = [np.atleast_2d(mbs.GetNodeOutput(twin.modal_nodes[k], out.Coordinates)) for k in range(n)]
    q = q_from_twin(twin, scene.system, q0, rigid, modal)[0]
    twin_q = q_from_twin(twin, scene.system, q0, rigid, modal, our_basis=False)[0]
    torque = -float(np.asarray(mbs.GetObjectOutput(twin.joints["joint3"], out.TorqueLocal))[2])
    ca = np.asarray(mbs.GetMarkerOutput(twin.markers["joint1"][1], out.Position))
    cb = np.asarray(mbs.GetMarkerOutput(twin.markers["joint2"][0], out.Position))
    tracked = np.stack([np.asarray(mbs.GetSensorValues(twin.sensors[f"node{i}"])) for i in range(9)])
    return q, torque, 0.5 * (ca + cb), tracked, twin_q


def assemble_exudyn_bennett(
    scene, bases: list[TwinBasis] | None = None, steps: int | None = None, tolerance: float = 1e-10
):
    """Exudyn's own static assembly at t = 0, as :func:`ffrf.scenes.bennett_scene.assemble`: gravity from
    ``scene.q_start``, then the misalignment in ``steps`` increments, each a new twin of
    ``scene.with_misalignment(k / steps)`` started from the previous equilibrium. Returns the
    static result of :func:`static_exudyn_bennett` at full misalignment."""
    misalignment = abs(scene.settings["alpha3_deg"] - 90.0)
    if steps is None:
        steps = max(1, int(np.ceil(4 * misalignment))) if misalignment > 1e-12 else 1
    result = static_exudyn_bennett(
        scene,
        to_twin_layout(scene.system, scene.q_start, bases),
        0.0,
        2,
        tolerance,
        scene.with_misalignment(0.0) if misalignment > 1e-12 else scene.system,
        bases,
    )
    if misalignment > 1e-12:
        for k in range(1, steps + 1):
            result = static_exudyn_bennett(
                scene, result[4], 0.0, 1, tolerance, scene.with_misalignment(k / steps), bases
            )
    return result


def quasi_static_exudyn_bennett(
    scene, start: tuple, times: NDArray, tolerance: float = 1e-10, bases: list[TwinBasis] | None = None
) -> BennettTrajectory:
    """Static equilibria at equally spaced ``times`` (from 0) with one ``SolveStatic``: the load
    steps' quasi-time turns the drive (``useLoadFactor=False``: gravity is always on).
    ``start``: the equilibrium at t = 0 (:func:`assemble_exudyn_bennett`), the first row."""
    q0 = start[4]
    times = np.asarray(times, dtype=float)
    if abs(times[0]) > 0 or np.abs(np.diff(times) - times[1] + times[0]).max() > 1e-9 * times[-1]:
        raise ValueError("times must start at 0 and be equally spaced (Exudyn's load steps)")
    started = time.perf_counter()
    twin = build_exudyn_twin(scene, q0, symbolic=True, bases=bases)
    settings = sweep_settings(times, tolerance)
    setup = time.perf_counter() - started
    started = time.perf_counter()
    solve_static(twin, settings)
    integration = time.perf_counter() - started
    out = _read_twin(twin, scene, q0)
    _check_times(out["time"], times, "static sweep")
    # Exudyn's static multipliers have the opposite sign of its dynamic ones (and ours); the
    # first row is the start state, whose multipliers the sweep never computed.
    torque = -out["torque"]
    torque[0] = start[1]
    return BennettTrajectory(
        out["time"],
        out["q"],
        out["coupler"],
        out["tracked"],
        torque,
        _zeta(scene.system, out["q"]),
        setup,
        integration,
        -1,
        _label(twin) + ", SolveStatic",
        {"symbolic": twin.symbolic, "twin_q": out["twin_q"], "notes": twin.notes},
    )


def static_ffrf_bennett(scene, system, q0: NDArray, t: float = 0.0, load_steps: int = 2, tolerance: float = 1e-12):
    """Our static equilibrium of ``system`` from ``q0``: (q, drive multiplier, coupler, tracked)."""
    from ffrf.solvers.static_solver import static_equilibrium

    solution = static_equilibrium(system, np.asarray(q0, float), t=t, load_steps=load_steps, tolerance=tolerance)
    coupler, tracked = system_points(scene, system, solution.q)
    return solution.q, float(solution.multipliers[-1]), coupler[0], tracked[0]


# --------------------------------------------------------------------------------------------
# Comparison
# --------------------------------------------------------------------------------------------


def compare(a: BennettTrajectory, b: BennettTrajectory, elastic: BennettTrajectory | None = None) -> dict[str, float]:
    """Max differences between two runs (same output times). ``elastic``: a run whose coupler
    motion away from its start measures the elastic deviation scale (default ``b``)."""
    assert a.time.shape == b.time.shape and np.abs(a.time - b.time).max() < 1e-9
    ref = b if elastic is None else elastic
    out = {
        "coupler_m": float(np.abs(a.coupler - b.coupler).max()),
        "tracked_m": float(np.abs(a.tracked - b.tracked).max()),
        "zeta": float(max(np.abs(za - zb).max() for za, zb in zip(a.zeta, b.zeta))),
        "zeta_scale": float(max(np.abs(zb).max() for zb in b.zeta)),
        "torque_Nm": float(np.abs(a.torque - b.torque).max()),
        "torque_scale_Nm": float(np.abs(b.torque).max()),
        "coupler_motion_m": float(np.linalg.norm(ref.coupler - ref.coupler[0], axis=1).max()),
        "tracked_motion_m": float(np.linalg.norm(ref.tracked - ref.tracked[0], axis=2).max()),
    }
    out["torque_relative"] = out["torque_Nm"] / max(out["torque_scale_Nm"], 1e-300)
    out["zeta_relative"] = out["zeta"] / max(out["zeta_scale"], 1e-300)
    out["coupler_relative_to_motion"] = out["coupler_m"] / max(out["coupler_motion_m"], 1e-300)
    return out


def probe_marker_offset(
    scene, link_index: int = 1, interface: str | None = None, zeta_scale: float = 0.03, offset=(0.01, -0.02, 0.005)
) -> dict[str, float]:
    """Where Exudyn puts a ``MarkerSuperElementRigid``'s ``localHT`` translation on a deformed body:
    distances of its marker position from R + A(x_bar + P zeta + o) (body frame) and from
    r_M + A exp(theta) o (marker frame, ours), and its orientation error against A exp(theta) R."""
    import exudyn as exu
    import exudyn.itemInterface as eii
    from exudyn.FEM import ObjectFFRFreducedOrderInterface

    from ffrf.body.euler_parameters import rotation_matrix
    from ffrf.system.markers import exp_so3

    from .exudyn_ffrf import _exudyn_fem

    link = scene.links[link_index]
    name = interface or list(link.interfaces)[-1]
    block = scene.q_start[scene.system.block(link_index)]
    a = rotation_matrix(block[3:7])
    m = link.reduction.basis.shape[1]
    zeta = zeta_scale * np.array([(-1.0) ** k * (k + 1) for k in range(m)]) / m
    body = SimpleNamespace(
        nodes=np.asarray(link.fe.nodes),
        mass=link.fe.mass,
        stiffness=link.fe.stiffness,
        basis=np.asarray(link.reduction.basis),
    )
    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    info = ObjectFFRFreducedOrderInterface(_exudyn_fem(body)).AddObjectFFRFreducedOrder(
        mbs, positionRef=list(block[:3]), rotationMatrixRef=a
    )
    mbs.SetNodeParameter(info["nGenericODE2"], "initialCoordinates", [float(z) for z in zeta])
    itf = link.interfaces[name]
    turn = rotation_matrix(np.array([np.cos(0.3), np.sin(0.3), 0.0, 0.0]))
    o = np.asarray(offset, float)
    marker = mbs.AddMarker(
        eii.MarkerSuperElementRigid(
            bodyNumber=info["oFFRFreducedOrder"],
            meshNodeNumbers=[int(i) for i in itf.nodes],
            weightingFactors=[float(w) for w in itf.weights],
            useAlternativeApproach=True,
            localHT=exu.HT(rotation=turn, translation=o),
        )
    )
    mbs.Assemble()
    out = exu.OutputVariableType
    position = np.asarray(mbs.GetMarkerOutput(marker, out.Position))
    rotation = np.asarray(mbs.GetMarkerOutput(marker, out.RotationMatrix)).reshape(3, 3)
    ours = link.markers[name]
    q = np.r_[block[:7], zeta]
    theta = ours.rotation_vector(q)
    return {
        "theta_norm": float(np.linalg.norm(theta)),
        "body_frame_distance": float(np.linalg.norm(position - (ours.position(q) + a @ o))),
        "marker_frame_distance": float(np.linalg.norm(position - (ours.position(q) + a @ exp_so3(theta) @ o))),
        "orientation_error": float(np.abs(rotation - a @ exp_so3(theta) @ turn).max()),
    }
