"""Static equilibrium against a direct FE solution and a hanging pendulum."""

import numpy as np
import pytest
import scipy.sparse.linalg as spla
from body_fixtures import clamped_cantilever
from pendulum_fixtures import pendulum

from ffrf.body.euler_parameters import rotation_matrix
from ffrf.errors import StaticDivergence
from ffrf.solvers.static_solver import static_equilibrium
from ffrf.system.multibody import MultibodySystem

GRAVITY = np.array([0.0, 0.0, -9.81])


def _cantilever(n_modes):
    return clamped_cantilever(n_modes, GRAVITY)


def test_cantilever_under_gravity_equals_ritz_and_approaches_full_fe():
    """With the frame clamped, the reduced static solution is the Ritz solution
    K_r zeta = Psi^T M (1 x g) (built here straight from the FE matrices), and it approaches the
    full FE solution K_ff u = f_f as modes are added."""
    model, clamp, _, _ = _cantilever(1)
    n = model.nodes.shape[0]
    load = model.mass @ np.tile(GRAVITY, n)
    free = np.setdiff1d(np.arange(3 * n), (3 * clamp[:, None] + np.arange(3)).ravel())
    full = np.zeros(3 * n)
    full[free] = spla.spsolve(model.stiffness[free][:, free].tocsc(), load[free])
    tip = int(np.argmin(np.linalg.norm(model.nodes - [0.2, 0.01, 0.005], axis=1)))
    errors = []
    for n_modes in (2, 6):
        model, clamp, psi, system = _cantilever(n_modes)
        solution = static_equilibrium(system, system.initial_state(), load_steps=2)
        ritz = np.linalg.solve(psi.T @ model.stiffness @ psi, psi.T @ load)
        np.testing.assert_allclose(solution.q[7:], ritz, rtol=1e-8, atol=1e-12 * np.abs(ritz).max())
        np.testing.assert_allclose(solution.q[:7], [0, 0, 0, 1, 0, 0, 0], atol=1e-12)
        errors.append(abs((psi @ solution.q[7:])[3 * tip + 2] - full[3 * tip + 2]) / abs(full[3 * tip + 2]))
    assert errors[1] < errors[0] and errors[1] < 0.02


def test_hinged_bar_hangs_straight_down():
    system, _, _, hinge = pendulum(n_modes=0)
    q0 = system.initial_state()
    tilt = np.radians(-70.0) / 2  # start 70 deg below horizontal: rotate about +y by 70 deg (x towards -z)
    q0[3:7] = [np.cos(-tilt), 0.0, np.sin(-tilt), 0.0]
    q0[:3] = hinge - rotation_matrix(q0[3:7]) @ hinge
    solution = static_equilibrium(system, q0)
    axis = rotation_matrix(solution.q[3:7]) @ np.array([1.0, 0, 0])
    np.testing.assert_allclose(axis, [0, 0, -1], atol=1e-10)  # the Newton tolerance
    # The hinge carries the full weight.
    assert -solution.multipliers[3] == pytest.approx(450.0 * 0.2 * 0.02 * 0.01 * 9.81, rel=1e-10)


def test_newton_out_of_iterations_says_whether_it_was_converging():
    """Out of iterations while the increments shrink steadily, the error says so and estimates the
    iterations still needed; the estimate is checked by running with that many. With a single
    iteration nothing shows convergence, and the advice is the load path (gravity in load steps)."""
    import re

    system, _, _, hinge = pendulum(n_modes=0)
    q0 = system.initial_state()
    tilt = np.radians(-70.0) / 2
    q0[3:7] = [np.cos(-tilt), 0.0, np.sin(-tilt), 0.0]
    q0[:3] = hinge - rotation_matrix(q0[3:7]) @ hinge
    with pytest.raises(StaticDivergence, match="was converging but ran out of iterations") as info:
        static_equilibrium(system, q0, max_iterations=4)
    more = int(re.search(r"about (\d+) more", str(info.value)).group(1))
    assert sum(static_equilibrium(system, q0, max_iterations=4 + more + 1).iterations) <= 4 + more + 1
    with pytest.raises(StaticDivergence, match=r"did not converge in 1 iterations.*more load_steps \(now 1\)"):
        static_equilibrium(system, q0, max_iterations=1)


def test_free_body_is_refused_with_a_clear_message():
    model, _, psi, system = _cantilever(1)
    free = MultibodySystem(system.bodies, (), gravity=GRAVITY)
    with pytest.raises(StaticDivergence, match="mechanism or a body is not held"):
        static_equilibrium(free, free.initial_state())


def test_quasi_static_drive_follows_the_prescribed_angle():
    """A rigid bar held by a driven hinge: without inertia the drive only balances gravity,
    tau = -m g (L/2) cos(phi) (about +y, see test_joints), at every prescribed angle."""
    from ffrf.solvers.static_solver import quasi_static
    from ffrf.system.joints import GroundFrame, driven_revolute_joint
    from ffrf.system.markers import frame_marker

    _, _, _, hinge = pendulum(n_modes=0)
    system, _, _, _ = pendulum(n_modes=0)
    axes = np.array([[0.0, 0, 1], [1, 0, 0], [0, 1, 0]]).T
    drive = driven_revolute_joint(
        GroundFrame(hinge, np.eye(3)), frame_marker(0, 0, hinge), lambda t: t, rotation0=axes, rotation1=axes
    )
    driven = MultibodySystem(system.bodies, (drive,), gravity=GRAVITY)
    times = np.linspace(0.0, 3.0, 7)
    solution = quasi_static(driven, driven.initial_state(), times)
    mass = 450.0 * 0.2 * 0.02 * 0.01
    np.testing.assert_allclose(solution.multipliers[:, -1], -mass * 9.81 * 0.1 * np.cos(times), atol=1e-12)
    # Intermediate equilibria (at most 0.1 rad of drive apart) are solved but not returned: the same rows.
    finer = quasi_static(driven, driven.initial_state(), times, max_step=0.1)
    assert finer.q.shape == solution.q.shape and len(finer.iterations) == len(times)
    np.testing.assert_allclose(finer.multipliers[:, -1], -mass * 9.81 * 0.1 * np.cos(times), atol=1e-12)


def test_a_quasi_static_run_that_stops_returns_the_equilibria_before_the_stop():
    """The driven bar of the test above, with a drive table that ends at t = 2.1 s (NaN after): the run stops
    at the first intermediate equilibrium after it (2.2 s), and the error carries the equilibria at the times
    asked for before (0 to 2 s), with the closed-form torque."""
    from ffrf.solvers.static_solver import quasi_static
    from ffrf.system.joints import GroundFrame, driven_revolute_joint
    from ffrf.system.markers import frame_marker

    system, _, _, hinge = pendulum(n_modes=0)
    axes = np.array([[0.0, 0, 1], [1, 0, 0], [0, 1, 0]]).T
    drive = driven_revolute_joint(
        GroundFrame(hinge, np.eye(3)),
        frame_marker(0, 0, hinge),
        lambda t: t if t <= 2.1 else float("nan"),
        rotation0=axes,
        rotation1=axes,
    )
    driven = MultibodySystem(system.bodies, (drive,), gravity=GRAVITY)
    times = np.linspace(0.0, 3.0, 7)
    with pytest.raises(StaticDivergence, match=r"at t = 2.2 s: NaN in the static residual") as stopped:
        quasi_static(driven, driven.initial_state(), times, max_step=0.1)
    partial = stopped.value.partial
    assert partial.q.shape == (5, driven.n_coordinates)
    mass = 450.0 * 0.2 * 0.02 * 0.01
    np.testing.assert_allclose(partial.multipliers[:, -1], -mass * 9.81 * 0.1 * np.cos(times[:5]), atol=1e-12)


def test_refined_times_keep_the_given_ones_and_split_long_intervals_equally():
    from ffrf.solvers.static_solver import refined_times

    times = np.array([0.0, 1.0, 1.05, 3.0])
    refined, given = refined_times(times, 0.4)
    np.testing.assert_array_equal(refined[given], times)  # exactly, not to round-off
    assert np.max(np.diff(refined)) <= 0.4 + 1e-15
    np.testing.assert_allclose(np.diff(refined[:4]), 1.0 / 3.0)  # [0, 1] in three equal pieces
    assert len(refined) == 1 + 3 + 1 + 5
    np.testing.assert_array_equal(refined_times(times, None)[0], times)
    with pytest.raises(ValueError, match="max_step must be > 0"):
        refined_times(times, 0.0)


def test_extrapolation_weights_reproduce_a_quadratic():
    """Eq. (S2): three Lagrange weights extrapolate any quadratic exactly (unequal spacing too)."""
    from ffrf.solvers.common import extrapolation_weights

    times = np.array([0.3, 0.7, 1.6])
    values = np.array([[2.0 - 3.0 * t + 0.5 * t**2, np.sin(1.0) * t**2] for t in times])
    weights = extrapolation_weights(times, 2.1)
    np.testing.assert_allclose(weights @ values, [2.0 - 6.3 + 0.5 * 2.1**2, np.sin(1.0) * 2.1**2], rtol=1e-13)
    np.testing.assert_allclose(extrapolation_weights(times[1:], 1.0), [2.0 / 3.0, 1.0 / 3.0], rtol=1e-14)


def test_secant_steps_equal_broyden_with_the_dense_updated_matrix():
    """Eq. (S3): the product form gives the steps of good Broyden with the explicit weighted update
    B += (y - B s) s^T W / (s^T W s), on a small nonlinear system started with a poor tangent."""
    from ffrf.solvers.static_solver import _Secant

    rng = np.random.default_rng(3)
    a = np.eye(4) * 3.0 + 0.3 * rng.standard_normal((4, 4))

    def f(x):
        return a @ x + 0.1 * x**3 - 1.0

    b0 = a + 0.2 * rng.standard_normal((4, 4))
    weights = np.array([1.0, 4.0, 0.25, 2.0])
    secant = _Secant(weights)
    x_product, x_dense, b = np.zeros(4), np.zeros(4), b0.copy()
    for _ in range(9):
        step_product = secant.step(np.linalg.solve(b0, -f(x_product)))
        step_dense = np.linalg.solve(b, -f(x_dense))
        np.testing.assert_allclose(step_product, step_dense, rtol=1e-9, atol=1e-13)
        y = f(x_dense + step_dense) - f(x_dense)
        b = b + np.outer(y - b @ step_dense, weights * step_dense) / (step_dense @ (weights * step_dense))
        x_product, x_dense = x_product + step_product, x_dense + step_dense
    assert np.abs(f(x_product)).max() < 1e-11  # and it converged without refactoring


def test_the_path_history_keeps_what_unsolved_outputs_need_across_many_jumps_and_long_crawls():
    """The path's history (``_History``) for outputs solved after a path step: after 40 jumps in one step, the
    stretch an earlier output lies on is still found (only 32 stretches were once kept, and the output was then
    solved on a later stretch, or not at all); after 100 parts of one stretch past the last solved output, every
    one is kept (once only the newest 32); once outputs are solved, the old stretches and equilibria go."""
    from ffrf.solvers.static_solver import _History

    def state(t: float) -> tuple[float, np.ndarray, np.ndarray]:
        return t, np.full(3, t), np.full(2, -t)

    path = _History(*state(0.0), order=2)
    path.forget_before(0.0)
    for k in range(1, 101):  # a crawl: 100 parts between outputs
        path.add(*state(0.001 * k))
    assert [point[0] for point in path.side(0.05)][0] == 0.0 and len(path.side(0.05)) == 101
    for k in range(40):  # 40 jumps in a row
        path.restart(*state(0.2 + 0.01 * k))
    before = [point for point in path.side(0.05) if point[0] < 0.05]
    assert len(before) == 50 and path.side(0.25)[0][0] == pytest.approx(0.25)
    path.forget_before(0.305)
    assert len(path.stretches) == 30 and path.stretches[0][0] == pytest.approx(0.3)
    for k in range(100):
        path.add(*state(0.6 + 0.001 * k))
    path.forget_before(0.7)
    assert len(path.kept) == 32
