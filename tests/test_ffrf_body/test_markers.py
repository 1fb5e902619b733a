"""Markers in O(m) against their node-by-node definitions."""

import numpy as np
import pytest
from body_fixtures import bar_model, random_state

from ffrf.body.euler_parameters import rotation_matrix
from ffrf.system.markers import exp_so3, frame_marker, node_marker, rigid_interface_marker


@pytest.fixture(scope="module")
def bar():
    model = bar_model()
    end = np.flatnonzero(model.nodes[:, 0] > 0.2 - 1e-9)
    return model, end


def test_interface_position_is_weighted_mean_of_moving_nodes(bar, rng):
    model, end = bar
    basis = rng.normal(size=(3 * model.nodes.shape[0], 5))
    weights = rng.uniform(0.5, 1.5, end.size)
    weights /= weights.sum()
    marker = rigid_interface_marker(0, model.nodes, basis, end, weights)
    r, p, zeta, _, _, _ = random_state(rng, 5)
    q = np.r_[r, p, zeta]
    moved = r + (model.nodes + (basis @ zeta).reshape(-1, 3)) @ rotation_matrix(p).T
    np.testing.assert_allclose(marker.position(q), weights @ moved[end], atol=1e-14)


def test_interface_rotation_is_exact_for_rigid_interface_motion(bar, rng):
    """A mode that moves the interface nodes rigidly (small rotation theta about the weighted centre
    plus a translation t) gives exactly theta and t, whatever it does elsewhere."""
    model, end = bar
    n = model.nodes.shape[0]
    theta, shift = rng.normal(size=3), rng.normal(size=3)
    weights = np.full(end.size, 1.0 / end.size)
    centre = weights @ model.nodes[end]
    mode = rng.normal(size=(n, 3))
    mode[end] = np.cross(theta, model.nodes[end] - centre) + shift
    basis = np.column_stack([rng.normal(size=3 * n), mode.reshape(-1)])
    marker = rigid_interface_marker(0, model.nodes, basis, end, weights)
    np.testing.assert_allclose(marker.rotation_modes[:, 1], theta, atol=1e-12)
    np.testing.assert_allclose(marker.position_modes[:, 1], shift, atol=1e-12)


def test_exponential_map_and_frame_markers(rng):
    theta = rng.normal(size=3)
    rotation = exp_so3(theta)
    np.testing.assert_allclose(rotation @ rotation.T, np.eye(3), atol=1e-14)
    np.testing.assert_allclose(rotation @ theta, theta, atol=1e-14)  # the axis is fixed
    assert np.arccos((np.trace(rotation) - 1) / 2) == pytest.approx(np.linalg.norm(theta) % (2 * np.pi))
    np.testing.assert_allclose(
        exp_so3(np.array([1e-9, 0, 0])), np.eye(3) + 1e-9 * np.array([[0, 0, 0], [0, 0, -1], [0, 1, 0]]), atol=1e-20
    )
    marker = frame_marker(0, 2, point=[1.0, 0, 0])
    q = np.r_[[0.0, 0, 1], [np.cos(0.5), 0, 0, np.sin(0.5)], [3.0, 4.0]]
    np.testing.assert_allclose(marker.position(q), [np.cos(1.0), np.sin(1.0), 1.0], atol=1e-15)


def test_position_jacobian_against_finite_differences(bar, rng):
    model, end = bar
    basis = rng.normal(size=(3 * model.nodes.shape[0], 4))
    for marker in (rigid_interface_marker(0, model.nodes, basis, end), node_marker(0, model.nodes, basis, 7)):
        r, p, zeta, _, _, _ = random_state(rng, 4)
        q = np.r_[r, p, zeta]
        h = 1e-6
        numeric = np.array(
            [(marker.position(q + h * e) - marker.position(q - h * e)) / (2 * h) for e in np.eye(q.size)]
        ).T
        np.testing.assert_allclose(marker.position_jacobian(q), numeric, atol=1e-8)


def test_bad_interfaces_are_named(bar):
    model, end = bar
    basis = np.zeros((3 * model.nodes.shape[0], 1))
    with pytest.raises(ValueError, match="no nodes"):
        rigid_interface_marker(0, model.nodes, basis, [], name="bore_1")
    with pytest.raises(ValueError, match="collinear"):
        line = np.flatnonzero((model.nodes[:, 1] < 1e-9) & (model.nodes[:, 2] < 1e-9))
        rigid_interface_marker(0, model.nodes, basis, line)
    with pytest.raises(ValueError, match="sum to 1"):
        rigid_interface_marker(0, model.nodes, basis, end, np.ones(end.size))


def test_marker_history_and_body_frame_offsets(bar, rng):
    """``marker_history`` over rows equals the single-state evaluations; ``attach_joint_point``
    puts the joint point at the given body point in the body frame ("body": the marker moves,
    no joint offset) or keeps the marker and returns the offset ("marker")."""
    from ffrf.system.markers import attach_joint_point, marker_history

    model, end = bar
    basis = rng.normal(size=(3 * model.nodes.shape[0], 4))
    marker = rigid_interface_marker(0, model.nodes, basis, end)
    rows = np.array([np.r_[s[0], s[1], s[2]] for s in (random_state(rng, 4) for _ in range(3))])
    positions, orientations = marker_history(marker, rows)
    for q, p, a in zip(rows, positions, orientations, strict=True):
        np.testing.assert_allclose(p, marker.position(q), atol=1e-15)
        np.testing.assert_allclose(a, marker.orientation(q), atol=1e-15)
    point = marker.point + np.array([0.0, 0.0, 0.0085])
    moved, offset = attach_joint_point(marker, point, "body")
    assert np.all(offset == 0) and np.allclose(moved.point, point) and moved.name == marker.name
    q = rows[0]
    np.testing.assert_allclose(
        moved.position(q) - marker.position(q), rotation_matrix(q[3:7]) @ (point - marker.point), atol=1e-15
    )
    same, offset = attach_joint_point(marker, point, "marker")
    assert same is marker and np.allclose(offset, point - marker.point)
    with pytest.raises(ValueError, match="joint_offsets"):
        attach_joint_point(marker, point, "world")
