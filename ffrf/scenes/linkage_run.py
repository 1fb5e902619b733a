r"""Run a linkage scene (the paper's Bennett or any single loop) quasi-statically or dynamically, evaluate
its sensors, write results.

Sensors (names as in the project's issues): ``drive_angle`` (the driven joint's prescribed angle, rad;
for the Bennett linkage link 3 about h3 relative to the base), ``driving_torque`` (N m, applied to the
driven joint's side 1 about its axis), ``coupler_point`` (mean of the tool link's two joint points, m;
link 2 of the Bennett linkage), ``joint_angles`` (the n relative rotations about the joint axes, rad),
``link{k}_node{j}`` (three tracked surface nodes of every moving link, m), ``energy_kinetic``,
``energy_strain``, ``energy_potential`` (J) and ``constraint_residual`` (largest ``|g|``), ``joint_reactions``
(rows x (n + 1) x 6: clamp, joints 0..n-1; force and torque on each joint's side 1 in its joint frame 0,
N and N m, :mod:`ffrf.system.reactions`; names in the metadata's ``joint_reaction_names``). The ideal
coupler point at the same drive angle comes from the scene's rigid nominal loop
(:meth:`ffrf.scenes.linkage_scene.LinkageScene.ideal_coupler_points`; the motion polynomial for the
paper's Bennett), giving ``coupler_deviation`` (same drive angle) and ``coupler_distance_to_path``
(closest point of the exact ideal curve, :func:`ffrf.output.path_distance.distance_to_curve`, Eq. (C1)).

An energy balance closes the books: the drive's work against the changes of kinetic,
gravity and strain energy plus the damping dissipation (``energy_balance_residual``).
A run is a :class:`ffrf.output.result.Result` (metadata: scene settings, versions, timings, summary, and under
``assembly`` the stress state of the assembled links, :mod:`ffrf.output.assembly_stress`); its ``save`` writes
``DIR/results.npz`` (``time`` and one array per sensor, SI units), ``DIR/metadata.json`` and the figures. Users
call it through the facade, :func:`ffrf.load` ``(scene).run()`` (:mod:`ffrf.model`); studies call it directly.
"""

from __future__ import annotations

import logging
import platform
import time as wallclock
from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import NDArray

from ffrf.errors import Interrupted, NewtonDivergence, StaticDivergence
from ffrf.output.assembly_stress import scene_assembly_stress
from ffrf.output.path_distance import distance_to_curve
from ffrf.output.result import Result
from ffrf.output.sensors import path_sensors, scene_sensors
from ffrf.output.verification import verify_run, weight_energy
from ffrf.reduction.craig_bampton import CraigBamptonBasis
from ffrf.scenes.assembly import assemble, dynamic_step, quasi_static_step
from ffrf.scenes.linkage_scene import LinkageScene
from ffrf.scenes.linkage_steps import (
    dynamic_error_tolerance,
    dynamic_step_limit,
    near_dead_point,
    near_dead_poses,
    quasi_static_path_step,
)
from ffrf.solvers.common import PathJump
from ffrf.solvers.generalized_alpha import replayed_limit, step_parts
from ffrf.solvers.simulate import MODES, Run, simulate
from ffrf.solvers.snap_through import SnapThrough, run_critical_pose, snap_summary
from ffrf.solvers.stability import check_judged_at_equilibria, stability_along, stability_summary
from ffrf.system.joints import MarkerJoint

__all__ = [
    "run_linkage",
    "evaluate_sensors",
    "PATH_SENSORS",
    "SENSOR_SETS",
    "choose_mode",
    "inertia_number",
]

log = logging.getLogger(__name__)


#: What :func:`run_linkage` evaluates: every sensor, or only the coupler's path and the drive's (:data:`PATH_SENSORS`).
SENSOR_SETS = ("all", "path")
#: The sensors of ``sensors="path"``: what :meth:`ffrf.output.result.Result.summary` reads of the path (a study's row).
PATH_SENSORS = (
    "drive_angle",
    "driving_torque",
    "coupler_point",
    "coupler_ideal",
    "coupler_deviation",
    "coupler_distance_to_path",
)
#: Largest inertia number (:func:`inertia_number`) for which quasi-static is chosen.
INERTIA_LIMIT = 0.01


def inertia_number(scene: LinkageScene) -> float:
    """Inertial against gravity forces of the moving links: ``max(omega^2, alpha_ramp) L / g`` with
    the longest link ``L`` (m), the drive's rate ``omega`` and the ramp's peak angular acceleration
    ``alpha_ramp`` (a Froude number; infinite without gravity). Measured on the PLA scene
    (``bench/hard_cases.py``, speed case): the quasi-static driving torque is off by about 0.75 times
    this number of its peak (0.28 % at 1 rpm, 2.7 % at 10 rpm, 28 % at 60 rpm)."""
    g = float(np.linalg.norm(scene.gravity))
    omega = float(scene.drive.omega)
    alpha = float(np.max(np.abs(scene.drive.acceleration(np.linspace(0.0, scene.drive.ramp_time, 65)))))
    length = scene.link_length
    return float("inf") if g == 0.0 else max(omega * omega, alpha) * length / g


def choose_mode(scene: LinkageScene) -> tuple[str, float]:
    """``quasi_static`` when the drive is slow compared with the links' vibrations (the time to
    turn one radian at full speed against the longest fixed-interface period of any link, ratio
    > 100) *and* with gravity (:func:`inertia_number` below :data:`INERTIA_LIMIT`: inertia
    changes the driving torque by less than about 1 %), else ``dynamic``. Returns the mode and
    the vibration ratio. The second test matters: at 60 rpm the vibration ratio is still about
    100 while inertia changes the torque by 28 % (``docs/hard_cases.md``)."""
    longest = max(
        1.0 / float(reduction.fixed_interface_frequencies_hz[0])
        for reduction in (link.reduction for link in scene.links)
        if isinstance(reduction, CraigBamptonBasis) and reduction.fixed_interface_frequencies_hz.size
    )
    ratio = (1.0 / scene.drive.omega) / longest
    slow = ratio > 100.0 and inertia_number(scene) < INERTIA_LIMIT
    return ("quasi_static" if slow else "dynamic"), ratio


def _joints(scene: LinkageScene) -> list[MarkerJoint]:
    return [c for c in scene.system.constraints if isinstance(c, MarkerJoint) and c.name != "clamp"]


def evaluate_sensors(
    scene: LinkageScene,
    time: NDArray,
    q: NDArray,
    qd: NDArray | None,
    multipliers: NDArray,
    which: str = "all",
    jumps: Sequence[PathJump] = (),
) -> dict[str, NDArray]:
    """The sensors of the module docstring at every output row: with ``which="all"`` every one, the scene sensors of
    any run (:func:`ffrf.output.sensors.scene_sensors`, its energy balance kept apart across the path's ``jumps``)
    and the linkage ones built from them; with ``"path"`` only those of :data:`PATH_SENSORS`
    (:func:`ffrf.output.sensors.path_sensors`), the same values."""
    if which not in SENSOR_SETS:
        raise ValueError(f"which must be one of {SENSOR_SETS}, got {which!r}")
    if which == "all":
        out = scene_sensors(scene, time, q, multipliers, qd, jumps)
        joints = _joints(scene)
        out["joint_angles"] = np.column_stack([out[f"{j.name}_angle"] for j in joints])
        names = [c.name for c in scene.system.constraints if isinstance(c, MarkerJoint)]
        out["joint_reactions"] = np.stack([out[f"{name}_reaction"] for name in names], axis=1)
    else:
        out = {name: value for name, value in path_sensors(scene, time, q, multipliers).items() if name in PATH_SENSORS}
    ideal = scene.ideal_coupler_points(out["drive_angle"])
    out["coupler_ideal"] = ideal
    out["coupler_deviation"] = out["coupler_point"] - ideal
    # The closest point of the exact ideal curve (Eq. (C1)), not of a polyline through its samples (issue #32).
    out["coupler_distance_to_path"] = distance_to_curve(out["coupler_point"], scene.ideal_coupler_exact()).distance
    return out


def run_linkage(
    scene: LinkageScene,
    mode: str = "auto",
    n_outputs: int = 241,
    step: float | None = None,
    rho_inf: float = 0.9,
    progress: Callable[[float, float], None] | None = None,
    t_end: float | None = None,
    stability: bool = False,
    sensors: str = "all",
    error_tolerance: float | None = None,
    step_parts: list[list[int]] | None = None,
) -> Result:
    """Assemble (static, with misalignment continuation), then run over the drive's ramp and
    revolution(s): ``quasi_static`` equilibria at ``n_outputs`` times, or ``dynamic``
    generalized-alpha with ``step`` (s; default :func:`ffrf.scenes.assembly.dynamic_step`, 10 ms at 1 rpm) starting
    from the assembled state at rest, each step in more parts where its local error estimate exceeds
    ``error_tolerance`` (m; default :func:`~ffrf.scenes.linkage_steps.dynamic_error_tolerance`, 1e-6 of the longest
    link, Eq. (G8)). ``t_end``
    shortens the run (default: the scene's ramp plus revolutions). A run that stops raises the solver's error
    (:class:`ffrf.errors.StaticDivergence` or :class:`ffrf.errors.NewtonDivergence`; :class:`ffrf.errors.Interrupted`
    when ``progress`` asked it to stop, ``stopped.reason`` then ``"interrupted"``) with ``partial``, the
    :class:`~ffrf.output.result.Result` up to its last output (its metadata's ``stopped`` says where and why), when
    there is one.
    With ``stability`` (quasi-static runs) every equilibrium's three smallest squared frequencies of Eq. (B1) are
    the sensor ``stability_squared_frequencies`` (rad^2/s^2) and the metadata's ``stability`` sums them up.
    ``sensors``: ``"all"``, or ``"path"`` for only the coupler's path and the drive's (:data:`PATH_SENSORS`, what a
    study's row reads; the same values, without the reactions, energies and tracked nodes). ``step_parts`` (dynamic):
    another run's parts per step (its metadata's ``step_parts``), taken again instead of the step rules' (Eqs. (G7),
    (G8)): runs of variants of one scene that must take the same steps (a cross-validation's)."""
    if sensors not in SENSOR_SETS:
        raise ValueError(f"sensors must be one of {SENSOR_SETS}, got {sensors!r}")
    chosen, ratio = choose_mode(scene)
    mode = chosen if mode == "auto" else mode
    if mode not in MODES:
        raise ValueError(f"mode must be 'auto', 'quasi_static' or 'dynamic', got {mode!r}")
    check_judged_at_equilibria(mode, stability, "run quasi-statically (mode='quasi_static') to monitor it")
    started = wallclock.perf_counter()
    assembly = assemble(scene)
    stress = scene_assembly_stress(scene, assembly.q, assembly.multipliers)
    assembled = wallclock.perf_counter()
    t_end = scene.t_end if t_end is None else float(t_end)
    step = dynamic_step(scene) if step is None else float(step)
    tolerance: float | None = dynamic_error_tolerance(scene) if error_tolerance is None else error_tolerance
    step_limit = dynamic_step_limit(scene) if mode == "dynamic" else None
    if step_parts is not None and mode == "dynamic":  # another run's steps, taken again (no error control)
        step_limit, tolerance = replayed_limit(t_end / max(1, round(t_end / step)), step_parts), None
    try:
        run = simulate(
            scene.system,
            assembly.q,
            mode,
            t_end,
            n_outputs,
            step=step,
            rho_inf=rho_inf,
            progress=progress,
            max_static_step=quasi_static_step(scene),
            through_snaps=stability,
            static_path_step=quasi_static_path_step(scene) if mode == "quasi_static" else None,
            step_limit=step_limit,
            error_tolerance=tolerance if mode == "dynamic" else None,
        )
        stopped = None
    except (StaticDivergence, NewtonDivergence, Interrupted) as error:
        if not isinstance(error, Interrupted):
            reached = error.partial.time[-1] if error.partial is not None and len(error.partial.time) else 0.0
            near = near_dead_point(scene, float(reached))
            if near is not None:  # the solver's own message cannot know the loop: name the real cause first
                error.args = (
                    f"{near}; the run's steps were refined there and still failed: drive another joint, one that "
                    f"turns steadily through this pose, or run more slowly. The solver said: {error}",
                )
        if error.partial is None or len(error.partial.time) < 2:
            error.partial = None  # too little to evaluate: no Result to write
            raise
        run, stopped = error.partial, error
    times, q, qd, lam = run.time, run.q, run.qd, run.multipliers
    solved = wallclock.perf_counter()
    values = evaluate_sensors(scene, times, q, qd, lam, sensors, run.jumps)
    if stability:
        values["stability_squared_frequencies"] = np.array(
            [s.squared_frequencies for s in stability_along(scene.system, times, q, lam, count=3)]
        )
    # the scene's play table is kept as ``joint_play``: ``clearance`` is the links' clearance (Result.add_clearance)
    settings = {("joint_play" if k == "clearance" else k): v for k, v in scene.settings.items()}
    metadata = dict(
        settings,
        mode=mode,
        quasi_static_ratio=ratio,
        inertia_number=inertia_number(scene),
        t_end=t_end,
        n_outputs=len(times),
        joint_reaction_names=[c.name for c in scene.system.constraints if isinstance(c, MarkerJoint)],
        step=step if mode == "dynamic" else None,
        # how many parts each step took (Eqs. (G7), (G8)): what the run's Exudyn twin is told to take
        step_parts=_step_parts(run, t_end, step) if mode == "dynamic" else None,
        step_error_estimate=_step_error_summary(run),
        rho_inf=rho_inf if mode == "dynamic" else None,
        timings_s={
            "assembly": assembled - started,
            "solve": solved - assembled,
            "sensors": wallclock.perf_counter() - solved,
        },
        python=platform.python_version(),
        numpy=np.__version__,
        n_coordinates=scene.system.n_coordinates,
        n_constraints=scene.system.n_constraints,
        energy_floor_j=weight_energy(scene),
        path_jumps=len(run.jumps),
        modes_per_link=[link.reduction.n_modes for link in scene.links],
        assembly=stress.as_dict(),
    )
    out = Result(times, values, q, metadata, stress, qd=qd, multipliers=lam, kind="linkage", scene=scene)
    out.metadata["summary"] = out.summary()
    out.metadata["near_dead_poses"] = near_dead_poses(
        scene, values["drive_angle"], np.linalg.norm(values["coupler_deviation"], axis=1)
    )
    out.verification = verify_run(out, scene)
    out.metadata["verification"] = out.verification.as_dict()
    for warning in out.verification.warnings:
        log.warning(warning)
    if stability:
        out.metadata["stability"] = stability_summary(
            values["stability_squared_frequencies"], np.degrees(values["drive_angle"]), "drive_angle_deg"
        )
        snaps = getattr(run, "snaps", ())
        out.metadata["stability"]["snaps"] = [_snap_report(scene, snap) for snap in snaps]
        out.critical = run_critical_pose(scene.system, times, q, lam, values["stability_squared_frequencies"], snaps)
        out.metadata["stability"]["critical"] = {
            **out.critical.summary(scene.system, shares="link_shares"),
            "drive_angle_deg": float(np.degrees(scene.drive_angle(out.critical.t))),
        }
    if stopped is not None:
        out.metadata["stopped"] = {
            "time_s": float(times[-1]),
            "drive_angle_rad": scene.drive_angle(times[-1]),
            "drive_angle_deg": float(np.degrees(scene.drive_angle(times[-1]))),
            "reason": "interrupted" if isinstance(stopped, Interrupted) else str(stopped),
            "message": str(stopped),
        }
        stopped.partial = out
        raise stopped
    return out


def _step_parts(run: Run, t_end: float, step: float) -> list[list[int]] | None:
    """:func:`~ffrf.solvers.generalized_alpha.step_parts` of a dynamic run (its fixed step as the integrator takes
    it: ``t_end`` in a whole number of steps)."""
    if run.step_sizes is None or run.step_sizes.size == 0:
        return None
    return step_parts(run.step_sizes, t_end / max(1, round(t_end / step)))


def _step_error_summary(run: Run) -> dict | None:
    """The local error estimates of a dynamic run's steps (Eq. (G5), bodies' positions): the largest, when, and the
    median, and the number of steps and the shortest (s, Eq. (G7)); ``None`` for a quasi-static run. The largest is
    usually in the first steps, while the numerical damping removes the start's high-frequency accelerations, and
    bounds the path's error loosely; the median is the steady motion's (``docs/speed_vs_error.md``)."""
    errors = run.position_errors
    if errors is None or errors.size == 0 or run.step_sizes is None:
        return None
    largest = int(np.argmax(errors))
    ends = np.cumsum(run.step_sizes)
    return {
        "largest_m": float(errors[largest]),
        "largest_at_s": float(ends[largest]),
        "median_m": float(np.median(errors)),
        "steps": int(errors.size),
        "shortest_step_s": float(np.min(run.step_sizes)),
    }


def _snap_report(scene: LinkageScene, snap: SnapThrough) -> dict:
    """A snap of a linkage (Eq. (S6)) in the user's terms: :func:`~ffrf.solvers.snap_through.snap_summary` with the
    drive angle and the driving torque at the fold, the jump of the coupler point and the driving torque after it
    (``None`` without a landing) and the other fold's drive angle."""
    summary = snap_summary(scene.system, snap)
    landed = summary["landed"]
    states = [snap.fold_q] + ([snap.landing_q] if landed else [])
    lams = [snap.fold_multipliers] + ([snap.landing_multipliers] if landed else [])
    at = evaluate_sensors(scene, np.full(len(states), snap.fold_t), np.array(states), None, np.array(lams))
    return {
        **summary,
        "drive_angle_deg": float(np.degrees(at["drive_angle"][0])),
        "driving_torque_Nm": float(at["driving_torque"][0]),
        "driving_torque_after_Nm": float(at["driving_torque"][1]) if landed else None,
        "coupler_jump_m": float(np.linalg.norm(at["coupler_point"][1] - at["coupler_point"][0])) if landed else None,
        "return_drive_angle_deg": None
        if snap.return_t is None
        else float(np.degrees(scene.drive_angle(snap.return_t))),
    }
