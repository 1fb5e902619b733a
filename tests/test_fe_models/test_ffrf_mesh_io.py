"""Mesh import (meshio formats, STL via gmsh) and .vtu export."""

from __future__ import annotations

import meshio
import numpy as np
import pytest
from test_fe_models.ffrf_reference import prism_mesh

from ffrf import MeshError
from ffrf.geometry.link_geometry import mesh_link
from ffrf.geometry.meshing import mesh_stl
from ffrf.mesh.tet_mesh import TetMesh, read_mesh, write_vtu
from ffrf.paper.axes import paper_link_axes


@pytest.fixture(scope="module")
def link_with_msh(tmp_path_factory):
    path = tmp_path_factory.mktemp("msh") / "link1.msh"
    a, b, names = paper_link_axes(1)
    mesh, _ = mesh_link(a, b, h=0.008, names=names, msh_path=path)
    return mesh, path


def test_gmsh_file_round_trip_keeps_groups(link_with_msh):
    mesh, path = link_with_msh
    loaded = read_mesh(path)
    np.testing.assert_allclose(loaded.points, mesh.points)
    np.testing.assert_array_equal(loaded.tets, mesh.tets)
    assert set(loaded.groups) == set(mesh.groups)
    for name in mesh.groups:
        np.testing.assert_array_equal(np.sort(loaded.groups[name], axis=None), np.sort(mesh.groups[name], axis=None))


def test_vtu_round_trip_with_groups_and_point_data(link_with_msh, tmp_path):
    mesh, _ = link_with_msh
    displacement = np.random.default_rng(1).standard_normal((len(mesh.points), 3))
    path = write_vtu(tmp_path / "link.vtu", mesh, {"displacement": displacement})
    raw = meshio.read(path)
    np.testing.assert_allclose(raw.point_data["displacement"], displacement)
    for name in mesh.groups:
        flag = raw.point_data[f"group:{name}"]
        np.testing.assert_array_equal(np.flatnonzero(flag), mesh.group_nodes(name))
    loaded = read_mesh(path)
    np.testing.assert_array_equal(loaded.tets, mesh.tets)
    assert set(loaded.groups) == set(mesh.groups)


def test_millimetre_input_is_scaled(tmp_path):
    points, tets = prism_mesh(0.02, 0.01, 0.01, 0.005)
    path = tmp_path / "box.inp"
    meshio.write(path, meshio.Mesh(points * 1e3, [("tetra", tets)]))
    loaded = read_mesh(path, unit="mm")
    np.testing.assert_allclose(loaded.points, points, atol=1e-12)
    assert loaded.volume == pytest.approx(0.02 * 0.01 * 0.01, rel=1e-12)
    with pytest.raises(MeshError, match="either unit"):
        read_mesh(path, unit="mm", scale=1e-3)


def test_surface_only_files_are_rejected(tmp_path):
    path = tmp_path / "surface.vtu"
    meshio.write(path, meshio.Mesh(np.eye(3), [("triangle", np.array([[0, 1, 2]]))]))
    with pytest.raises(MeshError, match="no tetrahedra"):
        read_mesh(path)
    with pytest.raises(MeshError, match="mesh_stl"):
        read_mesh(tmp_path / "part.stl")


def _write_box_stl(path, size_mm):
    """Closed triangulated box surface (12 triangles, outward normals) in millimetres."""
    a, b, c = size_mm
    corners = np.array([[x, y, z] for z in (0, c) for y in (0, b) for x in (0, a)], float)
    faces = np.array(
        [
            [0, 2, 1],
            [1, 2, 3],
            [4, 5, 6],
            [5, 7, 6],
            [0, 1, 4],
            [1, 5, 4],
            [2, 6, 3],
            [3, 6, 7],
            [0, 4, 2],
            [2, 4, 6],
            [1, 3, 5],
            [3, 7, 5],
        ]
    )
    meshio.write(path, meshio.Mesh(corners, [("triangle", faces)]), file_format="stl")


@pytest.mark.parametrize("remesh_surface", [True, False])
def test_stl_in_millimetres_is_filled_with_tetrahedra(tmp_path, remesh_surface):
    path = tmp_path / "box.stl"
    _write_box_stl(path, (40.0, 20.0, 10.0))
    mesh = mesh_stl(path, h=0.005, unit="mm", remesh_surface=remesh_surface)
    assert isinstance(mesh, TetMesh)
    assert mesh.volume == pytest.approx(0.04 * 0.02 * 0.01, rel=1e-9)
    assert np.ptp(mesh.points, axis=0) == pytest.approx([0.04, 0.02, 0.01], rel=1e-9)
    assert len(mesh.tets) > 50


def test_missing_stl_file(tmp_path):
    with pytest.raises(MeshError, match="does not exist"):
        mesh_stl(tmp_path / "nope.stl")
