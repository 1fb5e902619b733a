"""The jitted generalized-alpha Newton iterations (ffrf/solvers/newton_kernels.py) against LAPACK and
against the Python loop of ffrf.solvers.generalized_alpha._step evaluating the same packed kernels."""

import numpy as np
import pytest
import scipy.linalg

from ffrf.scenes.bennett_scene import assemble, build_bennett
from ffrf.solvers.common import consistent_accelerations
from ffrf.solvers.generalized_alpha import AlphaParameters, _Newton, _State, _step
from ffrf.solvers.newton_kernels import lu_solve
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


def test_non_finite_residual_is_reported(bennett):
    system, q0 = bennett
    packed = pack_system(system)
    par = AlphaParameters(0.9)
    qdd, lam = consistent_accelerations(system, q0, np.zeros_like(q0))
    state = _State(q0.copy(), np.zeros_like(q0), qdd, qdd.copy(), lam)
    state.qd[0] = np.nan
    new, count, diagnostics = _step(_Newton(packed, par, 1e-10, 12, True), state, 1e-3, 1e-3)
    assert new is None and count == 1 and "NaN" in diagnostics
