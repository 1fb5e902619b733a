"""The fast path (ffrf/system/packed_system.py, whole-system numba kernels) against the reference Python
path of MultibodySystem: every Newton piece on random states, whole trajectories, and the
fallback for constraints it does not know (docs/formulation.md, Eqs. (FP4)-(FP6))."""

import logging
from dataclasses import replace

import numpy as np
import pytest
from body_fixtures import two_bar_chain
from pendulum_fixtures import pendulum

from ffrf.paper.bennett_scene import assemble, build_bennett
from ffrf.solvers.generalized_alpha import generalized_alpha
from ffrf.solvers.static_solver import quasi_static, static_equilibrium
from ffrf.system.joints import MarkerJoint
from ffrf.system.multibody import MultibodySystem
from ffrf.system.packed_system import newton_model, pack_system


@pytest.fixture(scope="module")
def bennett():
    scene = build_bennett("pla", h=6e-3, order=1, n_modes=2)
    return scene, assemble(scene).q


@pytest.fixture(scope="module")
def chain():
    return two_bar_chain()


def _random_state(rng, system, q, scale):
    n = system.n_coordinates
    q = q + scale * rng.normal(size=n)
    return q, rng.normal(size=n), rng.normal(size=n), rng.normal(size=system.n_constraints)


def _relative(a, b):
    return np.abs(a - b).max() / max(np.abs(b).max(), 1e-300)


def _compare(system, q, qd, qdd, lam, t, hessian_rtol=1e-12):
    fast = pack_system(system)
    assert fast is not None
    forces, gap = system.residual(q, qd, qdd, lam, t)
    fast_forces, fast_gap = fast.residual(q, qd, qdd, lam, t)
    assert _relative(fast_forces, forces) < 1e-12
    assert _relative(fast_gap, gap) < 1e-12
    assert _relative(fast.constraint_jacobian(q, t), system.constraint_jacobian(q, t)) < 1e-12
    assert _relative(fast.mass_matrix(q), system.mass_matrix(q)) < 1e-12
    for ours, ref in zip(fast.body_tangents(q, qd, qdd), system.body_tangents(q, qd, qdd), strict=True):
        assert _relative(ours, ref) < 1e-12
    assert _relative(fast.constraint_hessian(q, lam, t), system.constraint_hessian(q, lam, t)) < hessian_rtol
    for factors in ((1.0, 1e-6, 2e-3), (0.0, 1.0, 0.0)):
        ours, ref = (
            fast.iteration_matrix(q, qd, qdd, lam, t, *factors),
            system.iteration_matrix(q, qd, qdd, lam, t, *factors),
        )
        assert _relative(ours, ref) < 1e-12


def test_chain_pieces_on_random_states(rng, chain):
    """Deformations large enough (marker rotations ~0.1-1 rad) that the reference's complex-step
    Hessian is exact too (its Rodrigues closed forms cancel below ~1e-2 rad, see the next test)."""
    q0 = chain.initial_state(positions=[[0.0, 0.0, 0.0], [0.2, 0.0, 0.0]])
    for _ in range(3):
        q, qd, qdd, lam = _random_state(rng, chain, q0, 0.3)
        _compare(chain, q, qd, qdd, lam, t=0.7)


def test_bennett_pieces_on_random_states(rng, bennett):
    """Near the assembled state the marker rotations are ~1e-4 rad: there the reference Hessian
    (complex step through (1 - cos phi)/phi^2) carries relative errors ~eps/phi^2, so it is
    compared at 1e-8 and at 1e-12 only on states with large deformation."""
    scene, q_assembled = bennett
    system = scene.system
    for scale, hessian_rtol in ((1e-4, 1e-8), (0.3, 1e-12)):
        q, qd, qdd, lam = _random_state(rng, system, q_assembled, scale)
        _compare(system, q, qd, qdd, lam, t=1.3, hessian_rtol=hessian_rtol)


def test_pendulum_and_free_body_bodies(rng):
    """Body residuals and tangents of the fixtures' bodies (their ground constraints fall back)."""
    system = pendulum(n_modes=3, beta=0.01)[0]
    assert pack_system(system) is None
    free = MultibodySystem(system.bodies, gravity=system.gravity)
    q, qd, qdd, lam = _random_state(rng, free, free.initial_state(), 0.1)
    _compare(free, q, qd, qdd, lam, t=0.0)


def test_dynamic_trajectories_agree(bennett, chain):
    scene, q_assembled = bennett
    for system, q0, t_end in (
        (scene.system, q_assembled, 0.05),
        (chain, chain.initial_state(positions=[[0.0, 0.0, 0.0], [0.2, 0.0, 0.0]]), 0.05),
    ):
        if system is chain:  # start on the constraints
            q0 = static_equilibrium(replace(chain, gravity=np.zeros(3)), q0, fast_path=False).q
        runs = [generalized_alpha(system, q0, np.zeros_like(q0), t_end, 1e-3, fast_path=fast) for fast in (False, True)]
        np.testing.assert_allclose(runs[1].q, runs[0].q, rtol=0, atol=1e-10 * max(1.0, np.abs(runs[0].q).max()))
        np.testing.assert_array_equal(runs[1].newton_iterations, runs[0].newton_iterations)


def test_quasi_static_equilibria_agree(bennett):
    scene, q_assembled = bennett
    times = np.linspace(0.0, scene.drive.time_for_angle(np.radians(30.0)), 4)
    ref, fast = (quasi_static(scene.system, q_assembled, times, fast_path=f) for f in (False, True))
    np.testing.assert_allclose(fast.q, ref.q, rtol=0, atol=1e-10)
    np.testing.assert_allclose(fast.multipliers[:, -1], ref.multipliers[:, -1], rtol=1e-8)  # driving torque


def test_predictor_and_secant_updates_find_the_same_equilibria_in_fewer_iterations(bennett):
    """Eqs. (S2)-(S3) change only Newton's iterates: the equilibria agree to the Newton tolerance
    with plain modified Newton from the previous equilibrium, and take fewer iterations."""
    scene, q_assembled = bennett
    times = np.linspace(0.0, scene.drive.time_for_angle(np.radians(60.0)), 13)
    plain = quasi_static(scene.system, q_assembled, times, predictor_order=0, secant=False)
    faster = quasi_static(scene.system, q_assembled, times)
    np.testing.assert_allclose(faster.q, plain.q, rtol=0, atol=1e-10)
    np.testing.assert_allclose(faster.multipliers[:, -1], plain.multipliers[:, -1], rtol=1e-8)
    assert sum(faster.iterations) < sum(plain.iterations)


class _OverridingJoint(MarkerJoint):
    """A subclass with its own equations (as validation's ExudynMarkerJoint): only it knows them."""

    def value(self, blocks, t):
        return 2.0 * super().value(blocks, t)

    def jacobian(self, blocks, t):
        return [2.0 * rows for rows in super().jacobian(blocks, t)]


def test_unsupported_constraints_fall_back(caplog, chain):
    joint = chain.constraints[1]
    custom = _OverridingJoint(
        joint.bodies,
        joint.name,
        joint.marker0,
        joint.marker1,
        joint.rotation0,
        joint.rotation1,
        joint.offset0,
        joint.offset1,
        joint.locked,
        joint.angle,
    )
    system = MultibodySystem(chain.bodies, (chain.constraints[0], custom), gravity=chain.gravity)
    with caplog.at_level(logging.DEBUG, logger="ffrf.system.packed_system"):
        assert newton_model(system) is system
    assert "_OverridingJoint" in caplog.text
    q0 = static_equilibrium(
        replace(system, gravity=np.zeros(3)),
        system.initial_state(positions=[[0.0, 0.0, 0.0], [0.2, 0.0, 0.0]]),
        fast_path=False,
    ).q
    runs = [generalized_alpha(system, q0, np.zeros_like(q0), 0.01, 1e-3, fast_path=fast) for fast in (False, True)]
    np.testing.assert_array_equal(runs[1].q, runs[0].q)
    pendulum_system = pendulum(n_modes=2)[0]
    assert newton_model(pendulum_system) is pendulum_system
