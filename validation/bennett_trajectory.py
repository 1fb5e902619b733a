r"""Runs on the Bennett scene: the sensors the cross-validation compares (:func:`bennett_sensors`, read from the
system's own joints by :func:`system_points`), our solver's runs as :class:`~ffrf.output.result.Result` s
(:func:`bennett_result`, :func:`run_ffrf_bennett`, dynamic and static, on any of our systems of the scene) and the
comparison of two runs (:func:`compare`). The Exudyn twin's runs (:mod:`validation.exudyn_bennett`) are
:class:`validation.twin_run.TwinRun` s with the same sensors.

Sensors (named as in :func:`ffrf.scenes.linkage_run.evaluate_sensors`): ``drive_angle`` (rad), ``driving_torque``
(N m; the multiplier of the drive's x0'.y1 equation, dynamic sign: the constraint force is -C_q^T lambda),
``coupler_point`` (mean of link 2's two joint points, m) and ``link{k}_node{j}`` (three tracked nodes of each of
links 1..3, m; :data:`TRACKED`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ffrf.output.result import Result

from .twin_run import ComparedRun, run_metadata

__all__ = [
    "TRACKED",
    "bennett_sensors",
    "bennett_result",
    "tracked_nodes",
    "system_points",
    "modal_coordinates",
    "run_ffrf_bennett",
    "static_ffrf_bennett",
    "compare",
]

#: The tracked nodes' sensors, in the order of :func:`system_points`' rows: links 1..3, three nodes each.
TRACKED = tuple(f"link{k}_node{j}" for k in (1, 2, 3) for j in range(3))


def bennett_sensors(scene, system, time: NDArray, q: NDArray, torque: NDArray) -> dict[str, NDArray]:
    """The sensors of the module docstring at coordinate rows ``q`` (our layout and basis) at ``time``, with the
    drive's multiplier ``torque``; the joints' points by ``system``'s joints (:func:`system_points`)."""
    coupler, tracked = system_points(scene, system, q)
    sensors = {
        "drive_angle": np.array([scene.drive_angle(float(t)) for t in time]),
        "driving_torque": torque,
        "coupler_point": coupler,
    }
    return sensors | {name: tracked[:, i] for i, name in enumerate(TRACKED)}


def bennett_result(
    label: str,
    scene,
    system,
    time: NDArray,
    q: NDArray,
    multipliers: NDArray,
    setup_s: float,
    solve_s: float,
    newton_iterations: int,
    qd: NDArray | None = None,
) -> Result:
    """Our run of ``system`` (``scene.system`` or a variant of it, e.g.
    :func:`validation.exudyn_conventions.exudyn_convention_system`) as a :class:`~ffrf.output.result.Result`: rows
    ``q`` and ``multipliers`` (the drive's last) at ``time``, the velocities ``qd`` of a dynamic run, the
    :func:`bennett_sensors` and :func:`validation.twin_run.run_metadata` (``label``; wall times in s)."""
    time = np.asarray(time)
    sensors = bennett_sensors(scene, system, time, q, multipliers[:, -1])
    metadata = run_metadata(label, "ffrf", setup_s, solve_s, newton_iterations)
    return Result(time, sensors, q, metadata, qd=qd, multipliers=multipliers, kind="linkage", scene=scene)


def tracked_nodes(run: ComparedRun) -> NDArray[np.float64]:
    """The tracked nodes of a run, (n, 9, 3) in the order of :data:`TRACKED`."""
    return np.stack([run.sensors[name] for name in TRACKED], axis=1)


def _joints(system):
    from ffrf.system.joints import MarkerJoint

    return {c.name: c for c in system.constraints if isinstance(c, MarkerJoint)}


def system_points(scene, system, q: NDArray) -> tuple[NDArray, NDArray]:
    """Coupler point (mean of link 2's joint points, as :func:`ffrf.scenes.linkage_run.evaluate_sensors`)
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


def modal_coordinates(system, q: NDArray) -> list:
    """Each body's modal coordinates ``zeta`` from coordinate rows ``q``: a list of (n, m_k)."""
    return [q[:, system.block(k)][:, 7:] for k in range(len(system.bodies))]


def run_ffrf_bennett(
    scene,
    system,
    q0: NDArray,
    t_end: float,
    step: float = 1e-3,
    rho_inf: float = 0.9,
    tolerance: float = 1e-12,
    label: str = "ffrf",
) -> Result:
    """Our generalized-alpha on ``system`` (``scene.system`` or
    :func:`validation.exudyn_conventions.exudyn_convention_system`) from ``q0`` at rest (:func:`bennett_result`)."""
    from ffrf.solvers.generalized_alpha import generalized_alpha

    result = generalized_alpha(
        system, np.asarray(q0, float), np.zeros_like(q0), t_end, step, rho_inf=rho_inf, tolerance=tolerance
    )
    iterations = int(result.newton_iterations.sum())
    return bennett_result(
        label, scene, system, result.time, result.q, result.multipliers, 0.0, result.wall_time, iterations, result.qd
    )


def static_ffrf_bennett(scene, system, q0: NDArray, t: float = 0.0, load_steps: int = 2, tolerance: float = 1e-12):
    """Our static equilibrium of ``system`` from ``q0``: (q, drive multiplier, coupler, tracked)."""
    from ffrf.solvers.static_solver import static_equilibrium

    solution = static_equilibrium(system, np.asarray(q0, float), t=t, load_steps=load_steps, tolerance=tolerance)
    coupler, tracked = system_points(scene, system, solution.q)
    return solution.q, float(solution.multipliers[-1]), coupler[0], tracked[0]


def compare(a: Result, b: ComparedRun, elastic: ComparedRun | None = None) -> dict[str, float]:
    """Max differences between our run ``a`` and a run ``b`` (ours or the twin's, same output times; modal
    coordinates by ``a``'s scene's layout). ``elastic``: a run whose coupler motion away from its start measures the
    elastic deviation scale (default ``b``)."""
    if a.time.shape != b.time.shape or np.abs(a.time - b.time).max() >= 1e-9:
        raise ValueError(f"{a.metadata['label']} and {b.metadata['label']} have different output times")
    ref = b if elastic is None else elastic
    zeta_a, zeta_b = (modal_coordinates(a.scene.system, run.q) for run in (a, b))
    coupler_a, coupler_b, coupler_ref = (run.sensors["coupler_point"] for run in (a, b, ref))
    torque_a, torque_b = a.sensors["driving_torque"], b.sensors["driving_torque"]
    tracked_ref = tracked_nodes(ref)
    out = {
        "coupler_m": float(np.abs(coupler_a - coupler_b).max()),
        "tracked_m": float(np.abs(tracked_nodes(a) - tracked_nodes(b)).max()),
        "zeta": float(max(np.abs(za - zb).max() for za, zb in zip(zeta_a, zeta_b, strict=True))),
        "zeta_scale": float(max(np.abs(zb).max() for zb in zeta_b)),
        "torque_Nm": float(np.abs(torque_a - torque_b).max()),
        "torque_scale_Nm": float(np.abs(torque_b).max()),
        "coupler_motion_m": float(np.linalg.norm(coupler_ref - coupler_ref[0], axis=1).max()),
        "tracked_motion_m": float(np.linalg.norm(tracked_ref - tracked_ref[0], axis=2).max()),
    }
    out["torque_relative"] = out["torque_Nm"] / max(out["torque_scale_Nm"], 1e-300)
    out["zeta_relative"] = out["zeta"] / max(out["zeta_scale"], 1e-300)
    out["coupler_relative_to_motion"] = out["coupler_m"] / max(out["coupler_motion_m"], 1e-300)
    return out
