"""M and K against NGsolve's independent assembly on one identical mesh (the Exudyn users' route).

NGsolve's H1 space of order 2 is hierarchical (vertex hats + edge bubbles), so its
matrices are mapped to the Lagrange (nodal) basis by the exact change of basis
U_lagrange = T c before comparison; T is built from NGsolve's own point evaluation.
"""

from __future__ import annotations

import ngsolve as ng
import numpy as np
import pytest
import scipy.sparse as sp

from ffrf.fe.fe_model import FEModel
from ffrf.fe.materials import PLA
from ffrf.geometry.link_geometry import mesh_link
from ffrf.geometry.meshing import configure_meshing, gmsh_session, mesh_current_model
from ffrf.paper.axes import paper_link_axes

#: Largest relative entry difference, about 100x the largest measured over the four cases on 2026-11-24
#: (AMD EPYC; the same under OPENBLAS_CORETYPE=Sandybridge and Prescott).
K_RTOL = 5e-13  # measured 4.4e-15 (link, P2); 3.6e-16 to 4.5e-16 on the others
M_RTOL = 2e-12  # measured 2.0e-14 (cylinder, P1); 1.6e-14 to 2.0e-14 on the others


@pytest.fixture(scope="module")
def cylinder_mesh():
    with gmsh_session("cylinder") as gmsh:
        gmsh.model.occ.addCylinder(0, 0, 0, 0.005, 0.002, 0.03, 0.01)
        gmsh.model.occ.synchronize()
        configure_meshing(0.005)
        return mesh_current_model("cylinder")


@pytest.fixture(scope="module")
def link_mesh():
    first, second, names = paper_link_axes(1)
    return mesh_link(first, second, h=0.008, names=names)[0]


def _ngsolve_mesh(points, tets):
    from netgen.csg import Pnt
    from netgen.meshing import Element3D, MeshPoint
    from netgen.meshing import Mesh as NetgenMesh

    netgen_mesh = NetgenMesh(dim=3)
    ids = [netgen_mesh.Add(MeshPoint(Pnt(*p))) for p in points]
    region = netgen_mesh.AddRegion("solid", dim=3)
    for tet in tets:
        netgen_mesh.Add(Element3D(region, [ids[i] for i in tet]))
    mesh = ng.Mesh(netgen_mesh)
    assert np.allclose([v.point for v in mesh.vertices], points)  # vertex numbering preserved
    return mesh


def _ngsolve_matrices(mesh, order, material):
    """Elasticity in NGsolve's own notation: sigma = 2 mu eps + lambda tr(eps) I
    (NGsolve i-tutorials, unit-2.x linear elasticity)."""
    fes = ng.VectorH1(mesh, order=order)
    u, v = fes.TnT()
    E, nu, rho = material.E, material.nu, material.rho
    mu, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))

    def eps(w):
        return ng.Sym(ng.Grad(w))

    k = ng.BilinearForm(fes)
    k += (2 * mu * ng.InnerProduct(eps(u), eps(v)) + lam * ng.Trace(eps(u)) * ng.Trace(eps(v))) * ng.dx
    m = ng.BilinearForm(fes)
    m += rho * u * v * ng.dx(bonus_intorder=2)
    k.Assemble()
    m.Assemble()

    def to_scipy(form):
        rows, cols, values = form.mat.COO()
        return sp.csr_matrix((np.asarray(values), (np.asarray(rows), np.asarray(cols))), shape=(fes.ndof, fes.ndof))

    return fes, to_scipy(k), to_scipy(m)


def _scalar_dof_of_node(mesh, order, model):
    """NGsolve scalar H1 DOF of every ffrf node (vertices, then edge midpoints)."""
    nv = mesh.nv
    dofs = list(range(nv))
    if order == 2:
        scalar = ng.H1(mesh, order=2)
        by_pair = {}
        for edge in mesh.edges:
            pair = tuple(sorted(v.nr for v in edge.vertices))
            (dof,) = scalar.GetDofNrs(edge)
            by_pair[pair] = dof
        dofs += [by_pair[tuple(sorted(e))] for e in model.edges]
    return np.array(dofs)


def _hierarchical_to_lagrange(mesh, model, scalar_dofs):
    """T with U_lagrange = T c for the scalar order-2 space: vertex values are the vertex
    coefficients, midpoint values are (c_i + c_j)/2 + beta_e c_e. beta_e and the
    structure are checked against NGsolve's point evaluation."""
    scalar = ng.H1(mesh, order=2)
    gf = ng.GridFunction(scalar)
    nv, n_nodes = model.n_vertices, len(model.nodes)
    xs, ys, zs = model.nodes.T
    points = mesh(xs, ys, zs)
    gf.vec.FV().NumPy()[:] = 0.0
    gf.vec.FV().NumPy()[scalar_dofs[nv:]] = 1.0
    beta = gf(points)[nv:, 0]
    rows = list(range(nv)) + [nv + e for e in range(len(model.edges)) for _ in range(3)]
    cols = list(scalar_dofs[:nv]) + [
        d for e, (i, j) in enumerate(model.edges) for d in (scalar_dofs[i], scalar_dofs[j], scalar_dofs[nv + e])
    ]
    vals = [1.0] * nv + [v for e in range(len(model.edges)) for v in (0.5, 0.5, beta[e])]
    t = sp.csr_matrix((vals, (rows, cols)), shape=(n_nodes, scalar.ndof))
    coefficients = np.random.default_rng(0).standard_normal(scalar.ndof)
    gf.vec.FV().NumPy()[:] = coefficients
    np.testing.assert_allclose(gf(points)[:, 0], t @ coefficients, rtol=1e-12, atol=1e-12)
    return t


def _relative_difference(a, b):
    return abs(a - b).max() / abs(b).max()


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("which", ["cylinder_mesh", "link_mesh"])
def test_mass_and_stiffness_equal_ngsolve(request, which, order):
    tet_mesh = request.getfixturevalue(which)
    model = FEModel.from_tet_mesh(tet_mesh, PLA, order)
    mesh = _ngsolve_mesh(tet_mesh.points, tet_mesh.tets)
    fes, k_ng, m_ng = _ngsolve_matrices(mesh, order, PLA)
    scalar_dofs = _scalar_dof_of_node(mesh, order, model)
    n_scalar = fes.ndof // 3
    if order == 1:
        t_scalar = sp.identity(n_scalar, format="csr")[scalar_dofs]
    else:
        t_scalar = _hierarchical_to_lagrange(mesh, model, scalar_dofs)
    # Vector space: NGsolve blocks by component (dof = c n_scalar + d), ffrf interleaves (3 node + c).
    t_coo = t_scalar.tocoo()
    rows = np.concatenate([3 * t_coo.row + c for c in range(3)])
    cols = np.concatenate([c * n_scalar + t_coo.col for c in range(3)])
    t_full = sp.csr_matrix((np.tile(t_coo.data, 3), (rows, cols)), shape=(model.n_dofs, fes.ndof))
    # Same space, two bases: K_ng = T^T K_lagrange T (and M alike), since U_lagrange = T c.
    k_from_ffrf = t_full.T @ model.stiffness @ t_full
    m_from_ffrf = t_full.T @ model.mass @ t_full
    dk = _relative_difference(k_from_ffrf, k_ng)
    dm = _relative_difference(m_from_ffrf, m_ng)
    print(f"{which} P{order}: max relative difference K {dk:.2e}, M {dm:.2e} ({model.n_dofs} DOFs)")
    assert dk < K_RTOL
    assert dm < M_RTOL
