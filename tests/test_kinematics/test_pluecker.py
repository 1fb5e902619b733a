"""Pluecker lines: common normals against brute force, transformations against point maps."""

import numpy as np
import pytest
from kinematics_reference import random_rigid_displacement
from scipy.optimize import minimize

from kinematics import DualQuaternion, Line, angle, common_normal, distance


def test_point_direction_moment_convention():
    """m = p x l, independent of the point; the closest point to the origin is l x m."""
    line = Line.from_point_direction([1.0, 2.0, 3.0], [0.0, 0.0, 2.0])
    np.testing.assert_allclose(line.direction, [0, 0, 1])
    np.testing.assert_allclose(line.moment, np.cross([1, 2, 3], [0, 0, 1]))
    np.testing.assert_allclose(line.point, [1, 2, 0])
    shifted = Line.from_point_direction([1.0, 2.0, -7.0], [0.0, 0.0, 1.0])
    assert line.is_close(shifted)


def _squared_distance(s, l0, l1):
    """Squared distance between the point at parameter s[0] on l0 and at s[1] on l1."""
    return np.sum((l0.point_at(s[0]) - l1.point_at(s[1])) ** 2)


def test_skew_common_normal_against_brute_force(rng):
    for _ in range(10):
        l0 = Line.from_point_direction(rng.normal(size=3), rng.normal(size=3))
        l1 = Line.from_point_direction(rng.normal(size=3), rng.normal(size=3))
        result = minimize(
            _squared_distance,
            [0.0, 0.0],
            args=(l0, l1),
            method="BFGS",
            options={"gtol": 1e-12},
        )
        normal = common_normal(l0, l1)
        assert normal.kind == "skew"
        np.testing.assert_allclose(normal.foot0, l0.point_at(result.x[0]), atol=1e-6)
        np.testing.assert_allclose(normal.foot1, l1.point_at(result.x[1]), atol=1e-6)
        assert normal.distance == pytest.approx(np.sqrt(result.fun), abs=1e-9)
        # The normal is perpendicular to both lines.
        assert abs(normal.unit @ l0.direction) < 1e-12 and abs(normal.unit @ l1.direction) < 1e-12


def test_parallel_and_intersecting_lines():
    z0 = Line.from_point_direction([0, 0, 0], [0, 0, 1])
    z1 = Line.from_point_direction([0.3, 0.4, 0], [0, 0, -1])
    parallel = common_normal(z0, z1, reference=[0, 0, 2.0])
    assert parallel.kind == "parallel" and parallel.distance == pytest.approx(0.5)
    np.testing.assert_allclose(parallel.foot0, [0, 0, 2.0])
    assert angle(z0, z1) == pytest.approx(np.pi)
    x = Line.from_point_direction([0, 0, 1.5], [1, 0, 0])
    crossing = common_normal(z0, x)
    assert crossing.kind == "intersecting" and crossing.distance == 0.0
    np.testing.assert_allclose(crossing.foot0, [0, 0, 1.5], atol=1e-15)
    np.testing.assert_allclose(crossing.unit, [0, 1, 0])
    assert distance(z0, z0).__eq__(0.0)
    assert common_normal(z0, z0).kind == "coincident"


def test_dual_quaternion_embedding_and_transformation(rng):
    """sigma h sigma~ moves a line like the displacement moves its points."""
    line = Line.from_point_direction(rng.normal(size=3), rng.normal(size=3))
    assert Line.from_dual_quaternion(line.to_dual_quaternion()).is_close(line)
    rotation, translation = random_rigid_displacement(rng)
    sigma = DualQuaternion.from_rotation_translation(rotation, translation) * 3.0
    image = line.transformed(sigma)
    moved_points = sigma.act(line.point_at(np.array([-1.0, 2.0])))
    expected = Line.from_point_direction(moved_points[0], moved_points[1] - moved_points[0])
    assert image.is_close(expected, tol=1e-12)


def test_rotation_about_a_line_is_cos_plus_sin_h(rng):
    """cos(phi/2) + sin(phi/2) h rotates by phi about h (right-hand rule), fixing its points."""
    line = Line.from_point_direction([0.2, -0.1, 0.5], [0, 0, 1])
    phi = 0.9
    sigma = DualQuaternion(np.cos(phi / 2) * np.eye(8)[0] + np.sin(phi / 2) * line.to_dual_quaternion().coeffs)
    np.testing.assert_allclose(sigma.act(line.point_at(0.7)), line.point_at(0.7), atol=1e-15)
    moved = sigma.act(line.point + np.array([1.0, 0, 0]))
    np.testing.assert_allclose(moved, line.point + [np.cos(phi), np.sin(phi), 0], atol=1e-15)


def test_invalid_lines_are_rejected():
    with pytest.raises(ValueError, match="zero length"):
        Line.from_point_direction([0, 0, 0], [0, 0, 0])
    with pytest.raises(ValueError, match="Pluecker condition"):
        Line([0, 0, 1.0], [0, 0, 1.0])
    with pytest.raises(ValueError, match="NaN"):
        Line.from_point_direction([np.nan, 0, 0], [0, 0, 1])
