r"""The metrics of a Bennett cross-validation (:mod:`validation.bennett_validation`): differences
of trajectories and torques relative to the coupler's elastic deviation, energy balances and
constraint residuals of both solvers' runs in our equations, wall times, versions, and the checks
against issue 7's targets.
"""

from __future__ import annotations

import platform

import numpy as np
from numpy.typing import NDArray

from .bennett_trajectory import TRACKED, tracked_nodes
from .twin_run import ComparedRun, solution_time

__all__ = ["TARGETS", "SCALE_FLOOR_M", "bennett_metrics"]

#: Issue 7's targets: frequencies (relative), MAC diagonal (1 - value), torque (relative to its
#: maximum), trajectories (relative to the coupler's elastic deviation from the ideal path).
TARGETS = {"freq": 1e-8, "mac": 1e-6, "torque": 1e-4, "trajectory": 1e-3}

#: Floor of the trajectory scale (m): an ideally rigid linkage has no elastic deviation to
#: measure differences against, so they are taken relative to at least a micrometre.
SCALE_FLOOR_M = 1e-6


def _trajectory_metrics(a: ComparedRun, b: ComparedRun, scale_m: float) -> dict:
    """Max and RMS differences per sensor (coupler and the nine tracked nodes), torque."""
    if a.time.shape != b.time.shape or np.abs(a.time - b.time).max() > 1e-9 * max(1.0, a.time[-1]):
        raise ValueError(f"{a.metadata['label']} and {b.metadata['label']} have different output times")
    out = {}
    names = ["coupler_point", *TRACKED]
    tracked_a, tracked_b = tracked_nodes(a), tracked_nodes(b)
    series_a = [a.sensors["coupler_point"]] + [tracked_a[:, i] for i in range(len(TRACKED))]
    series_b = [b.sensors["coupler_point"]] + [tracked_b[:, i] for i in range(len(TRACKED))]
    for name, xa, xb in zip(names, series_a, series_b, strict=True):
        distance = np.linalg.norm(xa - xb, axis=1)
        out[name] = {
            "max_abs_diff_m": float(distance.max()),
            "rms_diff_m": float(np.sqrt(np.mean(distance**2))),
            "relative_to_elastic_deviation": float(distance.max() / scale_m),
        }
    torque_a, torque_b = a.sensors["driving_torque"], b.sensors["driving_torque"]
    torque_scale = float(np.abs(torque_b).max())
    torque = {"max_abs_diff_Nm": float(np.abs(torque_a - torque_b).max()), "max_abs_Nm": torque_scale}
    torque["max_rel_diff"] = torque["max_abs_diff_Nm"] / max(torque_scale, 1e-300)
    return {"trajectories": out, "torque": torque}


def _energy_balance(scene, system, run: ComparedRun, qd: NDArray | None = None) -> float:
    """Drive work minus the change of stored energy, relative to the work (Simpson over the rows)."""
    from ffrf.output.energy_balance import energy_balance

    energies = [
        system.energies(q, np.zeros_like(q) if qd is None else v)
        for q, v in zip(run.q, run.q if qd is None else qd, strict=True)
    ]
    sensors = {name: run.sensors[name] for name in ("driving_torque", "drive_angle")}
    for kind in ("kinetic", "potential", "strain"):
        sensors[f"energy_{kind}"] = np.array([e[kind] for e in energies])
    balance = energy_balance(system, run.time, sensors, qd)
    return float(
        np.abs(balance["energy_balance_residual"]).max() / max(np.abs(balance["energy_drive_work"]).max(), 1e-300)
    )


def _constraint_residual(system, run: ComparedRun) -> float:
    return float(max(np.abs(system.constraint_values(q, float(t))).max() for q, t in zip(run.q, run.time, strict=True)))


def bennett_metrics(settings, production, equivalent, modes, qs, dyn, ideal, exudyn_version: str) -> dict:
    """The metrics of one variant's runs (:func:`validation.bennett_validation.validate_bennett`):
    ``qs``/``dyn`` the quasi-static and dynamic runs by label (ours :class:`~ffrf.output.result.Result` s, the
    twin's a :class:`validation.twin_run.TwinRun`), ``ideal`` the ideal coupler points at the quasi-static rows,
    ``modes`` the mode comparisons; with the checks against :data:`TARGETS` and the verdict ``passed``."""
    deviation = {
        label: float(np.linalg.norm(run.sensors["coupler_point"] - ideal, axis=1).max()) for label, run in qs.items()
    }
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
        "max_abs_driving_torque_Nm": {
            label: float(np.abs(run.sensors["driving_torque"]).max()) for label, run in qs.items()
        },
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


def _trajectory_summary(a: ComparedRun, b: ComparedRun, scale: float) -> dict:
    full = _trajectory_metrics(a, b, scale)
    worst = max(v["max_abs_diff_m"] for v in full["trajectories"].values())
    return {
        "max_abs_diff_m": worst,
        "coupler_max_abs_diff_m": full["trajectories"]["coupler_point"]["max_abs_diff_m"],
        "relative_to_elastic_deviation": worst / scale,
        "torque_max_rel_diff": full["torque"]["max_rel_diff"],
    }


def _timing(quasi_static: ComparedRun, dynamic: ComparedRun | None) -> dict:
    """Wall times (s): building (``setup``), the quasi-static revolution with the assembly it started from
    (``integration``), the dynamic window, and their ``total``."""
    setup, solution = quasi_static.metadata["timings_s"]["setup"], solution_time(quasi_static)
    out = {"setup": setup, "integration": solution, "total": setup + solution}
    if dynamic is not None:
        out["dynamic_window"] = dynamic.metadata["timings_s"]["solve"]
        out["total"] += out["dynamic_window"]
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
