"""One run of a system: quasi-static equilibria or a dynamic generalized-alpha run, with the output
stride that puts ``outputs`` rows between t = 0 and ``t_end``. Every scene runs through here.

A run that stops (:class:`ffrf.errors.StaticDivergence`, :class:`ffrf.errors.NewtonDivergence`) raises with
``partial``, the :class:`Run` up to its last output, so that callers can still write what was computed; so does a
run stopped by its ``progress`` callback (:class:`ffrf.errors.Interrupted`)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ffrf.errors import Interrupted, NewtonDivergence, StaticDivergence
from ffrf.solvers.common import PathJump, StaticSolution
from ffrf.solvers.generalized_alpha import generalized_alpha
from ffrf.solvers.snap_through import SnapThrough, quasi_static_through_snaps
from ffrf.solvers.static_solver import quasi_static
from ffrf.system.multibody import MultibodySystem

__all__ = ["MODES", "Run", "simulate", "output_stride"]

MODES = ("quasi_static", "dynamic")


@dataclass(frozen=True)
class Run:
    """Output times and coordinates, velocities (``None`` for quasi-static runs) and multipliers, and the snaps a
    quasi-static run went through (:func:`ffrf.solvers.snap_through.quasi_static_through_snaps`); of a dynamic run,
    the steps' local error estimates of the bodies' positions (m, Eq. (G5), the largest of each step) and the steps'
    lengths (s); ``jumps``, every jump of a quasi-static path between equilibria, snaps that landed included, in the
    order of t."""

    time: NDArray[np.float64]
    q: NDArray[np.float64]
    qd: NDArray[np.float64] | None
    multipliers: NDArray[np.float64]
    snaps: tuple[SnapThrough, ...] = ()
    position_errors: NDArray[np.float64] | None = None
    step_sizes: NDArray[np.float64] | None = None
    jumps: tuple[PathJump, ...] = ()


def _all_jumps(solution: StaticSolution | None, snaps: tuple[SnapThrough, ...]) -> tuple[PathJump, ...]:
    """The path's jumps where contacts let go and its snaps that landed, in the order of t."""
    landed = [snap.as_jump() for snap in snaps]
    found = [*(() if solution is None else solution.jumps), *(jump for jump in landed if jump is not None)]
    return tuple(sorted(found, key=lambda jump: jump.t_from))


def output_stride(t_end: float, step: float, outputs: int) -> int:
    """Time steps between two outputs so that about ``outputs`` rows span [0, t_end]."""
    return max(1, int(round(t_end / step / max(outputs - 1, 1))))


def simulate(
    system: MultibodySystem,
    q0: NDArray,
    mode: str,
    t_end: float,
    outputs: int,
    *,
    step: float = 1e-3,
    rho_inf: float = 0.9,
    progress: Callable[[float, float], None] | None = None,
    max_static_step: float | None = None,
    qd0: NDArray | None = None,
    through_snaps: bool = False,
    static_path_step: Callable[[float], float] | None = None,
    static_path_breaks: tuple[float, ...] = (),
    step_limit: Callable[[float, float], float] | None = None,
    error_tolerance: float | None = None,
) -> Run:
    """``quasi_static``: equilibria at ``outputs`` equally spaced times, followed through intermediate
    ones at most ``max_static_step`` (s) apart, and with ``through_snaps`` on past folds of the equilibrium
    path (the jump to another branch, Eq. (S6)); ``dynamic``: generalized-alpha from ``q0`` with velocities ``qd0``
    (default at rest) with time step ``step`` and spectral radius ``rho_inf``.

    ``static_path_step`` (quasi-static): the path on its own steps, the outputs solved from it
    (:func:`ffrf.solvers.static_solver.quasi_static`, Eq. (S10)), also through snaps
    (:func:`ffrf.solvers.snap_through.quasi_static_through_snaps`), restarting its predictor at
    ``static_path_breaks`` (kinks of the time laws); ``step_limit`` (dynamic): the longest step between two times,
    each step done in as many parts as it needs (Eq. (G7)); ``error_tolerance`` (dynamic, m): the local error
    estimate each part may make, more parts where it is larger (Eq. (G8); default ``None``, off)."""
    if mode == "quasi_static":
        times = np.linspace(0.0, t_end, outputs)
        snaps: tuple[SnapThrough, ...] = ()
        try:
            if through_snaps:
                solution, snaps = quasi_static_through_snaps(
                    system,
                    q0,
                    times,
                    progress=progress,
                    max_step=max_static_step,
                    path_step=static_path_step,
                    path_breaks=static_path_breaks,
                )
            else:
                solution = quasi_static(
                    system,
                    q0,
                    times,
                    progress=progress,
                    max_step=max_static_step,
                    path_step=static_path_step,
                    path_breaks=static_path_breaks,
                )
        except (StaticDivergence, Interrupted) as error:
            done = error.partial
            if done is not None:
                reached = times[: len(done.q)] if done.times is None else done.times
                error.partial = Run(
                    reached, done.q, None, done.multipliers, error.snaps, jumps=_all_jumps(done, error.snaps)
                )
            raise
        reached = times if solution.times is None else solution.times
        return Run(reached, solution.q, None, solution.multipliers, snaps, jumps=_all_jumps(solution, snaps))
    if mode == "dynamic":
        try:
            result = generalized_alpha(
                system,
                q0,
                np.zeros_like(q0) if qd0 is None else np.asarray(qd0, dtype=float),
                t_end,
                step,
                rho_inf=rho_inf,
                output_every=output_stride(t_end, step, outputs),
                progress=progress,
                step_limit=step_limit,
                error_tolerance=error_tolerance,
            )
        except (NewtonDivergence, Interrupted) as error:
            done = error.partial
            if done is not None:
                error.partial = Run(
                    done.time, done.q, done.qd, done.multipliers, (), done.position_errors, done.step_sizes
                )
            raise
        return Run(result.time, result.q, result.qd, result.multipliers, (), result.position_errors, result.step_sizes)
    raise ValueError(f"run mode {mode!r}: use one of {list(MODES)}")
