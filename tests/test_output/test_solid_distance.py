"""Signed distance of two solids (ffrf.output.solid_distance, docs/formulation.md Eqs. (CL1)-(CL3)) on shapes with a
closed form: cylinders (parallel and crossing: distance d - r1 - r2 apart, depth r1 + r2 - d overlapping), a cylinder
and a box, a box face pushed into a box (depth t), a box inside a box; and the joint zone of two links that share a
joint.

Faceting: the cylinders are prisms of n sides inscribed in the circle, so a faceted radius lies between r cos(pi/n) and
r; the closed forms hold to (r1 + r2)(1 - cos(pi / n)) plus the depth's tolerance (1e-5 m). Boxes are exact."""

from __future__ import annotations

import manifold3d
import numpy as np
import pytest
import trimesh

from ffrf.errors import GeometryError
from ffrf.output.solid_distance import DEPTH_TOLERANCE, JointZone, LinkSolid, signed_distance

SIDES = 64
R1, R2 = 0.010, 0.008


def _solid(mesh: trimesh.Trimesh, name: str = "shape") -> LinkSolid:
    # Long sides split into triangles of 10 mm at most, as a tetrahedral mesh's surface has them.
    vertices, faces = trimesh.remesh.subdivide_to_size(mesh.vertices, mesh.faces, 1e-2)
    return LinkSolid(vertices, faces, name)


def _cylinder(radius: float, length: float = 0.06) -> LinkSolid:
    return _solid(trimesh.creation.cylinder(radius, length, sections=SIDES))


def _box(size: float) -> LinkSolid:
    return _solid(trimesh.creation.box((size, size, size)))


def _moved(shift, axis=None) -> np.ndarray:
    """Turned by 90 deg about ``axis`` (if any), then shifted."""
    transform = np.eye(4) if axis is None else trimesh.transformations.rotation_matrix(np.pi / 2, axis)
    transform[:3, 3] = shift
    return transform


FACETING = (R1 + R2) * (1 - np.cos(np.pi / SIDES))


@pytest.mark.parametrize("d", [0.030, 0.019])
def test_parallel_cylinders_apart_are_their_axes_distance_less_both_radii(d):
    gap = signed_distance(_cylinder(R1), _cylinder(R2), _moved([d, 0.0, 0.0]))
    assert d - R1 - R2 <= gap + 1e-12 and gap - (d - R1 - R2) <= FACETING


@pytest.mark.parametrize("axis", [None, [1.0, 0.0, 0.0]], ids=["parallel", "crossing"])
@pytest.mark.parametrize("d", [0.015, 0.012])
def test_overlapping_cylinders_are_r1_plus_r2_minus_d_deep(d, axis):
    depth = -signed_distance(_cylinder(R1), _cylinder(R2), _moved([d, 0.0, 0.0], axis))
    assert abs(depth - (R1 + R2 - d)) <= FACETING + DEPTH_TOLERANCE


def test_a_cylinder_pushed_into_a_box_face_is_as_deep_as_pushed():
    """Box of 100 mm about the origin, face at x = 0.05; a cylinder along y with its side 2 mm into the face."""
    t = 0.002
    depth = -signed_distance(_box(0.1), _cylinder(R2), _moved([0.05 + R2 - t, 0.0, 0.0], [1.0, 0.0, 0.0]))
    assert abs(depth - t) <= R2 * (1 - np.cos(np.pi / SIDES)) + DEPTH_TOLERANCE


def test_a_box_face_pushed_into_a_box_and_a_box_inside_a_box():
    big, small = _box(0.1), _box(0.04)
    assert signed_distance(big, small, _moved([0.07 - 0.003, 0.01, 0.0])) == pytest.approx(-0.003, abs=1e-12)
    assert signed_distance(big, small, _moved([0.07 + 0.004, 0.01, 0.0])) == pytest.approx(0.004, abs=1e-12)
    # Wholly inside (the surfaces never meet): every point of the small box's surface is 30 mm from the big one's.
    assert signed_distance(big, small) == pytest.approx(-0.03, abs=1e-12)
    assert signed_distance(small, big) == pytest.approx(-0.03, abs=1e-12)


def test_a_surface_that_is_not_closed_is_refused():
    box = trimesh.creation.box((0.01, 0.01, 0.01))
    with pytest.raises(GeometryError, match="not a closed, consistently oriented 2-manifold"):
        signed_distance(LinkSolid(box.vertices, box.faces[1:], "open box"), _box(0.01), _moved([0.1, 0.0, 0.0]))


# Two links that share a joint on the z axis: housings of radius 16 mm, 16 mm long, one 1 mm gap apart (the offset
# rule of ffrf.geometry.link_geometry); an arm 12 x 12 mm along x from each housing, 2 mm off the facing housing end,
# link a with a second, tall housing at x = 100 mm.
HOUSING_RADIUS, HOUSING_LENGTH, GAP = 0.016, 0.016, 0.001


def _link(lower: float, second_housing: bool) -> LinkSolid:
    housing = manifold3d.Manifold.cylinder(HOUSING_LENGTH, HOUSING_RADIUS, -1.0, 48).translate((0.0, 0.0, lower))
    arm = manifold3d.Manifold.cube((0.1, 0.012, 0.012)).translate((0.0, -0.006, lower + 0.002))
    shape = housing + arm
    if second_housing:
        shape += manifold3d.Manifold.cylinder(0.06, HOUSING_RADIUS, -1.0, 48).translate((0.1, 0.0, -0.03))
    mesh = shape.to_mesh64()
    return LinkSolid(np.asarray(mesh.vert_properties)[:, :3], np.asarray(mesh.tri_verts, dtype=np.int64))


def test_the_joint_zone_leaves_out_the_facing_housings_but_not_an_arm_through_a_housing():
    a = _link(0.5 * GAP, second_housing=True)
    b = _link(-0.5 * GAP - HOUSING_LENGTH, second_housing=False)
    centres = [[0.0, 0.0, 0.5 * (GAP + HOUSING_LENGTH)], [0.0, 0.0, -0.5 * (GAP + HOUSING_LENGTH)]]
    zone = JointZone.around_housings([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], centres, HOUSING_LENGTH, HOUSING_RADIUS, GAP)
    assert (zone.radius, zone.lower, zone.upper) == pytest.approx((0.017, -0.0165, 0.0165))
    turned = _moved([0.0, 0.0, 0.0], [0.0, 0.0, 1.0])  # b turned 90 deg about the joint: its arm along y
    # Whole solids: the facing housing ends are one gap apart, whatever the joint angle.
    assert signed_distance(a, b, turned) == pytest.approx(GAP, abs=1e-12)
    # With the zone (radius 17 mm, 16.5 mm either side): the housings and the arms' roots are left out; the closest
    # is then a's arm (from z = 2.5 mm, cut at the zone's radius) to b's housing (to z = -0.5 mm, radius 16 mm):
    # sqrt(1^2 + 3^2) mm, a little more by the faceting of b's 48-sided housing and the zone's 1 um slack.
    free = signed_distance(a, b, turned, zone)
    assert np.hypot(0.001, 0.003) < free < np.hypot(0.001 + HOUSING_RADIUS * (1 - np.cos(np.pi / 48)) + 2e-6, 0.003)
    # Not turned: b's arm runs along x through a's second housing (x = 100 mm, z from -30 to 30 mm): a clash.
    assert signed_distance(a, b, np.eye(4), zone) < -1e-3
