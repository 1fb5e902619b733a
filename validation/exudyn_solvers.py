"""Exudyn's solvers set up as ours: generalized-alpha (index 3, no Newmark, fixed steps, full
Newton, consistent initial accelerations, dense linear solver, one thread) and ``SolveStatic``
(fixed load steps), with every step's sensor values stored in memory.

``exudyn`` is imported lazily.
"""

from __future__ import annotations

import time

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "dynamic_settings",
    "static_settings",
    "sweep_settings",
    "solve_dynamic",
    "solve_static",
    "check_output_times",
]


def dynamic_settings(
    t_end: float,
    step: float,
    rho_inf: float,
    relative_tolerance: float = 1e-12,
    absolute_tolerance: float = 1e-12,
    modified_newton: bool = False,
):
    """Generalized-alpha (index 3, no Newmark) with ``round(t_end / step)`` fixed steps of spectral
    radius ``rho_inf``; ``relative_tolerance``/``absolute_tolerance`` are Exudyn's Newton criteria
    (residual norm relative to the first residual of the step / absolute, mixed units)."""
    import exudyn as exu

    s = exu.SimulationSettings()
    ti = s.timeIntegration
    ti.numberOfSteps = int(round(t_end / step))
    ti.endTime = t_end
    ti.adaptiveStep = False
    ti.automaticStepSize = False
    ti.verboseMode = 0
    ti.generalizedAlpha.spectralRadius = rho_inf
    ti.generalizedAlpha.useIndex2Constraints = False
    ti.generalizedAlpha.useNewmark = False
    ti.generalizedAlpha.computeInitialAccelerations = True
    ti.newton.useModifiedNewton = modified_newton
    ti.newton.relativeTolerance = relative_tolerance
    ti.newton.absoluteTolerance = absolute_tolerance
    ti.newton.maxIterations = 25
    s.solution.file.write = False
    s.solution.sensors.writePeriod = 0.5 * step  # every step
    s.show.statistics = False
    s.show.computationTime = False
    s.linearSolver.solverType = exu.LinearSolverType.EXUdense
    s.parallel.numberOfThreads = 1
    return s


def static_settings(load_steps: int, tolerance: float, duration: float = 1.0, load_factor: bool = True):
    """``SolveStatic`` settings: fixed load steps over ``duration`` of quasi-time (drives turn with
    it), loads ramped with the steps only if ``load_factor``; dense solver; Newton to ``tolerance``; sensors stored at
    every load step."""
    import exudyn as exu

    s = exu.SimulationSettings()
    s.staticSolver.numberOfLoadSteps = load_steps
    s.staticSolver.loadStepDuration = duration
    s.staticSolver.useLoadFactor = load_factor
    s.staticSolver.adaptiveStep = False
    s.staticSolver.newton.relativeTolerance = tolerance
    s.staticSolver.newton.absoluteTolerance = tolerance
    s.staticSolver.newton.maxIterations = 50
    s.staticSolver.verboseMode = 0
    s.linearSolver.solverType = exu.LinearSolverType.EXUdense
    s.solution.file.write = False
    # every load step's sensor values: Exudyn's default period (10 ms) skips load steps shorter than it
    s.solution.sensors.writePeriod = 0.5 * duration / load_steps
    return s


def sweep_settings(times: NDArray, tolerance: float):
    """``SolveStatic`` settings for equilibria at equally spaced ``times`` from 0: one load step per
    interval, the drives turned by the quasi-time, loads always fully on (``useLoadFactor=False``)."""
    return static_settings(len(times) - 1, tolerance, duration=float(times[-1]), load_factor=False)


def solve_dynamic(mbs, settings, what: str, schedule: tuple[NDArray, NDArray] | None = None) -> tuple[float, int]:
    """Integrate the assembled ``mbs`` with ``settings`` (:func:`dynamic_settings`); returns the wall
    time (s) and the Newton iterations (-1 where Exudyn does not report them). ``what`` names the
    run in the error raised when Exudyn stops. ``schedule``: the end times and lengths of the steps to take
    (:func:`ffrf.solvers.generalized_alpha.part_schedule`: our run's steps, each fixed step in as many parts as ours
    took), set by Exudyn's UpdateCurrentTime user function; sensors are then stored at every one of them."""
    import exudyn as exu

    started = time.perf_counter()
    solver = exu.MainSolverImplicitSecondOrder()
    if schedule is not None:
        times, sizes = schedule
        settings.solution.sensors.writePeriod = 0.5 * float(np.min(sizes))

        def take_our_step(solver, mbs, settings) -> bool:
            k = solver.it.currentStepIndex - 1  # Exudyn counts its steps from 1
            solver.it.currentStepSize, solver.it.currentTime = float(sizes[k]), float(times[k])
            return True

        solver.SetUserFunctionUpdateCurrentTime(mbs, take_our_step)
    success = solver.SolveSystem(mbs, settings)
    seconds = time.perf_counter() - started
    if not success:
        raise RuntimeError(f"Exudyn did not finish {what}: {solver.GetErrorString()}")
    return seconds, int(solver.it.newtonStepsCount) if hasattr(solver, "it") else -1


def solve_static(mbs, settings) -> None:
    """``SolveStatic`` of the assembled ``mbs`` with ``settings`` (:func:`static_settings`)."""
    import exudyn as exu

    solver = exu.MainSolverStatic()
    if not solver.SolveSystem(mbs, settings):
        raise RuntimeError(f"Exudyn SolveStatic failed: {solver.GetErrorString()}")


def check_output_times(times: NDArray, expected: NDArray, what: str) -> None:
    """Exudyn's sensor rows must be one per step (or load step) at ``expected``."""
    if times.shape != expected.shape or np.abs(times - expected).max() > 1e-9 * max(1.0, expected[-1]):
        raise RuntimeError(
            f"Exudyn {what} output has {len(times)} rows at unexpected times; expected one per step "
            f"({len(expected)} rows); check solution.sensors.writePeriod"
        )
