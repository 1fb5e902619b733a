"""Inertia invariants against exact geometry, a slow but obvious computation, and Exudyn.

Exact truths: for linear tetrahedra the consistent mass integrates 1, x and
x x^T exactly (coordinates are in the P1 space), so mass, centre of mass and
inertia tensor must equal the box formulas and the closed-form tetrahedron
moments to round-off.
"""

import numpy as np
import pytest
import scipy.sparse as sp
from reduction_fixtures import (
    RHO_PLA,
    SmallFEModel,
    assemble,
    bar_model,
    end_faces,
    plate_with_bores,
    surface_area_weights,
)

from ffrf.reduction.craig_bampton import craig_bampton
from ffrf.reduction.invariants import inertia_invariants, is_isotropic_mass, nodal_tilde

FIELDS = (
    "theta",
    "reduced_mass",
    "m_phit_psi",
    "m_phit_psi_tilde",
    "m_x_tilde_psi",
    "m_x_tilde_psi_tilde",
    "m_psi_tilde_psi",
    "m_psi_tilde_psi_tilde",
)


def relative_error(a, b):
    return np.abs(np.asarray(a) - np.asarray(b)).max() / np.abs(b).max()


def rotation(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def test_box_mass_center_and_inertia_exact_in_a_moved_frame():
    """Bar 160 x 20 x 12 mm, rotated and shifted: m = rho V, chi = R c + d, J = R J_box R^T."""
    base = bar_model()
    r, d = rotation([1.0, -2.0, 0.5], 0.7), np.array([0.03, -0.01, 0.02])
    model = assemble(base.nodes @ r.T + d, base.tets)
    inv = inertia_invariants(model, craig_bampton(model, end_faces(base), 4))
    length, width, height = 0.16, 0.02, 0.012
    mass = RHO_PLA * length * width * height
    box = mass / 12 * np.diag([width**2 + height**2, length**2 + height**2, length**2 + width**2])
    assert abs(inv.mass / mass - 1) < 1e-12
    center = r @ np.array([length, width, height]) / 2 + d
    assert relative_error(inv.center_of_mass, center) < 1e-12
    assert relative_error(inv.inertia_tensor, r @ box @ r.T) < 1e-12


def tetrahedron_moments(points, tets, rho):
    """Exact mass, first and second moments of a tetrahedral solid (closed form per tetrahedron):
    int x dV = V p_mean, int x x^T dV = V/20 (sum_i p_i p_i^T + (sum_i p_i)(sum_i p_i)^T)."""
    p = points[tets]
    volume = np.abs(np.einsum("ij,ij->i", p[:, 1] - p[:, 0], np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]))) / 6
    total = p.sum(axis=1)
    second = volume[:, None, None] / 20 * (np.einsum("tia,tib->tab", p, p) + np.einsum("ta,tb->tab", total, total))
    return rho * volume.sum(), rho * (volume[:, None] * total / 4).sum(axis=0), rho * second.sum(axis=0)


def test_plate_with_bores_mass_center_and_inertia_exact():
    model, bores = plate_with_bores()
    red = craig_bampton(model, list(bores), 6, [surface_area_weights(model, b) for b in bores])
    inv = inertia_invariants(model, red)
    mass, first, second = tetrahedron_moments(model.nodes, model.tets, RHO_PLA)
    center = first / mass
    about_center = second - mass * np.outer(center, center)
    inertia = np.trace(about_center) * np.eye(3) - about_center
    assert abs(inv.mass / mass - 1) < 1e-12
    assert relative_error(inv.center_of_mass, center) < 1e-12
    assert relative_error(inv.inertia_tensor, inertia) < 1e-12
    assert relative_error(inv.theta, np.trace(second) * np.eye(3) - second) < 1e-12


def obvious_invariants(model, psi):
    """Slow but obvious: explicit 3x3 skew blocks node by node, dense products (as Exudyn's FEM.py)."""

    def skew(v):
        return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])

    def tilde(vector):
        return np.vstack([skew(vector[3 * i : 3 * i + 3]) for i in range(len(vector) // 3)])

    m = model.mass.toarray()
    n = len(model.nodes)
    phi_t = np.vstack([np.eye(3)] * n)
    x = model.nodes.reshape(-1)
    x_t = tilde(x)
    psi_t = np.hstack([tilde(psi[:, j]) for j in range(psi.shape[1])])
    return {
        "theta": x_t.T @ m @ x_t,
        "reduced_mass": psi.T @ m @ psi,
        "m_phit_psi": phi_t.T @ m @ psi,
        "m_phit_psi_tilde": phi_t.T @ m @ psi_t,
        "m_x_tilde_psi": x_t.T @ m @ psi,
        "m_x_tilde_psi_tilde": x_t.T @ m @ psi_t,
        "m_psi_tilde_psi": psi_t.T @ m @ psi,
        "m_psi_tilde_psi_tilde": psi_t.T @ m @ psi_t,
        "mass": (phi_t.T @ m @ phi_t)[0, 0],
        "center_of_mass": phi_t.T @ m @ x / (phi_t.T @ m @ phi_t)[0, 0],
    }


@pytest.fixture(scope="module")
def small():
    model = bar_model(divisions=(6, 2, 2))
    return model, craig_bampton(model, end_faces(model), 5)


@pytest.mark.parametrize("isotropic", [True, False])
def test_fast_and_general_paths_equal_obvious_computation(small, isotropic):
    model, red = small
    assert is_isotropic_mass(model.mass)
    inv = inertia_invariants(model, red, isotropic=isotropic)
    reference = obvious_invariants(model, red.basis)
    for name in FIELDS + ("center_of_mass",):
        assert getattr(inv, name).shape == np.shape(reference[name]), name
        assert relative_error(getattr(inv, name), reference[name]) < 1e-12, name
    assert abs(inv.mass / reference["mass"] - 1) < 1e-13


def test_non_isotropic_mass_uses_general_path(small):
    """A mass with x-y coupling is detected and still handled exactly."""
    model, red = small
    coupling = sp.lil_matrix(model.mass.shape)
    coupling[0, 4], coupling[4, 0] = 1e-3 * model.mass[0, 0], 1e-3 * model.mass[0, 0]
    coupled = SmallFEModel(model.nodes, sp.csr_matrix(model.mass + coupling), model.stiffness, model.tets)
    assert not is_isotropic_mass(coupled.mass)
    inv = inertia_invariants(coupled, red)
    reference = obvious_invariants(coupled, red.basis)
    for name in FIELDS:
        assert relative_error(getattr(inv, name), reference[name]) < 1e-12, name


def test_nodal_tilde_is_the_cross_product(rng):
    v, w = rng.normal(size=(5, 3)), rng.normal(size=3)
    assert np.allclose(nodal_tilde(v.reshape(-1)) @ w, np.cross(v, w).reshape(-1), atol=1e-14)


def test_invariants_equal_exudyn_object_ffrf_reduced_order_interface(small):
    from exudyn.FEM import FEMinterface, ObjectFFRFreducedOrderInterface

    model, red = small
    fem = FEMinterface()
    fem.nodes = {"Position": model.nodes}
    fem.massMatrix, fem.stiffnessMatrix = model.mass, model.stiffness
    fem.modeBasis = {"matrix": red.basis, "type": "HCBmodes"}
    exudyn = ObjectFFRFreducedOrderInterface(fem)
    inv = inertia_invariants(model, red)
    names = {
        "theta": "inertiaLocal",
        "m_phit_psi": "mPhitTPsi",
        "m_phit_psi_tilde": "mPhitTPsiTilde",
        "m_x_tilde_psi": "mXRefTildePsi",
        "m_x_tilde_psi_tilde": "mXRefTildePsiTilde",
        "m_psi_tilde_psi": "mPsiTildePsi",
        "m_psi_tilde_psi_tilde": "mPsiTildePsiTilde",
    }
    # Thresholds about 100x the largest value measured on 2026-11-24 (AMD EPYC, and under
    # OPENBLAS_CORETYPE=Sandybridge and Prescott).
    for ours, theirs in names.items():
        assert relative_error(getattr(inv, ours), getattr(exudyn, theirs)) < 7e-14, ours  # measured 6.7e-16
    assert abs(inv.mass / exudyn.totalMass - 1) < 1e-13  # measured 6.7e-16
    assert relative_error(inv.center_of_mass, exudyn.chiU) < 1e-13  # measured 6.9e-16
