"""Steps refined from the solution (issue #32, Eq. (G8)): a generalized-alpha step whose local error estimate, every
coordinate in metres, exceeds ``error_tolerance`` is redone in twice as many parts; a step whose Newton needed more
than ``SLOW_NEWTON`` iterations makes the next one start in twice as many; the parts grow back where the estimate
is small, and a run whose estimates stay far below the tolerance takes the very same steps as without it.

The case: the soft bar pendulum of ``pendulum_fixtures`` (hinged at one end, gravity, E = 1e8 Pa, one clamped-
interface mode of about 61 Hz, ``omega = sqrt(K_red / M_red)``) started horizontal at rest with a modal velocity:
its vibration has a period of 16 ms, shorter than two 10 ms drive steps."""

from functools import cache

import numpy as np
import pytest
from pendulum_fixtures import pendulum, tip_position

from ffrf.solvers.generalized_alpha import MAX_PARTS, SLOW_NEWTON, generalized_alpha

H, RHO = 1e-2, 0.9  # the drive rule's longest step (10 ms) and the linkage runs' spectral radius
BAR = 0.2  # m, the bar's length


@cache
def _bar(beta: float = 0.0):
    return pendulum(n_modes=1, E=1e8, beta=beta)


def _start(modal_velocity: float, beta: float = 0.0):
    system, _, _, _ = _bar(beta)
    q0 = system.initial_state()
    qd0 = np.zeros_like(q0)
    qd0[7] = modal_velocity
    return system, q0, qd0


def _parts(result) -> np.ndarray:
    """Parts each drive step of ``result`` was done in (its steps are equal parts of the drive steps)."""
    ends = np.cumsum(result.step_sizes)
    last = np.searchsorted(ends, H * np.arange(1, int(round(ends[-1] / H)) + 1) - 1e-12)
    return np.round(H / result.step_sizes[last]).astype(int)


def test_the_mode_is_faster_than_the_drive_step():
    """The closed form of the case: a period 2 pi / omega below two drive steps, so that a drive step cannot
    resolve the vibration (the premise of the tests below)."""
    system, _, _, _ = _bar()
    body = system.bodies[0]
    omega = np.sqrt(body.stiffness[0, 0] / body.moments.reduced_mass[0, 0])
    assert 2.0 * np.pi / omega < 2.0 * H


def test_refined_first_drive_step_meets_the_tolerance():
    """Over the first drive step (the same start, so the error is the step's own, local one) the tip's error
    against a reference run with 512 parts per drive step is below the tolerance with refinement (G8) and more
    than ten times above it on the drive's step. Measured: 1.7e-6 m with 32 parts, 6.1e-5 m in one step."""
    tolerance = 1e-5 * BAR
    system, model, psi, _ = _bar()
    _, q0, qd0 = _start(0.01)
    reference = generalized_alpha(system, q0, qd0, H, H / 512, rho_inf=RHO, output_every=512)
    tip = tip_position(reference.q[-1], model, psi)
    fixed = generalized_alpha(system, q0, qd0, H, H, rho_inf=RHO)
    refined = generalized_alpha(system, q0, qd0, H, H, rho_inf=RHO, error_tolerance=tolerance)
    assert np.abs(tip_position(fixed.q[-1], model, psi) - tip).max() > 10.0 * tolerance
    assert np.abs(tip_position(refined.q[-1], model, psi) - tip).max() < tolerance
    assert 1 < len(refined.step_sizes) < MAX_PARTS  # refined, by halvings, below the cap
    assert refined.time[-1] == fixed.time[-1] == pytest.approx(H)


def test_estimates_far_below_the_tolerance_change_nothing():
    """The pendulum at rest (no vibration; Newton needs at most SLOW_NEWTON iterations): with a tolerance far above
    every estimate the run is bit for bit the one without control, with and without a step limit."""
    system, q0, qd0 = _start(0.0)
    plain = generalized_alpha(system, q0, qd0, 0.3, H, rho_inf=RHO)
    assert plain.newton_iterations.max() <= SLOW_NEWTON
    for limit in (None, lambda t0, t1: H / 2):
        without = generalized_alpha(system, q0, qd0, 0.3, H, rho_inf=RHO, step_limit=limit)
        controlled = generalized_alpha(system, q0, qd0, 0.3, H, rho_inf=RHO, step_limit=limit, error_tolerance=1.0)
        np.testing.assert_array_equal(controlled.q, without.q)
        np.testing.assert_array_equal(controlled.qd, without.qd)
        np.testing.assert_array_equal(controlled.step_sizes, without.step_sizes)


def test_refinement_is_local_parts_grow_back():
    """A damped vibration (stiffness-proportional damping, ratio beta omega / 2 = 0.38): the first drive steps are
    refined while it rings, the later ones are back to the drive's step."""
    system, q0, qd0 = _start(0.01, beta=2e-3)
    result = generalized_alpha(system, q0, qd0, 0.3, H, rho_inf=RHO, error_tolerance=5e-3 * BAR)
    parts = _parts(result)
    assert parts[0] > 1
    assert np.all(parts[-10:] == 1)
    assert np.all(parts[1:] <= 2 * parts[:-1])  # parts at most double from one step to the next


def test_slow_newton_refines_the_next_step():
    """A strong vibration (modal velocity 0.1) makes some 10 ms steps need more than SLOW_NEWTON iterations (a
    retried Newton); with control the step after such a step is done in at least twice as many parts, even with a
    tolerance no estimate reaches."""
    system, q0, qd0 = _start(0.1)
    plain = generalized_alpha(system, q0, qd0, 0.1, H, rho_inf=RHO)
    slow = np.flatnonzero(plain.newton_iterations > SLOW_NEWTON)
    assert slow.size and slow[0] + 1 < plain.newton_iterations.size
    controlled = generalized_alpha(system, q0, qd0, 0.1, H, rho_inf=RHO, error_tolerance=1e3)
    parts = _parts(controlled)
    np.testing.assert_array_equal(controlled.step_sizes[: slow[0] + 1], plain.step_sizes[: slow[0] + 1])
    assert parts[slow[0] + 1] >= 2


def test_bad_tolerance_is_refused():
    system, q0, qd0 = _start(0.0)
    with pytest.raises(ValueError, match="error_tolerance must be positive"):
        generalized_alpha(system, q0, qd0, H, H, error_tolerance=0.0)


def test_modal_error_in_metres_is_the_nodal_rms_displacement():
    """Eq. (G8)'s modal term against the full nodal model: an estimate e_zeta of the modal coordinates alone
    measures sqrt(u^T M u / m) with the nodal displacements u = Psi e_zeta and the FE mass matrix M (m = the bar's
    mass, the sum of M's translational rows); a position estimate alone measures its largest component."""
    from body_fixtures import free_bar

    from ffrf.solvers.generalized_alpha import AlphaParameters
    from ffrf.solvers.step_control import DisplacementScales, displacement_error
    from ffrf.system.multibody import MultibodySystem

    model, psi, _, body = free_bar()
    system = MultibodySystem((body,))
    par, h = AlphaParameters(RHO), 1e-3
    scale = (par.beta - 1.0 / 6.0) * h * h  # Eq. (G5): e = scale (qdd_new - qdd_old)
    rng = np.random.default_rng(1)
    change = np.zeros(system.n_coordinates)
    change[7:] = rng.normal(size=body.n_modes)
    u = psi @ (scale * change[7:])
    mass = model.mass.sum() / 3.0
    expected = np.sqrt(u @ (model.mass @ u) / mass)
    scales = DisplacementScales.of(system)
    measured = displacement_error(par.beta, h, change, np.zeros_like(change), scales)
    assert measured == pytest.approx(expected, rel=1e-9)
    change[:] = 0.0
    change[:3] = [1.0, -3.0, 2.0]
    assert displacement_error(par.beta, h, change, np.zeros_like(change), scales) == pytest.approx(3.0 * abs(scale))


def test_a_tolerance_beyond_the_cap_is_said(caplog):
    """A tolerance no part of 1/MAX_PARTS of the drive step meets (the 0.16 ms part's estimate is about 3.6e-8 m):
    the parts are kept at the cap and the run says so."""
    system, q0, qd0 = _start(0.01)
    with caplog.at_level("WARNING", logger="ffrf.solvers.generalized_alpha"):
        result = generalized_alpha(system, q0, qd0, 2 * H, H, rho_inf=RHO, error_tolerance=1e-9)
    assert np.all(_parts(result) == MAX_PARTS)
    assert "above error_tolerance" in caplog.text


def test_a_refined_run_replayed_by_its_parts_is_the_same_run():
    """The damped vibration's refined run, encoded by ``step_parts`` and taken again with ``replayed_limit`` and no
    error control, is the same run to the last bit (what a cross-validation's variants of one scene rely on)."""
    from ffrf.solvers.generalized_alpha import replayed_limit, step_parts

    system, q0, qd0 = _start(0.01, beta=2e-3)
    refined = generalized_alpha(system, q0, qd0, 0.3, H, rho_inf=RHO, error_tolerance=5e-3 * BAR)
    parts = step_parts(refined.step_sizes, H)
    assert parts[0][0] > 1 and parts[-1][0] == 1  # refined at the start, back to whole steps later
    replayed = generalized_alpha(system, q0, qd0, 0.3, H, rho_inf=RHO, step_limit=replayed_limit(H, parts))
    np.testing.assert_array_equal(replayed.step_sizes, refined.step_sizes)
    np.testing.assert_array_equal(replayed.q, refined.q)
    with pytest.raises(ValueError, match="replayed steps end at t = 0.3"):
        generalized_alpha(system, q0, qd0, 0.31, H, rho_inf=RHO, step_limit=replayed_limit(H, parts))
