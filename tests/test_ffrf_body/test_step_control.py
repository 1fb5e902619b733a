"""Step-size control of generalized-alpha (``StepControl``, Eq. (G5)) on the flexible bar
pendulum (E = 1e6 Pa so that its first modes are resolved; rho_inf = 0.8), against a fixed-step
reference with h = 2.5e-5 s. The run starts with a step of 1e-2 s, far too large."""

from functools import cache

import numpy as np
import pytest
from pendulum_fixtures import pendulum, tip_position

from ffrf.errors import NewtonDivergence
from ffrf.solvers.generalized_alpha import generalized_alpha
from ffrf.solvers.step_control import StepControl

T_END, RHO = 0.2, 0.8


@cache
def setup():
    system, model, psi, _ = pendulum(n_modes=3, E=1e6)
    q0 = system.initial_state()
    reference = generalized_alpha(system, q0, np.zeros_like(q0), T_END, 2.5e-5, rho_inf=RHO, output_every=400)
    return system, model, psi, q0, np.array([tip_position(q, model, psi) for q in reference.q])


def adaptive(tol: float, **kw):
    system, model, psi, q0, _ = setup()
    return generalized_alpha(
        system,
        q0,
        np.zeros_like(q0),
        T_END,
        1e-2,
        rho_inf=RHO,
        output_every=1,
        step_control=StepControl(tol, tol, **kw),
    )


def tip_error(result) -> float:
    _, model, psi, _, reference = setup()
    return float(np.abs(np.array([tip_position(q, model, psi) for q in result.q]) - reference).max())


def test_error_follows_the_tolerance():
    """Measured: 2.4e-5, 7.1e-6, 1.5e-6 m with 203, 420, 859 steps (fixed steps of 1e-3, 5e-4,
    2.5e-4 s: 2.2e-5, 6.9e-6, 1.6e-6 m with 200, 400, 800)."""
    coarse, fine = adaptive(1e-5), adaptive(1e-7)
    assert tip_error(fine) < 0.2 * tip_error(coarse)
    assert tip_error(fine) < 3e-6 and tip_error(coarse) < 5e-5
    assert len(fine.step_sizes) > 2 * len(coarse.step_sizes)


def test_steps_shrink_from_a_bad_start_and_land_on_the_outputs():
    result = adaptive(1e-6)
    np.testing.assert_allclose(result.time, 1e-2 * np.arange(21), atol=1e-12)
    assert result.step_sizes.max() < 1e-2 and result.step_sizes.min() < 1e-4
    assert result.step_sizes.sum() == pytest.approx(T_END, rel=1e-12)
    assert result.complete and len(result.newton_iterations) == len(result.step_sizes)


def test_unreachable_tolerance_fails_with_partial_results():
    with pytest.raises(NewtonDivergence, match="min_step") as failure:
        adaptive(1e-14, min_step=1e-5)
    assert not failure.value.partial.complete
