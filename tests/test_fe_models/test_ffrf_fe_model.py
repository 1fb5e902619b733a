"""Consistency of the FE matrices against closed-form truth."""

from __future__ import annotations

import numpy as np
import pytest
from test_fe_models.ffrf_reference import prism_mesh

from ffrf import Material
from ffrf.fe.fe_model import FEModel, rigid_body_modes
from ffrf.fe.materials import PLA
from ffrf.geometry.meshing import configure_meshing, gmsh_session, mesh_current_model
from ffrf.mesh.tet_mesh import signed_volumes

R, L = 0.02, 0.1  # solid cylinder along z, base at the origin


def cylinder_mesh(h):
    with gmsh_session("cylinder") as gmsh:
        gmsh.model.occ.addCylinder(0, 0, 0, 0, 0, L, R)
        gmsh.model.occ.synchronize()
        configure_meshing(h, elements_per_circle=0)
        return mesh_current_model(f"cylinder h={h}")


@pytest.fixture(scope="module")
def cylinder_10mm():
    return cylinder_mesh(0.01)


@pytest.mark.parametrize("order", [1, 2])
def test_rigid_body_motions_are_stress_free(cylinder_10mm, order):
    model = FEModel.from_tet_mesh(cylinder_10mm, PLA, order)
    r = rigid_body_modes(model.nodes)
    residual = np.abs(model.stiffness @ r).max(axis=0)
    scale = abs(model.stiffness).max() * np.abs(r).max(axis=0)
    assert np.all(residual / scale < 1e-10), residual / scale


@pytest.mark.parametrize("order", [1, 2])
def test_constant_strain_energy(cylinder_10mm, order):
    """u^T K u = V (lambda tr(eps)^2 + 2 mu eps:eps) for u = eps x (Timoshenko & Goodier, eq. 84);
    exact because linear fields are in the FE space."""
    model = FEModel.from_tet_mesh(cylinder_10mm, PLA, order)
    eps = np.array([[1.0, 0.3, -0.2], [0.3, -0.5, 0.1], [-0.2, 0.1, 0.7]]) * 1e-3
    u = (model.nodes @ eps.T).reshape(-1)
    mu = PLA.shear_modulus
    lam = PLA.E * PLA.nu / ((1 + PLA.nu) * (1 - 2 * PLA.nu))
    volume = signed_volumes(cylinder_10mm.points, cylinder_10mm.tets).sum()
    expected = volume * (lam * np.trace(eps) ** 2 + 2 * mu * np.sum(eps * eps))
    assert u @ model.stiffness @ u == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("order", [1, 2])
def test_vertex_strains_of_an_interpolated_field_are_exact(cylinder_10mm, order):
    """A field of the element's own degree is interpolated exactly, so the strains at the corners
    are the analytic ones there: u = A x (P1 and P2, constant strain) and, for P2, the quadratic
    u_i = B_ijk x_j x_k, whose gradient is H_ij = (B_ijk + B_ikj) x_k."""
    model = FEModel.from_tet_mesh(cylinder_10mm, PLA, order)
    rng = np.random.default_rng(7)
    a = 1e-3 * rng.standard_normal((3, 3))
    b = 1e-2 * rng.standard_normal((3, 3, 3)) if order == 2 else np.zeros((3, 3, 3))
    x = model.nodes
    u = x @ a.T + np.einsum("ijk,nj,nk->ni", b, x, x)
    corners = cylinder_10mm.points[cylinder_10mm.tets]  # (n_tets, 4, 3)
    h = a + np.einsum("ijk,tck->tcij", b + np.swapaxes(b, 1, 2), corners)
    expected = 0.5 * (h + np.swapaxes(h, -1, -2))
    strains = model.vertex_strains(u)
    assert strains.shape == (len(cylinder_10mm.tets), 4, 3, 3)
    # the quadrature points are the reference corners; their order within an element is scikit-fem's
    for tet_strains, tet_expected in zip(strains[:50], expected[:50], strict=True):
        for corner in tet_expected:
            assert np.min(np.abs(tet_strains - corner).max(axis=(1, 2))) < 1e-12 * np.abs(expected).max()


def test_matrices_symmetric_csr_and_node_layout(cylinder_10mm):
    model = FEModel.from_tet_mesh(cylinder_10mm, PLA, 2)
    for matrix in (model.mass, model.stiffness):
        assert matrix.format == "csr"
        assert abs(matrix - matrix.T).max() <= 1e-12 * abs(matrix).max()
    nv = len(cylinder_10mm.points)
    np.testing.assert_array_equal(model.nodes[:nv], cylinder_10mm.points)
    np.testing.assert_allclose(model.nodes[nv:], cylinder_10mm.points[model.edges].mean(axis=1), atol=1e-15)
    # Interleaved layout: a unit translation along y is [0, 1, 0, 0, 1, 0, ...]; its mass is m.
    t_y = np.tile([0.0, 1.0, 0.0], len(model.nodes))
    assert t_y @ model.mass @ t_y == pytest.approx(model.total_mass, rel=1e-12)
    assert np.tile([1.0, 0, 0], len(model.nodes)) @ model.mass @ t_y == pytest.approx(0.0, abs=1e-18)


@pytest.mark.parametrize("order", [1, 2])
def test_mass_is_rho_times_volume(cylinder_10mm, order):
    model = FEModel.from_tet_mesh(cylinder_10mm, PLA, order)
    volume = np.sum(np.abs(signed_volumes(cylinder_10mm.points, cylinder_10mm.tets)))
    assert model.total_mass == pytest.approx(PLA.rho * volume, rel=1e-12)


@pytest.mark.parametrize("order", [1, 2])
def test_box_inertia_is_exact(order):
    """A box is meshed exactly, so mass, centre and inertia are exact:
    J_xx = m (b^2 + c^2) / 12 (Goldstein, Classical Mechanics, table of moments)."""
    a, b, c = 0.06, 0.02, 0.01
    points, tets = prism_mesh(a, b, c, 0.005)
    steel = Material(210e9, 0.3, 7850.0, "steel")
    model = FEModel.from_mesh(points + [0.01, -0.02, 0.03], tets, steel.E, steel.nu, steel.rho, order=order)
    m = steel.rho * a * b * c
    assert model.total_mass == pytest.approx(m, rel=1e-12)
    np.testing.assert_allclose(model.center_of_mass, [0.01 + a / 2, -0.02 + b / 2, 0.03 + c / 2], rtol=1e-12)
    expected = m / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    np.testing.assert_allclose(model.inertia_tensor, expected, rtol=1e-12, atol=1e-12 * expected.max())


def _cylinder_errors(h):
    model = FEModel.from_tet_mesh(cylinder_mesh(h), PLA, 1)
    m = PLA.rho * np.pi * R * R * L
    # Solid cylinder about its centre: J_xx = J_yy = m (3 R^2 + L^2) / 12, J_zz = m R^2 / 2.
    j = np.diag([m * (3 * R * R + L * L) / 12] * 2 + [m * R * R / 2])
    mass_error = abs(model.total_mass - m) / m
    inertia_error = np.abs(model.inertia_tensor - j).max() / j.max()
    com_error = np.abs(model.center_of_mass - [0, 0, L / 2]).max() / L
    return mass_error, inertia_error, com_error


def test_cylinder_inertia_converges_to_analytic():
    errors = [_cylinder_errors(h) for h in (0.01, 0.005)]
    print("cylinder mass/inertia relative errors (h = 10, 5 mm):", errors)
    (m10, j10, c10), (m5, j5, c5) = errors
    assert m10 < 0.03 and j10 < 0.05  # polygonal boundary: O(h^2) error
    assert m5 < m10 / 2.5 and j5 < j10 / 2.5  # and it converges at about second order
    assert max(c10, c5) < 1e-3


@pytest.mark.parametrize("order", [1, 2])
def test_the_matrices_are_scikit_fems_own_vector_forms(cylinder_10mm, order):
    """The element matrices formed for all elements at once (``docs/fe_models.md``) against scikit-fem's own vector
    forms, ``linear_elasticity(lame_parameters(E, nu))`` and ``rho u.v`` on ``ElementVector``, taken to our DOF
    layout: equal to round-off (measured 3e-16 to 6e-16 of the largest entry)."""
    from skfem import Basis, BilinearForm, ElementTetP1, ElementTetP2, ElementVector, MeshTet, asm
    from skfem.helpers import dot
    from skfem.models.elasticity import lame_parameters, linear_elasticity

    model = FEModel.from_tet_mesh(cylinder_10mm, PLA, order)
    mesh = MeshTet(np.ascontiguousarray(cylinder_10mm.points.T), np.ascontiguousarray(cylinder_10mm.tets.T))
    basis = Basis(mesh, ElementVector(ElementTetP1() if order == 1 else ElementTetP2()), intorder=2 * order)
    layout = np.concatenate([basis.nodal_dofs.T] + ([basis.edge_dofs.T] if order == 2 else [])).reshape(-1)

    @BilinearForm
    def mass(u, v, w):
        return PLA.rho * dot(u, v)

    stiffness = asm(linear_elasticity(*lame_parameters(PLA.E, PLA.nu)), basis).tocsr()[layout][:, layout]
    for ours, theirs in ((model.stiffness, stiffness), (model.mass, asm(mass, basis).tocsr()[layout][:, layout])):
        print("largest difference", abs(ours - theirs).max() / abs(theirs).max())
        assert abs(ours - theirs).max() <= 1e-14 * abs(theirs).max()
