"""Equilibrium paths through limit points (ffrf.solvers.continuation, Eq. (S5)) against the closed form of a von
Mises truss: an apex on a vertical slide held by two axial springs (Eq. (E6)) under a growing downward load snaps
through at P_max = 2 k (L0 - L*) z* / L*, L* = (L0 a^2)^(1/3), z* = sqrt(L*^2 - a^2). Load control (a plain
quasi-static run) stops there; continuation passes it, and the equilibria beyond it, on the falling branch, are
unstable (Eq. (B1): the squared frequency changes sign at the limit point)."""

from __future__ import annotations

import numpy as np
import pytest
from body_fixtures import bar_model
from scipy.optimize import brentq

from ffrf.body.flexible_body import FlexibleBody
from ffrf.body.modal_moments import modal_moments
from ffrf.errors import StaticDivergence
from ffrf.solvers.continuation import continue_path
from ffrf.solvers.snap_through import trace_snap
from ffrf.solvers.stability import equilibrium_stability
from ffrf.solvers.static_solver import quasi_static, static_equilibrium
from ffrf.system.forces import AxialSpringDamper, MarkerLoad
from ffrf.system.joints import GroundFrame, MarkerJoint
from ffrf.system.markers import frame_marker
from ffrf.system.multibody import MultibodySystem

HALF_SPAN, RISE, STIFFNESS, LOAD_RATE = 0.3, 0.1, 1e4, 10.0  # m, m, N/m, N per unit of t


def _truss() -> tuple[MultibodySystem, float]:
    """The apex (a rigid bar, sliding along world z at its centre of mass) and the limit load of the closed form."""
    model = bar_model(E=1e8, rho=450.0)
    body = FlexibleBody(
        "apex",
        modal_moments(model.nodes, model.mass, np.zeros((3 * len(model.nodes), 0))),
        np.zeros((0, 0)),
        np.zeros((0, 0)),
    )
    centre = model.center_of_mass
    marker = frame_marker(0, 0, centre, "apex")
    slide = MarkerJoint((0,), "slide", GroundFrame(point=centre), marker, locked=(True, True, False, True, True, True))
    length = float(np.hypot(HALF_SPAN, RISE))
    springs = tuple(
        AxialSpringDamper(
            (0,),
            f"bar {side}",
            GroundFrame(point=centre + [side * HALF_SPAN, 0.0, -RISE]),
            marker,
            STIFFNESS,
            0.0,
            length,
        )
        for side in (-1.0, 1.0)
    )
    load = MarkerLoad((0,), "load", marker, force=lambda t: [0.0, 0.0, -LOAD_RATE * t])
    system = MultibodySystem((body,), (slide,), forces=springs + (load,))
    critical = (length * HALF_SPAN**2) ** (1.0 / 3.0)
    rise = np.sqrt(critical**2 - HALF_SPAN**2)
    return system, 2.0 * STIFFNESS * (length - critical) * rise / critical


def test_load_control_stops_at_the_limit_load():
    """A quasi-static run with the load growing past P_max finds no equilibrium beyond it."""
    system, limit = _truss()
    times = np.linspace(0.0, 1.2 * limit / LOAD_RATE, 25)
    with pytest.raises(StaticDivergence) as stopped:
        quasi_static(system, system.initial_state(), times)
    reached = times[len(stopped.value.partial.q) - 1]
    assert 0.9 * limit / LOAD_RATE < reached <= limit / LOAD_RATE


def test_continuation_passes_the_limit_point_of_the_closed_form():
    """The path rises to the limit load, snaps through the flat truss and comes back up on the inverted branch:
    its largest t is P_max / rate (parabola through the points around it; measured 3.8e-6 relative), its smallest
    -P_max / rate (5.7e-5), every point satisfies the closed-form equilibrium P(z) = 2 k (L0 - L) z / L (3.7e-13 N),
    and the smallest squared frequency (Eq. (B1)) is positive before the limit point and negative after it."""
    system, limit = _truss()
    start = static_equilibrium(system, system.initial_state())
    end = 1.2 * limit / LOAD_RATE
    path = continue_path(system, start.q, start.multipliers, 0.0, end, step=0.4, max_step=0.8, max_points=400)
    assert path.t[-1] >= end  # back up on the inverted branch
    peaks = path.limit_points() * LOAD_RATE / limit
    assert peaks.shape == (2,)
    assert abs(peaks[0] - 1.0) < 5e-4 and abs(peaks[1] + 1.0) < 5e-3
    rise = RISE + path.q[:, 2] - path.q[0, 2]
    length = np.hypot(HALF_SPAN, rise)
    force = 2.0 * STIFFNESS * (np.hypot(HALF_SPAN, RISE) - length) * rise / length
    assert np.max(np.abs(force - LOAD_RATE * path.t)) < 1e-9
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
    system, limit = _truss()
    start = static_equilibrium(system, system.initial_state())
    snap = trace_snap(system, start.q, start.multipliers, 0.0, 1.2 * limit / LOAD_RATE, step=0.4, max_points=400)
    assert snap is not None and snap.landing_q is not None and snap.return_t is not None
    assert snap.fold_t * LOAD_RATE / limit == pytest.approx(1.0, abs=5e-5)
    assert snap.return_t * LOAD_RATE / limit == pytest.approx(-1.0, abs=5e-3)
    length0 = np.hypot(HALF_SPAN, RISE)

    def load(rise: float) -> float:
        length = np.hypot(HALF_SPAN, rise)
        return 2.0 * STIFFNESS * (length0 - length) * rise / length

    critical_rise = np.sqrt((length0 * HALF_SPAN**2) ** (2.0 / 3.0) - HALF_SPAN**2)
    applied = LOAD_RATE * snap.fold_t
    landing_rise = brentq(lambda z: load(z) - applied, -10.0 * RISE, -critical_rise)
    rise = RISE + snap.landing_q[2] - start.q[2]
    assert abs(rise - landing_rise) < 1e-12
    fold_rise = RISE + snap.fold_q[2] - start.q[2]
    stretch = [np.hypot(HALF_SPAN, z) - length0 for z in (fold_rise, landing_rise)]
    released = STIFFNESS * (stretch[0] ** 2 - stretch[1] ** 2) + applied * (fold_rise - landing_rise)
    print("energy released error", snap.energy_released(system) / released - 1.0)
    assert snap.energy_released(system) == pytest.approx(released, rel=1e-10)


def test_a_path_without_a_fold_is_no_snap():
    """Up to 0.9 P_max the truss path rises monotonically: no snap."""
    system, limit = _truss()
    start = static_equilibrium(system, system.initial_state())
    assert trace_snap(system, start.q, start.multipliers, 0.0, 0.9 * limit / LOAD_RATE, step=0.4) is None
