"""Interface area weights against closed-form surface integrals."""

from __future__ import annotations

import numpy as np
import pytest
from test_fe_models.ffrf_reference import prism_mesh

from ffrf import InterfaceError
from ffrf.fe.fe_model import FEModel
from ffrf.fe.interfaces import boundary_triangles, interface_from_group, interface_from_triangles, interface_in_cylinder
from ffrf.mesh.tet_mesh import TetMesh

A, B, C = 0.03, 0.02, 0.01  # box [0, A] x [0, B] x [0, C]


@pytest.fixture(scope="module")
def box():
    points, tets = prism_mesh(A, B, C, 0.005)
    tris = boundary_triangles(TetMesh(points, tets))
    bottom = tris[np.all(np.abs(points[tris][:, :, 2]) < 1e-12, axis=1)]
    return points, tets, bottom


def test_boundary_triangles_cover_the_box_surface(box):
    points, tets, _ = box
    tris = boundary_triangles(TetMesh(points, tets))
    p = points[tris]
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1).sum()
    assert area == pytest.approx(2 * (A * B + B * C + A * C), rel=1e-12)


def test_p1_weights_integrate_linear_fields_exactly(box):
    """area/3 per vertex is the exact integral of linear fields: mean of x over z = 0 is A/2."""
    points, tets, bottom = box
    model = FEModel.from_mesh(points, tets, 1e9, 0.3, 1000.0, order=1, groups={"bottom": bottom})
    face = interface_from_group(model, "bottom")
    x, y = model.nodes[face.nodes, 0], model.nodes[face.nodes, 1]
    assert face.area == pytest.approx(A * B, rel=1e-12)
    assert face.weights.sum() == pytest.approx(1.0, rel=1e-14)
    assert face.weights @ x == pytest.approx(A / 2, rel=1e-12)
    assert face.weights @ y == pytest.approx(B / 2, rel=1e-12)
    # Exudyn's rule: only triangles with all three nodes in the set count -> all nodes on z = 0.
    np.testing.assert_allclose(model.nodes[face.nodes, 2], 0.0)


def test_p2_weights_integrate_quadratic_fields_exactly(box):
    """Corner weights 0, midside weights area/3 (6-node triangle consistent load) integrate
    quadratics exactly: mean of x^2 over the face is A^2/3, of x y is A B / 4."""
    points, tets, bottom = box
    model = FEModel.from_mesh(points, tets, 1e9, 0.3, 1000.0, order=2, groups={"bottom": bottom})
    face = interface_from_group(model, "bottom")
    x, y = model.nodes[face.nodes, 0], model.nodes[face.nodes, 1]
    assert face.weights @ x**2 == pytest.approx(A**2 / 3, rel=1e-12)
    assert face.weights @ (x * y) == pytest.approx(A * B / 4, rel=1e-12)
    assert face.weights @ y**2 == pytest.approx(B**2 / 3, rel=1e-12)
    corners = face.nodes < model.n_vertices
    assert np.all(face.weights[corners] == 0.0)
    assert np.all(face.weights[~corners] > 0.0)
    # every midside node of the face is in the set, so the whole surface moves with the joint
    midside_on_face = np.flatnonzero((np.abs(model.nodes[:, 2]) < 1e-12)[model.n_vertices :]) + model.n_vertices
    np.testing.assert_array_equal(face.nodes[~corners], midside_on_face)


def test_p1_weights_are_not_exact_for_quadratics(box):
    """Sanity of the previous test: the P1 rule does differ from A^2/3 for x^2."""
    points, tets, bottom = box
    model = FEModel.from_mesh(points, tets, 1e9, 0.3, 1000.0, order=1, groups={"bottom": bottom})
    face = interface_from_group(model, "bottom")
    assert abs(face.weights @ model.nodes[face.nodes, 0] ** 2 - A**2 / 3) > 1e-7


def test_bad_interfaces(box):
    points, tets, bottom = box
    model = FEModel.from_mesh(points, tets, 1e9, 0.3, 1000.0, groups={"bottom": bottom})
    with pytest.raises(InterfaceError, match="no physical group 'bore'.*available: \\['bottom'\\]"):
        interface_from_group(model, "bore")
    with pytest.raises(InterfaceError, match="no surface triangles"):
        interface_from_triangles(model, "empty", np.zeros((0, 3), dtype=int))
    with pytest.raises(InterfaceError, match="no boundary triangle lies on the cylinder.*units"):
        interface_in_cylinder(model, "bore", (0, 0, 0), (0, 0, 1), radius=9.5, axial_extent=(-8, 8))
    with pytest.raises(InterfaceError, match="zero length"):
        interface_in_cylinder(model, "bore", (0, 0, 0), (0, 0, 0), radius=0.01, axial_extent=(0, 1))
