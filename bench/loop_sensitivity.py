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
derivatives against the two full runs that central differences take per parameter. The smallest clearance of each
pair of links along the rigid revolution (72 poses) and its rates by each parameter (Eq. (CL6)) against the whole
check re-run on the changed linkages at +-1e-4 (crossing pairs: central differences; adjacent pairs, whose smallest
has one-sided rates: the forward and backward differences inside them) and on the remeshed ones.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from bench.report import write_report
from ffrf.errors import MeshError
from ffrf.output.clearance import Clearance
from ffrf.output.sensors import path_sensors
from ffrf.paper.bennett_scene import bennett_changes, bennett_options, build_bennett_from_options
from ffrf.scenes.linkage_run import run_linkage
from ffrf.scenes.linkage_scene import LinkageScene, build_linkage
from ffrf.scenes.path_sensitivity import (
    ClearanceRates,
    changed_linkage,
    loop_clearance_slopes,
    loop_sensitivity,
    loop_velocities,
)
from ffrf.solvers.static_solver import static_equilibrium

POSES = 13
CLEARANCE_POSES = 72
CLEARANCE_STEP = 1e-4
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


def _clearance_errors(found: Clearance, rates: ClearanceRates, plus: Clearance, minus: Clearance, step: float) -> dict:
    """The rates against the differences of the whole check at ``+-step``: where one pose holds a pair's smallest,
    the largest difference from the central difference; elsewhere, how far the forward and backward differences lie
    inside the one-sided rates (negative: outside); both relative to the largest rate."""
    central = (plus.distance - minus.distance) / (2 * step)
    forward, backward = (plus.distance - found.distance) / step, (found.distance - minus.distance) / step
    largest = float(np.abs(rates.at_smallest[:, 0]).max())
    one = rates.differentiable
    inside = np.minimum(forward - rates.right[:, 0], rates.left[:, 0] - backward)[~one]
    return {
        "differentiable_error": float(np.abs(rates.at_smallest[one, 0] - central[one]).max() / largest)
        if one.any()
        else None,
        "one_sided_inside": float(inside.min() / largest) if inside.size else None,
        "central": central.tolist(),
    }


def gradients() -> list[dict]:
    options = bennett_options("pla")
    scene = build_bennett_from_options(options)
    started = time.perf_counter()
    result = run_linkage(scene, mode="quasi_static", n_outputs=POSES, sensors="path")
    run_s = time.perf_counter() - started
    assert result.multipliers is not None  # a quasi-static run keeps its equilibria's multipliers
    angles = np.array([scene.drive_angle(float(t)) for t in result.time])
    started = time.perf_counter()
    clearance = scene.clearance(CLEARANCE_POSES)
    clearance_s = time.perf_counter() - started
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
        started = time.perf_counter()
        rates = loop_clearance_slopes(scene, clearance, (change,), CLEARANCE_POSES, velocities=velocities)
        rates_s = time.perf_counter() - started
        delta = CLEARANCE_STEP * abs(change.value)
        plus_c, minus_c = (
            changed_linkage(scene, change, sign * delta, velocities).clearance(CLEARANCE_POSES) for sign in (1.0, -1.0)
        )
        clearance_row = {
            "pairs": clearance.pairs.tolist(),
            "smallest_mm": (1e3 * clearance.distance).tolist(),
            "at_smallest": rates.at_smallest[:, 0].tolist(),
            "right": rates.right[:, 0].tolist(),
            "left": rates.left[:, 0].tolist(),
            "poses_holding": rates.poses.tolist(),
            "morphed": _clearance_errors(clearance, rates, plus_c, minus_c, delta),
            "rates_s": rates_s,
            "check_s": clearance_s,
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
        sides, checks = [], []
        for sign in (1.0, -1.0):
            built = build_linkage(*change.linkage(sign * delta))
            sides.append((_re_solved(result, built, angles), sum(b.moments.mass for b in built.system.bodies)))
            checks.append(built.clearance(CLEARANCE_POSES))
        clearance_row["remeshed"] = _clearance_errors(clearance, rates, checks[0], checks[1], delta)
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
            "clearance": clearance_row,
        }
        print(change.name, best, remeshed, f"{sensitivity_s:.1f} s", clearance_row["morphed"], flush=True)
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
