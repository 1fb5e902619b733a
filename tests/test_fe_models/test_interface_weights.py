"""One weighting rule for every interface selector: area weights of the boundary triangles the
selected nodes span. Truth: the area centroid and the area of a flat rectangular face, exact for
any triangulation (each triangle's weights put its load at its centroid)."""

import logging

import numpy as np
import pytest
import skfem

from ffrf.errors import InterfaceError
from ffrf.fe.fe_model import FEModel
from ffrf.fe.interfaces import boundary_triangles, interface_from_nodes, interface_from_nodes_file
from ffrf.mesh.tet_mesh import orient_positive

WIDTH, HEIGHT = 0.02, 0.01  # the x = 0 end face, metres


def graded_bar(order: int) -> FEModel:
    """A 0.1 m bar whose end faces are meshed unevenly, so equal node weights miss the face centre."""
    mesh = skfem.MeshTet.init_tensor(
        np.linspace(0, 0.1, 4), np.array([0.0, 0.003, 0.005, WIDTH]), np.array([0.0, 0.001, HEIGHT])
    )
    return FEModel.from_mesh(mesh.p.T, orient_positive(mesh.p.T, mesh.t.T), E=1e8, nu=0.3, rho=450.0, order=order)


def end_face_vertices(model: FEModel) -> np.ndarray:
    return np.flatnonzero(model.mesh.points[:, 0] < 1e-12)


@pytest.mark.parametrize("order", [1, 2])
def test_node_list_gets_area_weights(order):
    model = graded_bar(order)
    interface = interface_from_nodes(model, "face", end_face_vertices(model))
    np.testing.assert_allclose(interface.weighted_center(model.nodes), [0.0, WIDTH / 2, HEIGHT / 2], atol=1e-15)
    assert interface.area == pytest.approx(WIDTH * HEIGHT, rel=1e-14)
    equal_weights = model.nodes[end_face_vertices(model)].mean(axis=0)
    assert abs(equal_weights[1] - WIDTH / 2) > 1e-3  # the old rule would be off by millimetres here


def test_p2_node_list_includes_the_midside_nodes_of_its_triangles():
    model = graded_bar(2)
    interface = interface_from_nodes(model, "face", end_face_vertices(model))
    on_face = np.flatnonzero(np.abs(model.nodes[:, 0]) < 1e-12)  # vertices and midside nodes at x = 0
    np.testing.assert_array_equal(interface.nodes, on_face)
    corner = interface.nodes < model.n_vertices
    assert np.all(interface.weights[corner] == 0.0) and np.all(interface.weights[~corner] > 0.0)


def test_nodes_file_one_column_equals_node_list(tmp_path):
    model = graded_bar(1)
    np.savetxt(tmp_path / "face.txt", end_face_vertices(model), fmt="%d")
    from_file = interface_from_nodes_file(model, "face", tmp_path / "face.txt")
    from_list = interface_from_nodes(model, "face", end_face_vertices(model))
    np.testing.assert_array_equal(from_file.nodes, from_list.nodes)
    np.testing.assert_array_equal(from_file.weights, from_list.weights)


def test_nodes_file_second_column_gives_the_weights(tmp_path):
    model = graded_bar(1)
    nodes = end_face_vertices(model)
    weights = np.arange(1.0, len(nodes) + 1.0)
    np.savetxt(tmp_path / "face.txt", np.column_stack([nodes, weights]), fmt=["%d", "%.17g"])
    interface = interface_from_nodes_file(model, "face", tmp_path / "face.txt")
    np.testing.assert_array_equal(interface.nodes, nodes)
    np.testing.assert_allclose(interface.weights, weights / weights.sum(), rtol=1e-15)


def test_listed_node_off_the_surface_keeps_weight_zero(caplog):
    model = graded_bar(1)
    interior = [i for i in range(model.n_vertices) if i not in np.unique(boundary_triangles(model.mesh))]
    nodes = np.append(end_face_vertices(model), interior[:1])
    with caplog.at_level(logging.WARNING, logger="ffrf.fe.interfaces"):
        interface = interface_from_nodes(model, "face", nodes)
    assert "1 listed nodes lie on no spanned boundary triangle" in caplog.text
    assert interface.weights[np.searchsorted(interface.nodes, interior[0])] == 0.0
    np.testing.assert_allclose(interface.weighted_center(model.nodes), [0.0, WIDTH / 2, HEIGHT / 2], atol=1e-15)


@pytest.mark.parametrize(
    "content, message",
    [
        (None, "not found"),
        ("0 1 2\n3 4 5\n", "3 columns"),
        ("0\n1.5\n", "non-integer"),
        ("0\nabc\n", "not a table of numbers"),
        ("\n", "is empty"),
    ],
)
def test_bad_nodes_file_is_refused(tmp_path, content, message):
    model = graded_bar(1)
    path = tmp_path / "nodes.txt"
    if content is not None:
        path.write_text(content)
    with pytest.raises(InterfaceError, match=message):
        interface_from_nodes_file(model, "pad", path)


def test_nodes_spanning_no_triangle_are_refused():
    model = graded_bar(1)
    a_line = np.flatnonzero((model.mesh.points[:, 0] < 1e-12) & (model.mesh.points[:, 2] < 1e-12))
    with pytest.raises(InterfaceError, match="span no boundary triangle.*second column"):
        interface_from_nodes(model, "edge", a_line)
