"""The capsule proxy of a parametric link (:mod:`ffrf.geometry.link_capsules`): segment distances against closed
forms and a dense search, and the capsules enclosing every node of the meshed link."""

import numpy as np
import pytest

from ffrf.geometry.joint_axes import Axis
from ffrf.geometry.link_capsules import ARM, MOUNT, link_capsules, segment_distances
from ffrf.geometry.link_geometry import LinkDesign, mesh_link


def test_skew_perpendicular_segments_are_their_offset_apart():
    """Two perpendicular segments crossing over each other at height 3: the common normal's length."""
    d = segment_distances([-1, 0, 0], [1, 0, 0], [0, -1, 3], [0, 1, 3])
    assert d == pytest.approx(3.0, abs=1e-15)


def test_parallel_segments_side_by_side_and_end_to_end():
    """Parallel overlapping segments: their offset; collinear ones: the gap between the near ends."""
    side = segment_distances([0, 0, 0], [2, 0, 0], [1, 0.5, 0], [3, 0.5, 0])
    ends = segment_distances([0, 0, 0], [1, 0, 0], [3, 0, 0], [5, 0, 0])
    assert side == pytest.approx(0.5, abs=1e-15)
    assert ends == pytest.approx(2.0, abs=1e-15)


def test_point_against_segment():
    """A degenerate segment (a point) against a segment: the distance to its nearest point, either way round."""
    point, a, b = np.array([3.0, 4.0, 0.0]), np.array([0.0, 0.0, 0.0]), np.array([1.0, 0.0, 0.0])
    expected = np.hypot(2.0, 4.0)  # nearest point: the end (1, 0, 0)
    assert segment_distances(point, point, a, b) == pytest.approx(expected, abs=1e-14)
    assert segment_distances(a, b, point, point) == pytest.approx(expected, abs=1e-14)


def test_random_segments_against_a_dense_search(rng):
    """Random segment pairs: the closed form is never above a dense grid's minimum and at most its spacing below."""
    p0, p1, q0, q1 = (rng.normal(size=(60, 3)) for _ in range(4))
    closed = segment_distances(p0, p1, q0, q1)
    s = np.linspace(0.0, 1.0, 201)
    on_p = p0[:, None] + s[None, :, None] * (p1 - p0)[:, None]
    on_q = q0[:, None] + s[None, :, None] * (q1 - q0)[:, None]
    grid = np.linalg.norm(on_p[:, :, None] - on_q[:, None, :], axis=-1).min(axis=(1, 2))
    spacing = (np.linalg.norm(p1 - p0, axis=1) + np.linalg.norm(q1 - q0, axis=1)) / 200
    assert np.all(closed <= grid + 1e-12)
    assert np.all(grid - closed <= spacing)


def _outside(nodes: np.ndarray, capsules) -> np.ndarray:
    """How far each node lies outside every capsule (<= 0: inside one)."""
    d = segment_distances(nodes[:, None], nodes[:, None], capsules.starts[None], capsules.ends[None])
    return (d - capsules.radii[None]).min(axis=1)


@pytest.mark.parametrize(
    "first, second, mount",
    [
        # skew axes 110 mm apart, twisted 90 deg: a straight arm, with the mount block
        (((0, 0, 0), (0, 0, 1)), ((0.11, 0, 0), (0, 1, 0)), True),
        # joint points 100 mm apart along the first axis: the arm would run along it, so it leaves by stubs
        (((0, 0, 0), (0, 0, 1)), ((0, 0.05, 0.1), (1, 0, 0)), False),
    ],
)
def test_capsules_enclose_every_node_of_the_meshed_link(first, second, mount):
    """Every node of the meshed link lies within one of its capsules (the proxy encloses the solid)."""
    design = LinkDesign()
    axes = (Axis.of(first), Axis.of(second))
    points = np.array([axes[0].point, axes[1].point]) if not mount else None
    mesh, geometry = mesh_link(*axes, h=8e-3, design=design, mount=mount, joint_points=points)
    capsules = link_capsules(*axes, geometry.joint_points, design, mount)
    assert (ARM in capsules.parts) and ((MOUNT in capsules.parts) == mount)
    if not mount:
        assert capsules.parts.count(ARM) == 3  # the stubs' case
    assert _outside(mesh.points, capsules).max() <= 1e-9
