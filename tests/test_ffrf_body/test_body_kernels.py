"""FFRF body kernels (O(m^2), from modal moments) against plain numpy built from the full nodal model."""

import numpy as np
import pytest
from body_fixtures import bar_model, nodal_jacobian, nodal_velocities, random_state

from ffrf.body.body_kernels import gravity_force, mass_matrix, quadratic_velocity
from ffrf.body.euler_parameters import g_bar, rotation_derivative, rotation_matrix, transposed_rotation_derivative
from ffrf.body.modal_moments import modal_moments
from ffrf.numerics.small_linalg import skew


@pytest.fixture(scope="module")
def body():
    model = bar_model()
    rng = np.random.default_rng(5)
    basis = rng.normal(size=(3 * model.nodes.shape[0], 6))  # any basis: the kernels must not care
    return model, basis, modal_moments(model.nodes, model.mass, basis)


def test_euler_parameter_identities(rng):
    p = rng.normal(size=4)
    p /= np.linalg.norm(p)
    a = rotation_matrix(p)
    np.testing.assert_allclose(a @ a.T, np.eye(3), atol=1e-15)
    assert np.linalg.det(a) == pytest.approx(1.0)
    np.testing.assert_allclose(g_bar(p) @ p, 0, atol=1e-15)
    pd = rng.normal(size=4)
    np.testing.assert_allclose(g_bar(pd) @ pd, 0, atol=1e-14)  # so omega_dot = G p_dd
    # Ad = A omega~ with omega = G pd (body-frame angular velocity), by central differences.
    pd -= p * (p @ pd)
    h = 1e-6
    a_dot = (rotation_matrix(p + h * pd) - rotation_matrix(p - h * pd)) / (2 * h)
    np.testing.assert_allclose(a_dot, a @ skew(g_bar(p) @ pd), atol=1e-9)
    u = rng.normal(size=3)
    jac = np.array([(rotation_matrix(p + h * e) @ u - rotation_matrix(p - h * e) @ u) / (2 * h) for e in np.eye(4)]).T
    np.testing.assert_allclose(rotation_derivative(p, u), jac, atol=1e-9)
    jac_t = np.array(
        [(rotation_matrix(p + h * e).T @ u - rotation_matrix(p - h * e).T @ u) / (2 * h) for e in np.eye(4)]
    ).T
    np.testing.assert_allclose(transposed_rotation_derivative(p, u), jac_t, atol=1e-9)


def test_modal_moments_reproduce_mass_and_reduced_mass(body):
    model, basis, moments = body
    assert moments.mass == pytest.approx(7850.0 * 0.2 * 0.02 * 0.01, rel=1e-12)
    np.testing.assert_allclose(moments.reduced_mass, basis.T @ (model.mass @ basis), rtol=1e-12)


def test_mass_matrix_equals_nodal_projection(body, rng):
    model, basis, mm = body
    _, p, zeta, _, _, _ = random_state(rng, basis.shape[1])
    zeta = zeta * 1e3  # large deformation: every zeta-dependent term matters
    lmat = nodal_jacobian(model.nodes, basis, p, zeta)
    reference = lmat.T @ (model.mass @ lmat)
    ours = mass_matrix(p, zeta, mm.mass, mm.s0, mm.s1, mm.x2, mm.c, mm.d, mm.reduced_mass)
    np.testing.assert_allclose(ours, reference, atol=1e-12 * np.abs(reference).max())


def test_quadratic_velocity_equals_nodal_inertia_forces(body, rng):
    """Q_v = -L^T M a_q with a_q the nodal acceleration at q_dd = 0 (central difference of rd along qd)."""
    model, basis, mm = body
    r, p, zeta, r_dot, pd, zetad = random_state(rng, basis.shape[1])
    zeta *= 1e3
    h = 1e-5

    def velocities(shift):
        return nodal_velocities(model.nodes, basis, r_dot, p + shift * pd, zeta + shift * zetad, pd, zetad)

    accel = (velocities(h) - velocities(-h)) / (2 * h)
    reference = -nodal_jacobian(model.nodes, basis, p, zeta).T @ (model.mass @ accel)
    ours = quadratic_velocity(p, zeta, pd, zetad, mm.s0, mm.s1, mm.x2, mm.c, mm.d)
    np.testing.assert_allclose(ours, reference, atol=1e-7 * np.abs(reference).max())


@pytest.mark.parametrize("exact", [True, False])
def test_gravity_equals_consistent_nodal_load(body, rng, exact):
    model, basis, mm = body
    _, p, zeta, _, _, _ = random_state(rng, basis.shape[1])
    zeta *= 1e3
    g = np.array([0.0, 0.0, -9.81])
    lmat = nodal_jacobian(model.nodes, basis, p, zeta)
    reference = lmat.T @ (model.mass @ np.tile(g, model.nodes.shape[0]))
    ours = gravity_force(p, zeta, g, mm.mass, mm.s0, mm.s1, exact)
    scale = np.abs(reference).max()
    if exact:
        np.testing.assert_allclose(ours, reference, atol=1e-12 * scale)
    else:  # Exudyn's simplification drops G^T (S1 zeta)~ A^T g from the rotational row only
        missing = g_bar(p).T @ (skew(mm.s1 @ zeta) @ (rotation_matrix(p).T @ g))
        np.testing.assert_allclose(ours[3:7] + missing, reference[3:7], atol=1e-12 * scale)
        np.testing.assert_allclose(
            ours[[0, 1, 2, *range(7, ours.size)]], reference[[0, 1, 2, *range(7, ours.size)]], atol=1e-12 * scale
        )
        assert np.abs(missing).max() > 1e-6 * scale


def test_complex_step_jacobians_against_finite_differences(body, rng):
    from ffrf.body.flexible_body import FlexibleBody

    model, basis, mm = body
    kred = basis.T @ (model.stiffness @ basis)
    flex = FlexibleBody("bar", mm, kred, 0.005 * kred)
    r, p, zeta, r_dot, pd, zetad = random_state(rng, basis.shape[1])
    q, qd = np.r_[r, p, zeta * 1e3], np.r_[r_dot, pd, zetad]
    qdd = rng.normal(size=q.size)
    g = np.array([0.0, 0.0, -9.81])
    jac_q, jac_qd = flex.jacobians(q, qd, qdd, g)
    h = 1e-6
    fd_q = np.array(
        [
            (flex.residual(q + h * e, qd, qdd, g) - flex.residual(q - h * e, qd, qdd, g)) / (2 * h)
            for e in np.eye(q.size)
        ]
    ).T
    fd_qd = np.array(
        [
            (flex.residual(q, qd + h * e, qdd, g) - flex.residual(q, qd - h * e, qdd, g)) / (2 * h)
            for e in np.eye(q.size)
        ]
    ).T
    np.testing.assert_allclose(jac_q, fd_q, atol=1e-6 * np.abs(fd_q).max())
    np.testing.assert_allclose(jac_qd, fd_qd, atol=1e-6 * np.abs(fd_qd).max())


def test_modal_moments_agree_with_exudyn_style_invariants(body):
    """The component moments and the invariants of Zwoelfer and Gerstmayr (2021), which Exudyn uses
    and which tests/test_reduction checks against Exudyn, describe the same inertia."""
    from ffrf.reduction.invariants import inertia_invariants

    model, basis, mm = body
    inv = inertia_invariants(model, basis)
    assert mm.mass == pytest.approx(inv.mass, rel=1e-14)
    np.testing.assert_allclose(mm.s0 / mm.mass, inv.center_of_mass, rtol=1e-13)
    np.testing.assert_allclose(mm.s1, inv.m_phit_psi, atol=1e-13 * np.abs(mm.s1).max())
    theta = np.trace(mm.x2) * np.eye(3) - mm.x2  # Eq. (F6) at zeta = 0
    np.testing.assert_allclose(theta, inv.theta, rtol=1e-13)


@pytest.mark.parametrize("exact", [True, False])
def test_body_frame_residual_equals_the_mass_matrix_form(body, rng, exact):
    """Eq. (F12) (no mass matrix formed) against Eqs. (F8)-(F11) term by term: M(q) qdd - Q_v - Q_g + [0; 0; K zeta +
    D zetad], with M, Q_v and Q_g from the kernels checked above against the nodal model."""
    from ffrf.body.flexible_body import FlexibleBody

    model, basis, mm = body
    kred = basis.T @ (model.stiffness @ basis)
    flex = FlexibleBody("bar", mm, kred, 0.005 * kred, exact)
    r, p, zeta, r_dot, pd, zetad = random_state(rng, basis.shape[1])
    zeta *= 1e3
    q, qd = np.r_[r, p, zeta], np.r_[r_dot, pd, zetad]
    qdd = rng.normal(size=q.size)
    g = np.array([0.3, -1.2, -9.81])
    reference = mass_matrix(p, zeta, mm.mass, mm.s0, mm.s1, mm.x2, mm.c, mm.d, mm.reduced_mass) @ qdd
    reference -= quadratic_velocity(p, zeta, pd, zetad, mm.s0, mm.s1, mm.x2, mm.c, mm.d)
    reference -= gravity_force(p, zeta, g, mm.mass, mm.s0, mm.s1, exact)
    reference[7:] += kred @ zeta + 0.005 * kred @ zetad
    ours = flex.residual(q, qd, qdd, g)
    np.testing.assert_allclose(ours, reference, rtol=0, atol=1e-12 * np.abs(reference).max())
