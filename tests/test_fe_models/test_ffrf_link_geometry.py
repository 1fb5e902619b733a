"""Parametric Bennett links: interfaces, housing offsets, mounting block, determinism, errors."""

from __future__ import annotations

import numpy as np
import pytest

from ffrf import GeometryError, LinkDesign
from ffrf.fe.fe_model import FEModel
from ffrf.fe.interfaces import interface_from_group, interface_in_cylinder
from ffrf.fe.materials import PLA
from ffrf.geometry.joint_axes import Axis, common_normal_feet
from ffrf.geometry.link_geometry import mesh_link
from ffrf.mesh.tet_mesh import check_mesh, quality_summary
from ffrf.paper.axes import paper_link_axes

H = 0.006  # coarse on purpose: tests check geometry, not accuracy
DESIGN = LinkDesign()


@pytest.fixture(scope="module")
def links():
    meshed = {}
    for i in range(4):
        a, b, names = paper_link_axes(i)
        meshed[i] = mesh_link(a, b, h=H, names=names, mount=i == 0, name=f"link{i}")
    return meshed


def axial_and_radial(points, axis: Axis, origin):
    rel = points - origin
    t = rel @ axis.direction
    return t, np.linalg.norm(rel - np.outer(t, axis.direction), axis=1)


def test_meshes_are_sound_and_named(links):
    for i, (mesh, _geometry) in links.items():
        check_mesh(mesh)
        expected = {f"joint{(i - 1) % 4}", f"joint{i}"} | ({"mount"} if i == 0 else set())
        assert set(mesh.groups) == expected
        quality = quality_summary(mesh)
        assert quality.min_quality > 0.02 and quality.mean_quality > 0.6
    assert links[1][1].length == pytest.approx(0.11) and links[2][1].length == pytest.approx(0.22)


def test_bores_lie_on_their_axes_with_recorded_offsets(links):
    s = DESIGN.housing_offset
    assert s >= DESIGN.housing_length / 2
    for mesh, geometry in links.values():
        for k, (axis, name) in enumerate(zip(geometry.axes, geometry.interface_names, strict=True)):
            foot = geometry.joint_points[k]
            t, r = axial_and_radial(mesh.points[mesh.group_nodes(name)], axis, foot)
            np.testing.assert_allclose(r, DESIGN.bore_radius, atol=1e-7)  # OCC tolerance
            offset = geometry.interface_offsets[name]
            assert offset == (s if k == 0 else -s)  # first axis at +s, second at -s
            assert t.min() == pytest.approx(offset - DESIGN.housing_length / 2, abs=1e-9)
            assert t.max() == pytest.approx(offset + DESIGN.housing_length / 2, abs=1e-9)


def test_housings_meeting_at_a_joint_do_not_overlap(links):
    """At joint i the link (i+1) material near axis h_i is on the + side, link i's on the - side."""
    for joint in range(4):
        axis = paper_link_axes(joint)[1]
        second_owner, first_owner = links[joint], links[(joint + 1) % 4]
        ranges = []
        for mesh, geometry in (second_owner, first_owner):
            foot = geometry.joint_points[list(geometry.interface_names).index(f"joint{joint}")]
            t, r = axial_and_radial(mesh.points, axis, foot)
            near = (r <= DESIGN.housing_outer_radius + 1e-9) & (np.abs(t) < 0.05)
            ranges.append((t[near].min(), t[near].max()))
        (lo_i, hi_i), (lo_next, hi_next) = ranges
        assert hi_i <= -DESIGN.axial_gap / 2 + 1e-9
        assert lo_next >= DESIGN.axial_gap / 2 - 1e-9


def test_base_link_mount_face(links):
    mesh, geometry = links[0]
    tris = mesh.groups["mount"]
    p = mesh.points[np.unique(tris)]
    distance = (p - geometry.mount_center) @ geometry.mount_normal
    np.testing.assert_allclose(distance, 0.0, atol=1e-9)
    corners = mesh.points[tris]
    area = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1).sum()
    assert area == pytest.approx(DESIGN.mount_length * DESIGN.mount_width, rel=1e-9)
    # away from the bores: the whole face is farther than a housing radius from both axes
    for axis, foot in zip(geometry.axes, geometry.joint_points, strict=True):
        assert axial_and_radial(p, axis, foot)[1].min() > DESIGN.housing_outer_radius


def test_meshing_is_deterministic():
    a, b, names = paper_link_axes(1)
    first, _ = mesh_link(a, b, h=H, names=names)
    second, _ = mesh_link(a, b, h=H, names=names)
    np.testing.assert_array_equal(first.points, second.points)
    np.testing.assert_array_equal(first.tets, second.tets)
    for name in first.groups:
        np.testing.assert_array_equal(first.groups[name], second.groups[name])


def test_misaligned_base_link_follows_its_axes():
    """alpha_3 = 91 deg: h3 turned by 1 deg about the common normal (the x-axis)."""
    alpha3 = np.radians(91.0)
    h3 = Axis((0.22, 0.0, 0.0), (0.0, -np.sin(alpha3), np.cos(alpha3)))
    h0 = paper_link_axes(0)[1]
    mesh, geometry = mesh_link(h3, h0, h=H, names=("joint3", "joint0"), mount=True)
    t, r = axial_and_radial(mesh.points[mesh.group_nodes("joint3")], h3, geometry.joint_points[0])
    np.testing.assert_allclose(r, DESIGN.bore_radius, atol=1e-9)
    assert geometry.length == pytest.approx(0.22)
    nominal = paper_link_axes(0)[0]
    _, r_nominal = axial_and_radial(mesh.points[mesh.group_nodes("joint3")], nominal, nominal.point)
    assert np.abs(r_nominal - DESIGN.bore_radius).max() > 1e-4  # really moved


def test_interfaces_by_group_and_by_cylinder_agree(links):
    mesh, geometry = links[1]
    for order in (1, 2):
        model = FEModel.from_tet_mesh(mesh, PLA, order)
        for k, name in enumerate(geometry.interface_names):
            by_group = interface_from_group(model, name)
            center = geometry.housing_centers[k]
            half = DESIGN.housing_length / 2
            by_cylinder = interface_in_cylinder(
                model, name, center, geometry.axes[k].direction, DESIGN.bore_radius, (-half, half), tol=1e-6
            )
            np.testing.assert_array_equal(by_group.nodes, by_cylinder.nodes)
            np.testing.assert_allclose(by_group.weights, by_cylinder.weights, rtol=1e-12)
            assert by_group.weights.sum() == pytest.approx(1.0)
            # Polygonal bore: area slightly below 2 pi r L
            exact = 2 * np.pi * DESIGN.bore_radius * DESIGN.housing_length
            assert 0.97 * exact < by_group.area < exact
            # By symmetry the area-weighted centre is on the axis, at the housing centre.
            np.testing.assert_allclose(by_group.weighted_center(model.nodes), center, atol=2e-4)


def test_geometry_errors():
    with pytest.raises(GeometryError, match="parallel"):
        common_normal_feet(Axis((0, 0, 0), (0, 0, 1)), Axis((0.1, 0, 0), (0, 0, 2)))
    with pytest.raises(GeometryError, match="millimetres"):
        LinkDesign(bore_radius=9.5, housing_outer_radius=16.0)
    a, b, names = paper_link_axes(1)
    with pytest.raises(GeometryError, match="suspicious units"):
        mesh_link(Axis(a.point * 1e3, a.direction), Axis(b.point * 1e3, b.direction), h=H)
    with pytest.raises(GeometryError, match="0, 1, 2 or 3"):
        paper_link_axes(4)


def test_the_arm_is_trimmed_near_the_axis_as_far_as_asked():
    """An arm that runs along its first axis (the other housing 25 mm off it, 150 mm up) keeps material within one
    gap of the housing radius of that axis beyond the default reach, 80 mm past the end face; asked to trim 200 mm,
    none is left there (but the other housing's own)."""
    first, second = ((0.0, 0.0, 0.0), (0.0, 0.0, 1.0)), ((0.025, 0.0, 0.15), (0.0, 1.0, 0.0))
    seats = [(0.0, 0.0, -DESIGN.housing_offset), (0.025, 0.0, 0.15)]
    left = {}
    for trim in (None, (0.2, None)):
        mesh, geometry = mesh_link(first, second, h=0.004, joint_points=seats, trim=trim)
        beyond = mesh.points[:, 2] - (geometry.housing_centers[0][2] + 0.5 * DESIGN.housing_length)
        # (the cut's own surface lies at R + gap: nodes on it are left)
        near_axis = (
            np.hypot(mesh.points[:, 0], mesh.points[:, 1]) < DESIGN.housing_outer_radius + DESIGN.axial_gap - 1e-6
        )
        rel = mesh.points - geometry.housing_centers[1]
        other_housing = (np.hypot(rel[:, 0], rel[:, 2]) <= DESIGN.housing_outer_radius + 1e-9) & (
            np.abs(rel[:, 1]) <= 0.5 * DESIGN.housing_length + 1e-9
        )
        left[trim is None] = beyond[near_axis & (beyond > 1e-9) & ~other_housing]
    assert left[True].size > 0 and left[True].min() == pytest.approx(0.080, abs=1e-6)
    assert left[False].size == 0


def test_a_trim_reach_must_be_positive():
    a, b, names = paper_link_axes(1)
    with pytest.raises(GeometryError, match="trim reaches"):
        mesh_link(a, b, h=H, names=names, trim=(0.0, None))
