r"""Where an equilibrium path snaps: its fold and the equilibrium it lands on (``docs/formulation.md``, Eq. (S6)).

A quasi-static run prescribes the parameter t (a drive angle's or a load's time law). At a limit point (fold) of
the equilibrium path the path turns back in t, so no nearby equilibrium exists beyond it: a position-controlled
drive or a dead load taken past the fold makes the structure jump, at that t, to an equilibrium of another
branch. Continuation (Eq. (S5)) follows the path through the fold, back along the unstable branch to the other
fold, where it turns forward again; where it passes the first fold's t once more lies the landing equilibrium.
The jump happens at fixed t, so the drive does no work in it and a load that depends on time alone is a dead load
in it: the potential energy the structure holds at the fold (strain, gravity, force elements, and such loads'
potential -F.x) less that at the landing is what the jump releases, as kinetic energy that damping then
dissipates.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from ffrf.errors import Interrupted, StaticDivergence
from ffrf.solvers.common import PathJump
from ffrf.solvers.continuation import EquilibriumPath, equilibrium_path, parabola_vertex, path_points, path_speed
from ffrf.solvers.snap_passage import Passage, dynamic_passage
from ffrf.solvers.stability import CriticalPose, critical_pose, equilibrium_stability, mode_shares
from ffrf.solvers.static_solver import StaticSolution, path_times, quasi_static, static_equilibrium
from ffrf.system.multibody import MultibodySystem

__all__ = [
    "NO_LANDING",
    "NO_LANDING_WORDS",
    "SnapThrough",
    "run_critical_pose",
    "snap_summary",
    "trace_snap",
    "quasi_static_through_snaps",
]

log = logging.getLogger(__name__)

#: Steps per arclength of the first trace when a fold is traced again to locate it.
REFINEMENT = 10
#: Quarterings of a trace's first step that may be needed to see the path rise in t before its fold.
MAX_STEP_CUTS = 12
#: Snaps one quasi-static run may pass before it is stopped.
MAX_SNAPS = 4
#: Points a trace through a fold may take to come back to the fold's t (else the landing is the passage's, (S11)).
TRACE_POINTS = 600


@dataclass(frozen=True)
class SnapThrough:
    """A fold at ``fold_t`` (equilibrium ``fold_q``, ``fold_multipliers`` there), the other fold ``return_t``
    where the path turns forward again (``None`` if it does not within the traced points), the landing
    equilibrium at ``fold_t`` beyond it (``None`` likewise), the traced ``path``, and what found the landing:
    the traced path (Eq. (S6)) or a dynamic passage (Eq. (S11), ``passage`` its record)."""

    fold_t: float
    fold_q: NDArray[np.float64]
    fold_multipliers: NDArray[np.float64]
    return_t: float | None
    landing_q: NDArray[np.float64] | None
    landing_multipliers: NDArray[np.float64] | None
    path: EquilibriumPath
    passage: Passage | None = None

    def energy_released(self, system: MultibodySystem) -> float | None:
        """Potential energy at the fold less that at the landing (J): strain, gravity, force elements and the dead
        loads at the fold's t, whose work in the jump it includes
        (:meth:`~ffrf.system.multibody.MultibodySystem.potential_energy`)."""
        if self.landing_q is None:
            return None
        return system.potential_energy(self.fold_q, self.fold_t) - system.potential_energy(self.landing_q, self.fold_t)

    def as_jump(self) -> PathJump | None:
        """The snap as a jump of the path at the fold's t, from the fold to the landing; ``None`` without one."""
        if self.landing_q is None or self.landing_multipliers is None:
            return None
        return PathJump(
            self.fold_t, self.fold_q, self.fold_multipliers, self.fold_t, self.landing_q, self.landing_multipliers
        )


def snap_summary(system: MultibodySystem, snap: SnapThrough) -> dict:
    """A snap as plain data for a run's metadata: the fold's t (``time_s``), whether it landed, the energy released
    (J, ``None`` without a landing), the other fold's t, and Eq. (B1) at the fold (its smallest squared frequency,
    near zero) with each body's share of the critical mode's kinetic energy (which bodies it moves)."""
    critical = equilibrium_stability(system, snap.fold_q, snap.fold_multipliers, snap.fold_t, count=1)
    shares = mode_shares(system, snap.fold_q, critical.modes[:, 0])
    return {
        "kind": "limit point",
        "time_s": snap.fold_t,
        "landed": snap.landing_q is not None and snap.landing_multipliers is not None,
        "energy_released_J": snap.energy_released(system),
        "landed_by": None if snap.landing_q is None else "traced path" if snap.passage is None else "dynamic passage",
        "passage_peak_kinetic_energy_J": None if snap.passage is None else snap.passage.peak_kinetic_energy_j,
        "return_time_s": snap.return_t,
        "squared_frequency_at_fold": float(critical.squared_frequencies[0]),
        "critical_mode_body_shares": {
            body.name: float(share) for body, share in zip(system.bodies, shares, strict=True)
        },
    }


def trace_snap(
    system: MultibodySystem,
    q0: NDArray,
    multipliers0: NDArray,
    t0: float,
    t_end: float,
    step: float,
    max_points: int = TRACE_POINTS,
    tolerance: float = 1e-10,
    max_step: float | None = None,
) -> SnapThrough | None:
    """Follow the path from the equilibrium ``(q0, multipliers0)`` at ``t0`` towards ``t_end`` (Eq. (S5), first
    arclength ``step``, at most ``max_step``, default 8 ``step``). ``None`` if t reaches ``t_end`` without a fold;
    otherwise the :class:`SnapThrough` at the first fold, with the landing equilibrium if the path comes forward past
    the fold's t within ``max_points``."""
    direction = 1.0 if t_end >= t0 else -1.0
    points: list[tuple[float, NDArray, NDArray, float]] = []
    fold: tuple[float, NDArray, NDArray] | None = None
    return_t = None
    speed = path_speed(system, q0, multipliers0, t0)  # one c for the trace and the refinement: one arclength
    step = _forward_step(system, q0, multipliers0, t0, direction, step, tolerance, speed)
    for point in path_points(system, q0, multipliers0, t0, direction, step, tolerance, max_step=max_step, speed=speed):
        points.append(point)
        if len(points) >= max_points:
            break
        if len(points) < 3:
            continue
        rise = (points[-1][0] - points[-2][0]) * direction
        before = (points[-2][0] - points[-3][0]) * direction
        if fold is None:
            if (point[0] - t_end) * direction >= 0.0 and rise > 0.0:
                return None
            if before > 0.0 >= rise:
                fold = _refined_fold(system, points[-3], points[-1][3] - points[-3][3], direction, tolerance, speed)
        elif return_t is None:
            if before < 0.0 <= rise:
                return_t = _vertex(points[-3:])[0]
        elif (point[0] - fold[0]) * direction >= 0.0:
            landing_q, landing_lam = _landing(system, points[-2], points[-1], fold[0], tolerance)
            return SnapThrough(fold[0], fold[1], fold[2], return_t, landing_q, landing_lam, equilibrium_path(points))
    if fold is None:
        return None
    return SnapThrough(fold[0], fold[1], fold[2], return_t, None, None, equilibrium_path(points))


def _forward_step(
    system: MultibodySystem,
    q0: NDArray,
    multipliers0: NDArray,
    t0: float,
    direction: float,
    step: float,
    tolerance: float,
    speed: float,
) -> float:
    """``step``, quartered until the path's first point lies ahead in t. A start closer to the fold than one step
    would otherwise turn back within the first step, before three points can show the turn, and the fold go
    unseen (a quasi-static run stops just short of it)."""
    for _ in range(MAX_STEP_CUTS):
        points = path_points(system, q0, multipliers0, t0, direction, step, tolerance, speed=speed)
        next(points)  # the start
        if (next(points)[0] - t0) * direction > 0.0:
            return step
        step /= 4.0
    raise StaticDivergence(f"the path from t = {t0:.6g} turns back within every first step down to {step:.3g}")


def _vertex(three: list[tuple[float, NDArray, NDArray, float]]) -> tuple[float, NDArray, NDArray]:
    """The fold's t, coordinates and multipliers, interpolated on the parabola through three path points."""
    t_fold, weights = parabola_vertex(np.array([p[3] for p in three]), np.array([p[0] for p in three]))
    q = sum(w * p[1] for w, p in zip(weights, three, strict=True))
    lam = sum(w * p[2] for w, p in zip(weights, three, strict=True))
    return t_fold, np.asarray(q), np.asarray(lam)


def _refined_fold(
    system: MultibodySystem, before: tuple, span: float, direction: float, tolerance: float, speed: float
) -> tuple[float, NDArray, NDArray]:
    """The fold between ``before`` and the point ``span`` of arclength on, traced again in steps of a tenth of it
    (the parabola's error falls with the cube of the spacing: 1e-3 of the first trace's)."""
    step = span / REFINEMENT
    points: list[tuple[float, NDArray, NDArray, float]] = []
    for point in path_points(
        system, before[1], before[2], before[0], direction, step, tolerance, max_step=step, speed=speed
    ):
        points.append(point)
        if len(points) >= 3 and (points[-1][0] - points[-2][0]) * direction <= 0.0:
            return _vertex(points[-3:])
        if len(points) > 3 * REFINEMENT:
            break
    raise StaticDivergence(f"the fold near t = {before[0]:.6g} was not found again at a tenth of the step")


def _landing(system: MultibodySystem, before: tuple, after: tuple, t: float, tolerance: float):
    """The equilibrium at ``t`` between two path points that bracket it, Newton from their linear interpolation."""
    share = (t - before[0]) / (after[0] - before[0])
    guess = (1.0 - share) * before[1] + share * after[1]
    solution = static_equilibrium(system, guess, t, tolerance=tolerance)
    return solution.q, solution.multipliers


def bridge(
    system: MultibodySystem,
    q0: NDArray,
    multipliers0: NDArray,
    t0: float,
    t_target: float,
    step: float,
    max_points: int = 600,
    tolerance: float = 1e-10,
) -> tuple[NDArray, NDArray] | None:
    """The equilibrium at ``t_target`` reached from ``(q0, multipliers0)`` at ``t0`` by pseudo-arclength continuation
    (Eq. (S5), first arclength ``step``) across a stretch the quasi-static steps cannot follow (the path turns
    sharply within a step, as near a singular pose of the rigid loop); ``None`` if the path turns back in t first
    (a fold: :func:`trace_snap` follows it) or takes more than ``max_points`` points."""
    found = _bridged(system, q0, multipliers0, t0, [t_target], step, max_points, tolerance)
    return None if found is None else found[-1]


def _bridged(
    system: MultibodySystem,
    q0: NDArray,
    multipliers0: NDArray,
    t0: float,
    targets: list[float],
    step: float,
    max_points: int,
    tolerance: float,
) -> list[tuple[NDArray, NDArray]] | None:
    """:func:`bridge` to the last of ``targets`` (ascending along the path), with the equilibria at every one of
    them, each by Newton from the continuation points that bracket it."""
    direction = 1.0 if targets[-1] >= t0 else -1.0
    speed = path_speed(system, q0, multipliers0, t0)
    step = _forward_step(system, q0, multipliers0, t0, direction, step, tolerance, speed)
    previous = None
    found: list[tuple[NDArray, NDArray]] = []
    for k, point in enumerate(path_points(system, q0, multipliers0, t0, direction, step, tolerance, speed=speed)):
        if previous is not None:
            if (point[0] - previous[0]) * direction <= 0.0:
                return None
            while len(found) < len(targets) and (point[0] - targets[len(found)]) * direction >= 0.0:
                found.append(_landing(system, previous, point, targets[len(found)], tolerance))
            if len(found) == len(targets):
                return found
        if k >= max_points:
            return None
        previous = point
    return None


def quasi_static_through_snaps(
    system: MultibodySystem,
    q0: NDArray,
    times: NDArray,
    *,
    max_step: float | None = None,
    progress=None,
    max_snaps: int = MAX_SNAPS,
    path_step: Callable[[float], float] | None = None,
    path_breaks: tuple[float, ...] = (),
    trace_points: int = TRACE_POINTS,
) -> tuple[StaticSolution, tuple[SnapThrough, ...]]:
    """:func:`ffrf.solvers.static_solver.quasi_static` over ``times`` that goes on past folds: where it stops,
    the path is traced from the last equilibrium (:func:`trace_snap`, first step the spacing of ``times``); at a
    fold the run jumps to the landing equilibrium and resumes from it over the remaining times. Returns the
    equilibria at ``times`` and the snaps. A stop with no fold ahead, or a fold with no landing, is raised as it
    was, ``partial`` holding every equilibrium found (before and after earlier snaps). A trace that does not come
    back to the fold's t within ``trace_points`` points, or meets no stable landing there, leaves the landing to a
    dynamic passage from the fold (:func:`~ffrf.solvers.snap_passage.dynamic_passage`, Eq. (S11)).

    With ``path_step`` (s, from a time; Eq. (S10)) the path is followed on its own times, the outputs solved from it
    (:func:`ffrf.solvers.static_solver.quasi_static`), and the traces and bridges start with the path's step, not
    the outputs' spacing: where the run folds and lands does not depend on ``times``
    (:func:`_through_snaps_on_own_steps`)."""
    times = np.asarray(times, dtype=float)
    if path_step is not None:
        return _through_snaps_on_own_steps(
            system, np.asarray(q0, dtype=float), times, path_step, progress, max_snaps, tuple(path_breaks), trace_points
        )
    spacing = float(np.max(np.diff(times))) if times.size > 1 else 1.0
    qs: list[NDArray] = []
    lams: list[NDArray] = []
    counts: list[int] = []
    snaps: list[SnapThrough] = []
    jumps: list[PathJump] = []  # those of the quasi-static legs (contacts letting go), not the snaps
    start, todo, landed = np.asarray(q0, dtype=float), times, False
    while True:
        try:
            part = quasi_static(system, start, todo, max_step=max_step, progress=progress)
            stop = None
        except StaticDivergence as error:
            part, stop = error.partial, error
        except Interrupted as error:  # asked to stop: leave with every equilibrium found and the snaps passed
            if error.partial is not None:
                qs.extend(error.partial.q[1 if landed else 0 :])
                lams.extend(error.partial.multipliers[1 if landed else 0 :])
                counts.extend(error.partial.iterations[1 if landed else 0 :])
                jumps.extend(error.partial.jumps)
            error.partial = StaticSolution(np.array(qs), np.array(lams), tuple(counts), jumps=tuple(jumps))
            error.snaps = tuple(snaps)
            raise
        skip = 1 if landed else 0  # the landing itself, solved again at the fold's t, is no output
        qs.extend(part.q[skip:])
        lams.extend(part.multipliers[skip:])
        counts.extend(part.iterations[skip:])
        jumps.extend(part.jumps)
        if stop is None:
            return StaticSolution(np.array(qs), np.array(lams), tuple(counts), jumps=tuple(jumps)), tuple(snaps)
        if not qs or len(snaps) >= max_snaps:
            raise _with_partial(stop, qs, lams, counts, snaps, jumps)
        reached = times[len(qs) - 1]
        remaining = times[len(qs) :]
        crossed = None
        if remaining.size:  # a sharp stretch of the path without a fold: bridged to the next output
            crossed = bridge(system, qs[-1], lams[-1], float(reached), float(remaining[0]), step=spacing / 8.0)
        if crossed is not None:
            log.info("quasi-static path bridged by continuation from t = %.6g to %.6g s", reached, remaining[0])
            qs.append(crossed[0])
            lams.append(crossed[1])
            counts.append(0)
            start, todo, landed = crossed[0], remaining, True
            continue
        snap = trace_snap(system, qs[-1], lams[-1], float(reached), float(times[-1]), spacing, trace_points)
        if snap is None:
            raise _with_partial(stop, qs, lams, counts, snaps, jumps)
        snap = _landed(system, snap)
        if snap.landing_q is None:
            snaps.append(snap)
            raise _with_partial(stop, qs, lams, counts, snaps, jumps, NO_LANDING.format(t=snap.fold_t))
        _log_snap(snap)
        snaps.append(snap)
        remaining = times[len(qs) :]
        if remaining.size == 0 or remaining[0] <= snap.fold_t:
            raise _with_partial(stop, qs, lams, counts, snaps, jumps)
        start, todo, landed = np.asarray(snap.landing_q), np.concatenate([[snap.fold_t], remaining]), True


def _through_snaps_on_own_steps(
    system: MultibodySystem,
    q0: NDArray,
    outputs: NDArray,
    path_step: Callable[[float], float],
    progress,
    max_snaps: int,
    breaks: tuple[float, ...] = (),
    trace_points: int = TRACE_POINTS,
) -> tuple[StaticSolution, tuple[SnapThrough, ...]]:
    """:func:`quasi_static_through_snaps` with the path on its own steps (``breaks``: as ``path_breaks`` of
    :func:`~ffrf.solvers.static_solver.quasi_static`). Each leg is
    :func:`~ffrf.solvers.static_solver.quasi_static` with ``path_step`` from the leg's start (the run's start, or a
    landing at a fold's t, or the end of a bridge) to the last output; where a leg stops, the path is bridged from
    its last equilibrium to its next own time (:func:`path_times` from the leg's start), or traced through the fold
    (:func:`trace_snap`), first arclength step an eighth of the path step there, at most eight path steps. The
    outputs a bridge or a trace passes are
    solved from its continuation points (Newton from the two that bracket each). Rows carry their ``times``; a stop
    ends them with the path's last equilibrium."""
    scale = max(1.0, float(np.abs(outputs).max()))
    times: list[float] = []
    qs: list[NDArray] = []
    lams: list[NDArray] = []
    counts: list[int] = []
    snaps: list[SnapThrough] = []
    jumps: list[PathJump] = []  # those of the legs (contacts letting go), not the snaps

    def keep(t: float, q: NDArray, lam: NDArray, count: int) -> None:
        times.append(float(t))
        qs.append(np.asarray(q))
        lams.append(np.asarray(lam))
        counts.append(int(count))

    def is_output(t: float) -> bool:
        return bool(np.any(np.abs(outputs - t) <= 1e-12 * scale))

    def result(end: tuple[float, NDArray, NDArray] | None = None) -> StaticSolution:
        rows_t, rows_q, rows_lam, rows_n = list(times), list(qs), list(lams), list(counts)
        if end is not None and (not rows_t or end[0] > rows_t[-1] + 1e-12 * scale):
            rows_t.append(end[0])
            rows_q.append(end[1])
            rows_lam.append(end[2])
            rows_n.append(0)
        return StaticSolution(np.array(rows_q), np.array(rows_lam), tuple(rows_n), np.array(rows_t), tuple(jumps))

    def stopped(stop: StaticDivergence, end, reason: str | None = None) -> StaticDivergence:
        error = StaticDivergence(f"{stop}; {reason}") if reason else stop
        error.partial = result(end)
        error.snaps = tuple(snaps)
        return error

    start_t, start_q, skip = float(outputs[0]), q0, 0
    while True:
        todo = outputs[outputs > start_t + 1e-12 * scale]
        leg = np.concatenate([[start_t], todo]) if skip else outputs
        try:
            part = quasi_static(system, start_q, leg, progress=progress, path_step=path_step, path_breaks=breaks)
            stop = None
        except StaticDivergence as error:
            part, stop = error.partial, error
        except Interrupted as error:  # asked to stop: leave with the outputs solved and the snaps passed
            for t, q, lam, n in _rows(error.partial)[skip:]:
                keep(t, q, lam, n)
            jumps.extend(() if error.partial is None else error.partial.jumps)
            error.partial = result()
            error.snaps = tuple(snaps)
            raise
        rows = _rows(part)
        jumps.extend(() if part is None else part.jumps)
        end = (float(rows[-1][0]), rows[-1][1], rows[-1][2]) if rows else None
        for t, q, lam, n in rows[skip:]:
            if is_output(float(t)):  # a stopped leg ends with the path's last equilibrium, no output
                keep(t, q, lam, n)
        if stop is None:
            return result(), tuple(snaps)
        if end is None or len(snaps) >= max_snaps:
            raise stopped(stop, end)
        t_last, q_last, lam_last = end
        step = float(path_step(t_last))
        own = path_times(start_t, float(outputs[-1]), path_step, breaks)
        ahead = own[own > t_last + 1e-12 * scale]
        if ahead.size:  # a sharp stretch of the path without a fold: bridged to the path's next own time
            targets = [float(t) for t in todo if t_last + 1e-12 * scale < t < ahead[0]] + [float(ahead[0])]
            crossed = _bridged(system, q_last, lam_last, t_last, targets, step / 8.0, 600, 1e-10)
            if crossed is not None:
                log.info("quasi-static path bridged by continuation from t = %.6g to %.6g s", t_last, targets[-1])
                for t, (q, lam) in zip(targets, crossed, strict=True):
                    if is_output(t):
                        keep(t, q, lam, 0)
                start_t, start_q, skip = targets[-1], crossed[-1][0], 1
                continue
        # The stop lies within 1/256 of a path step of the fold (the halvings, Eq. (S4)): a whole path step as the
        # first arclength can cross the fold's turn unseen (plane_fold_6r, 8e-4 s from it); an eighth of it, growing
        # to eight path steps along the unstable branch, finds it.
        snap = trace_snap(
            system, q_last, lam_last, t_last, float(outputs[-1]), step / 8.0, trace_points, max_step=8.0 * step
        )
        if snap is None:
            raise stopped(stop, end)
        snap = _landed(system, snap)
        if snap.landing_q is None:
            snaps.append(snap)
            raise stopped(stop, end, NO_LANDING.format(t=snap.fold_t))
        _log_snap(snap)
        snaps.append(snap)
        for t in todo[(todo > t_last + 1e-12 * scale) & (todo < snap.fold_t)]:  # outputs between the stop and the fold
            q, lam = _before_fold(system, snap, float(t))
            keep(t, q, lam, 0)
        if not np.any(todo > snap.fold_t):
            raise stopped(stop, end)
        start_t, start_q, skip = snap.fold_t, np.asarray(snap.landing_q), 1


def _rows(solution: StaticSolution | None) -> list[tuple[float, NDArray, NDArray, int]]:
    """``(t, q, multipliers, iterations)`` per row of a solution on its own steps (whose rows carry their times)."""
    if solution is None or solution.times is None:
        return []
    return list(zip(solution.times, solution.q, solution.multipliers, solution.iterations, strict=True))


def _before_fold(system: MultibodySystem, snap: SnapThrough, t: float) -> tuple[NDArray, NDArray]:
    """The equilibrium at ``t`` on the traced path's stable part before the fold: Newton from the two points that
    bracket it (the fold itself as the last)."""
    path = snap.path
    rising = [(path.t[0], path.q[0], path.multipliers[0])]
    for k in range(1, len(path.t)):
        if path.t[k] <= rising[-1][0] or path.t[k] >= snap.fold_t:
            break
        rising.append((path.t[k], path.q[k], path.multipliers[k]))
    rising.append((snap.fold_t, snap.fold_q, snap.fold_multipliers))
    for before, after in zip(rising, rising[1:], strict=False):
        if before[0] <= t <= after[0]:
            return _landing(system, before, after, t, 1e-10)
    raise StaticDivergence(f"t = {t:.9g} s lies outside the traced path before the fold at t = {snap.fold_t:.9g} s")


#: What a stop at a fold without a landing says (``{t}``: the fold's t); :data:`NO_LANDING_WORDS` name it in a message.
NO_LANDING = (
    "the equilibrium path folds at t = {t:.6g} s, and the path traced beyond it meets no stable equilibrium at that "
    "t with less potential energy, nor does a dynamic passage from the fold settle on one: where the jump goes takes "
    "a dynamic run"
)
NO_LANDING_WORDS = "meets no stable equilibrium at that t"


def _landed(system: MultibodySystem, snap: SnapThrough) -> SnapThrough:
    """``snap`` with the landing the jump ends on: the traced path's if the jump can end there (:func:`_lands`),
    else the dynamic passage's from the fold (Eq. (S11)) if it can end there, else none."""
    if _lands(system, snap):
        return snap
    beyond = _beyond_fold(snap.path)
    passage = None
    if beyond is not None:
        passage = dynamic_passage(system, snap.fold_t, snap.fold_q, snap.fold_multipliers, beyond)
    if passage is not None:
        passed = replace(snap, landing_q=passage.q, landing_multipliers=passage.multipliers, passage=passage)
        if _lands(system, passed):
            return passed
    return replace(snap, landing_q=None, landing_multipliers=None)


def _beyond_fold(path: EquilibriumPath) -> tuple[float, NDArray, NDArray] | None:
    """The traced path's first point past its first turn in t, on the unstable branch; ``None`` if it has none."""
    direction = np.sign(path.t[1] - path.t[0]) if len(path.t) > 1 else 0.0
    for k in range(1, len(path.t)):
        if (path.t[k] - path.t[k - 1]) * direction < 0.0:
            return float(path.t[k]), path.q[k], path.multipliers[k]
    return None


def _log_snap(snap: SnapThrough) -> None:
    if snap.passage is None:
        log.info("snap at t = %.6g: fold of the equilibrium path, landing on another branch", snap.fold_t)
    else:
        log.info(
            "snap at t = %.6g: fold of the equilibrium path; the path traced beyond it lands nowhere, a dynamic "
            "passage at that t (%d steps) settles on another branch",
            snap.fold_t,
            snap.passage.steps,
        )


def _lands(system: MultibodySystem, snap: SnapThrough) -> bool:
    """Can the jump end at ``snap``'s landing? Only if it is stable (Eq. (B1)) and holds less potential energy
    than the fold: the jump happens at fixed t, with no work done on the structure."""
    if snap.landing_q is None or snap.landing_multipliers is None:
        return False
    landing = equilibrium_stability(system, snap.landing_q, snap.landing_multipliers, snap.fold_t, count=1)
    released = snap.energy_released(system)
    return landing.stable and released is not None and released >= 0.0


def _with_partial(
    stop: StaticDivergence,
    qs: list,
    lams: list,
    counts: list,
    snaps: list,
    jumps: list[PathJump],
    reason: str | None = None,
) -> StaticDivergence:
    """The run's stop, with every equilibrium found (and the legs' jumps) as ``partial`` and the snaps passed (or
    found) as ``snaps``."""
    error = StaticDivergence(f"{stop}; {reason}") if reason else stop
    error.partial = StaticSolution(np.array(qs), np.array(lams), tuple(counts), jumps=tuple(jumps))
    error.snaps = tuple(snaps)
    return error


def run_critical_pose(
    system: MultibodySystem,
    times: NDArray,
    q: NDArray,
    multipliers: NDArray,
    squared_frequencies: NDArray,
    snaps: tuple[SnapThrough, ...],
) -> CriticalPose:
    """The critical pose of a monitored quasi-static run: its first fold if it snapped, else the output with the
    smallest squared frequency of Eq. (B1) (``squared_frequencies``, one row per output)."""
    if snaps:
        return critical_pose(system, "fold", snaps[0].fold_t, snaps[0].fold_q, snaps[0].fold_multipliers)
    k = int(np.argmin(squared_frequencies[:, 0]))
    return critical_pose(system, "least stable output", float(times[k]), q[k], multipliers[k])
