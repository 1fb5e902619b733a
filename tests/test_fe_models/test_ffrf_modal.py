"""Free-free and clamped modes of a meshed link: rigid-body modes left out, eigenproblem satisfied."""

from __future__ import annotations

import numpy as np
import pytest

from ffrf import FEInputError
from ffrf.fe.fe_model import FEModel, rigid_body_modes
from ffrf.fe.materials import PLA
from ffrf.fe.modal import clamped_modes
from ffrf.geometry.link_geometry import mesh_link
from ffrf.paper.axes import paper_link_axes
from ffrf.reduction.free_free import free_free_basis


@pytest.fixture(scope="module")
def link_model():
    a, b, names = paper_link_axes(2)
    mesh, _ = mesh_link(a, b, h=0.006, names=names)
    return FEModel.from_tet_mesh(mesh, PLA, 2)


def test_elastic_modes_are_m_orthogonal_to_the_rigid_motions(link_model):
    modes = free_free_basis(link_model, 6)
    assert modes.basis.shape == (link_model.n_dofs, 6)
    assert len(modes.rigid_body_eigenvalues) == 6
    r = rigid_body_modes(link_model.nodes)
    m = link_model.mass
    # Elastic modes are M-orthonormal and M-orthogonal to every rigid motion.
    np.testing.assert_allclose(modes.basis.T @ (m @ modes.basis), np.eye(6), atol=1e-8)
    assert np.abs(modes.basis.T @ (m @ r)).max() < 1e-8 * np.sqrt(np.abs(r.T @ (m @ r)).max())
    assert np.all(np.diff(modes.frequencies_hz) >= 0) and modes.frequencies_hz[0] > 1.0


def test_flexible_eigenpairs_satisfy_the_eigenproblem(link_model):
    modes = free_free_basis(link_model, 3)
    for f, phi in zip(modes.frequencies_hz, modes.basis.T, strict=True):
        omega_sq = (2 * np.pi * f) ** 2
        residual = link_model.stiffness @ phi - omega_sq * (link_model.mass @ phi)
        assert np.linalg.norm(residual) < 1e-8 * np.linalg.norm(link_model.stiffness @ phi)


def test_clamped_modes_are_zero_on_fixed_dofs_and_above_free_free(link_model):
    fixed = np.flatnonzero(np.repeat(link_model.nodes[:, 0] > link_model.nodes[:, 0].max() - 0.01, 3))
    clamped = clamped_modes(link_model, fixed, n_modes=2)
    assert np.all(clamped.shapes[fixed] == 0.0)
    assert clamped.frequencies[0] > 0.0
    with pytest.raises(FEInputError, match="at least one fixed DOF"):
        clamped_modes(link_model, [], 2)
