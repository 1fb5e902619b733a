"""Meshes in the opposite node order are a convention and are fixed; a mix of orientations is refused."""

import numpy as np
import pytest
import skfem

from ffrf.errors import MeshError
from ffrf.fe.fe_model import FEModel
from ffrf.fe.materials import Material
from ffrf.mesh.tet_mesh import TetMesh, orient_positive, signed_volumes

STEEL = Material(2.1e11, 0.3, 7850.0, name="steel")


def positive_mesh() -> TetMesh:
    mesh = skfem.MeshTet.init_tensor(np.linspace(0, 0.1, 4), np.linspace(0, 0.02, 3), np.linspace(0, 0.01, 2))
    return TetMesh(mesh.p.T, orient_positive(mesh.p.T, mesh.t.T), name="bar")


@pytest.mark.parametrize("order", [1, 2])
def test_all_inverted_mesh_is_reoriented(order):
    good = positive_mesh()
    flipped = TetMesh(good.points, good.tets[:, [0, 1, 3, 2]], name="bar")
    assert np.all(signed_volumes(flipped.points, flipped.tets) < 0.0)
    with pytest.warns(UserWarning, match="opposite node order"):
        model = FEModel.from_tet_mesh(flipped, STEEL, order)
    reference = FEModel.from_tet_mesh(good, STEEL, order)
    np.testing.assert_array_equal(model.mesh.tets, good.tets)
    assert abs(model.mass - reference.mass).max() <= 1e-15 * abs(reference.mass).max()
    assert abs(model.stiffness - reference.stiffness).max() <= 1e-15 * abs(reference.stiffness).max()
    assert model.total_mass == pytest.approx(7850.0 * 0.1 * 0.02 * 0.01, rel=1e-13)


def test_mixed_orientation_is_refused():
    good = positive_mesh()
    tets = good.tets.copy()
    tets[[4, 9]] = tets[[4, 9]][:, [0, 1, 3, 2]]
    centroid = good.points[tets[4]].mean(axis=0)
    with pytest.raises(
        MeshError,
        match=r"2 of 36 tetrahedra are inverted.*first \[4, 9\] at \[\[" + f"{centroid[0]:g}".replace(".", r"\."),
    ):
        FEModel.from_tet_mesh(TetMesh(good.points, tets, name="bar"), STEEL, 1)
