"""The analytic body tangents (Eqs. (F12)-(F14)) against complex-step derivatives of the body residual.

The residual of Eqs. (F8)-(F11) is a polynomial in the coordinates and velocities, so its complex-step
derivative Im f(q + i h e_k) / h is exact to round-off (no subtractive cancellation): an independent truth
for every entry of the hand-derived tangents.
"""

import numpy as np
import pytest
from body_fixtures import bar_model, random_state

from ffrf.body.body_tangents import body_tangents
from ffrf.body.flexible_body import FlexibleBody, body_residual
from ffrf.body.modal_moments import modal_moments

STEP = 1e-30


@pytest.fixture(scope="module")
def flexible_body():
    model = bar_model()
    rng = np.random.default_rng(11)
    basis = rng.normal(size=(3 * model.nodes.shape[0], 5))  # any basis: the kernels must not care
    moments = modal_moments(model.nodes, model.mass, basis)
    stiffness = basis.T @ (model.stiffness @ basis)
    return moments, stiffness


def _complex_step(body, q, qd, qdd, gravity, wrt):
    """Columns ``Im f(x + i h e_k) / h`` of the residual along ``q`` (``wrt=0``) or ``qd`` (``wrt=1``)."""
    packed = tuple(a.astype(np.complex128) for a in body._packed)
    state = [v.astype(np.complex128) for v in (q, qd, qdd)]
    columns = []
    for k in range(q.size):
        state[wrt][k] += 1j * STEP
        f = body_residual(*state, gravity.astype(np.complex128), body.moments.mass, *packed, body.exact_gravity)
        columns.append(f.imag / STEP)
        state[wrt][k] -= 1j * STEP
    return np.array(columns).T


@pytest.mark.parametrize("exact_gravity", [True, False])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_tangents_equal_complex_step_derivatives(flexible_body, exact_gravity, seed):
    moments, stiffness = flexible_body
    body = FlexibleBody("bar", moments, stiffness, 0.005 * stiffness, exact_gravity)
    rng = np.random.default_rng(seed)
    r, p, zeta, r_dot, pd, zetad = random_state(rng, moments.n_modes)
    q = np.r_[r, p, 1e3 * zeta]  # large deformation: every zeta-dependent term matters
    qd = np.r_[r_dot, pd, zetad]
    qdd = rng.normal(size=q.size)
    gravity = np.array([0.3, -1.2, -9.81])
    jac_q, jac_qd = body_tangents(q, qd, qdd, gravity, moments.mass, *body._packed, exact_gravity, True)
    reference_q = _complex_step(body, q, qd, qdd, gravity, 0)
    reference_qd = _complex_step(body, q, qd, qdd, gravity, 1)
    np.testing.assert_allclose(jac_q, reference_q, rtol=0, atol=1e-12 * np.abs(reference_q).max())
    np.testing.assert_allclose(jac_qd, reference_qd, rtol=0, atol=1e-12 * np.abs(reference_qd).max())
    assert np.abs(reference_q[:, 3:]).min(axis=0).max() > 0  # the state exercises the columns compared


def test_statics_leaves_the_velocity_tangent_zero(flexible_body):
    moments, stiffness = flexible_body
    body = FlexibleBody("bar", moments, stiffness, 0.005 * stiffness)
    rng = np.random.default_rng(3)
    r, p, zeta, *_ = random_state(rng, moments.n_modes)
    q = np.r_[r, p, zeta]
    rest = np.zeros(q.size)
    gravity = np.array([0.0, 0.0, -9.81])
    jac_q, jac_qd = body_tangents(q, rest, rest, gravity, moments.mass, *body._packed, True, False)
    assert not jac_qd.any()
    np.testing.assert_allclose(
        jac_q, _complex_step(body, q, rest, rest, gravity, 0), rtol=0, atol=1e-12 * np.abs(jac_q).max()
    )
