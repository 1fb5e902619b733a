"""The capsule proxy of a parametric link (:mod:`ffrf.geometry.link_capsules`): segment distances against closed
forms and a dense search, and the capsules enclosing every node of the meshed link."""

import itertools

import numpy as np
import pytest

from ffrf.geometry.joint_axes import Axis
from ffrf.geometry.link_capsules import ARM, ARM_CELLS, MOUNT, link_capsules, segment_distances
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
        assert capsules.parts.count(ARM) == 3 * ARM_CELLS**2  # the stubs' case
    assert _outside(mesh.points, capsules).max() <= 1e-9


def test_arm_capsules_stand_off_the_arm_faces_by_the_cells_half_diagonal():
    """Beside the middle of a straight arm (skew axes 110 mm apart), off the arm's faces above a cell's middle line:
    a point 2.05 mm off the thickness face and one 1.05 mm off the width face lie outside every capsule (cells of
    8 x 6 mm, radius 5 mm: 2 and 1 mm), points 1.95 and 0.95 mm off inside one; the single capsule about the whole
    section (radius 10 mm) would hold all four."""
    design = LinkDesign()
    axes = (Axis.of(((0, 0, 0), (0, 0, 1))), Axis.of(((0.11, 0, 0), (0, 1, 0))))
    capsules = link_capsules(*axes, np.array([[0, 0, 0], [0.11, 0, 0]]), design)
    arm = np.array([p == ARM for p in capsules.parts])
    start, end = capsules.starts[arm].mean(axis=0), capsules.ends[arm].mean(axis=0)
    middle = 0.5 * (start + end)
    along = (end - start) / np.linalg.norm(end - start)
    width = axes[0].direction - (axes[0].direction @ along) * along  # build_link's e2: the first axis, projected
    width /= np.linalg.norm(width)
    thickness = np.cross(along, width)
    half_w, half_t = 0.5 * design.arm_width, 0.5 * design.arm_thickness
    for face, beside, half, outside, inside in (
        (thickness, width, half_t, 2.05e-3, 1.95e-3),
        (width, thickness, half_w, 1.05e-3, 0.95e-3),
    ):
        above_a_cell = middle + 0.5 * (half_w if beside is width else half_t) * beside  # over a cell's middle line
        assert _outside((above_a_cell + (half + outside) * face)[None], capsules)[0] > 0.0
        assert _outside((above_a_cell + (half + inside) * face)[None], capsules)[0] <= 0.0


def test_the_capsule_kernel_agrees_with_the_numpy_closest_points():
    """``capsule_clearances`` (numba) against ``segment_distances`` (numpy) on random segments, with degenerate ones
    (points), parallel ones and crossing ones among them."""
    from ffrf.geometry.capsule_kernels import capsule_clearances

    rng = np.random.default_rng(3)
    m, k = 5, 12
    starts = rng.normal(size=(m, k, 3))
    ends = starts + rng.normal(size=(m, k, 3))
    ends[:, 0] = starts[:, 0]  # a point
    ends[:, 1] = starts[:, 1] + 0.5 * (ends[:, 2] - starts[:, 2])  # parallel to capsule 2
    starts[:, 3], ends[:, 3] = (-1.0, 0.0, 0.0), (1.0, 0.0, 0.0)  # crossing capsule 4's segment at the origin
    starts[:, 4], ends[:, 4] = (0.0, -1.0, 0.0), (0.0, 1.0, 0.0)
    radii = rng.uniform(0.0, 0.2, k)
    first, second = (np.array(v, dtype=np.int64) for v in zip(*itertools.combinations(range(k), 2), strict=True))
    kernel = capsule_clearances(starts, ends, radii, first, second)
    numpy = (
        segment_distances(starts[:, first], ends[:, first], starts[:, second], ends[:, second])
        - radii[first]
        - radii[second]
    )
    np.testing.assert_allclose(kernel, numpy, rtol=0.0, atol=1e-13)
