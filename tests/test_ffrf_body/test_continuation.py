"""Equilibrium paths through limit points (ffrf.solvers.continuation, Eq. (S5)) against the closed form of a von
Mises truss: an apex on a vertical slide held by two axial springs (Eq. (E6)) under a growing downward load snaps
through at P_max = 2 k (L0 - L*) z* / L*, L* = (L0 a^2)^(1/3), z* = sqrt(L*^2 - a^2). Load control (a plain
quasi-static run) stops there; continuation passes it, and the equilibria beyond it, on the falling branch, are
unstable (Eq. (B1): the squared frequency changes sign at the limit point)."""

from __future__ import annotations

import numpy as np
import pytest
from body_fixtures import (
    TRUSS_HALF_SPAN,
    TRUSS_LOAD_RATE,
    TRUSS_RISE,
    TRUSS_STIFFNESS,
    spring_truss,
    spring_truss_landing,
)

from ffrf.errors import StaticDivergence
from ffrf.solvers.continuation import continue_path
from ffrf.solvers.snap_through import trace_snap
from ffrf.solvers.stability import equilibrium_stability
from ffrf.solvers.static_solver import quasi_static, static_equilibrium


def test_load_control_stops_at_the_limit_load():
    """A quasi-static run with the load growing past P_max finds no equilibrium beyond it."""
    system, limit = spring_truss()
    times = np.linspace(0.0, 1.2 * limit / TRUSS_LOAD_RATE, 25)
    with pytest.raises(StaticDivergence) as stopped:
        quasi_static(system, system.initial_state(), times)
    reached = times[len(stopped.value.partial.q) - 1]
    assert 0.9 * limit / TRUSS_LOAD_RATE < reached <= limit / TRUSS_LOAD_RATE


def test_continuation_passes_the_limit_point_of_the_closed_form():
    """The path rises to the limit load, snaps through the flat truss and comes back up on the inverted branch:
    its largest t is P_max / rate (parabola through the points around it; measured 3.8e-6 relative), its smallest
    -P_max / rate (5.7e-5), every point satisfies the closed-form equilibrium P(z) = 2 k (L0 - L) z / L (3.7e-13 N),
    and the smallest squared frequency (Eq. (B1)) is positive before the limit point and negative after it."""
    system, limit = spring_truss()
    start = static_equilibrium(system, system.initial_state())
    end = 1.2 * limit / TRUSS_LOAD_RATE
    path = continue_path(system, start.q, start.multipliers, 0.0, end, step=0.4, max_step=0.8, max_points=400)
    assert path.t[-1] >= end  # back up on the inverted branch
    peaks = path.limit_points() * TRUSS_LOAD_RATE / limit
    assert peaks.shape == (2,)
    assert abs(peaks[0] - 1.0) < 5e-4 and abs(peaks[1] + 1.0) < 5e-3
    rise = TRUSS_RISE + path.q[:, 2] - path.q[0, 2]
    length = np.hypot(TRUSS_HALF_SPAN, rise)
    force = 2.0 * TRUSS_STIFFNESS * (np.hypot(TRUSS_HALF_SPAN, TRUSS_RISE) - length) * rise / length
    assert np.max(np.abs(force - TRUSS_LOAD_RATE * path.t)) < 1e-9
    top = next(k for k in range(1, len(path.t) - 1) if path.t[k - 1] < path.t[k] > path.t[k + 1])
    before, after = (
        equilibrium_stability(system, path.q[k], path.multipliers[k], path.t[k]).squared_frequencies[0]
        for k in (top - 1, top + 1)
    )
    assert before > 0.0 > after


def test_the_truss_snaps_at_the_limit_load_onto_the_inverted_branch_of_the_closed_form():
    """Eq. (S6): past P_max the apex jumps, at that load, to the inverted branch. The landing rise solves the
    closed form P(z) = P_max beyond the other fold z < -z* (scipy's brentq on the closed form; measured
    1.5e-14 m), the fold is at P_max (1.4e-6 relative, traced again at a tenth of the step), the return fold
    at -P_max (5.6e-5), and the energy released is the springs' energy drop k [(L - L0)^2 at the fold less at
    the landing] plus the dead load's work in the jump, P (z_fold - z_landing) (no gravity, a rigid apex;
    measured 4e-16 relative)."""
    system, limit = spring_truss()
    start = static_equilibrium(system, system.initial_state())
    snap = trace_snap(system, start.q, start.multipliers, 0.0, 1.2 * limit / TRUSS_LOAD_RATE, step=0.4, max_points=400)
    assert snap is not None and snap.landing_q is not None and snap.return_t is not None
    assert snap.fold_t * TRUSS_LOAD_RATE / limit == pytest.approx(1.0, abs=5e-5)
    assert snap.return_t * TRUSS_LOAD_RATE / limit == pytest.approx(-1.0, abs=5e-3)
    length0 = np.hypot(TRUSS_HALF_SPAN, TRUSS_RISE)
    applied = TRUSS_LOAD_RATE * snap.fold_t
    landing_rise = spring_truss_landing(applied)
    rise = TRUSS_RISE + snap.landing_q[2] - start.q[2]
    assert abs(rise - landing_rise) < 1e-12
    fold_rise = TRUSS_RISE + snap.fold_q[2] - start.q[2]
    stretch = [np.hypot(TRUSS_HALF_SPAN, z) - length0 for z in (fold_rise, landing_rise)]
    released = TRUSS_STIFFNESS * (stretch[0] ** 2 - stretch[1] ** 2) + applied * (fold_rise - landing_rise)
    print("energy released error", snap.energy_released(system) / released - 1.0)
    assert snap.energy_released(system) == pytest.approx(released, rel=1e-10)


def test_a_path_without_a_fold_is_no_snap():
    """Up to 0.9 P_max the truss path rises monotonically: no snap."""
    system, limit = spring_truss()
    start = static_equilibrium(system, system.initial_state())
    assert trace_snap(system, start.q, start.multipliers, 0.0, 0.9 * limit / TRUSS_LOAD_RATE, step=0.4) is None
