"""Equilibrium paths through limit points (ffrf.solvers.continuation, Eq. (S5)) against the closed form of a von
Mises truss: an apex on a vertical slide held by two axial springs (Eq. (E6)) under a growing downward load snaps
through at P_max = 2 k (L0 - L*) z* / L*, L* = (L0 a^2)^(1/3), z* = sqrt(L*^2 - a^2). Load control (a plain
quasi-static run) stops there; continuation passes it, and the equilibria beyond it, on the falling branch, are
unstable (Eq. (B1): the squared frequency changes sign at the limit point)."""

from __future__ import annotations

import numpy as np
import pytest
from body_fixtures import bar_model

from ffrf.body.flexible_body import FlexibleBody
from ffrf.body.modal_moments import modal_moments
from ffrf.errors import StaticDivergence
from ffrf.solvers.continuation import continue_path
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
    path = continue_path(system, start.q, start.multipliers, 0.0, end, step=2e-3, max_step=4e-3, max_points=400)
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
