"""The jitted generalized-alpha Newton iterations (ffrf/solvers/newton_kernels.py) against LAPACK and
against the Python loop of ffrf.solvers.generalized_alpha._step evaluating the same packed kernels."""

import numpy as np
import pytest
import scipy.linalg

from ffrf.paper.bennett_scene import assemble, build_bennett
from ffrf.solvers.common import consistent_accelerations
from ffrf.solvers.generalized_alpha import AlphaParameters, _Newton, _State, _step
from ffrf.solvers.newton_kernels import lu_solve, static_rhs, static_update
from ffrf.system.packed_system import pack_system


def test_lu_solve_equals_lapack_with_pivoting():
    rng = np.random.default_rng(5)
    a = rng.standard_normal((40, 40))
    a[0, 0] = 1e-12  # forces a row swap at the first column
    lu, piv = scipy.linalg.lu_factor(a)
    assert np.any(piv != np.arange(40))
    b = rng.standard_normal(40)
    np.testing.assert_allclose(lu_solve(lu, piv, b), scipy.linalg.lu_solve((lu, piv), b), rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(a @ lu_solve(lu, piv, b), b, atol=1e-10)


class _Unpacked:
    """The packed system's residual and matrix without its type: _step takes its Python loop."""

    def __init__(self, packed):
        self.residual = packed.residual
        self.iteration_matrix = packed.iteration_matrix


@pytest.fixture(scope="module")
def bennett():
    scene = build_bennett("pla", h=6e-3, order=1, n_modes=2)
    return scene.system, assemble(scene).q


@pytest.mark.parametrize("modified", [True, False])
def test_jitted_iterations_equal_the_python_loop(bennett, modified):
    """Same steps, same iteration counts (refactorisations included), states equal to round-off. The
    LU solves differ in operation order; the difference grows from 1e-18 in the stiff modes'
    accelerations (the test stops on beta' |d qdd|, so these are fixed only to 1e-10 / beta' ~ 1e-4)
    to ~2e-9 of max |qdd| after 15 steps, while q stays at 1e-16: hence the bounds per quantity."""
    system, q0 = bennett
    packed = pack_system(system)
    par = AlphaParameters(0.9)
    qdd, lam = consistent_accelerations(system, q0, np.zeros_like(q0))
    states = [_State(q0.copy(), np.zeros_like(q0), qdd.copy(), qdd.copy(), lam.copy()) for _ in range(2)]
    newtons = [_Newton(model, par, 1e-10, 12, modified) for model in (packed, _Unpacked(packed))]
    h = 2e-3
    for k in range(1, 16):
        results = [_step(newton, state, k * h, h) for newton, state in zip(newtons, states, strict=True)]
        (fast, fast_count, _), (slow, slow_count, _) = results
        assert fast_count == slow_count
        for name, tolerance in (("q", 1e-14), ("qd", 1e-11), ("qdd", 1e-7), ("lam", 1e-9)):
            a, b = getattr(fast, name), getattr(slow, name)
            np.testing.assert_allclose(a, b, rtol=0, atol=tolerance * max(1.0, np.abs(b).max()))
        states = [fast, slow]


def test_jitted_static_iterations_equal_the_python_loop(bennett):
    """ffrf.solvers.static_solver._newton with the packed system (the kernel static_iterations between
    factorisations) and with the same residual and matrix behind an untyped model (its Python loop): the same
    iteration counts along a short quasi-static path from the assembled state, equilibria equal to round-off."""
    from ffrf.solvers.static_solver import _newton

    system, q0 = bennett
    packed = pack_system(system)
    unpacked = _Unpacked(packed)
    unpacked.n_coordinates = packed.n_coordinates  # type: ignore[attr-defined]
    states = [(q0.copy(), np.zeros(system.n_constraints), None) for _ in range(2)]
    for t in (0.0, 0.5, 1.0, 1.5):
        results = [
            _newton(model, q, lam, t, 1e-10, 25, tangent)
            for model, (q, lam, tangent) in zip((packed, unpacked), states, strict=True)
        ]
        (q_fast, lam_fast, count_fast, tangent_fast), (q_slow, lam_slow, count_slow, tangent_slow) = results
        assert count_fast == count_slow
        np.testing.assert_allclose(q_fast, q_slow, rtol=0, atol=1e-14)
        np.testing.assert_allclose(lam_fast, lam_slow, rtol=0, atol=1e-9 * np.abs(lam_slow).max())
        states = [(q_fast, lam_fast, tangent_fast), (q_slow, lam_slow, tangent_slow)]


def test_non_finite_residual_is_reported(bennett):
    system, q0 = bennett
    packed = pack_system(system)
    par = AlphaParameters(0.9)
    qdd, lam = consistent_accelerations(system, q0, np.zeros_like(q0))
    state = _State(q0.copy(), np.zeros_like(q0), qdd, qdd.copy(), lam)
    state.qd[0] = np.nan
    new, count, diagnostics = _step(_Newton(packed, par, 1e-10, 12, True), state, 1e-3, 1e-3)
    assert new is None and count == 1 and "NaN" in diagnostics


def _numpy_update(q, lam, delta, gap, tolerance):
    """The static Newton update as numpy expressions (what ffrf.solvers.static_solver._newton did before the kernel)."""
    n = q.shape[0]
    q_new, lam_new = q + delta[:n], lam + delta[n:]
    increment = np.abs(delta[:n]).max()
    scale = max(1.0, np.abs(q_new).max())
    settled = np.abs(delta[n:]).max(initial=0.0) <= tolerance * max(1.0, np.abs(lam_new).max(initial=0.0))
    converged = bool(
        increment <= tolerance * scale
        and np.abs(gap).max() <= tolerance
        and (settled or increment <= 1e3 * np.finfo(float).eps * scale)
    )
    return q_new, lam_new, increment, converged


@pytest.mark.parametrize("case", ["far", "converged", "positions only", "round-off", "nan"])
def test_the_static_update_kernel_equals_its_numpy_expressions_bit_for_bit(case):
    """static_rhs and static_update: the same numbers as numpy's elementwise sums and maxima, to the bit, and the
    same verdict, in each branch of the convergence test (and a NaN increment, which numpy propagates)."""
    rng = np.random.default_rng(11)
    n, k = 30, 12  # a system always has constraints: at least each body's Euler normalisation
    q, lam = rng.standard_normal(n) * 3.0, rng.standard_normal(k) * 50.0
    scale = {"far": 1e-3, "converged": 1e-13, "positions only": 1e-11, "round-off": 1e-14}
    delta = rng.standard_normal(n + k) * scale.get(case, 1e-3)
    gap = rng.standard_normal(k) * (1e-12 if case != "far" else 1e-3)
    if case == "positions only":
        delta[n:] *= 1e4  # the multipliers still move, the positions do not: not converged
    if case == "round-off":
        delta[n:] *= 1e8
        q *= 100.0
    if case == "nan":
        delta[3] = np.nan
    expected = _numpy_update(q, lam, delta, gap, 1e-10)
    got = static_update(q, lam, delta, gap, 1e-10)
    np.testing.assert_array_equal(got[0], expected[0])
    np.testing.assert_array_equal(got[1], expected[1])
    assert got[2] == expected[2] or (np.isnan(got[2]) and np.isnan(expected[2]))
    assert got[3] == expected[3] == (case in ("converged", "round-off"))
    residual = rng.standard_normal(n)
    residual[0] = np.nan if case == "nan" else residual[0]
    rhs, finite = static_rhs(residual, gap)
    np.testing.assert_array_equal(rhs, -np.concatenate([residual, gap]))
    assert finite == bool(np.all(np.isfinite(residual)) and np.all(np.isfinite(gap)))
