"""Any single loop (kinematics.single_loop) against independent truth.

- the Bennett linkage's closed-form configuration curve (kinematics.bennett, paper Eq. closure);
- Rational Linkages' own motion polynomials and factorisations for its 4R and 6R models;
- closed forms of the planar four-bar (Grashof's rule, the rocker's dead points);
- the closure Jacobian against finite differences of the closure residual.
"""

from __future__ import annotations

import numpy as np
import pytest

from kinematics import BennettLinkage, dh_from_axes, wrap_angle
from kinematics.dual_quaternion import DualQuaternion
from kinematics.pluecker import Line
from kinematics.rational_mechanism import factor_joint_angles, load_model, loop_from_mechanism, tool_link
from kinematics.single_loop import LoopFoldError, SingleLoop, trace_motion

RATIONAL_MODELS = ("bennett_ark24", "collisions_free_6r", "plane_fold_6r", "interp_4poses_6r")


def test_bennett_motion_equals_the_closed_form_configuration_curve():
    bennett = BennettLinkage.paper()
    motion = trace_motion(SingleLoop(bennett.axes), driver=3, n_poses=120)
    theta = bennett.joint_angles_from_driver(bennett.home_theta[3] + motion.driver_angles, joint=3)
    assert np.max(np.abs(wrap_angle(theta - bennett.home_theta - motion.phi))) < 1e-11  # measured 2e-13
    path = motion.path(2, bennett.coupler_point())
    assert np.max(np.abs(path - bennett.coupler_path(n=120, joint=3))) < 1e-12  # measured 1.7e-14 m
    assert np.max(motion.residual) < 1e-12


@pytest.mark.parametrize("name", RATIONAL_MODELS)
def test_motion_equals_rational_linkages_motion_polynomial(name):
    """A whole revolution of joint 0: every joint angle equals the factorisations' (L5) and the tool link's
    pose equals Rational Linkages' C(t) at the parameter its own joint-angle map gives (measured: angles 9.1e-14 rad,
    points 1.2e-14 m at most, plane_fold_6r; 1e-9 in the issue)."""
    mechanism = load_model(name)
    loop = loop_from_mechanism(mechanism, scale=0.1)
    # plane_fold_6r's home pose is singular (it lies folded in a plane): start on the curve instead.
    start = factor_joint_angles(mechanism, 0.5) if name == "plane_fold_6r" else None
    motion = trace_motion(loop, driver=0, n_poses=72, start=start)
    points = 0.1 * np.array([[0.3, -0.2, 0.5], [1.0, 0.4, -0.7]])
    first = mechanism.factorizations[0]
    worst_angle, worst_point = 0.0, 0.0
    for phi in motion.phi:
        t = first.joint_angle_to_t_param(float(np.mod(-phi[0], 2.0 * np.pi)))  # Rational Linkages' own map
        worst_angle = max(worst_angle, float(np.max(np.abs(wrap_angle(factor_joint_angles(mechanism, t) - phi)))))
        pose = DualQuaternion(np.asarray(mechanism.evaluate(t), dtype=float)).normalized()
        tool = loop.link_transforms(phi)[tool_link(mechanism)]
        ours = points @ tool[:3, :3].T + tool[:3, 3]
        theirs = pose.act(points / 0.1) * 0.1
        worst_point = max(worst_point, float(np.max(np.abs(ours - theirs))))
    assert worst_angle < 1e-11
    assert worst_point < 1e-12
    assert np.max(motion.residual) < 1e-12


def test_mobility_of_generic_and_special_loops():
    rng = np.random.default_rng(7)
    generic = SingleLoop.from_points_directions(rng.normal(size=(4, 3)), rng.normal(size=(4, 3)))
    assert generic.mobility() == 0  # four lines in general position: a rigid structure
    with pytest.raises(ValueError, match="rigid"):
        trace_motion(generic)
    seven = SingleLoop.from_points_directions(rng.normal(size=(7, 3)), rng.normal(size=(7, 3)))
    assert seven.mobility() == 1  # 7 joints, 6 closure equations
    assert loop_from_mechanism(load_model("collisions_free_6r")).mobility() == 1  # overconstrained 6R
    assert SingleLoop(BennettLinkage.paper().axes).mobility() == 1
    assert loop_from_mechanism(load_model("plane_fold_6r")).mobility() == 3  # home pose folded flat: singular


def _planar_four_bar(ground: float, crank: float, coupler: float, rocker: float) -> SingleLoop:
    """A planar four-bar with parallel joint axes along z (all lengths in m), crank at 60 deg."""
    phi = np.radians(60.0)
    a = np.array([0.0, 0.0])
    b = np.array([crank * np.cos(phi), crank * np.sin(phi)])
    d = np.array([ground, 0.0])
    distance = np.linalg.norm(b - d)
    # The coupler-rocker joint: intersection of two circles (above the line b-d).
    along = (coupler**2 - rocker**2 + distance**2) / (2 * distance)
    height = np.sqrt(coupler**2 - along**2)
    unit = (d - b) / distance
    c = b + along * unit + height * np.array([-unit[1], unit[0]])
    joints = np.array([[*p, 0.0] for p in (a, b, c, d)])
    return SingleLoop.from_points_directions(joints, np.tile([0.0, 0.0, 1.0], (4, 1)))


def test_planar_crank_rocker_follows_grashof():
    """Grashof crank-rocker (shortest + longest < others, shortest a crank): the crank turns fully, the rocker
    stops at its dead points, which lie where crank and coupler are collinear (closed form)."""
    ground, crank, coupler, rocker = 0.4, 0.1, 0.35, 0.3
    loop = _planar_four_bar(ground, crank, coupler, rocker)
    assert loop.mobility() == 1
    motion = trace_motion(loop, driver=0, n_poses=180)
    assert np.max(motion.residual) < 1e-12
    rocker_angle = motion.phi[:, 0] + motion.phi[:, 1] + motion.phi[:, 2]  # absolute turn of link 3
    # Closed form: rocker extremes where crank and coupler are stretched out / folded (law of cosines).
    extremes = [
        np.arccos((ground**2 + rocker**2 - (coupler + sign * crank) ** 2) / (2 * ground * rocker)) for sign in (1, -1)
    ]
    swing = abs(extremes[0] - extremes[1])
    assert abs((rocker_angle.max() - rocker_angle.min()) - swing) < 2e-3  # sampled every 2 deg of the crank
    with pytest.raises(LoopFoldError, match="joint 2 cannot turn further"):
        trace_motion(loop, driver=2, n_poses=360)


def test_jacobian_is_the_derivative_of_the_closure_where_the_loop_closes():
    loop = loop_from_mechanism(load_model("collisions_free_6r"), scale=0.1)
    motion = trace_motion(loop, driver=0, n_poses=12)
    phi = motion.phi[5]
    jacobian = loop.jacobian(phi)
    step = 1e-6
    for i in range(loop.n):
        delta = np.zeros(loop.n)
        delta[i] = step
        central = (loop.closure_residual(phi + delta) - loop.closure_residual(phi - delta)) / (2 * step)
        assert np.max(np.abs(central - jacobian[:, i])) < 1e-8


def test_dh_table_and_axes_describe_the_same_motion():
    """A 6R given by its DH table (with offsets d != 0) moves as the same 6R given by its axes."""
    loop = loop_from_mechanism(load_model("collisions_free_6r"), scale=0.1)
    dh = dh_from_axes(list(loop.axes))
    assert np.max(np.abs(dh.d)) > 0.01  # a real test of the offsets
    from_table = SingleLoop.from_dh(dh.a, dh.alpha, dh.d, dh.theta)
    a = trace_motion(loop, driver=0, n_poses=36)
    b = trace_motion(from_table, driver=0, n_poses=36)
    assert np.max(np.abs(wrap_angle(a.phi - b.phi))) < 1e-10


def test_singular_pose_is_reported_along_the_motion():
    """plane_fold_6r passes its folded (flat) pose once per revolution: the Jacobian's rank drops there."""
    mechanism = load_model("plane_fold_6r")
    loop = loop_from_mechanism(mechanism, scale=0.1)
    start = factor_joint_angles(mechanism, 0.5)
    motion = trace_motion(loop, driver=0, n_poses=360, start=start)
    measure = motion.singularity_measure
    nearest = motion.phi[np.argmin(measure)]
    assert np.max(np.abs(wrap_angle(nearest))) < np.radians(1.0)  # the flat pose is home, phi = 0
    assert measure.min() < 0.01 * np.median(measure)  # 1 deg of the driver from it (measured 1.1e-3)
    values = loop.singular_values(np.zeros(6))
    assert values[4] < 1e-12 * values[0]  # at the flat pose itself the rank has dropped from 5 to 3


def test_bad_input_is_named():
    with pytest.raises(ValueError, match="at least 4 revolute joints"):
        SingleLoop.from_points_directions(np.eye(3), np.eye(3))
    line = Line.from_point_direction([0, 0, 0], [0, 0, 1])
    other = Line.from_point_direction([1, 0, 0], [0, 1, 0])
    with pytest.raises(ValueError, match="coincide"):
        SingleLoop((line, line, other, other.reversed()))
    loop = SingleLoop(BennettLinkage.paper().axes)
    with pytest.raises(ValueError, match="expected 4 joint angles"):
        loop.closure_residual(np.zeros(3))
    with pytest.raises(ValueError, match="NaN"):
        loop.closure_residual(np.array([0.0, np.nan, 0.0, 0.0]))
    with pytest.raises(ValueError, match="unknown Rational Linkages model"):
        load_model("bennet")
    with pytest.raises(ValueError, match="driver must be a joint index"):
        trace_motion(loop, driver=4)


def test_loops_closed_near_samples_are_the_closed_form_bennett_poses(rng):
    """close_near, all poses at once from the sample before each angle (72 samples of a revolution), gives the
    Bennett linkage's closed-form joint angles at any driver angle (measured 3.6e-15 rad) and the coupler's points
    of point_paths those of the motion polynomial (measured 2.1e-16 m); its tangents are the kernel of the closure
    Jacobian with the driver's share 1."""
    from kinematics import close_near, motion_tangents, point_paths

    bennett = BennettLinkage.paper()
    loop = SingleLoop(bennett.axes)
    motion = trace_motion(loop, driver=3, n_poses=72)
    step = motion.driver_angles[1] - motion.driver_angles[0]
    seeds = rng.integers(0, 72, 500)
    angles = motion.driver_angles[seeds] + rng.uniform(0.0, step, 500)
    phi = close_near(loop, 3, motion.phi[seeds], angles)
    theta = bennett.joint_angles_from_driver(bennett.home_theta[3] + angles, joint=3)
    assert np.max(np.abs(wrap_angle(theta - bennett.home_theta - phi))) < 1e-12
    points = point_paths(loop, phi, 2, bennett.coupler_point())
    truth = bennett.coupler_pose(bennett.parameter_from_joint(bennett.home_theta[3] + angles, 3)).act(
        bennett.coupler_point()
    )
    assert np.max(np.abs(points - truth)) < 1e-13
    tangents = motion_tangents(loop, 3, phi[:20])
    assert np.allclose(tangents[:, 3], 1.0)
    for p, tangent in zip(phi[:20], tangents, strict=True):
        assert np.max(np.abs(loop.jacobian(p) @ tangent)) < 1e-12
