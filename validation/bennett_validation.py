r"""Cross-validation of one Bennett variant: our solver against its Exudyn twin, in one run.

What is compared (issue 7), each on identical input (our mesh, M, K, interface node sets and
weights, joints, drive, gravity, damping, solver settings):

1. **Modes** per link: our fixed-interface frequencies and mode shapes against Exudyn's own
   Craig-Bampton reduction (:mod:`validation.modes`). The twin's bodies use Exudyn's basis.
2. **Quasi-static revolution** (the paper's 1 rpm drive is quasi-static, see
   :func:`ffrf.scenes.linkage_run.choose_mode`): our static equilibria along the drive against one
   Exudyn ``SolveStatic`` whose load steps turn the drive; each solver assembles itself
   (misalignment continuation in both).
3. **Dynamic window**: generalized-alpha in both (same step and spectral radius) from each
   solver's own assembled state over the cosine ramp, where inertia matters most.

Three of our systems take part, so that every difference is attributed:

* ``production``: the scene as users run it (exact gravity, exact marker Jacobian);
* ``equivalent``: gravity as Exudyn's ``LoadMassProportional`` (``exact_gravity=False``, Eq.
  (F10)); the solver comparison and the issue's targets use this one;
* ``exudyn_jacobian``: also Exudyn's marker rotation Jacobian
  (:func:`validation.exudyn_conventions.exudyn_convention_system`), which is not the derivative of
  its constraint equations; with it both solvers solve the same discrete equations.

Plus the ideal path from :mod:`kinematics` as third reference, energy balances of both
solvers' runs (evaluated with our energy functions), constraint residuals of both runs in our
constraint equations, and wall times split into set-up and solution
(:mod:`validation.bennett_metrics`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ffrf.output.result import Result

from .twin_run import ComparedRun, solution_time

__all__ = [
    "ValidationSettings",
    "BennettValidation",
    "validate_bennett",
    "run_ours",
    "quasi_static_solve",
    "dynamic_solve",
]


@dataclass(frozen=True)
class ValidationSettings:
    """What to build and run. Defaults: the README's default scene (6 mm P2, 4 modes, 4 ms steps)."""

    variant: str = "pla"
    h: float = 6e-3
    order: int = 2
    n_modes: int = 4
    outputs: int = 241  # quasi-static rows over ramp + revolution
    dynamic_t_end: float = 1.0  # s; 0 skips the dynamic window
    step: float = 4e-3
    rho_inf: float = 0.9
    basis: str = "exudyn"  # the twin's mode basis: Exudyn's own HCB, or "ffrf" (ours)

    def as_dict(self) -> dict:
        return dict(self.__dict__)


@dataclass
class BennettValidation:
    """All runs, the mode comparisons and the metrics of one variant. Runs by label: ours are
    :class:`~ffrf.output.result.Result` s, Exudyn's (``exudyn``) a :class:`validation.twin_run.TwinRun`."""

    settings: ValidationSettings
    modes: dict  # link name -> validation.modes.ModeComparison
    quasi_static: dict[str, ComparedRun]  # production, equivalent, exudyn_jacobian, exudyn
    dynamic: dict[str, ComparedRun]  # equivalent, exudyn (empty if skipped)
    ideal_coupler: NDArray[np.float64]  # at the quasi-static rows
    metrics: dict


def _progress_default(message: str) -> None:
    print(message, flush=True)


def run_ours(label, scene, system, times, q0, setup_s, solve) -> Result:
    """Our run of ``system`` from ``q0`` at ``times`` with ``solve(system, q0, times) -> (q, multipliers, qd,
    newton_iterations)`` (``qd``: ``None`` for equilibria), as a
    :func:`validation.bennett_trajectory.bennett_result`."""
    from .bennett_trajectory import bennett_result

    started = time.perf_counter()
    q, multipliers, qd, iterations = solve(system, q0, times)
    solve_s = time.perf_counter() - started
    return bennett_result(label, scene, system, times, q, multipliers, setup_s, solve_s, iterations, qd)


def quasi_static_solve(system, q0, times):
    """Static equilibria at ``times`` (:func:`ffrf.solvers.static_solver.quasi_static`)."""
    from ffrf.solvers.static_solver import quasi_static

    solution = quasi_static(system, q0, times)
    return solution.q, solution.multipliers, None, int(sum(solution.iterations))


def dynamic_solve(step, rho_inf):
    """A ``solve`` for :func:`run_ours`: generalized-alpha from rest with ``step``, one row per step."""

    def solve(system, q0, times):
        from ffrf.solvers.generalized_alpha import generalized_alpha

        result = generalized_alpha(system, q0, np.zeros_like(q0), float(times[-1]), step, rho_inf=rho_inf)
        return result.q, result.multipliers, result.qd, int(result.newton_iterations.sum())

    return solve


def _add_timings(run: ComparedRun, setup_s: float = 0.0, assembly_s: float = 0.0) -> None:
    """Add to a run's wall times what was done for it before: building the twin's bases (``setup``), the assembly
    its run started from (``assembly``; the validation counts it with the solution)."""
    timings = run.metadata["timings_s"]
    timings["setup"] += setup_s
    timings["assembly"] = assembly_s


def validate_bennett(
    settings: ValidationSettings = ValidationSettings(), progress: Callable[[str], None] = _progress_default
) -> BennettValidation:
    """Build the variant, run every comparison of the module docstring, compute the metrics."""
    import exudyn

    from ffrf.paper.bennett_scene import assemble, build_bennett

    from .bennett_metrics import bennett_metrics
    from .exudyn_bennett import (
        assemble_exudyn_bennett,
        bennett_bodies,
        quasi_static_exudyn_bennett,
        run_exudyn_bennett,
    )
    from .exudyn_conventions import exudyn_convention_system
    from .modes import compare_modes
    from .twin_bases import twin_bases
    from .twin_clock import compiled_kernels

    kernels_s = compiled_kernels(None)
    progress(f"[{settings.variant}] our kernels compiled or loaded in {kernels_s:.1f} s (not in the runs' times)")
    started = time.perf_counter()
    production = build_bennett(settings.variant, h=settings.h, order=settings.order, n_modes=settings.n_modes)
    setup_ours = time.perf_counter() - started
    equivalent = production.with_exact_gravity(False)
    progress(
        f"[{settings.variant}] scene built in {setup_ours:.1f} s "
        f"({sum(link.fe.nodes.shape[0] for link in production.links)} nodes, "
        f"{[link.reduction.n_modes for link in production.links]} modes)"
    )

    started = time.perf_counter()
    bases = twin_bases(bennett_bodies(production), settings.basis)
    setup_bases = time.perf_counter() - started
    modes = {}
    for link, basis in zip(production.links, bases, strict=True):
        if basis.source == "exudyn":
            modes[f"link{link.index}"] = compare_modes(
                link.fe, link.reduction, basis.matrix, basis.fixed_interface_frequencies_hz, basis.setup_s
            )
    progress(f"[{settings.variant}] Exudyn's HCB on the same matrices in {setup_bases:.1f} s")

    # Quasi-static revolution ------------------------------------------------------------------
    times = np.linspace(0.0, production.t_end, settings.outputs)
    qs: dict[str, ComparedRun] = {}
    for label, scene, convert in (
        ("production", production, None),
        ("equivalent", equivalent, None),
        ("exudyn_jacobian", equivalent, lambda s: exudyn_convention_system(s, True)),
    ):
        system = scene.system if convert is None else convert(scene.system)
        t0 = time.perf_counter()
        q0 = assemble(scene, convert=convert).q
        assembly_s = time.perf_counter() - t0
        qs[label] = run_ours(label, scene, system, times, q0, setup_ours, quasi_static_solve)
        _add_timings(qs[label], assembly_s=assembly_s)
        progress(f"[{settings.variant}] ours ({label}): quasi-static revolution in {solution_time(qs[label]):.1f} s")
    t0 = time.perf_counter()
    start = assemble_exudyn_bennett(production, bases)
    assembly_exudyn = time.perf_counter() - t0
    qs["exudyn"] = quasi_static_exudyn_bennett(production, start, times, bases=bases)
    _add_timings(qs["exudyn"], setup_bases, assembly_exudyn)
    progress(f"[{settings.variant}] Exudyn: quasi-static revolution in {solution_time(qs['exudyn']):.1f} s")

    # Dynamic window ---------------------------------------------------------------------------
    dyn: dict[str, ComparedRun] = {}
    if settings.dynamic_t_end > 0:
        n_steps = int(round(settings.dynamic_t_end / settings.step))
        dyn_times = settings.step * np.arange(n_steps + 1)
        dyn["equivalent"] = run_ours(
            "equivalent",
            equivalent,
            equivalent.system,
            dyn_times,
            qs["equivalent"].q[0],
            setup_ours,
            dynamic_solve(settings.step, settings.rho_inf),
        )
        progress(f"[{settings.variant}] ours: {n_steps} dynamic steps in {solution_time(dyn['equivalent']):.1f} s")
        dyn["exudyn"] = run_exudyn_bennett(
            production, start[4], settings.dynamic_t_end, settings.step, settings.rho_inf, bases=bases
        )
        _add_timings(dyn["exudyn"], setup_bases)
        progress(f"[{settings.variant}] Exudyn: {n_steps} dynamic steps in {solution_time(dyn['exudyn']):.1f} s")

    ideal = production.ideal_coupler_points(qs["production"].sensors["drive_angle"])
    metrics = bennett_metrics(settings, production, equivalent, modes, qs, dyn, ideal, exudyn.__version__)
    metrics["timing_s"]["kernels_before_s"] = kernels_s
    return BennettValidation(settings, modes, qs, dyn, ideal, metrics)
