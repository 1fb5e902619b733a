"""The time step of a dynamic run from accuracy (issue #22): the default Bennett scene's whole ramp and revolution
(61 s of drive at 1 rpm) with generalized-alpha at several steps, each scored against a run at ``--reference`` s:
the coupler point's largest distance and the driving torque's largest difference over the reference's largest
torque, at the same output times; with the Newton iterations per step, the factorisations of the iteration matrix,
the wall time (warm kernels) and the local error estimate of Eq. (G5) (median and largest over the steps). The same
at 10 ms with Newton's start extrapolated by a line instead of a parabola (Eq. (G6)), and at 10 ms with looser
Newton tolerances (``--tolerances``): how the tolerance maps to the coupler's error.

The default step of a dynamic run, 0.06 deg of drive per step (10 ms at 1 rpm,
:func:`ffrf.scenes.assembly.dynamic_step`), comes from this sweep.

Usage::

    .venv/bin/python -m bench dynamic_step_rule --json out/dynamic_step_rule.json
"""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import numpy as np

import ffrf.solvers.generalized_alpha as alpha  # noqa: E402
from bench.full_revolution import count_factorisations
from bench.report import write_report
from ffrf.paper.bennett_scene import build_bennett
from ffrf.scenes.assembly import assemble
from ffrf.scenes.linkage_run import evaluate_sensors

#: Output rows every 0.08 s (a multiple of every step below).
OUTPUT_INTERVAL = 0.08


def run(
    scene,
    q0,
    factorisations: dict,
    step: float,
    predictor_degree: int = alpha.PREDICTOR_DEGREE,
    tolerance: float = 1e-10,
) -> dict:
    """One dynamic run at ``step`` (s) with Newton to ``tolerance``: its path sensors and statistics
    (``factorisations``: the counter of :func:`full_revolution.count_factorisations`)."""
    kept, alpha.PREDICTOR_DEGREE = alpha.PREDICTOR_DEGREE, predictor_degree
    try:
        factored_before = factorisations["n"]
        started = time.perf_counter()
        result = alpha.generalized_alpha(
            scene.system,
            q0,
            np.zeros_like(q0),
            scene.t_end,
            step,
            tolerance=tolerance,
            output_every=round(OUTPUT_INTERVAL / step),
        )
        wall = time.perf_counter() - started
        factored = factorisations["n"] - factored_before
    finally:
        alpha.PREDICTOR_DEGREE = kept
    sensors = evaluate_sensors(scene, result.time, result.q, result.qd, result.multipliers, "path")
    return {
        "sensors": sensors,
        "row": {
            "step_s": step,
            "predictor_polynomial_order": predictor_degree,
            "newton_tolerance": tolerance,
            "steps": len(result.newton_iterations),
            "iterations_per_step": float(result.newton_iterations.mean()),
            "factorisations": factored,
            "wall_s": wall,
            "ms_per_step": 1e3 * wall / len(result.newton_iterations),
            "estimate_median_m": float(np.median(result.position_errors)),
            "estimate_largest_m": float(result.position_errors.max()),
        },
    }


def errors(sensors: dict, reference: dict) -> dict:
    """Coupler distance (m) and driving-torque difference (relative to the reference's largest) at the outputs."""
    coupler = np.linalg.norm(sensors["coupler_point"] - reference["coupler_point"], axis=1).max()
    torque = np.abs(sensors["driving_torque"] - reference["driving_torque"]).max()
    return {
        "coupler_error_m": float(coupler),
        "torque_error_rel": float(torque / np.abs(reference["driving_torque"]).max()),
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=float, nargs="+", default=[4e-3, 1e-2, 2e-2])
    parser.add_argument("--reference", type=float, default=2e-3, help="the reference run's step (s)")
    parser.add_argument("--tolerances", type=float, nargs="*", default=[1e-8, 1e-6], help="looser ones at 10 ms")
    parser.add_argument("--json", type=Path, required=True)
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    scene = build_bennett("pla")
    q0 = assemble(scene).q
    alpha.generalized_alpha(scene.system, q0, np.zeros_like(q0), 0.1, 1e-2)  # compile or load the kernels first
    factorisations = count_factorisations()
    reference = run(scene, q0, factorisations, args.reference)
    rows = []
    settings = [(step, alpha.PREDICTOR_DEGREE, 1e-10) for step in args.steps] + [(1e-2, 1, 1e-10)]
    settings += [(1e-2, alpha.PREDICTOR_DEGREE, tolerance) for tolerance in args.tolerances]
    for step, degree, tolerance in settings:
        measured = run(scene, q0, factorisations, step, degree, tolerance)
        rows.append({**measured["row"], **errors(measured["sensors"], reference["sensors"])})
        print(rows[-1], flush=True)
    report = {
        "scene": "default PLA Bennett (6 mm P2, 4 modes per link), 1 s ramp + one revolution at 1 rpm",
        "rho_inf": 0.9,
        "reference": reference["row"],
        "runs": rows,
    }
    write_report(report, args.json, echo=False)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
