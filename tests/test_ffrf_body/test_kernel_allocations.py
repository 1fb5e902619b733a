"""Allocations of the jitted generalized-alpha Newton loop (issue #22; ffrf/solvers/newton_kernels.py), counted by
numba's runtime (``bench/memory_probe.py``): the same number in every iteration, so that a step's allocations grow
with its iterations and nothing else, and none left behind, so that a long run does not leak."""

import os
from collections.abc import Callable

import numpy as np
import pytest

from bench import memory_probe
from ffrf.paper.bennett_scene import assemble, build_bennett
from ffrf.solvers.common import consistent_accelerations
from ffrf.solvers.generalized_alpha import AlphaParameters, _factor_iteration_matrix
from ffrf.solvers.newton_kernels import EXHAUSTED, alpha_iterations
from ffrf.system.packed_system import pack_system


@pytest.fixture(scope="module")
def first_step():
    """The arguments of :func:`alpha_iterations` for the first step (h = 2 ms) of the coarse Bennett scene from rest,
    as :func:`ffrf.solvers.generalized_alpha._step` makes them. The iteration matrix is factored at the start for a
    step 1.5 h long: the iterations then contract steadily (increments shrink by about 0.3 each, 2e-4 to 2e-8 m/s^2
    over eight), where the exact matrix reaches round-off in two and its noise can trigger the refactoring rule."""
    scene = build_bennett("pla", h=6e-3, order=1, n_modes=2)
    system = scene.system
    packed = pack_system(system)
    q0 = assemble(scene).q
    qdd, lam = consistent_accelerations(system, q0, np.zeros_like(q0))
    par, h, t = AlphaParameters(0.9), 2e-3, 2e-3
    to_accel = (1.0 - par.alpha_f) / (1.0 - par.alpha_m)
    beta_p, gamma_p = h * h * par.beta * to_accel, h * par.gamma * to_accel
    q_base = q0 + h * h * (0.5 - par.beta) * qdd
    qd_base = h * (1.0 - par.gamma) * qdd
    accel_base = (par.alpha_f * qdd - par.alpha_m * qdd) / (1.0 - par.alpha_m)
    lu, piv = _factor_iteration_matrix(packed, q0, np.zeros_like(q0), qdd, lam, t, 2.25 * beta_p, 1.5 * gamma_p)
    head = (packed.bodies, packed.joints, packed.gravity, packed.phi(t), lu, piv, q_base, qd_base, accel_base)
    return head + (to_accel, h * h * par.beta, h * par.gamma, beta_p, gamma_p), qdd, lam


@pytest.mark.skipif(
    os.environ.get("NUMBA_DISABLE_JIT", "0") not in ("", "0"),
    reason="numba's runtime counts the allocations of compiled code; the JIT is off",
)
def test_newton_iterations_allocate_alike_and_free_all(first_step):
    """With tolerance 0 (Newton never converges) and ``done`` far below the refactoring rule's third iteration, a call
    runs exactly ``max_iterations`` iterations: its allocations must be a fixed number plus the same number per
    iteration, and every allocation must be freed by the time the call returns."""
    head, qdd, lam = first_step
    kernel: Callable[..., tuple] = alpha_iterations

    def run(iterations: int) -> tuple[int, int]:
        unknowns = (qdd.copy(), lam.copy())
        before = memory_probe.nrt_counts()
        status, used, _, _ = kernel(*head, *unknowns, 0.0, iterations, np.inf, -100)
        after = memory_probe.nrt_counts()
        assert (status, used) == (EXHAUSTED, iterations)
        return after[0] - before[0], after[1] - before[1]

    run(1)  # counting starts here
    counts = {n: run(n) for n in (1, 2, 5)}
    assert counts[1][0] > 0  # at least numba's records of the argument arrays: the counter is on
    per_iteration = counts[2][0] - counts[1][0]
    assert counts[5][0] - counts[2][0] == 3 * per_iteration, counts
    for allocated, freed in counts.values():
        assert allocated == freed, counts
