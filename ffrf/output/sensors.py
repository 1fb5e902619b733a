"""Sensors of any run: what rows of coordinates ``q`` (and velocities, multipliers) of a scene mean.

For every output row, and for any scene built by :mod:`ffrf.scenes.builder` (duck-typed: ``system``,
``bodies[k].fe``, ``bodies[k].reduction``, ``sensors`` name -> (body, node), ``joint_sensors``):

* node sensors: world positions of the scene's sensor nodes (Eq. (F1)), m; joint-point sensors: the
  mean of the named joints' points on one body (the paper's coupler point: link 2's two joint points);
* for every joint ``J`` (a :class:`~ffrf.system.joints.MarkerJoint`): ``J_angle``, the rotation of side 1
  against side 0 about side 0's z axis (rad); ``J_reaction``, force and torque on side 1 in joint
  frame 0 (N, N m; :mod:`ffrf.system.reactions`); for a driven joint ``J_torque``, the multiplier of its
  angle equation, the driving torque applied to side 1 (N m); ``J_point0``, ``J_point1``, the joint
  point on each side (world, m); a joint with play (:mod:`ffrf.system.clearance_joint`) has the angle and points
  too, ``J_eccentricity``, the distance of the pin's centre from the bore's axis (m), and ``J_contacts``, the
  penetration (m) and normal force (N) of its rims and its axial stop (rows x 2 x 3);
* ``energy_kinetic``, ``energy_strain``, ``energy_potential`` (J), ``energy_elements`` (stored in force
  elements, when there are any) and ``constraint_residual``
  (largest ``|g|``), and with exactly one driven joint its work and the energy balance
  (:mod:`ffrf.output.energy_balance`).
"""

from __future__ import annotations

import logging
from collections.abc import Collection, Sequence

import numpy as np
from numpy.typing import NDArray

from ffrf.body.flexible_body import node_positions
from ffrf.output.energy_balance import energy_balance
from ffrf.solvers.common import PathJump
from ffrf.system.clearance_joint import ClearanceJoint
from ffrf.system.joints import MarkerJoint
from ffrf.system.multibody import MultibodySystem
from ffrf.system.packed_system import newton_model
from ffrf.system.reactions import driving_torques, joint_poses, joint_reactions, relative_angle

__all__ = [
    "relative_angle",
    "joint_rows",
    "joint_point_sensors",
    "node_sensors",
    "scene_sensors",
    "path_sensors",
    "with_jump_ends",
]

log = logging.getLogger(__name__)


def _marker_joints(system: MultibodySystem) -> list[tuple[int, MarkerJoint]]:
    return [(k, c) for k, c in enumerate(system.all_constraints) if isinstance(c, MarkerJoint)]


def joint_rows(
    system: MultibodySystem,
    time: NDArray,
    q: NDArray,
    multipliers: NDArray | None,
    qd: NDArray | None = None,
    only: Collection[str] | None = None,
) -> dict[str, NDArray]:
    """Per joint ``J``: ``J_angle``, ``J_reaction`` (rows x 6), ``J_torque`` (driven joints), the joint
    points of side 0 and side 1 ``J_point0``, ``J_point1`` (world; equal where the joint holds), plus
    energies and ``constraint_residual``; rows = ``q``'s rows. ``only``: just the angles, points and torques of the
    joints so named (no reactions, energies or residual), each value as the whole evaluation gives it; there
    ``multipliers=None`` leaves out the torques (the points of a state known by its coordinates alone)."""
    if multipliers is None and only is None:
        raise ValueError("joint_rows needs the multipliers for the reactions; give them, or name the joints (only)")
    model = newton_model(system)  # its constraint values: the fast path's kernel when supported
    joints = [(k, j) for k, j in _marker_joints(system) if only is None or j.name in only]
    rows: dict[str, list] = {}
    if only is None:
        rows = {k: [] for k in ("energy_kinetic", "energy_strain", "energy_potential", "constraint_residual")}
    for _, joint in joints:
        kinds = ("angle", "reaction", "point0", "point1") if only is None else ("angle", "point0", "point1")
        for kind in kinds + (("torque",) if joint.angle is not None and multipliers is not None else ()):
            rows[f"{joint.name}_{kind}"] = []
    for row, t in enumerate(time):
        qq = q[row]
        poses = {j.name: joint_poses(j, [qq[system.block(i)] for i in j.bodies]) for _, j in joints}
        torques = {} if multipliers is None else driving_torques(system, multipliers[row])
        for _, joint in joints:
            rows[f"{joint.name}_angle"].append(relative_angle(poses[joint.name]))
            rows[f"{joint.name}_point0"].append(poses[joint.name][0])
            rows[f"{joint.name}_point1"].append(poses[joint.name][2])
            if joint.name in torques and joint.angle is not None:
                rows[f"{joint.name}_torque"].append(torques[joint.name])
        if only is not None or multipliers is None:
            continue
        reactions = joint_reactions(system, qq, multipliers[row], float(t), poses)
        for _, joint in joints:
            reaction = reactions[joint.name]
            rows[f"{joint.name}_reaction"].append(np.concatenate([reaction.force_local, reaction.torque_local]))
        energies = system.energies(qq, np.zeros_like(qq) if qd is None else qd[row], float(t))
        for kind, value in energies.items():  # kinetic, strain, potential; elements with force elements
            rows.setdefault(f"energy_{kind}", []).append(value)
        rows["constraint_residual"].append(np.abs(model.constraint_values(qq, float(t))).max())
    rows |= _loose_joint_rows(system, q, qd, only)
    return {name: np.array(values) for name, values in rows.items()}


def _loose_joint_rows(
    system: MultibodySystem, q: NDArray, qd: NDArray | None, only: Collection[str] | None
) -> dict[str, list]:
    """The sensors of the joints with play (module docstring), as lists of rows."""
    rows: dict[str, list] = {}
    for element in system.forces:
        if not isinstance(element, ClearanceJoint) or (only is not None and element.name not in only):
            continue
        name = element.name
        for kind in ("angle", "point0", "point1") + (() if only is not None else ("eccentricity", "contacts")):
            rows[f"{name}_{kind}"] = []
        for row in range(q.shape[0]):
            blocks = [q[row][system.block(i)] for i in element.bodies]
            pose = joint_poses(element.joint, blocks)
            rows[f"{name}_angle"].append(relative_angle(pose))
            rows[f"{name}_point0"].append(pose[0])
            rows[f"{name}_point1"].append(pose[2])
            if only is not None:
                continue
            axis = pose[1][:, 2]
            offset = pose[2] - pose[0]
            rows[f"{name}_eccentricity"].append(float(np.linalg.norm(offset - axis * (axis @ offset))))
            rates = None if qd is None else [qd[row][system.block(i)] for i in element.bodies]
            contacts = element.contacts(blocks, rates)
            rows[f"{name}_contacts"].append([[c.penetration for c in contacts], [c.force for c in contacts]])
    return rows


def node_sensors(scene, q: NDArray) -> dict[str, NDArray]:
    """World positions (rows x 3) of every sensor node of ``scene``."""
    out = {}
    for name, (body, node) in scene.sensors.items():
        b = scene.bodies[body]
        out[name] = node_positions(q[:, scene.system.block(body)], b.fe.nodes, b.reduction.basis, [node])[:, 0]
    return out


def scene_sensors(
    scene,
    time: NDArray,
    q: NDArray,
    multipliers: NDArray,
    qd: NDArray | None = None,
    jumps: Sequence[PathJump] = (),
) -> dict[str, NDArray]:
    """Every sensor of the module docstring; with exactly one driven joint also ``drive_angle``,
    ``driving_torque`` and the energy balance. ``jumps`` of a quasi-static path: the balance is kept on the rows
    and the equilibria on both sides of each jump, the stretches between jumps apart
    (:func:`ffrf.output.energy_balance.energy_balance`); the sensors are those of the rows."""
    system = scene.system
    if qd is None and jumps:
        time, q, multipliers, rows, breaks = with_jump_ends(time, q, multipliers, jumps)
    else:
        rows, breaks = np.arange(len(time)), []
    out = {**node_sensors(scene, q), **joint_rows(system, time, q, multipliers, qd)}
    out |= _joint_sensors_and_drive(scene, time, out)
    if "drive_angle" in out:
        out.update(energy_balance(system, time, out, qd, q, breaks))
    return out if len(rows) == len(time) else {name: value[rows] for name, value in out.items()}


def with_jump_ends(
    time: NDArray, q: NDArray, multipliers: NDArray, jumps: Sequence[PathJump]
) -> tuple[NDArray, NDArray, NDArray, NDArray[np.int64], list[int]]:
    """The rows with the equilibria on both sides of each jump within them, in the order of t:
    ``(time, q, multipliers, rows, breaks)``, ``rows`` where the given rows are and ``breaks`` the rows i where the
    path jumps from i to i + 1. A jump's end that is a row already, or another jump's end (a path that jumps again
    from where it landed), is that one (the same t, coordinates within :data:`SAME_STATE` of their size: Newton may
    have solved it twice). Where the states cannot be put in an order of strictly increasing t between the jumps
    (an output at a snap's t, between its fold and its landing), the rows alone are returned, without breaks: the
    balance then spans the jumps and misses what they released, which its check says."""
    scale = 1e-12 * max(1.0, float(np.max(np.abs(time), initial=0.0)))
    entries: list[list] = [[float(t), q[k], multipliers[k], k] for k, t in enumerate(time)]
    starts: list[list] = []
    inside = [jump for jump in jumps if time[0] - scale <= jump.t_from and jump.t_to <= time[-1] + scale]
    for jump in sorted(inside, key=lambda jump: (jump.t_from, jump.t_to)):
        start = _find(entries, jump.t_from, jump.q_from, scale)
        if start is None:
            start = sum(1 for entry in entries if entry[0] <= jump.t_from + scale)
            entries.insert(start, [jump.t_from, jump.q_from, jump.multipliers_from, -1])
        landing = _find(entries, jump.t_to, jump.q_to, scale)
        if landing is None:
            entries.insert(start + 1, [jump.t_to, jump.q_to, jump.multipliers_to, -1])
        elif landing != start + 1:
            continue  # other states lie between its ends: no break
        starts.append(entries[start])
    breaks = sorted({next(k for k, entry in enumerate(entries) if entry is start) for start in starts})
    times = np.array([entry[0] for entry in entries])
    steps = np.diff(times)
    steps[breaks] = 1.0  # a snap's two ends share their t
    if np.any(steps <= 0.0):
        log.warning("the energy balance spans the path's jumps: their ends are not in an order of t among the rows")
        return time, q, multipliers, np.arange(len(time)), []
    return (
        times,
        np.array([entry[1] for entry in entries]),
        np.array([entry[2] for entry in entries]),
        np.array([k for k, entry in enumerate(entries) if entry[3] >= 0], dtype=np.int64),
        breaks,
    )


#: Coordinates of one state solved twice differ by Newton's tolerance; those of two states of a jump by far more.
SAME_STATE = 1e-8


def _find(entries: list[list], t: float, q: NDArray, scale: float) -> int | None:
    """The index of the entry at ``t`` with the coordinates ``q`` (within :data:`SAME_STATE` of their size)."""
    size = SAME_STATE * max(1.0, float(np.max(np.abs(q))))
    return next(
        (
            k
            for k, entry in enumerate(entries)
            if abs(entry[0] - t) <= scale and float(np.max(np.abs(entry[1] - q))) <= size
        ),
        None,
    )


def joint_point_sensors(scene, time: NDArray, q: NDArray) -> dict[str, NDArray]:
    """The joint-point sensors of ``scene`` (each the mean of joint points on one body: a linkage's
    ``coupler_point``) at ``q``'s rows, from the coordinates alone (a state another solver computed)."""
    needed = {joint for parts in scene.joint_sensors.values() for joint, _ in parts}
    return _joint_point_means(scene, joint_rows(scene.system, time, q, None, only=needed))


def _joint_point_means(scene, rows: dict[str, NDArray]) -> dict[str, NDArray]:
    return {
        name: np.mean([rows[f"{joint}_point{side}"] for joint, side in parts], axis=0)
        for name, parts in scene.joint_sensors.items()
    }


def path_sensors(scene, time: NDArray, q: NDArray, multipliers: NDArray) -> dict[str, NDArray]:
    """Of :func:`scene_sensors`, only the joint-point sensors (the mean of joint points on one body) and, with
    exactly one driven joint, ``drive_angle`` and ``driving_torque``: the same values, without the node sensors,
    the reactions, the energies and the other joints."""
    needed = {joint for parts in scene.joint_sensors.values() for joint, _ in parts}
    needed |= {j.name for _, j in _marker_joints(scene.system) if j.angle is not None}
    out = joint_rows(scene.system, time, q, multipliers, only=needed)
    return _joint_sensors_and_drive(scene, time, out)


def _joint_sensors_and_drive(scene, time: NDArray, rows: dict[str, NDArray]) -> dict[str, NDArray]:
    """The joint-point sensors from the joints' points in ``rows`` (:func:`joint_rows`) and, with exactly one driven
    joint, ``drive_angle`` (its prescribed angle at each time) and ``driving_torque``."""
    out = _joint_point_means(scene, rows)
    driven = [(j, j.angle) for _, j in _marker_joints(scene.system) if j.angle is not None]  # play: never driven
    if len(driven) == 1:
        joint, angle = driven[0]
        out["drive_angle"] = np.array([angle(float(t)) for t in time])
        out["driving_torque"] = rows[f"{joint.name}_torque"]
    return out
