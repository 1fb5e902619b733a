"""Steps chosen from the solution (issue #32): the rigid loop's joint rates (Eq. (L9)) against the closed-form
velocities of a planar four-bar, the dynamic step rule (G7) built from them, generalized-alpha's steps done in
parts, and a quasi-static path on its own steps (S10) whose equilibria and stop do not depend on the outputs."""

from types import SimpleNamespace

import numpy as np
import pytest
from pendulum_fixtures import pendulum

from ffrf.errors import StaticDivergence
from ffrf.scenes.linkage_steps import JOINT_ANGLE_PER_STEP, dynamic_step_limit, joint_rate_profile, near_dead_point
from ffrf.scenes.scene_cache import SceneCache
from ffrf.solvers.generalized_alpha import generalized_alpha
from ffrf.solvers.static_solver import path_times, quasi_static
from ffrf.system.drives import CosineRamp
from ffrf.system.multibody import MultibodySystem
from kinematics import SingleLoop, joint_rates, rate_profile

# A crank-rocker four-bar (Grashof: shortest + longest < the other two): ground d, crank a, coupler b, rocker c.
A, B, C, D = 0.02, 0.07, 0.05, 0.06
GRAVITY = np.array([0.0, 0.0, -9.81])


def _four_bar(theta2: float) -> tuple[float, float, np.ndarray, np.ndarray]:
    """Closed form: coupler and rocker angles (theta3, theta4) at crank angle theta2 (the open branch), and the
    joint points O2, A, B, O4."""
    o2, o4 = np.zeros(2), np.array([D, 0.0])
    a = o2 + A * np.array([np.cos(theta2), np.sin(theta2)])
    gap = o4 - a
    length = np.linalg.norm(gap)
    # B on the circle of radius B about A and of radius C about O4 (the branch above the line A-O4)
    along = (B * B - C * C + length * length) / (2.0 * length)
    up = np.sqrt(B * B - along * along)
    unit = gap / length
    b = a + along * unit + up * np.array([-unit[1], unit[0]])
    theta3 = np.arctan2(*(b - a)[::-1])
    theta4 = np.arctan2(*(b - o4)[::-1])
    return float(theta3), float(theta4), a, b


def _closed_form_rates(theta2: float) -> np.ndarray:
    """|d(joint rotation)/d theta2| of the four joints from the four-bar's velocity equations (Norton, Design of
    Machinery, Sect. 6.7): w3/w2 = a sin(t4 - t2) / (b sin(t3 - t4)), w4/w2 = a sin(t2 - t3) / (c sin(t4 - t3));
    the joints turn by t2, t3 - t2, t4 - t3 and -t4."""
    theta3, theta4, _, _ = _four_bar(theta2)
    w3 = A * np.sin(theta4 - theta2) / (B * np.sin(theta3 - theta4))
    w4 = A * np.sin(theta2 - theta3) / (C * np.sin(theta4 - theta3))
    return np.abs([1.0, w3 - 1.0, w4 - w3, -w4])


def _loop(theta2: float = 0.3) -> SingleLoop:
    _, _, a, b = _four_bar(theta2)
    points = np.array([[0.0, 0.0, 0.0], [*a, 0.0], [*b, 0.0], [D, 0.0, 0.0]])
    return SingleLoop.from_points_directions(points, np.tile([0.0, 0.0, 1.0], (4, 1)))


def test_joint_rates_of_a_four_bar_equal_its_velocity_equations():
    """Eq. (L9) along 300 deg of the crank, traced by rate_profile, against the closed-form velocity ratios."""
    theta_home = 0.3
    loop = _loop(theta_home)
    profile = rate_profile(loop, 0, np.zeros(4), np.radians(300.0), np.radians(1.0), np.radians(2.0))
    expected = np.array([_closed_form_rates(theta_home + angle).max() for angle in profile.driver_angles])
    np.testing.assert_allclose(profile.ratios, expected, rtol=1e-8)
    # the rates at one pose, joint by joint
    phi = np.zeros(4)
    np.testing.assert_allclose(joint_rates(loop, phi, 0), _closed_form_rates(theta_home), rtol=1e-10)
    # the largest sample around an interval of the travel
    middle = 0.5 * (profile.driver_angles[1:] + profile.driver_angles[:-1])
    ratio, joint, at = profile.largest(middle[10], middle[19])  # between samples 10, 11 and 19, 20
    assert ratio == profile.ratios[10:21].max() and 10 <= np.flatnonzero(profile.driver_angles == at)[0] <= 20
    assert joint == profile.fastest[np.flatnonzero(profile.driver_angles == at)[0]]


def test_dynamic_step_rule_bounds_the_fastest_joint_turn():
    """Eq. (G7) on the four-bar driven at 1 rpm: the longest step in a window is JOINT_ANGLE_PER_STEP over
    (drive rate x the largest closed-form joint-rate ratio there), so that the fastest joint turns at most that."""
    omega = 2.0 * np.pi / 60.0
    drive = CosineRamp(omega, 1.0)
    scene = SimpleNamespace(
        loop=_loop(0.3),
        driver=0,
        start_phi=np.zeros(4),
        t_end=20.0,
        drive=drive,
        drive_angle=lambda t: float(drive(t)),
        cache=SceneCache(enabled=False),
    )
    limit = dynamic_step_limit(scene)
    fine = np.linspace(0.0, float(drive(20.0)), 4001)
    closed = np.array([_closed_form_rates(0.3 + angle).max() for angle in fine])
    for t0 in (2.0, 7.5, 13.0):
        t1 = t0 + 0.5
        inside = (fine >= drive(t0)) & (fine <= drive(t1))
        step = limit(t0, t1)
        _, _, at = joint_rate_profile(scene).largest(float(drive(t0)), float(drive(t1)))
        assert step == pytest.approx(JOINT_ANGLE_PER_STEP / (omega * _closed_form_rates(0.3 + at).max()), rel=1e-8)
        # samples bracket the window, 2 deg of the fastest joint apart: within 2 % of the closed form's bound there
        assert step <= JOINT_ANGLE_PER_STEP / (omega * closed[inside].max()) * 1.02
    assert limit(0.0, 0.0) == np.inf  # the drive rests at t = 0
    assert joint_rate_profile(scene).ratios.max() == pytest.approx(closed.max(), rel=1e-3)


def test_generalized_alpha_steps_in_parts_as_the_step_limit_asks():
    """A step limit at or above the step changes nothing (the same floats); one of a quarter of it gives the run
    with a quarter step, at the same outputs."""
    system, _, _, _ = pendulum(n_modes=2, E=1e6)
    q0 = system.initial_state()
    qd0 = np.zeros_like(q0)
    plain = generalized_alpha(system, q0, qd0, 0.05, 1e-3, rho_inf=0.8, output_every=10)
    same = generalized_alpha(system, q0, qd0, 0.05, 1e-3, rho_inf=0.8, output_every=10, step_limit=lambda a, b: 1e-3)
    np.testing.assert_array_equal(same.q, plain.q)
    quarter = generalized_alpha(system, q0, qd0, 0.05, 2.5e-4, rho_inf=0.8, output_every=40)
    parts = generalized_alpha(system, q0, qd0, 0.05, 1e-3, rho_inf=0.8, output_every=10, step_limit=lambda a, b: 2.5e-4)
    assert parts.step_sizes.size == 200 and np.allclose(parts.step_sizes, 2.5e-4)
    np.testing.assert_allclose(parts.time, quarter.time, rtol=0, atol=1e-15)
    np.testing.assert_allclose(parts.q, quarter.q, rtol=0, atol=1e-9)


def test_a_runs_parts_encoded_and_replayed_are_its_steps():
    """``step_parts`` of a run whose step limit changes with time (1, 2, then 4 parts per step) and ``part_schedule``
    of them give back the run's own part lengths (the same floats) and end times at the fixed steps' ends: what an
    Exudyn twin is told to take (validation.exudyn_scene)."""
    from ffrf.solvers.generalized_alpha import part_schedule, step_parts

    system, _, _, _ = pendulum(n_modes=2, E=1e6)
    q0 = system.initial_state()
    run = generalized_alpha(
        system,
        q0,
        np.zeros_like(q0),
        0.03,
        1e-3,
        rho_inf=0.8,
        step_limit=lambda a, b: 1e-3 / (1 + int(b > 0.01)) if b <= 0.02 else 2.5e-4,
    )
    parts = step_parts(run.step_sizes, 1e-3)
    assert parts == [[1, 10], [2, 10], [4, 10]]
    times, sizes = part_schedule(1e-3, parts)
    np.testing.assert_array_equal(sizes, run.step_sizes)
    assert times.size == 70
    np.testing.assert_allclose(times[[9, 29, 69]], [0.01, 0.02, 0.03], rtol=0, atol=1e-17)  # the fixed steps' ends
    np.testing.assert_allclose(np.diff(times, prepend=0.0), sizes, rtol=0, atol=1e-17)


def _driven_bar(end: float = 2.15) -> MultibodySystem:
    """A rigid bar held by a driven hinge whose drive table ends at ``end`` (NaN after)."""
    from ffrf.system.joints import GroundFrame, driven_revolute_joint
    from ffrf.system.markers import frame_marker

    system, _, _, hinge = pendulum(n_modes=0)
    axes = np.array([[0.0, 0, 1], [1, 0, 0], [0, 1, 0]]).T
    drive = driven_revolute_joint(
        GroundFrame(hinge, np.eye(3)),
        frame_marker(0, 0, hinge),
        lambda t: t if t <= end else float("nan"),
        rotation0=axes,
        rotation1=axes,
    )
    return MultibodySystem(system.bodies, (drive,), gravity=GRAVITY)


def test_quasi_static_path_on_its_own_steps_does_not_depend_on_the_outputs():
    """Eq. (S10): with path_step the outputs are solved from the path, not on it. The driven bar's torque at every
    output is the closed form -m g (L/2) cos(phi), and the path stops at its own last equilibrium (t = 2.15 s, where
    the drive table ends, reached by halving the path's step) for 7, 13 and 31 outputs alike, the last row being
    that equilibrium."""
    driven = _driven_bar()
    mass = 450.0 * 0.2 * 0.02 * 0.01
    stops = []
    for outputs in (7, 13, 31):
        times = np.linspace(0.0, 3.0, outputs)
        with pytest.raises(StaticDivergence, match=r"the last equilibrium at t = 2\.149") as stopped:
            quasi_static(driven, driven.initial_state(), times, path_step=lambda t: 0.1)
        partial = stopped.value.partial
        reached = partial.times
        assert 2.15 - 0.1 / 2**8 <= reached[-1] <= 2.15
        np.testing.assert_array_equal(reached[:-1], times[times < reached[-1] - 1e-9])
        np.testing.assert_allclose(partial.multipliers[:, -1], -mass * 9.81 * 0.1 * np.cos(reached), atol=1e-12)
        stops.append(reached[-1])
    assert stops[0] == stops[1] == stops[2]
    whole = quasi_static(_driven_bar(10.0), driven.initial_state(), np.linspace(0.0, 3.0, 13), path_step=lambda t: 0.3)
    np.testing.assert_allclose(whole.multipliers[:, -1], -mass * 9.81 * 0.1 * np.cos(whole.times), atol=1e-12)
    np.testing.assert_allclose(path_times(0.0, 1.0, lambda t: 0.32), [0.0, 0.32, 0.64, 1.0])


def test_a_near_dead_pose_is_named_with_its_joint_and_rate():
    """The crank-rocker driven by its rocker towards the rocker's extreme (crank and coupler in line): there the
    crank turns ever faster than the rocker. near_dead_point names the pose with the closed-form rate ratio of the
    velocity equations (Norton, Sect. 6.7) inverted for the rocker as driver, and says nothing far from it."""
    theta2_home = 1.2  # the rocker then rises for about 50 deg to its extreme
    theta3, theta4_home, a, b = _four_bar(theta2_home)
    # the rocker loop: joint 0 at O4 (driven), 1 at B, 2 at A, 3 at O2; joints turn by t4, t3 - t4, t2 - t3, -t2
    points = np.array([[D, 0.0, 0.0], [*b, 0.0], [*a, 0.0], [0.0, 0.0, 0.0]])
    loop = SingleLoop.from_points_directions(points, np.tile([0.0, 0.0, 1.0], (4, 1)))
    crank = np.linspace(theta2_home, theta2_home + 2.0 * np.pi, 200001)
    rocker = np.array([_four_bar(t)[1] for t in crank])
    # the rocker's extreme reached first from home, and the crank angle there (crank and coupler in line)
    moving = np.sign(rocker[1] - rocker[0])
    turn_back = int(np.flatnonzero(np.diff(rocker) * moving < 0.0)[0])
    extreme = rocker[turn_back] - theta4_home
    end = extreme - moving * np.radians(0.05)  # stop 0.05 deg before the extreme
    k_end = int(np.argmin(np.abs(rocker[: turn_back + 1] - theta4_home - end)))
    t3, t4 = _four_bar(crank[k_end])[:2]
    w3 = A * np.sin(t4 - crank[k_end]) / (B * np.sin(t3 - t4))
    w4 = A * np.sin(crank[k_end] - t3) / (C * np.sin(t4 - t3))
    expected = np.abs([1.0, (w3 - w4) / w4, (1.0 - w3) / w4, 1.0 / w4])
    assert expected.max() > 10.0
    omega = 2.0 * np.pi / 60.0
    assert moving > 0.0
    drive = CosineRamp(omega, 1.0)
    t_end = drive.time_for_angle(end)  # the drive turns the way the rocker goes to its extreme
    scene = SimpleNamespace(
        loop=loop,
        driver=0,
        start_phi=np.zeros(4),
        t_end=t_end,
        drive=drive,
        drive_angle=lambda t: float(drive(t)),
        cache=SceneCache(enabled=False),
    )
    message = near_dead_point(scene, t_end, window=np.radians(0.01))
    assert message is not None and f"joint {int(np.argmax(expected))} turns" in message
    ratio = float(message.split(" turns ")[1].split(" times")[0])
    assert ratio == pytest.approx(expected.max(), rel=0.02)
    assert near_dead_point(scene, 0.5 * t_end) is None


def test_joint_rates_of_interp_4poses_6r_equal_rational_linkages_factorisation():
    """Issue #32's near-dead pose, from independent truth: a factor t - h of the motion polynomial turns by
    phi = 2 atan2(-|v|, t - s) (Eq. (L5), Rational Linkages' factorisations), so d phi / dt = 2|v| / ((t - s)^2 + |v|^2)
    and the joint rates against joint 0 are ratios of these. Their peak over the curve equals the peak of the
    continuation's rate_profile (Eq. (L9)) over a revolution: joint 5, 41.6 times the driver."""
    from kinematics.rational_mechanism import load_model, loop_from_mechanism, regular_start

    mechanism = load_model("interp_4poses_6r")
    first, second = mechanism.factorizations
    factors = [np.asarray(axis.array(), dtype=float) for axis in first.dq_axes]
    factors += [np.asarray(axis.array(), dtype=float) for axis in second.dq_axes][::-1]

    def rates(t: np.ndarray) -> np.ndarray:
        speed = np.array([2.0 * np.linalg.norm(c[1:4]) / ((t - c[0]) ** 2 + c[1:4] @ c[1:4]) for c in factors])
        return speed / speed[0]

    curve = np.concatenate([np.linspace(-50.0, 50.0, 400001), [-1e3, 1e3]])  # the curve parameter, t = inf home
    closed = rates(curve).max(axis=0)
    k = int(np.argmax(closed))
    loop = loop_from_mechanism(mechanism)
    profile = rate_profile(loop, 0, regular_start(mechanism, loop), 2.0 * np.pi, np.radians(1.0), np.radians(4.0))
    assert profile.ratios.max() == pytest.approx(closed[k], rel=2e-3)
    assert profile.fastest[np.argmax(profile.ratios)] == int(np.argmax(rates(curve[k : k + 1])[:, 0]))
    assert closed[k] == pytest.approx(41.6, abs=0.05)
