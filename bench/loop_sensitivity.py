"""Derivatives by the loop's own DH parameters of the PLA Bennett (issue #35, Eqs. (D12)-(D13)).

    .venv/bin/python -m bench record loop_sensitivity                  # docs/results/loop_sensitivity.json
    .venv/bin/python -m bench loop_sensitivity --json out/loop.json     # the same, written elsewhere

The paper's PLA Bennett at the default discretisation, its collision-free stacking, under its weight, 13 poses of a
quasi-static revolution; for each free DH parameter of the Bennett family (a0, alpha0, alpha1;
:func:`ffrf.paper.bennett_scene.bennett_changes`) the derivatives of the coupler point, its deviation from the ideal
path and the driving torque against central differences of equilibria re-solved by Newton for the changed loop's
linkage on the morphed meshes (relative steps 1e-2 .. 1e-6: the truncation and round-off window; a step whose morph
folds tetrahedra is recorded as such) and of linkages
built on the changed loop and remeshed (+-0.5 % of the parameter: the discretisation), with the time of the
derivatives against the two full runs that central differences take per parameter.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from bench.report import write_report
from ffrf.errors import MeshError
from ffrf.output.sensors import path_sensors
from ffrf.paper.bennett_scene import bennett_changes, bennett_options, build_bennett_from_options
from ffrf.scenes.linkage_run import run_linkage
from ffrf.scenes.linkage_scene import LinkageScene, build_linkage
from ffrf.scenes.path_sensitivity import changed_linkage, loop_sensitivity, loop_velocities
from ffrf.solvers.static_solver import static_equilibrium

POSES = 13
STEPS = (1e-2, 1e-3, 1e-4, 1e-5, 1e-6)
REMESH_STEP = 5e-3


def _re_solved(result, scene: LinkageScene, angles: np.ndarray) -> dict:
    """The path sensors of ``scene`` at ``result``'s times, each equilibrium re-solved from ``result``'s, and the
    deviation from ``scene``'s own ideal path at ``angles``."""
    solved = []
    for q, t in zip(result.q, result.time, strict=True):
        first = static_equilibrium(scene.system, q, t=float(t), tolerance=1e-13)
        solved.append(static_equilibrium(scene.system, first.q, t=float(t), tolerance=1e-15))
    q = np.array([s.q for s in solved])
    sensors = path_sensors(scene, result.time, q, np.array([s.multipliers for s in solved]))
    return sensors | {"deviation": sensors["coupler_point"] - scene.ideal_coupler_points(angles)}


def _errors(plus: dict, minus: dict, step: float, exact: dict) -> dict:
    """The largest difference between central differences of ``plus`` and ``minus`` at ``+-step`` and our
    derivatives ``exact``, each relative to its largest derivative."""
    return {f"{name}_error": _error(ours, (plus[name] - minus[name]) / (2 * step)) for name, ours in exact.items()}


def _error(ours: np.ndarray, theirs: np.ndarray) -> float:
    return float(np.abs(ours - theirs).max() / np.abs(theirs).max())


def gradients() -> list[dict]:
    options = bennett_options("pla")
    scene = build_bennett_from_options(options)
    started = time.perf_counter()
    result = run_linkage(scene, mode="quasi_static", n_outputs=POSES, sensors="path")
    run_s = time.perf_counter() - started
    assert result.multipliers is not None  # a quasi-static run keeps its equilibria's multipliers
    angles = np.array([scene.drive_angle(float(t)) for t in result.time])
    rows = []
    for change in bennett_changes(options):
        started = time.perf_counter()
        velocities = loop_velocities(scene, (change,))
        found = loop_sensitivity(scene, result.time, result.q, result.multipliers, (change,), velocities=velocities)
        sensitivity_s = time.perf_counter() - started
        exact = {
            "coupler_point": found.coupler_point[:, :, 0],
            "deviation": found.deviation[:, :, 0],
            "driving_torque": found.driving_torque[:, 0],
        }
        steps: list[dict[str, float | str]] = []
        for relative in STEPS:
            delta = relative * abs(change.value)
            try:
                plus, minus = (
                    _re_solved(result, changed_linkage(scene, change, sign * delta, velocities), angles)
                    for sign in (1.0, -1.0)
                )
            except MeshError as error:  # a step too large for the morph: its tetrahedra fold
                steps.append({"relative_step": relative, "folded": str(error)})
                continue
            steps.append({"relative_step": relative, **_errors(plus, minus, delta, exact)})
        delta = REMESH_STEP * abs(change.value)
        sides = []
        for sign in (1.0, -1.0):
            built = build_linkage(*change.linkage(sign * delta))
            sides.append((_re_solved(result, built, angles), sum(b.moments.mass for b in built.system.bodies)))
        assert found.mass is not None
        remeshed = _errors(sides[0][0], sides[1][0], delta, exact)
        remeshed["mass_error"] = abs((sides[0][1] - sides[1][1]) / (2 * delta) / found.mass[0] - 1.0)
        best = min((s for s in steps if "folded" not in s), key=lambda s: float(s["deviation_error"]))
        row = {
            "parameter": change.name,
            "value": change.value,
            "largest_coupler_derivative": float(np.abs(exact["coupler_point"]).max()),
            "largest_deviation_derivative": float(np.abs(exact["deviation"]).max()),
            "largest_torque_derivative": float(np.abs(exact["driving_torque"]).max()),
            "mass_derivative": float(found.mass[0]),
            "steps": steps,
            "best": best,
            "remeshed": remeshed,
            "sensitivity_s": sensitivity_s,
            "run_s": run_s,
            "speedup_vs_central_differences": 2.0 * run_s / sensitivity_s,
        }
        print(change.name, best, remeshed, f"{sensitivity_s:.1f} s", flush=True)
        rows.append(row)
    return rows


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, required=True)
    args = parser.parse_args()
    write_report({"poses": POSES, "gradients": gradients()}, args.json)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
