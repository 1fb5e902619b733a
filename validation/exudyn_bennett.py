r"""The Exudyn twin of the flexible Bennett scene and its runs: dynamic, static, Exudyn's own
assembly and the quasi-static sweep, each returning a :class:`validation.twin_run.TwinRun` with the sensors of our
runs (:mod:`validation.bennett_trajectory`).

The twin is built from a :class:`ffrf.paper.bennett_scene.BennettScene` only (identical input in both
solvers):

* four ``ObjectFFRFreducedOrder`` bodies (``FEMinterface`` with our nodes, consistent M, K and
  **our** Craig-Bampton basis, :func:`validation.exudyn_items.add_ffrf_body`), each with
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

The twin applies a joint offset in the body frame, as our default ``joint_offsets="body"``, and
its joint reactions use Exudyn's marker rotation Jacobian; both conventions are measured and
reproduced in our solver in :mod:`validation.exudyn_conventions`.

Measured on the coarse PLA scene (h = 6 mm, 2 modes, from ``q_start``, h = 1e-3, 0.2 s):
with Exudyn's Jacobian: coupler 1e-16 m, torque 1e-9 relative; production system (our exact
Jacobian): coupler 2e-9 m (4e-5 of its motion), torque 2.4e-6 relative; marker-frame offsets:
coupler 1.2e-6 m (3 %), torque 4 % (``tests/test_validation/test_bennett_vs_exudyn.py``).

``exudyn`` is imported lazily.
"""

from __future__ import annotations

import time

import numpy as np
from numpy.typing import NDArray

from .bennett_trajectory import TRACKED
from .exudyn_solvers import (
    check_output_times,
    dynamic_settings,
    solve_dynamic,
    solve_static,
    static_settings,
    sweep_settings,
)
from .exudyn_twin import ExudynTwin, add_marker_sensor, add_node_sensor, build_twin, q_from_twin, read_twin
from .twin_bases import TwinBasis, to_twin_layout
from .twin_run import TwinRun, run_metadata, twin_run

__all__ = [
    "bennett_bodies",
    "build_exudyn_twin",
    "run_exudyn_bennett",
    "static_exudyn_bennett",
    "assemble_exudyn_bennett",
    "quasi_static_exudyn_bennett",
]


def bennett_bodies(scene) -> list:
    """The scene's links as :class:`validation.twin_bases.TwinBody` s."""
    from .twin_bases import TwinBody

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


def _read_trajectory(
    twin: ExudynTwin,
    scene,
    q0: NDArray,
    expected_times: NDArray,
    what: str,
    setup: float,
    integration: float,
    iterations: int,
    start_torque: float | None = None,
) -> TwinRun:
    """The twin's run: rows of every Bennett sensor (:mod:`validation.bennett_trajectory`) of a run of ``twin``, ``q``
    in our basis, the drive multiplier with the dynamic sign. ``start_torque``: a static sweep's, whose multipliers
    have the opposite sign of Exudyn's dynamic ones (and ours) and whose first row, the start state given by its
    equilibrium at t = 0, the sweep never computed."""
    import exudyn as exu

    data = read_twin(twin, scene.system, q0)
    check_output_times(data["time"], expected_times, what)
    torque = data["torque"][:, 2]
    solver = f"exudyn {exu.__version__}" + (" (symbolic drive)" if twin.symbolic else " (Python drive)")
    if start_torque is not None:
        torque = -torque
        torque[0] = start_torque
        solver += ", SolveStatic"
    sensors = {
        "drive_angle": np.array([scene.drive_angle(float(t)) for t in data["time"]]),
        "driving_torque": torque,
        "coupler_point": 0.5 * (data["coupler_a"] + data["coupler_b"]),
    }
    sensors |= {name: data[f"node{i}"] for i, name in enumerate(TRACKED)}
    metadata = run_metadata("exudyn", solver, setup, integration, iterations)
    metadata |= {"symbolic": twin.symbolic, "notes": twin.notes}
    return twin_run(data["time"], data["q"], sensors, metadata)


def run_exudyn_bennett(
    scene,
    q0: NDArray,
    t_end: float,
    step: float = 1e-3,
    rho_inf: float = 0.9,
    tolerance: float = 1e-10,
    symbolic: bool = True,
    bases: list[TwinBasis] | None = None,
) -> TwinRun:
    """Build the twin at ``q0`` (at rest; modal part in ``bases``), integrate to ``t_end`` with
    generalized-alpha and read every step back (``q`` in our basis)."""
    started = time.perf_counter()
    twin = build_exudyn_twin(scene, q0, symbolic=symbolic, bases=bases)
    settings = dynamic_settings(t_end, step, rho_inf, tolerance, tolerance)
    setup = time.perf_counter() - started
    integration, iterations = solve_dynamic(twin.mbs, settings, "the Bennett run")
    expected = step * np.arange(int(round(t_end / step)) + 1)
    return _read_trajectory(twin, scene, q0, expected, "dynamic", setup, integration, iterations)


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
    solve_static(twin.mbs, static_settings(load_steps, tolerance))
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
    """Exudyn's own static assembly at t = 0, as :func:`ffrf.paper.bennett_scene.assemble`: gravity from
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
) -> TwinRun:
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
    solve_static(twin.mbs, settings)
    integration = time.perf_counter() - started
    return _read_trajectory(twin, scene, q0, times, "static sweep", setup, integration, -1, start_torque=start[1])
