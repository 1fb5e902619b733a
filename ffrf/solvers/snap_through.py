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
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from ffrf.errors import Interrupted, StaticDivergence
from ffrf.solvers.continuation import EquilibriumPath, equilibrium_path, parabola_vertex, path_points, path_speed
from ffrf.solvers.stability import CriticalPose, critical_pose, equilibrium_stability, mode_shares
from ffrf.solvers.static_solver import StaticSolution, quasi_static, static_equilibrium
from ffrf.system.multibody import MultibodySystem

__all__ = ["SnapThrough", "run_critical_pose", "snap_summary", "trace_snap", "quasi_static_through_snaps"]

log = logging.getLogger(__name__)

#: Steps per arclength of the first trace when a fold is traced again to locate it.
REFINEMENT = 10
#: Quarterings of a trace's first step that may be needed to see the path rise in t before its fold.
MAX_STEP_CUTS = 12
#: Snaps one quasi-static run may pass before it is stopped.
MAX_SNAPS = 4


@dataclass(frozen=True)
class SnapThrough:
    """A fold at ``fold_t`` (equilibrium ``fold_q``, ``fold_multipliers`` there), the other fold ``return_t``
    where the path turns forward again (``None`` if it does not within the traced points), the landing
    equilibrium at ``fold_t`` beyond it (``None`` likewise) and the traced ``path``."""

    fold_t: float
    fold_q: NDArray[np.float64]
    fold_multipliers: NDArray[np.float64]
    return_t: float | None
    landing_q: NDArray[np.float64] | None
    landing_multipliers: NDArray[np.float64] | None
    path: EquilibriumPath

    def energy_released(self, system: MultibodySystem) -> float | None:
        """Potential energy at the fold less that at the landing (J): strain, gravity, force elements and the dead
        loads at the fold's t, whose work in the jump it includes
        (:meth:`~ffrf.system.multibody.MultibodySystem.potential_energy`)."""
        if self.landing_q is None:
            return None
        return system.potential_energy(self.fold_q, self.fold_t) - system.potential_energy(self.landing_q, self.fold_t)


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
    max_points: int = 600,
    tolerance: float = 1e-10,
) -> SnapThrough | None:
    """Follow the path from the equilibrium ``(q0, multipliers0)`` at ``t0`` towards ``t_end`` (Eq. (S5), first
    arclength ``step``). ``None`` if t reaches ``t_end`` without a fold; otherwise the :class:`SnapThrough` at the
    first fold, with the landing equilibrium if the path comes forward past the fold's t within ``max_points``."""
    direction = 1.0 if t_end >= t0 else -1.0
    points: list[tuple[float, NDArray, NDArray, float]] = []
    fold: tuple[float, NDArray, NDArray] | None = None
    return_t = None
    speed = path_speed(system, q0, multipliers0, t0)  # one c for the trace and the refinement: one arclength
    step = _forward_step(system, q0, multipliers0, t0, direction, step, tolerance, speed)
    for point in path_points(system, q0, multipliers0, t0, direction, step, tolerance, speed=speed):
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
    direction = 1.0 if t_target >= t0 else -1.0
    speed = path_speed(system, q0, multipliers0, t0)
    step = _forward_step(system, q0, multipliers0, t0, direction, step, tolerance, speed)
    previous = None
    for k, point in enumerate(path_points(system, q0, multipliers0, t0, direction, step, tolerance, speed=speed)):
        if previous is not None:
            if (point[0] - previous[0]) * direction <= 0.0:
                return None
            if (point[0] - t_target) * direction >= 0.0:
                return _landing(system, previous, point, t_target, tolerance)
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
) -> tuple[StaticSolution, tuple[SnapThrough, ...]]:
    """:func:`ffrf.solvers.static_solver.quasi_static` over ``times`` that goes on past folds: where it stops,
    the path is traced from the last equilibrium (:func:`trace_snap`, first step the spacing of ``times``); at a
    fold the run jumps to the landing equilibrium and resumes from it over the remaining times. Returns the
    equilibria at ``times`` and the snaps. A stop with no fold ahead, or a fold with no landing, is raised as it
    was, ``partial`` holding every equilibrium found (before and after earlier snaps)."""
    times = np.asarray(times, dtype=float)
    spacing = float(np.max(np.diff(times))) if times.size > 1 else 1.0
    qs: list[NDArray] = []
    lams: list[NDArray] = []
    counts: list[int] = []
    snaps: list[SnapThrough] = []
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
            error.partial = StaticSolution(np.array(qs), np.array(lams), tuple(counts))
            error.snaps = tuple(snaps)
            raise
        skip = 1 if landed else 0  # the landing itself, solved again at the fold's t, is no output
        qs.extend(part.q[skip:])
        lams.extend(part.multipliers[skip:])
        counts.extend(part.iterations[skip:])
        if stop is None:
            return StaticSolution(np.array(qs), np.array(lams), tuple(counts)), tuple(snaps)
        if not qs or len(snaps) >= max_snaps:
            raise _with_partial(stop, qs, lams, counts, snaps)
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
        snap = trace_snap(system, qs[-1], lams[-1], float(reached), float(times[-1]), step=spacing)
        if snap is None:
            raise _with_partial(stop, qs, lams, counts, snaps)
        if not _lands(system, snap):
            snaps.append(replace(snap, landing_q=None, landing_multipliers=None))
            raise _with_partial(stop, qs, lams, counts, snaps, _NO_LANDING.format(t=snap.fold_t))
        log.info("snap at t = %.6g: fold of the equilibrium path, landing on another branch", snap.fold_t)
        snaps.append(snap)
        remaining = times[len(qs) :]
        if remaining.size == 0 or remaining[0] <= snap.fold_t:
            raise _with_partial(stop, qs, lams, counts, snaps)
        start, todo, landed = np.asarray(snap.landing_q), np.concatenate([[snap.fold_t], remaining]), True


_NO_LANDING = (
    "the equilibrium path folds at t = {t:.6g} s, and the path traced beyond it meets no stable equilibrium at that "
    "t with less potential energy: where the jump goes takes a dynamic run"
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
    stop: StaticDivergence, qs: list, lams: list, counts: list, snaps: list, reason: str | None = None
) -> StaticDivergence:
    """The run's stop, with every equilibrium found as ``partial`` and the snaps passed (or found) as ``snaps``."""
    error = StaticDivergence(f"{stop}; {reason}") if reason else stop
    error.partial = StaticSolution(np.array(qs), np.array(lams), tuple(counts))
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
