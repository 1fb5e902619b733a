"""The energy books of a quasi-static path that jumps (ffrf.output.energy_balance, Eq. (C2)): each stretch between
jumps is integrated on its own, a jump's gap in the books is the energy it released, and the rows and the two
sides of each jump are put in the order of t (ffrf.output.sensors.with_jump_ends)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from numpy.typing import NDArray

from ffrf.output.energy_balance import energy_balance, stretch_integral
from ffrf.output.sensors import with_jump_ends
from ffrf.solvers.common import PathJump

#: A drive of stiffness A (N m / rad) whose torque law drops by B (N m) where the path jumps, at THETA_FROM (rad)
A, B, THETA_FROM, THETA_TO, RELEASED = 0.3, 0.05, 1.0, 1.01, 2e-3


def test_each_stretch_is_integrated_on_its_own_and_a_trapezoid_spans_the_jump():
    """A quadratic on each side of a jump (Simpson's rule is exact on quadratics): the cumulative integral is the
    closed form on both stretches, the trapezoid across the jump added; Simpson through both sides is not."""
    left = np.linspace(0.0, 1.0, 7)
    right = np.linspace(1.1, 2.0, 6)
    x = np.concatenate([left, right])
    values = np.concatenate([left**2, right**2 + 5.0])
    found = stretch_integral(values, x, [6])
    across = 0.5 * (1.0 + 1.1**2 + 5.0) * 0.1
    expected = np.concatenate([left**3 / 3.0, 1.0 / 3.0 + across + (right**3 - 1.1**3) / 3.0 + 5.0 * (right - 1.1)])
    np.testing.assert_allclose(found, expected, rtol=0.0, atol=1e-14)
    assert np.abs(stretch_integral(values, x) - expected).max() > 1e-3


def _jumping_drive() -> tuple[NDArray, dict]:
    """A drive that stores its work as strain energy A theta^2 / 2 up to THETA_FROM; there the path jumps to
    THETA_TO, the torque law drops by B and the strain energy by what the jump releases (RELEASED, beyond the
    drive's work across it), and the drive goes on storing its work."""
    before = np.linspace(0.0, THETA_FROM, 9)
    after = np.linspace(THETA_TO, 2.0, 8)
    angle = np.concatenate([before, after])
    torque = np.concatenate([A * before, A * after - B])
    across = 0.5 * (A * THETA_FROM + A * THETA_TO - B) * (THETA_TO - THETA_FROM)
    landed = 0.5 * A * THETA_FROM**2 + across - RELEASED
    strain = np.concatenate([0.5 * A * before**2, landed + 0.5 * A * (after**2 - THETA_TO**2) - B * (after - THETA_TO)])
    zeros = np.zeros_like(angle)
    sensors = {
        "drive_angle": angle,
        "driving_torque": torque,
        "energy_kinetic": zeros,
        "energy_potential": zeros,
        "energy_strain": strain,
    }
    return angle, sensors


def test_what_a_jump_releases_is_counted_as_dissipated_and_the_books_close_on_both_sides():
    angle, sensors = _jumping_drive()
    system = SimpleNamespace(forces=())
    books = energy_balance(system, angle, sensors, None, None, [8])
    assert books["energy_released_in_jumps"][:9] == pytest.approx(0.0, abs=0.0)
    np.testing.assert_allclose(books["energy_released_in_jumps"][9:], RELEASED, rtol=1e-12)
    np.testing.assert_allclose(books["energy_balance_residual"], 0.0, rtol=0.0, atol=1e-15)
    # kept across the jump, the books miss what it released (and Simpson's rule misreads the torque's step)
    unkept = energy_balance(system, angle, sensors, None, None)
    assert np.abs(unkept["energy_balance_residual"]).max() > 0.5 * RELEASED


def _state(value: float) -> NDArray:
    return np.full(2, value)


def test_the_sides_of_each_jump_are_put_among_the_rows_in_the_order_of_t():
    """Rows at t = 0, 1, 2, 3. A path that jumps from its row at t = 1 to t = 1.5, from there at once again to 1.75,
    and snaps at t = 2.5 (fold to landing, one t): the series holds each state once, the given rows where they
    were, and a break before each jump's landing; a jump beyond the last row is left out, and a jump that lands on
    a row (t = 3) ends there."""
    time = np.array([0.0, 1.0, 2.0, 3.0])
    q = np.array([_state(v) for v in (0.0, 1.0, 2.0, 3.0)])
    lam = -q
    jumps = [
        PathJump(1.0, _state(1.0), -_state(1.0), 1.5, _state(1.5), -_state(1.5)),
        PathJump(1.5, _state(1.5), -_state(1.5), 1.75, _state(1.75), -_state(1.75)),
        PathJump(2.5, _state(2.4), -_state(2.4), 2.5, _state(2.6), -_state(2.6)),
        PathJump(2.8, _state(2.8), -_state(2.8), 3.0, _state(3.0), -_state(3.0)),
        PathJump(3.5, _state(3.4), -_state(3.4), 3.6, _state(3.6), -_state(3.6)),
    ]
    series, states, multipliers, rows, breaks = with_jump_ends(time, q, lam, jumps)
    np.testing.assert_array_equal(series, [0.0, 1.0, 1.5, 1.75, 2.0, 2.5, 2.5, 2.8, 3.0])
    np.testing.assert_array_equal(states[:, 0], [0.0, 1.0, 1.5, 1.75, 2.0, 2.4, 2.6, 2.8, 3.0])
    np.testing.assert_array_equal(multipliers, -states)
    np.testing.assert_array_equal(rows, [0, 1, 4, 8])
    assert breaks == [1, 2, 5, 7]
    np.testing.assert_array_equal(states[rows], q)


def test_a_state_solved_twice_is_one_and_a_snap_lands_before_the_next_jump_from_its_landing():
    """A snap at t = 1.5 whose landing the next leg re-solved (1e-12 off) and jumped from at once, listed before the
    snap as the run lists them; a jump that leaves a row re-solved likewise: each state once, in the order of the
    path. States that cannot be ordered (an output between a snap's fold and landing) give the rows alone."""
    time = np.array([0.0, 1.0, 2.0])
    q = np.array([_state(v) for v in (0.0, 1.0, 2.0)])
    lam = -q
    polished = _state(1.6) + 1e-12
    jumps = [
        PathJump(1.5, polished, -polished, 1.7, _state(1.7), -_state(1.7)),
        PathJump(1.5, _state(1.4), -_state(1.4), 1.5, _state(1.6), -_state(1.6)),
        PathJump(1.0, _state(1.0) + 1e-12, -_state(1.0), 1.2, _state(1.2), -_state(1.2)),
    ]
    series, states, _, rows, breaks = with_jump_ends(time, q, lam, jumps)
    np.testing.assert_array_equal(series, [0.0, 1.0, 1.2, 1.5, 1.5, 1.7, 2.0])
    np.testing.assert_allclose(states[:, 0], [0.0, 1.0, 1.2, 1.4, 1.6, 1.7, 2.0])
    np.testing.assert_array_equal(rows, [0, 1, 6])
    assert breaks == [1, 3, 4]
    # an output row at a snap's t that is neither its fold nor its landing: no order, no breaks
    crowded = np.array([0.0, 1.5, 2.0])
    series, _, _, rows, breaks = with_jump_ends(crowded, q, lam, jumps[1:2])
    np.testing.assert_array_equal(series, crowded)
    np.testing.assert_array_equal(rows, [0, 1, 2])
    assert breaks == []
