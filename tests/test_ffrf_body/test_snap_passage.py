"""Where a snap goes when the traced path shows no landing: the dynamic passage at the fold's t (Eq. (S11)), on the
von Mises truss of axial springs, whose landing on the inverted branch has a closed form."""

from __future__ import annotations

import numpy as np
import pytest
from body_fixtures import TRUSS_HALF_SPAN, TRUSS_LOAD_RATE, TRUSS_RISE, TRUSS_STIFFNESS, spring_truss
from body_fixtures import spring_truss_landing as landing_rise

from ffrf.errors import NewtonDivergence
from ffrf.solvers.generalized_alpha import generalized_alpha
from ffrf.solvers.snap_passage import dynamic_passage
from ffrf.solvers.snap_through import quasi_static_through_snaps, snap_summary, trace_snap
from ffrf.solvers.static_solver import static_equilibrium

#: Trace points that end the truss's trace on its unstable branch, before it comes back to the fold's load.
SHORT_TRACE = 12


def _apex_rise(q: np.ndarray, start_q: np.ndarray) -> float:
    return float(TRUSS_RISE + q[2] - start_q[2])


def test_held_time_holds_the_load():
    """``held_time``: the load stays at its value at that t while the integration's time runs. The equilibrium at
    t = 2 stays at rest to Newton's tolerance (measured 7.7e-11 m) over 0.1 s; the same start without it moves under
    the load of t from 0 (a 20 N drop of the load: 22 mm)."""
    system, _ = spring_truss()
    at_two = static_equilibrium(system, system.initial_state(), 2.0)
    rest = np.zeros_like(at_two.q)
    held = generalized_alpha(system, at_two.q, rest, 0.1, 1e-3, held_time=2.0)
    moving = generalized_alpha(system, at_two.q, rest, 0.1, 1e-3)
    print("held drift", np.abs(held.q - at_two.q).max(), "unheld", np.abs(moving.q - at_two.q).max())
    assert np.abs(held.q - at_two.q).max() < 1e-9
    assert np.abs(moving.q - at_two.q).max() > 1e-3


@pytest.fixture(scope="module")
def short_trace():
    """The truss's trace through its fold cut short (:data:`SHORT_TRACE` points): it has no landing."""
    system, limit = spring_truss()
    start = static_equilibrium(system, system.initial_state())
    snap = trace_snap(system, start.q, start.multipliers, 0.0, 1.2 * limit / TRUSS_LOAD_RATE, 0.4, SHORT_TRACE)
    assert snap is not None and snap.landing_q is None
    return system, start, snap


def test_the_passage_lands_on_the_inverted_branch_of_the_closed_form(short_trace):
    """From the fold nudged along its softest mode, the apex falls under the load held at P_max through the flat
    truss into the inverted branch's well; settled from the kinetic energy's peak it lands where the closed form
    P(z) = P_max has its root z < -z* (measured 7e-17 m). By conservation the swing's kinetic energy at the well's
    bottom is the energy the jump releases (the springs' energy drop plus the load's work, from the closed form);
    the peak sampled at the passage's outputs holds it to 6e-3 (measured), the generalized-alpha's
    dissipation included."""
    system, start, snap = short_trace
    path = snap.path
    k = next(k for k in range(1, len(path.t)) if path.t[k] < path.t[k - 1])
    beyond = (path.t[k], path.q[k], path.multipliers[k])  # the trace's first point past the fold
    passage = dynamic_passage(system, snap.fold_t, snap.fold_q, snap.fold_multipliers, beyond)
    assert passage is not None
    applied = TRUSS_LOAD_RATE * snap.fold_t
    expected = landing_rise(applied)
    print("landing error", _apex_rise(passage.q, start.q) - expected, "steps", passage.steps)
    assert _apex_rise(passage.q, start.q) == pytest.approx(expected, abs=1e-12)
    fold_rise = _apex_rise(snap.fold_q, start.q)
    length0 = np.hypot(TRUSS_HALF_SPAN, TRUSS_RISE)
    stretch = [np.hypot(TRUSS_HALF_SPAN, z) - length0 for z in (fold_rise, expected)]
    released = TRUSS_STIFFNESS * (stretch[0] ** 2 - stretch[1] ** 2) + applied * (fold_rise - expected)
    print("peak kinetic energy / released", passage.peak_kinetic_energy_j / released - 1.0)
    assert passage.peak_kinetic_energy_j == pytest.approx(released, rel=1e-2)


def test_a_run_whose_trace_lands_nowhere_goes_on_from_the_passage(short_trace):
    """A quasi-static run to 1.2 P_max whose trace through the fold is cut short lands by the dynamic passage and
    goes on along the inverted branch: every output after the fold solves the closed form at its load (measured
    8.8e-13 m), and the snap's summary says how it landed. (With the trace not cut short the same run's rows are
    the same to 2e-20 m, measured once; the traced landing is tested in test_continuation.py.)"""
    system, start, _ = short_trace
    limit = spring_truss()[1]
    times = np.linspace(0.0, 1.2 * limit / TRUSS_LOAD_RATE, 8)  # no output and no path step at the fold itself
    step = times[-1] / 20.0  # the path on its own steps (Eq. (S10))
    run, snaps = quasi_static_through_snaps(system, start.q, times, path_step=lambda t: step, trace_points=SHORT_TRACE)
    assert len(snaps) == 1 and snaps[0].passage is not None
    summary = snap_summary(system, snaps[0])
    assert summary["landed"] and summary["landed_by"] == "dynamic passage"
    after = times > snaps[0].fold_t
    rises = np.array([_apex_rise(q, start.q) for q in run.q[after]])
    expected = np.array([landing_rise(TRUSS_LOAD_RATE * t) for t in times[after]])
    print("rows against the closed form", np.abs(rises - expected).max())
    assert after.sum() >= 2 and np.abs(rises - expected).max() < 1e-11


def test_held_time_holds_a_linkage_s_drive_on_the_whole_system_kernels():
    """The PLA Bennett (coarse links) runs on the packed kernels, whose drive angles come from the held time too: an
    equilibrium of its quasi-static run stays at rest over 20 ms with the drive held at its t (to Newton's tolerance
    over the coordinates' size, measured 4.5e-14 m), while the same start with the drive at the integration's own time,
    from 0, is yanked back towards the drive's start angle within a step, which Newton cannot follow."""
    from dataclasses import replace

    from ffrf.fe.materials import PLA
    from ffrf.paper.bennett_scene import bennett_options, build_bennett_from_options
    from ffrf.scenes.linkage_run import run_linkage
    from ffrf.system.packed_system import pack_system

    scene = build_bennett_from_options(replace(bennett_options("pla", h=8e-3, order=1, n_modes=2), material=PLA))
    assert pack_system(scene.system) is not None  # the fast path runs it
    result = run_linkage(scene, mode="quasi_static", n_outputs=5, t_end=0.4 * scene.t_end)
    q, t = result.q[-1], float(result.time[-1])
    rest = np.zeros_like(q)
    held = generalized_alpha(scene.system, q, rest, 0.02, 1e-3, held_time=t)
    print("held drift", np.abs(held.q - q).max())
    assert np.abs(held.q - q).max() < 1e-9
    with pytest.raises(NewtonDivergence):  # the drive at t = 1 ms of its ramp: the links yanked through the loop
        generalized_alpha(scene.system, q, rest, 0.02, 1e-3)


@pytest.mark.slow  # two monitored runs of a 6R to its fold, 25 s
def test_a_printed_6r_whose_trace_is_cut_short_lands_by_the_passage_where_the_trace_lands(monkeypatch):
    """plane_fold_6r printed in PLA (6 mm quadratic links, the snap of docs/stability.md), run with stability
    monitoring past its first fold twice: once as it is (the trace comes back to the fold's drive angle and lands),
    once with every trace cut at 12 points, so that the landing is the dynamic passage's (667 steps, measured). Both
    snap at the same drive angle, release the same energy and go on from the same equilibrium: the coupler point of
    every output after the snap agrees to round-off (measured 1.5e-16 m against a jump of 8.6 mm)."""
    import ffrf.solvers.snap_through as snap_through
    from bench.snap_plane_fold import _scene
    from ffrf.scenes.linkage_run import run_linkage

    scene = _scene(6.0, 2, 4)
    traced = run_linkage(scene, "quasi_static", 31, t_end=30.0, stability=True)
    original = snap_through.trace_snap

    def cut(system, q0, multipliers0, t0, t_end, step, max_points=600, *args, **kwargs):
        return original(system, q0, multipliers0, t0, t_end, step, min(max_points, SHORT_TRACE), *args, **kwargs)

    monkeypatch.setattr(snap_through, "trace_snap", cut)
    passed = run_linkage(scene, "quasi_static", 31, t_end=30.0, stability=True)
    (first,), (second,) = traced.metadata["stability"]["snaps"], passed.metadata["stability"]["snaps"]
    assert first["landed_by"] == "traced path" and second["landed_by"] == "dynamic passage"
    assert second["drive_angle_deg"] == pytest.approx(first["drive_angle_deg"], abs=1e-9)
    assert second["energy_released_J"] == pytest.approx(first["energy_released_J"], rel=1e-6)
    difference = np.abs(traced.sensors["coupler_point"] - passed.sensors["coupler_point"]).max()
    print("coupler difference", difference, "jump", first["coupler_jump_m"])
    assert difference < 1e-9 * first["coupler_jump_m"]
