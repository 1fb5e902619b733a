r"""A run on the Bennett scene as plain time histories (:class:`BennettTrajectory`), our solver's
runs of it (dynamic and static, on any of our systems of the scene), their sensors read from the
system's own joints (:func:`system_points`), and the comparison of two runs (:func:`compare`).
The Exudyn twin's runs (:mod:`validation.exudyn_bennett`) return the same trajectories.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "BennettTrajectory",
    "system_points",
    "modal_coordinates",
    "run_ffrf_bennett",
    "static_ffrf_bennett",
    "compare",
]


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
) -> BennettTrajectory:
    """Our generalized-alpha on ``system`` (``scene.system`` or
    :func:`validation.exudyn_conventions.exudyn_convention_system`) from ``q0`` at rest."""
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
        modal_coordinates(system, result.q),
        0.0,
        result.wall_time,
        int(result.newton_iterations.sum()),
        label,
    )


def static_ffrf_bennett(scene, system, q0: NDArray, t: float = 0.0, load_steps: int = 2, tolerance: float = 1e-12):
    """Our static equilibrium of ``system`` from ``q0``: (q, drive multiplier, coupler, tracked)."""
    from ffrf.solvers.static_solver import static_equilibrium

    solution = static_equilibrium(system, np.asarray(q0, float), t=t, load_steps=load_steps, tolerance=tolerance)
    coupler, tracked = system_points(scene, system, solution.q)
    return solution.q, float(solution.multipliers[-1]), coupler[0], tracked[0]


def compare(a: BennettTrajectory, b: BennettTrajectory, elastic: BennettTrajectory | None = None) -> dict[str, float]:
    """Max differences between two runs (same output times). ``elastic``: a run whose coupler
    motion away from its start measures the elastic deviation scale (default ``b``)."""
    assert a.time.shape == b.time.shape and np.abs(a.time - b.time).max() < 1e-9
    ref = b if elastic is None else elastic
    out = {
        "coupler_m": float(np.abs(a.coupler - b.coupler).max()),
        "tracked_m": float(np.abs(a.tracked - b.tracked).max()),
        "zeta": float(max(np.abs(za - zb).max() for za, zb in zip(a.zeta, b.zeta, strict=True))),
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
