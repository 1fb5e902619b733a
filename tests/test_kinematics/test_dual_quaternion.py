"""Dual quaternions against plain 4x4 matrices and against Rational Linkages."""

import numpy as np
import pytest
from kinematics_reference import random_rigid_displacement, rot_x, rot_z, trans
from scipy.spatial.transform import Rotation

from kinematics import DualQuaternion
from kinematics.quaternion import axis_angle_quaternion, quaternion_product, rotation_vector


def test_quaternion_units_multiply_like_hamilton():
    """i^2 = j^2 = k^2 = ijk = -1 and ij = k (Hamilton's rules)."""
    i, j, k = np.eye(4)[1:]
    minus_one = np.array([-1.0, 0, 0, 0])
    for unit in (i, j, k):
        np.testing.assert_array_equal(quaternion_product(unit, unit), minus_one)
    np.testing.assert_array_equal(quaternion_product(quaternion_product(i, j), k), minus_one)
    np.testing.assert_array_equal(quaternion_product(i, j), k)


def test_paper_factors_are_the_expected_displacements():
    """r_x(alpha) rotates by +alpha about x, t_x(a) = 1 - eps a/2 i translates by +a (paper's DH factors)."""
    alpha, a = 0.7, 0.3
    r_x = DualQuaternion(np.r_[axis_angle_quaternion([1, 0, 0], alpha), np.zeros(4)])
    t_x = DualQuaternion([1, 0, 0, 0, 0, -a / 2, 0, 0])
    np.testing.assert_allclose(r_x.to_matrix(), rot_x(alpha), atol=1e-15)
    np.testing.assert_allclose(t_x.to_matrix(), trans(x=a), atol=1e-15)


def test_product_composes_like_matrices(rng):
    for _ in range(20):
        (r1, t1), (r2, t2) = random_rigid_displacement(rng), random_rigid_displacement(rng)
        s1 = DualQuaternion.from_rotation_translation(r1, t1)
        s2 = DualQuaternion.from_rotation_translation(r2, t2)
        m1, m2 = np.eye(4), np.eye(4)
        m1[:3, :3], m1[:3, 3], m2[:3, :3], m2[:3, 3] = r1, t1, r2, t2
        np.testing.assert_allclose((s1 * s2).to_matrix(), m1 @ m2, atol=1e-12)
        np.testing.assert_allclose(DualQuaternion.from_matrix(m1).to_matrix(), m1, atol=1e-12)


def test_action_inverse_and_norm(rng):
    rotation, translation = random_rigid_displacement(rng)
    sigma = DualQuaternion.from_rotation_translation(rotation, translation) * 2.5  # non-unit scale
    points = rng.normal(size=(7, 3))
    np.testing.assert_allclose(sigma.act(points), points @ rotation.T + translation, atol=1e-12)
    identity = (sigma * sigma.inverse()).coeffs
    np.testing.assert_allclose(identity, [1, 0, 0, 0, 0, 0, 0, 0], atol=1e-12)
    norm = sigma.norm()
    assert norm[0] == pytest.approx(6.25)
    assert abs(norm[1]) < 1e-12  # Study condition
    assert sigma.is_displacement()
    np.testing.assert_allclose((sigma.conjugate() * sigma).coeffs[1:], 0, atol=1e-12)


def test_vectorised_over_batches(rng):
    angles = rng.uniform(-np.pi, np.pi, 5)
    batch = DualQuaternion(np.stack([np.r_[axis_angle_quaternion([0, 0, 1], t), np.zeros(4)] for t in angles]))
    assert batch.shape == (5,)
    expected = np.array([rot_z(t) for t in angles])
    np.testing.assert_allclose(batch.to_matrix(), expected, atol=1e-15)
    np.testing.assert_allclose((batch * batch.inverse()).coeffs[:, 0], 1.0)
    np.testing.assert_allclose(batch.act(np.array([1.0, 0, 0])), expected[:, :3, 0], atol=1e-15)


def test_bad_input_is_named():
    with pytest.raises(ValueError, match="8 coefficients"):
        DualQuaternion([1, 0, 0])
    with pytest.raises(ZeroDivisionError, match="zero primal"):
        DualQuaternion([0, 0, 0, 0, 1, 0, 0, 0]).inverse()


def test_point_action_agrees_with_rational_linkages(rng):
    """Rational Linkages (the paper's package) acts on points by sigma_eps x sigma~: same as ours."""
    import rational_linkages as rl

    for _ in range(5):
        rotation, translation = random_rigid_displacement(rng)
        sigma = DualQuaternion.from_rotation_translation(rotation, translation)
        point = rng.normal(size=3)
        theirs = rl.DualQuaternion(sigma.coeffs.tolist()).act(rl.PointHomogeneous(np.r_[1.0, point]))
        np.testing.assert_allclose(theirs.normalized_euclidean(), sigma.act(point), atol=1e-12)


def test_rotation_vector_is_the_axis_times_the_angle_up_to_pi():
    """The rotation vector of Rodrigues' matrix of a known axis and angle is that axis times that angle (the closed
    form, 1e-15), from the identity to half a turn, where v and -v are the same rotation; and it agrees with
    scipy's on random rotations."""
    rng = np.random.default_rng(7)
    for angle in (0.0, 1e-14, 1e-9, 1e-5, 0.3, 2.0, np.pi - 1e-4, np.pi - 1e-9):
        for _ in range(20):
            axis = rng.normal(size=3)
            axis /= np.linalg.norm(axis)
            skew = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
            matrix = np.eye(3) + np.sin(angle) * skew + (1 - np.cos(angle)) * skew @ skew
            found = rotation_vector(matrix)
            np.testing.assert_allclose(found, angle * axis, rtol=0, atol=2e-15 + 1e-7 * (angle > 3.1))
    half_turn = rotation_vector(np.diag([1.0, -1.0, -1.0]))
    np.testing.assert_allclose(np.abs(half_turn), [np.pi, 0.0, 0.0], atol=1e-15)
    for matrix in Rotation.random(200, random_state=3).as_matrix():
        np.testing.assert_allclose(rotation_vector(matrix), Rotation.from_matrix(matrix).as_rotvec(), atol=2e-15)
