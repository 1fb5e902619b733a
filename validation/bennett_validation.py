r"""Cross-validation of one Bennett variant: our solver against its Exudyn twin, in one run.

What is compared (issue 7), each on identical input (our mesh, M, K, interface node sets and
weights, joints, drive, gravity, damping, solver settings):

1. **Modes** per link: our fixed-interface frequencies and mode shapes against Exudyn's own
   Craig-Bampton reduction (:mod:`validation.modes`). The twin's bodies use Exudyn's basis.
2. **Quasi-static revolution** (the paper's 1 rpm drive is quasi-static, see
   :func:`ffrf.scenes.bennett_run.choose_mode`): our static equilibria along the drive against one
   Exudyn ``SolveStatic`` whose load steps turn the drive; each solver assembles itself
   (misalignment continuation in both).
3. **Dynamic window**: generalized-alpha in both (same step and spectral radius) from each
   solver's own assembled state over the cosine ramp, where inertia matters most.

Three of our systems take part, so that every difference is attributed:

* ``production``: the scene as users run it (exact gravity, exact marker Jacobian);
* ``equivalent``: gravity as Exudyn's ``LoadMassProportional`` (``exact_gravity=False``, Eq.
  (F10)); the solver comparison and the issue's targets use this one;
* ``exudyn_jacobian``: also Exudyn's marker rotation Jacobian
  (:func:`validation.exudyn_bennett.exudyn_convention_system`), which is not the derivative of
  its constraint equations; with it both solvers solve the same discrete equations.

Plus the ideal path from :mod:`kinematics` as third reference, energy balances of both
solvers' runs (evaluated with our energy functions), constraint residuals of both runs in our
constraint equations, and wall times split into set-up and solution.
"""

from __future__ import annotations

import platform
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "ValidationSettings",
    "SolverRun",
    "BennettValidation",
    "TARGETS",
    "validate_bennett",
    "run_ours",
    "quasi_static_solve",
    "dynamic_solve",
    "from_exudyn",
]

#: Issue 7's targets: frequencies (relative), MAC diagonal (1 - value), torque (relative to its
#: maximum), trajectories (relative to the coupler's elastic deviation from the ideal path).
TARGETS = {"freq": 1e-8, "mac": 1e-6, "torque": 1e-4, "trajectory": 1e-3}

#: Floor of the trajectory scale (m): an ideally rigid linkage has no elastic deviation to
#: measure differences against, so they are taken relative to at least a micrometre.
SCALE_FLOOR_M = 1e-6


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
class SolverRun:
    """One solver's run on one system: rows at ``time``; sensors in SI."""

    label: str
    time: NDArray[np.float64]
    drive_angle: NDArray[np.float64]
    q: NDArray[np.float64]  # our layout and basis
    coupler: NDArray[np.float64]  # (n, 3)
    tracked: NDArray[np.float64]  # (n, 9, 3): links 1..3, three nodes each
    torque: NDArray[np.float64]  # (n,) N m
    setup_s: float
    solve_s: float
    extra: dict = field(default_factory=dict)


@dataclass
class BennettValidation:
    """All runs, the mode comparisons and the metrics of one variant."""

    settings: ValidationSettings
    modes: dict  # link name -> validation.modes.ModeComparison
    quasi_static: dict[str, SolverRun]  # production, equivalent, exudyn_jacobian, exudyn
    dynamic: dict[str, SolverRun]  # equivalent, exudyn (empty if skipped)
    ideal_coupler: NDArray[np.float64]  # at the quasi-static rows
    metrics: dict


def _progress_default(message: str) -> None:
    print(message, flush=True)


def _trajectory_metrics(a: SolverRun, b: SolverRun, scale_m: float) -> dict:
    """Max and RMS differences per sensor (coupler and the nine tracked nodes), torque."""
    if a.time.shape != b.time.shape or np.abs(a.time - b.time).max() > 1e-9 * max(1.0, a.time[-1]):
        raise ValueError(f"{a.label} and {b.label} have different output times")
    out = {}
    names = ["coupler_point"] + [f"link{k}_node{j}" for k in (1, 2, 3) for j in range(3)]
    series_a = [a.coupler] + [a.tracked[:, i] for i in range(9)]
    series_b = [b.coupler] + [b.tracked[:, i] for i in range(9)]
    for name, xa, xb in zip(names, series_a, series_b):
        distance = np.linalg.norm(xa - xb, axis=1)
        out[name] = {
            "max_abs_diff_m": float(distance.max()),
            "rms_diff_m": float(np.sqrt(np.mean(distance**2))),
            "relative_to_elastic_deviation": float(distance.max() / scale_m),
        }
    torque_scale = float(np.abs(b.torque).max())
    torque = {"max_abs_diff_Nm": float(np.abs(a.torque - b.torque).max()), "max_abs_Nm": torque_scale}
    torque["max_rel_diff"] = torque["max_abs_diff_Nm"] / max(torque_scale, 1e-300)
    return {"trajectories": out, "torque": torque}


def _energy_balance(scene, system, run: SolverRun, qd: NDArray | None = None) -> float:
    """Drive work minus the change of stored energy, relative to the work (Simpson over the rows)."""
    from ffrf.output.energy_balance import energy_balance

    energies = [
        system.energies(q, np.zeros_like(q) if qd is None else v) for q, v in zip(run.q, run.q if qd is None else qd)
    ]
    sensors = {"driving_torque": run.torque, "drive_angle": run.drive_angle}
    for kind in ("kinetic", "potential", "strain"):
        sensors[f"energy_{kind}"] = np.array([e[kind] for e in energies])
    balance = energy_balance(system, run.time, sensors, qd)
    return float(
        np.abs(balance["energy_balance_residual"]).max() / max(np.abs(balance["energy_drive_work"]).max(), 1e-300)
    )


def _constraint_residual(system, run: SolverRun) -> float:
    return float(max(np.abs(system.constraint_values(q, float(t))).max() for q, t in zip(run.q, run.time)))


def run_ours(label, scene, system, times, q0, setup_s, solve) -> SolverRun:
    """Our run of ``system`` from ``q0`` at ``times`` with ``solve(system, q0, times) -> (q, torque, extra)``."""
    from .exudyn_bennett import system_points

    started = time.perf_counter()
    q, torque, extra = solve(system, q0, times)
    solve_s = time.perf_counter() - started
    coupler, tracked = system_points(scene, system, q)
    angles = np.array([scene.drive_angle(float(t)) for t in times])
    return SolverRun(label, np.asarray(times), angles, q, coupler, tracked, torque, setup_s, solve_s, extra)


def quasi_static_solve(system, q0, times):
    """Static equilibria at ``times`` (:func:`ffrf.solvers.static_solver.quasi_static`)."""
    from ffrf.solvers.static_solver import quasi_static

    solution = quasi_static(system, q0, times)
    return solution.q, solution.multipliers[:, -1], {"newton_iterations": int(sum(solution.iterations))}


def dynamic_solve(step, rho_inf):
    """A ``solve`` for :func:`run_ours`: generalized-alpha from rest with ``step``, one row per step."""

    def solve(system, q0, times):
        from ffrf.solvers.generalized_alpha import generalized_alpha

        result = generalized_alpha(system, q0, np.zeros_like(q0), float(times[-1]), step, rho_inf=rho_inf)
        return (
            result.q,
            result.multipliers[:, -1],
            {"newton_iterations": int(result.newton_iterations.sum()), "qd": result.qd},
        )

    return solve


def from_exudyn(label, scene, trajectory, setup_s) -> SolverRun:
    """A :class:`SolverRun` from an Exudyn :class:`validation.exudyn_bennett.BennettTrajectory`."""
    angles = np.array([scene.drive_angle(float(t)) for t in trajectory.time])
    return SolverRun(
        label,
        trajectory.time,
        angles,
        trajectory.q,
        trajectory.coupler,
        trajectory.tracked,
        trajectory.torque,
        setup_s,
        trajectory.integration_time,
        {
            "solver": trajectory.solver,
            "notes": trajectory.extra.get("notes", []),
            "newton_iterations": trajectory.newton_iterations,
        },
    )


def validate_bennett(
    settings: ValidationSettings = ValidationSettings(), progress: Callable[[str], None] = _progress_default
) -> BennettValidation:
    """Build the variant, run every comparison of the module docstring, compute the metrics."""
    import exudyn

    from ffrf.scenes.bennett_run import ideal_coupler_points
    from ffrf.scenes.bennett_scene import assemble, build_bennett

    from .exudyn_bennett import (
        assemble_exudyn_bennett,
        bennett_bodies,
        exudyn_convention_system,
        quasi_static_exudyn_bennett,
        run_exudyn_bennett,
    )
    from .exudyn_twin import twin_bases
    from .modes import compare_modes

    started = time.perf_counter()
    production = build_bennett(settings.variant, h=settings.h, order=settings.order, n_modes=settings.n_modes)
    setup_ours = time.perf_counter() - started
    equivalent = production.with_exact_gravity(False)
    progress(
        f"[{settings.variant}] scene built in {setup_ours:.1f} s "
        f"({sum(l.fe.nodes.shape[0] for l in production.links)} nodes, "
        f"{[l.reduction.n_modes for l in production.links]} modes)"
    )

    started = time.perf_counter()
    bases = twin_bases(bennett_bodies(production), settings.basis)
    setup_bases = time.perf_counter() - started
    modes = {}
    for link, basis in zip(production.links, bases):
        if basis.source == "exudyn":
            modes[f"link{link.index}"] = compare_modes(
                link.fe, link.reduction, basis.matrix, basis.fixed_interface_frequencies_hz, basis.setup_s
            )
    progress(f"[{settings.variant}] Exudyn's HCB on the same matrices in {setup_bases:.1f} s")

    # Quasi-static revolution ------------------------------------------------------------------
    times = np.linspace(0.0, production.t_end, settings.outputs)
    qs: dict[str, SolverRun] = {}
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
        qs[label].solve_s += assembly_s
        progress(f"[{settings.variant}] ours ({label}): quasi-static revolution in {qs[label].solve_s:.1f} s")
    t0 = time.perf_counter()
    start = assemble_exudyn_bennett(production, bases)
    assembly_exudyn = time.perf_counter() - t0
    trajectory = quasi_static_exudyn_bennett(production, start, times, bases=bases)
    qs["exudyn"] = from_exudyn("exudyn", production, trajectory, setup_bases + trajectory.setup_time)
    qs["exudyn"].solve_s += assembly_exudyn
    progress(f"[{settings.variant}] Exudyn: quasi-static revolution in {qs['exudyn'].solve_s:.1f} s")

    # Dynamic window ---------------------------------------------------------------------------
    dyn: dict[str, SolverRun] = {}
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
        progress(f"[{settings.variant}] ours: {n_steps} dynamic steps in {dyn['equivalent'].solve_s:.1f} s")
        trajectory = run_exudyn_bennett(
            production, start[4], settings.dynamic_t_end, settings.step, settings.rho_inf, bases=bases
        )
        dyn["exudyn"] = from_exudyn("exudyn", production, trajectory, setup_bases + trajectory.setup_time)
        progress(f"[{settings.variant}] Exudyn: {n_steps} dynamic steps in {dyn['exudyn'].solve_s:.1f} s")

    ideal = ideal_coupler_points(production, qs["production"].drive_angle)
    metrics = _metrics(settings, production, equivalent, modes, qs, dyn, ideal, exudyn.__version__)
    return BennettValidation(settings, modes, qs, dyn, ideal, metrics)


def _metrics(settings, production, equivalent, modes, qs, dyn, ideal, exudyn_version) -> dict:

    deviation = {label: float(np.linalg.norm(run.coupler - ideal, axis=1).max()) for label, run in qs.items()}
    scale = max(deviation["exudyn"], SCALE_FLOOR_M)  # the coupler's elastic deviation from the ideal path
    headline = _trajectory_metrics(qs["equivalent"], qs["exudyn"], scale)
    m: dict = {
        "variant": settings.variant,
        "modes": {name: c.metrics() for name, c in modes.items()},
        "trajectories": headline["trajectories"],
        "torque": headline["torque"],
        "coupler_deviation_from_ideal_m": {
            "inhouse": deviation["production"],
            "inhouse_equivalent": deviation["equivalent"],
            "exudyn": deviation["exudyn"],
        },
        "modelling_differences": {
            "exact_vs_exudyn_gravity": _trajectory_summary(qs["production"], qs["equivalent"], scale),
            "exact_vs_exudyn_marker_jacobian": _trajectory_summary(qs["equivalent"], qs["exudyn_jacobian"], scale),
            "with_exudyn_jacobian_vs_exudyn": _trajectory_summary(qs["exudyn_jacobian"], qs["exudyn"], scale),
        },
        "energy_balance_relative": {
            "inhouse": _energy_balance(equivalent, equivalent.system, qs["equivalent"]),
            "inhouse_exudyn_jacobian": _energy_balance(equivalent, equivalent.system, qs["exudyn_jacobian"]),
            "exudyn": _energy_balance(equivalent, equivalent.system, qs["exudyn"]),
        },
        "constraint_residual": {
            "inhouse": _constraint_residual(equivalent.system, qs["equivalent"]),
            "exudyn": _constraint_residual(equivalent.system, qs["exudyn"]),
        },
        "max_abs_driving_torque_Nm": {label: float(np.abs(run.torque).max()) for label, run in qs.items()},
        "timing_s": {
            "inhouse": _timing(qs["equivalent"], dyn.get("equivalent")),
            "exudyn": _timing(qs["exudyn"], dyn.get("exudyn")),
        },
        "versions": _versions(exudyn_version),
        "settings": dict(
            settings.as_dict(),
            **{k: v for k, v in production.settings.items() if k not in ("gravity",)},
            gravity=production.settings["gravity"],
        ),
    }
    if dyn:
        dynamic = _trajectory_metrics(dyn["equivalent"], dyn["exudyn"], scale)
        dynamic["constraint_residual"] = {
            "inhouse": _constraint_residual(equivalent.system, dyn["equivalent"]),
            "exudyn": _constraint_residual(equivalent.system, dyn["exudyn"]),
        }
        dynamic["t_end"] = settings.dynamic_t_end
        m["dynamic"] = dynamic
    m["checks"] = _checks(m)
    m["passed"] = all(c["passed"] for c in m["checks"])
    return m


def _trajectory_summary(a: SolverRun, b: SolverRun, scale: float) -> dict:
    full = _trajectory_metrics(a, b, scale)
    worst = max(v["max_abs_diff_m"] for v in full["trajectories"].values())
    return {
        "max_abs_diff_m": worst,
        "coupler_max_abs_diff_m": full["trajectories"]["coupler_point"]["max_abs_diff_m"],
        "relative_to_elastic_deviation": worst / scale,
        "torque_max_rel_diff": full["torque"]["max_rel_diff"],
    }


def _timing(quasi_static: SolverRun, dynamic: SolverRun | None) -> dict:
    out = {
        "setup": quasi_static.setup_s,
        "integration": quasi_static.solve_s,
        "total": quasi_static.setup_s + quasi_static.solve_s,
    }
    if dynamic is not None:
        out["dynamic_window"] = dynamic.solve_s
        out["total"] += dynamic.solve_s
    return out


def _versions(exudyn_version: str) -> dict:
    import numba
    import scipy
    import skfem

    return {
        "exudyn": exudyn_version,
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "numba": numba.__version__,
        "scikit-fem": skfem.__version__,
        "platform": platform.platform(),
    }


def _checks(m: dict) -> list[dict]:
    """The issue's targets, each with its measured value."""
    checks = []

    def add(name: str, value: float, target: float):
        checks.append({"name": name, "value": float(value), "target": float(target), "passed": bool(value <= target)})

    for body, c in m["modes"].items():
        add(f"{body}: fixed-interface frequencies, max relative difference", c["max_rel_freq_diff"], TARGETS["freq"])
        add(f"{body}: 1 - min diagonal MAC", 1.0 - c["min_mac_diag"], TARGETS["mac"])
    for kind, block in (("quasi-static", m), ("dynamic", m.get("dynamic"))):
        if block is None:
            continue
        add(f"{kind}: driving torque, max difference / max torque", block["torque"]["max_rel_diff"], TARGETS["torque"])
        worst = max(v["relative_to_elastic_deviation"] for v in block["trajectories"].values())
        add(
            f"{kind}: coupler and tracked nodes, max difference / coupler's elastic deviation",
            worst,
            TARGETS["trajectory"],
        )
    return checks
