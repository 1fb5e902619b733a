"""Joint reactions (``ffrf.system.reactions``) against Newton-Euler statics: in a static equilibrium
the joint wrenches and gravity on every link sum to zero, force and moment (the elastic
forces are internal). Independent of how the reactions were computed, so it checks the
signs, the lever arms and the torque directions of every joint, misaligned assembly included.
"""

from functools import cache

import numpy as np
import pytest
from body_fixtures import five_point_slope, potential_energy

from ffrf.body.euler_parameters import rotation_matrix
from ffrf.paper.bennett_scene import assemble, build_bennett
from ffrf.solvers.static_solver import quasi_static
from ffrf.system.reactions import joint_reactions


@cache
def equilibria(variant: str):
    scene = build_bennett(variant, h=6e-3, order=1, n_modes=2)
    q0 = assemble(scene).q
    times = np.array([0.0, 10.0, 30.0])
    return scene, times, quasi_static(scene.system, q0, times)


def wrench_sums(scene, q, lam, t):
    """Per link: sum of forces and of moments about the world origin (gravity + joints)."""
    system = scene.system
    reactions = joint_reactions(system, q, lam, t)
    force = np.zeros((4, 3))
    moment = np.zeros((4, 3))
    scale = 0.0
    for k, link in enumerate(scene.links):
        block = q[system.block(k)]
        moments = link.body.moments
        centre = block[:3] + rotation_matrix(block[3:7]) @ (moments.s0 + moments.s1 @ block[7:]) / moments.mass
        weight = moments.mass * system.gravity
        force[k] += weight
        moment[k] += np.cross(centre, weight)
        scale = max(scale, np.linalg.norm(weight))
    for c in system.constraints:
        r = reactions[c.name]
        sides = [(c.bodies[-1], 1.0)] + ([(c.bodies[0], -1.0)] if len(c.bodies) == 2 else [])
        for body, sign in sides:
            force[body] += sign * r.force
            moment[body] += sign * (np.cross(r.point, r.force) + r.torque)
        scale = max(scale, np.linalg.norm(r.force))
    return force, moment, scale


#: Moment balance achieved, relative to the largest force (N) times 1 m. Measured: PLA 5e-12; for
#: the ideally rigid links (E = 1e15 Pa) the quasi-static Newton stops at 5e-7, because its
#: convergence test works on the equilibrated residual, dominated by the stiff modal equations.
MOMENT_TOLERANCE = {"rigid": 2e-6, "pla": 1e-10, "pla2": 1e-10}


@pytest.mark.parametrize("variant", ["rigid", "pla", "pla2"])
def test_every_link_is_in_equilibrium(variant):
    scene, times, solution = equilibria(variant)
    for q, lam, t in zip(solution.q, solution.multipliers, times, strict=True):
        force, moment, scale = wrench_sums(scene, q, lam, t)
        assert np.abs(force).max() < 1e-12 * scale
        assert np.abs(moment).max() < MOMENT_TOLERANCE[variant] * scale


@pytest.mark.parametrize("pose", [1, 2], ids=["t=10s", "t=30s"])
def test_driving_torque_is_the_work_of_the_potential(pose):
    """Virtual work along the quasi-static path of the closed loop: the joints and the clamp do no
    work, so the drive's torque about its axis equals dV/dphi, V the strain plus gravity energy of the
    four links computed from the states alone (``body_fixtures.potential_energy``). dV/dphi by the
    five-point stencil over steps of 0.2 s of drive (1.2 deg at 1 rpm, h = 0.0209 rad), whose
    truncation h^4 V^(5) / 30 is about 6.4e-9 of the slope here (V is close to a sinusoid of phi):
    measured 6.5e-9 (t = 10 s) and 6.7e-9 (t = 30 s), 4.2e-10 at half the step (2026-11-24). The
    single driven link in ``tests/test_ffrf_body/test_drive_virtual_work.py`` checks the stencil's
    h^2 and h^4 error laws."""
    scene, times, solution = equilibria("pla")
    t, step = times[pose], 0.2  # s of drive at 1 rpm: 1.2 deg
    path = quasi_static(scene.system, solution.q[pose], t + step * np.arange(-2, 3))
    energy = [potential_energy(scene.system, q) for q in path.q]
    slope = five_point_slope(energy, scene.drive_angle(t + step) - scene.drive_angle(t))
    drive = joint_reactions(scene.system, path.q[2], path.multipliers[2], t)["joint3 (drive)"]
    assert abs(drive.torque_local[2]) > 5e-4  # 17 N mm at 10 s, 0.9 N mm at 30 s: not a vacuous check
    assert drive.torque_local[2] == pytest.approx(slope, rel=1e-7)


def test_reactions_are_not_trivially_zero():
    """Guard: the clamp carries the weight of the whole linkage (about 1 N for PLA links)."""
    scene, times, solution = equilibria("pla")
    clamp = joint_reactions(scene.system, solution.q[0], solution.multipliers[0], 0.0)["clamp"]
    total_weight = sum(link.body.moments.mass for link in scene.links) * 9.81
    assert clamp.force[2] == pytest.approx(total_weight, rel=1e-9)


def test_run_linkage_writes_reactions_in_joint_frames():
    """The ``joint_reactions`` sensor: the drive's torque about its axis is the driving torque,
    and the clamp carries the linkage's weight (vertical in the clamp's frame, the world's)."""
    from ffrf import load

    scene = build_bennett("pla", h=6e-3, order=1, n_modes=2)
    result = load(scene).run(mode="quasi_static", outputs=5)
    reactions = result.sensors["joint_reactions"]
    names = result.metadata["joint_reaction_names"]
    assert reactions.shape == (5, 5, 6) and names[0] == "clamp" and names[-1] == "joint3 (drive)"
    np.testing.assert_allclose(reactions[:, -1, 5], result.sensors["driving_torque"], rtol=1e-9)
    total_weight = sum(link.body.moments.mass for link in scene.links) * 9.81
    np.testing.assert_allclose(reactions[:, 0, 2], total_weight, rtol=1e-9)


def test_reactions_from_supplied_poses_equal_the_computed_ones():
    """evaluate_sensors hands its joint poses to joint_reactions; the wrenches must not change."""
    from ffrf.system.joints import MarkerJoint
    from ffrf.system.reactions import joint_poses

    scene, times, solution = equilibria("pla")
    system = scene.system
    q, lam, t = solution.q[1], solution.multipliers[1], times[1]
    poses = {
        c.name: joint_poses(c, [q[system.block(i)] for i in c.bodies])
        for c in system.constraints
        if isinstance(c, MarkerJoint) and c.name != "clamp"
    }
    plain, reused = joint_reactions(system, q, lam, t), joint_reactions(system, q, lam, t, poses)
    assert plain.keys() == reused.keys() and len(poses) == 4
    for name in plain:
        for field in ("point", "force", "torque", "frame"):
            np.testing.assert_array_equal(getattr(reused[name], field), getattr(plain[name], field))
