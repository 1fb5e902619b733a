"""The Bennett linkage: paper's motion polynomial, closure along the curve, independent checks."""

import numpy as np
import pytest
from kinematics_reference import dh_step, random_bennett

from kinematics import PAPER_A, PAPER_ALPHA, BennettConditionError, BennettLinkage, Line, loop_closure_residual

SQRT3 = np.sqrt(3.0)
# The paper's Eq. (motion), typed in from the text, coefficients of t^2, t^1, t^0.
PAPER_MOTION = np.array(
    [
        [SQRT3, 0, 0, 0, 0, 0, 0, 0],
        [0, 0, -0.5, -SQRT3 / 2, 0, 0, -11 * SQRT3 / 200, -11 / 200],
        [SQRT3 / 2, -0.5, 0, 0, -11 / 200, -11 * SQRT3 / 200, 0, 0],
    ]
)


def _normalised(c):
    return c / np.linalg.norm(c[0])


def test_paper_configuration_curve_and_motion_polynomial():
    bennett = BennettLinkage.paper()
    np.testing.assert_allclose(bennett.configuration(2.0), [2.0, 2 * SQRT3, -2.0, -2 * SQRT3], atol=1e-12)
    ours = bennett.motion_polynomial().coefficients
    np.testing.assert_allclose(_normalised(ours), _normalised(PAPER_MOTION), atol=1e-12)


def test_closure_on_random_bennett_curves(rng):
    """Closure residual < 1e-10 at 1000 points of the configuration curve of random linkages."""
    for _ in range(10):
        a, alpha = random_bennett(rng)
        bennett = BennettLinkage(a, alpha)
        t = np.tan(rng.uniform(-np.pi / 2, np.pi / 2, 1000))  # covers all of P^1 but infinity
        residual = bennett.closure_residual(np.r_[t, np.inf, 0.0])
        scale = max(a)
        assert residual.translation.max() < 1e-10 * scale
        assert residual.rotation.max() < 1e-10


def test_configuration_ratio_matches_bennetts_relation(rng):
    """Our k_1 (from the linear dependence of the axes) equals Bennett's classical
    tan(theta0/2) tan(theta1/2) = sin((alpha1+alpha0)/2) / sin((alpha1-alpha0)/2) (Bennett 1914)."""
    for _ in range(50):
        a, alpha = random_bennett(rng)
        bennett = BennettLinkage(a, alpha)
        expected = -np.sin(0.5 * (alpha[1] + alpha[0])) / np.sin(0.5 * (alpha[1] - alpha[0]))
        assert bennett.coefficients[1] == pytest.approx(expected, rel=1e-9)
        np.testing.assert_allclose(bennett.coefficients[2:], [-1.0, -expected], rtol=1e-9)


def _coupler_frame(a, alpha, theta):
    """Frame of the coupler (link 2) in frame 3: the DH steps of joints 0 and 1."""
    return dh_step(a[3], alpha[3], 0.0, theta[0]) @ dh_step(a[0], alpha[0], 0.0, theta[1])


def test_coupler_pose_equals_matrix_dh_chain(rng):
    """C(t) against a plain 4x4 DH chain (Lynch and Park) driven through the joint angles.

    The coupler (link 2) sits after joints 0 and 1; its displacement from home is
    W f_3^0(theta_0) f_0^1(theta_1) (W f_3^0(theta_0^h) f_0^1(theta_1^h))^-1 for any base frame W.
    """
    for _ in range(5):
        a, alpha = random_bennett(rng)
        bennett = BennettLinkage(a, alpha)
        home = bennett.home_theta
        home_inverse = np.linalg.inv(_coupler_frame(a, alpha, home))
        for t in rng.normal(size=10) * 3:
            theta = bennett.joint_angles(t)
            expected = _coupler_frame(a, alpha, theta) @ home_inverse  # in frame-3 coordinates
            base = dh_step(a[3], alpha[3], 0.0, home[0])  # frame 0 seen from frame 3
            world = base @ np.diag([-1.0, -1.0, 1.0, 1.0])  # paper's world frame seen from frame 3
            expected_world = np.linalg.inv(world) @ expected @ world
            np.testing.assert_allclose(bennett.coupler_pose(t).to_matrix(), expected_world, atol=1e-12)


def test_driver_angles_round_trip():
    bennett = BennettLinkage.paper()
    for joint in range(4):
        for angle in np.linspace(-3, 3, 13):
            theta = bennett.joint_angles_from_driver(angle, joint=joint)
            assert np.cos(theta[joint] - angle) == pytest.approx(1.0, abs=1e-12)
            assert loop_closure_residual(PAPER_A, PAPER_ALPHA, None, theta).translation < 1e-12
    np.testing.assert_allclose(bennett.joint_angles_from_driver(np.pi, joint=3), bennett.home_theta, atol=1e-12)


def test_coupler_path_is_closed_and_on_the_motion():
    bennett = BennettLinkage.paper()
    path = bennett.coupler_path(n=400)
    assert path.shape == (400, 3)
    steps = np.linalg.norm(np.diff(np.vstack([path, path[:1]]), axis=0), axis=1)
    assert steps.max() < 3 * steps.mean()  # one continuous loop, no jumps
    # The coupler point stays at the same distances from h1 and h2 (it rides on the coupler).
    point = bennett.coupler_point()
    for t in np.linspace(-4, 4, 9):
        pose = bennett.coupler_pose(t)
        h1 = bennett.axes[1].transformed(pose)
        assert h1.distance_to_point(pose.act(point)) == pytest.approx(0.11, abs=1e-12)


def test_factorisation_by_rational_linkages_recovers_all_four_axes():
    """Independent check: Rational Linkages factorises our C(t) two ways; the factors' axes are
    h0, h1 (one branch) and h3, h2 (the other branch) of the paper's linkage."""
    import rational_linkages as rl

    bennett = BennettLinkage.paper()
    curve = rl.RationalCurve.from_coeffs(bennett.motion_polynomial().coefficients.T.copy())
    factorisations = curve.factorize()
    found = []
    for factorisation in factorisations:
        for axis in factorisation.dq_axes:
            found.append(Line.from_dual_quaternion(np.asarray(axis.array(), dtype=float)))
    for ours in bennett.axes:
        assert any(ours.is_close(f, 1e-9) or ours.is_close(f.reversed(), 1e-9) for f in found), ours


def test_bennett_conditions_are_checked_and_named():
    alpha = list(PAPER_ALPHA)
    alpha[3] = np.radians(91.0)
    with pytest.raises(BennettConditionError, match="opposite twists"):
        BennettLinkage(PAPER_A, tuple(alpha))
    with pytest.raises(BennettConditionError, match="opposite sides"):
        BennettLinkage((0.11, 0.22, 0.12, 0.22), PAPER_ALPHA)
    with pytest.raises(BennettConditionError, match="a0/sin"):
        BennettLinkage((0.11, 0.20, 0.11, 0.20), PAPER_ALPHA)


def test_link_poses_keep_every_joint_together(rng):
    """Each joint axis (points at home) is carried identically by the two links it connects."""
    for _ in range(3):
        a, alpha = random_bennett(rng)
        bennett = BennettLinkage(a, alpha)
        t = np.r_[rng.normal(size=20) * 2, np.inf, 0.0]
        poses = bennett.link_poses(t)
        for joint, (left, right) in enumerate([(0, 1), (1, 2), (2, 3), (3, 0)]):
            points = bennett.axes[joint].point_at(np.array([-0.3, 0.4]))
            for p in points:
                np.testing.assert_allclose(poses[left].act(p), poses[right].act(p), atol=1e-12)
        np.testing.assert_allclose(poses[2].coeffs, bennett.coupler_pose(t).coeffs, atol=1e-12)
