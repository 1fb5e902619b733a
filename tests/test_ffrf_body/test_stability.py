"""Stability of equilibria (ffrf.solvers.stability, Eq. (B1)) against closed forms: a rigid bar hanging from its
hinge vibrates at mu = m g d / I, the same bar balanced upright has mu = -m g d / I (unstable), and a clamped
flexible bar without gravity has the eigenvalues of its reduced (K, M)."""

from __future__ import annotations

import numpy as np
import pytest
from body_fixtures import bar_model
from pendulum_fixtures import pendulum
from scipy.linalg import eigh

from ffrf.body.flexible_body import FlexibleBody
from ffrf.body.modal_moments import modal_moments
from ffrf.fe.fe_model import rigid_body_modes
from ffrf.reduction.craig_bampton import craig_bampton
from ffrf.solvers.stability import equilibrium_stability
from ffrf.solvers.static_solver import static_equilibrium
from ffrf.system.joints import GroundFrame, MarkerJoint
from ffrf.system.markers import frame_marker
from ffrf.system.multibody import MultibodySystem


@pytest.mark.parametrize("turn_deg, sign", [(90.0, 1.0), (-90.0, -1.0)])
def test_a_rigid_bar_on_its_hinge_is_stable_hanging_and_unstable_upright(turn_deg, sign):
    """Hanging (turned +90 deg about the hinge's y axis, the bar along -z) mu = m g d / I; upright mu = -m g d / I,
    with m, d (hinge to centre of mass) and I (about the hinge axis) from the FE model."""
    system, model, _, hinge = pendulum(n_modes=0)
    half = np.radians(turn_deg) / 2.0
    p = np.array([np.cos(half), 0.0, np.sin(half), 0.0])
    q = system.initial_state()
    q[3:7] = p
    rotation = 2.0 * np.outer(p[1:], p[1:]) + (p[0] ** 2 - p[1:] @ p[1:]) * np.eye(3)
    rotation += 2.0 * p[0] * np.array([[0, -p[3], p[2]], [p[3], 0, -p[1]], [-p[2], p[1], 0]])
    q[:3] = hinge - rotation @ hinge
    solution = static_equilibrium(system, q)
    stability = equilibrium_stability(system, solution.q, solution.multipliers)
    assert stability.free_motions == 1 and stability.stable == (sign > 0)
    arm = np.linalg.norm((model.center_of_mass - hinge)[[0, 2]])
    about_hinge = rigid_body_modes(model.nodes, hinge)[:, 4]
    expected = sign * model.total_mass * 9.81 * arm / float(about_hinge @ model.mass @ about_hinge)
    assert abs(stability.squared_frequencies[0] / expected - 1.0) < 1e-12  # measured 4e-15


def test_a_clamped_flexible_bar_vibrates_at_the_eigenfrequencies_of_its_reduced_model():
    """No gravity, the frame clamped: the free motions are the modal coordinates and mu are the eigenvalues of
    (K_red, M_red)."""
    model = bar_model(E=1e8, rho=450.0)
    basis = craig_bampton(model, [np.flatnonzero(model.nodes[:, 0] < 1e-9)], 6)
    body = FlexibleBody(
        "bar",
        modal_moments(model.nodes, model.mass, basis.basis),
        basis.reduced_stiffness,
        0.0 * basis.reduced_stiffness,
    )
    clamp = MarkerJoint((0,), "clamp", GroundFrame(), frame_marker(0, basis.n_modes), locked=(True,) * 6)
    system = MultibodySystem((body,), (clamp,))
    solution = static_equilibrium(system, system.initial_state())
    stability = equilibrium_stability(system, solution.q, solution.multipliers, count=3)
    expected = eigh(basis.reduced_stiffness, basis.reduced_mass, eigvals_only=True)[:3]
    assert stability.free_motions == 6
    np.testing.assert_allclose(stability.squared_frequencies, expected, rtol=1e-12)  # measured 1.6e-14
