"""Generalized-alpha on pendulums: against the analytic rigid pendulum, order of accuracy,
and constraint satisfaction (index 3)."""

import numpy as np
import pytest
from pendulum_fixtures import pendulum, tip_position
from scipy.integrate import solve_ivp

from ffrf.body.euler_parameters import rotation_matrix
from ffrf.errors import NewtonDivergence
from ffrf.solvers.generalized_alpha import AlphaParameters, generalized_alpha, precision_floor


def test_parameters_from_spectral_radius():
    """Chung and Hulbert (1993) / Arnold and Bruels (2007): rho_inf = 1 is the trapezoidal rule."""
    p = AlphaParameters(1.0)
    assert (p.alpha_m, p.alpha_f, p.gamma, p.beta) == pytest.approx((0.5, 0.5, 0.5, 0.25))
    p = AlphaParameters(0.0)
    assert p.gamma == pytest.approx(0.5 + p.alpha_f - p.alpha_m) and p.alpha_m == pytest.approx(-1.0)
    with pytest.raises(ValueError, match="rho_inf"):
        AlphaParameters(1.5)


def _swing_angle(result):
    """Angle of the body x-axis below the horizontal, unwrapped."""
    angles = [-np.arctan2(rotation_matrix(q[3:7])[2, 0], rotation_matrix(q[3:7])[0, 0]) for q in result.q]
    return np.unwrap(angles)


def test_rigid_pendulum_matches_the_pendulum_equation():
    """A bar with no modes is a compound pendulum: I phi'' = m g (L/2) cos(phi), with the exact
    consistent-mass inertia I = m (L^2/3 + t^2/12) about the hinge (P1 reproduces x^2 exactly).
    Released horizontal; errors must fall as h^2 (generalized-alpha is second order)."""
    system, _, _, _ = pendulum(n_modes=0)
    length, thickness, mass = 0.2, 0.01, 450.0 * 0.2 * 0.02 * 0.01
    inertia = mass * (length**2 / 3 + thickness**2 / 12)
    exact = solve_ivp(
        lambda t, y: [y[1], mass * 9.81 * length / 2 * np.cos(y[0]) / inertia],
        [0, 0.5],
        [0, 0],
        rtol=1e-12,
        atol=1e-14,
        dense_output=True,
    )
    q0 = system.initial_state()
    errors = []
    for step in (2e-3, 1e-3):
        result = generalized_alpha(system, q0, np.zeros_like(q0), 0.5, step, rho_inf=0.8)
        errors.append(np.abs(_swing_angle(result) - exact.sol(result.time)[0]).max())
    assert errors[1] < 5e-5  # rad, over a swing of more than 90 degrees
    assert np.log2(errors[0] / errors[1]) == pytest.approx(2.0, abs=0.15)
    # Hinge force at release: m g (1 - m L^2 / (4 I)) upwards; the constraint force on the body is
    # -C_q^T lambda, and the hinge point's multipliers follow the Euler normalisation's one row.
    lifting = mass * 9.81 * (1 - mass * length**2 / (4 * inertia))
    assert -result.multipliers[0, 3] == pytest.approx(lifting, rel=1e-10)
    np.testing.assert_allclose(result.multipliers[0, 1:3], 0, atol=1e-12)


def test_flexible_pendulum_is_second_order_and_keeps_its_constraints():
    system, model, psi, _ = pendulum(n_modes=3)
    q0 = system.initial_state()
    tips, results = {}, {}
    for step in (4e-3, 2e-3, 1e-3, 2.5e-4):
        results[step] = generalized_alpha(system, q0, np.zeros_like(q0), 0.2, step, rho_inf=0.8)
        tips[step] = tip_position(results[step].q[-1], model, psi)
    errors = [np.linalg.norm(tips[h] - tips[2.5e-4]) for h in (4e-3, 2e-3, 1e-3)]
    slopes = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(slopes > 1.7), slopes
    # Index 3: positions satisfy the hinge and the Euler normalisation at every step.
    result = results[1e-3]
    worst = max(np.abs(system.constraint_values(q, t)).max() for q, t in zip(result.q, result.time, strict=True))
    assert worst < 1e-10
    # Full Newton with the exact iteration matrix converges quadratically; modified Newton (the
    # default) reuses the matrix and reaches the same solution.
    full = generalized_alpha(system, q0, np.zeros_like(q0), 0.05, 1e-3, rho_inf=0.8, modified_newton=False)
    assert full.newton_iterations.max() <= 4
    np.testing.assert_allclose(full.q[-1], results[1e-3].q[50], atol=1e-12)


def test_newton_start_extrapolates_quadratic_histories_exactly():
    """Eq. (G6): unknowns quadratic in time are predicted exactly from two earlier steps, also across unequal
    steps; from one earlier step a linear history is; a step cut short stops the extrapolation there."""
    import sys

    module = sys.modules["ffrf.solvers.generalized_alpha"]
    a, b, c = np.array([1.0, -2.0, 0.5]), np.array([3.0, 0.25, -1.0]), np.array([-4.0, 7.0, 0.125])

    def quadratic(t):
        return a + b * t + c * t * t, 2 * a - b * t + 3 * c * t * t

    t_first, t_before, t_now, h = 0.27, 0.3, 0.35, 0.04
    state = module._State(None, None, quadratic(t_now)[0], None, quadratic(t_now)[1])
    history = ((*quadratic(t_first), t_before - t_first), (*quadratic(t_before), t_now - t_before))
    qdd, lam = module._predicted_unknowns(state, h, history)
    np.testing.assert_allclose(qdd, quadratic(t_now + h)[0], rtol=1e-12)
    np.testing.assert_allclose(lam, quadratic(t_now + h)[1], rtol=1e-12)

    def linear(t):
        return a + b * t, 2 * a - b * t

    state = module._State(None, None, linear(t_now)[0], None, linear(t_now)[1])
    qdd, lam = module._predicted_unknowns(state, h, ((*linear(t_before), t_now - t_before),))
    np.testing.assert_allclose(qdd, linear(t_now + h)[0], rtol=1e-14)
    np.testing.assert_allclose(lam, linear(t_now + h)[1], rtol=1e-14)
    same_qdd, _ = module._predicted_unknowns(state, h, ())
    np.testing.assert_array_equal(same_qdd, state.qdd)
    # after a step more than twice shorter (cut to land on an output) nothing is extrapolated
    short = (*linear(t_now - 1e-6), 1e-6)
    np.testing.assert_array_equal(module._predicted_unknowns(state, h, (short,))[0], state.qdd)
    # a cut step further back ends the history there: the line through the last two values
    history = ((*linear(t_before - 1e-6), 1e-6), (*linear(t_before), t_now - t_before))
    np.testing.assert_allclose(module._predicted_unknowns(state, h, history)[0], linear(t_now + h)[0], rtol=1e-14)


def test_a_tolerance_below_round_off_is_named_as_such_and_the_floor_is_where_newton_stalls():
    """The precision floor (``precision_floor``: an ulp of the positions seen through gamma'/beta')
    separates tolerances Newton meets from those it cannot: at 3x the floor a flexible pendulum's
    swing converges; at a tenth of it Newton stalls at round-off and the error says the tolerance is
    below what double precision reaches (not "reduce the step size", which would raise the floor)."""
    system, _, _, _ = pendulum(n_modes=3)
    q0 = system.initial_state()
    step = 1e-3
    floor = precision_floor(AlphaParameters(0.8), step, q0, np.zeros_like(q0))
    assert 1e-14 < floor < 1e-11  # 4.4e-13 at this step: gamma/(h beta) = 1978 ulps of |q| = 1
    generalized_alpha(system, q0, np.zeros_like(q0), 0.05, step, rho_inf=0.8, tolerance=3.0 * floor)
    with pytest.raises(NewtonDivergence, match="below what double precision can reach") as failure:
        generalized_alpha(system, q0, np.zeros_like(q0), 0.05, step, rho_inf=0.8, tolerance=0.1 * floor)
    assert "reduce the step size" not in str(failure.value)


def test_a_newton_failure_above_the_floor_still_advises_a_shorter_step():
    """Out of iterations with a reachable tolerance: the remedy is the step or the model."""
    system, _, _, _ = pendulum(n_modes=3)
    q0 = system.initial_state()
    with pytest.raises(NewtonDivergence, match="reduce the step size"):
        generalized_alpha(system, q0, np.zeros_like(q0), 0.05, 1e-3, rho_inf=0.8, tolerance=1e-10, max_iterations=1)
