"""Bad input gets a clear error naming the object, the bad value and the remedy."""

from __future__ import annotations

import numpy as np
import pytest
from test_fe_models.ffrf_reference import prism_mesh

from ffrf import FEInputError, InterfaceError, Material, MaterialError, MeshError
from ffrf.fe.fe_model import FEModel
from ffrf.fe.interfaces import interface_from_nodes
from ffrf.fe.materials import PLA, RIGID
from ffrf.mesh.tet_mesh import TetMesh, check_mesh, mesh_quality, orient_positive

UNIT_TET = (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float) * 0.01, np.array([[0, 1, 2, 3]]))


def test_paper_materials():
    assert (PLA.E, PLA.nu, PLA.rho) == (1.2e9, 0.33, 450.0)
    assert (RIGID.E, RIGID.nu, RIGID.rho) == (1e15, 0.33, 1250.0)
    assert PLA.shear_modulus == pytest.approx(1.2e9 / 2.66)


@pytest.mark.parametrize(
    "kwargs, words",
    [
        (dict(E=0.0, nu=0.3, rho=1000.0), ["E=0.0", "> 0"]),
        (dict(E=-1e9, nu=0.3, rho=1000.0), ["E=-1000000000.0"]),
        (dict(E=1e9, nu=0.3, rho=0.0), ["rho=0.0", "> 0"]),
        (dict(E=1e9, nu=0.5, rho=1000.0), ["nu=0.5", "(-1, 0.5)"]),
        (dict(E=1e9, nu=-1.0, rho=1000.0), ["nu=-1.0"]),
        (dict(E=float("nan"), nu=0.3, rho=1000.0), ["not a finite number"]),
    ],
)
def test_bad_material_data(kwargs, words):
    with pytest.raises(MaterialError) as info:
        Material(name="test PLA", **kwargs)
    assert isinstance(info.value, ValueError)
    for word in words + ["test PLA"]:
        assert word in str(info.value)


def test_from_mesh_rejects_bad_material():
    points, tets = UNIT_TET
    with pytest.raises(MaterialError, match="nu=0.6"):
        FEModel.from_mesh(points, tets, E=1e9, nu=0.6, rho=450.0)


def test_inverted_element_is_reported_with_remedy():
    points, tets = UNIT_TET
    with pytest.raises(MeshError, match="inverted.*orient_positive"):
        check_mesh(TetMesh(points, tets[:, [0, 2, 1, 3]]))
    with pytest.warns(UserWarning, match="opposite node order"):  # FEModel orients a consistent mesh itself
        FEModel.from_mesh(points, tets[:, [0, 2, 1, 3]], 1e9, 0.3, 450.0)
    fixed = orient_positive(points, tets[:, [0, 2, 1, 3]])
    assert FEModel.from_mesh(points, fixed, 1e9, 0.3, 450.0).total_mass == pytest.approx(450.0 * 1e-6 / 6)


def test_degenerate_element():
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], float) * 0.01  # flat
    with pytest.raises(MeshError, match="degenerate"):
        FEModel.from_mesh(points, [[0, 1, 2, 3]], 1e9, 0.3, 450.0)


def test_disconnected_parts():
    points, tets = UNIT_TET
    two = np.vstack([points, points + [0.05, 0, 0]])
    with pytest.raises(MeshError, match="2 disconnected parts"):
        FEModel.from_mesh(two, np.vstack([tets, tets + 4]), 1e9, 0.3, 450.0)


def test_tets_sharing_only_a_vertex_are_disconnected():
    points, tets = UNIT_TET
    mirrored = -points[1:]
    with pytest.raises(MeshError, match="disconnected"):
        FEModel.from_mesh(np.vstack([points, mirrored]), np.array([[0, 1, 2, 3], [0, 5, 4, 6]]), 1e9, 0.3, 450.0)


def test_millimetres_are_suspected():
    points, tets = prism_mesh(0.2, 0.012, 0.008, 0.004)
    with pytest.raises(MeshError, match="did you pass millimetres.*unit='mm'"):
        FEModel.from_mesh(points * 1e3, tets, 1e9, 0.3, 450.0)


def test_unused_points_and_bad_indices():
    points, tets = UNIT_TET
    with pytest.raises(MeshError, match="not used"):
        FEModel.from_mesh(np.vstack([points, [[1, 1, 1]]]), tets, 1e9, 0.3, 450.0)
    with pytest.raises(MeshError, match="out of range"):
        FEModel.from_mesh(points, tets + 1, 1e9, 0.3, 450.0)
    with pytest.raises(FEInputError, match="order 3"):
        FEModel.from_mesh(points, tets, 1e9, 0.3, 450.0, order=3)


def test_mean_ratio_quality_closed_form():
    regular = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], float)
    assert mesh_quality(regular, [[0, 1, 2, 3]])[0] == pytest.approx(1.0, rel=1e-12)
    # Corner tetrahedron: V = 1/6, edges 1, 1, 1, sqrt2 x3 -> q = 12 (1/2)^(2/3) / 9
    assert mesh_quality(*UNIT_TET)[0] == pytest.approx(12 * 0.5 ** (2 / 3) / 9, rel=1e-12)


def test_check_mesh_accepts_good_mesh():
    points, tets = prism_mesh(0.02, 0.01, 0.01, 0.005)
    check_mesh(TetMesh(points, tets))


def test_empty_and_collinear_node_interfaces():
    points, tets = prism_mesh(0.02, 0.01, 0.01, 0.005)
    model = FEModel.from_mesh(points, tets, 1e9, 0.3, 450.0)
    with pytest.raises(InterfaceError, match="empty"):
        interface_from_nodes(model, "bore", [])
    edge_nodes = np.flatnonzero((np.abs(points[:, 1]) < 1e-12) & (np.abs(points[:, 2]) < 1e-12))
    assert len(edge_nodes) >= 3
    with pytest.raises(InterfaceError, match="collinear"):
        interface_from_nodes(model, "edge", edge_nodes, np.ones(len(edge_nodes)))
    with pytest.raises(InterfaceError, match="span no boundary triangle"):
        interface_from_nodes(model, "edge", edge_nodes)
    face = np.flatnonzero(np.abs(points[:, 0]) < 1e-12)
    ok = interface_from_nodes(model, "face", face)
    assert ok.weights.sum() == pytest.approx(1.0)
