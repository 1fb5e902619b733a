"""Derivatives by the links' section and the lightest section of the PLA Bennett (issue #35, Eqs. (D5)-(D6)).

    .venv/bin/python -m bench record section_design                    # docs/results/section_design.json
    .venv/bin/python -m bench section_design --json out/design.json     # the same, written elsewhere

The paper's PLA Bennett at the default discretisation, its collision-free stacking, under its weight:

* gradients: the derivatives of the coupler point and driving torque at 13 poses by each section dimension of
  every link at once (the sum of the links') against central differences of equilibria re-solved by Newton on the
  morphed linkages (relative steps 1e-2 .. 1e-5: the truncation and round-off window) and of remeshed linkages
  (+-0.5 mm: the discretisation), with the time of the derivatives against the two runs per link that central
  differences take;
* designs: ``ffrf.scenes.section_design.optimise_section`` over arm width and thickness (8 .. 30 mm) for several
  bounds on the coupler's deviation (37 design poses, as ``examples/design_bennett_section.toml``), each optimum
  then run on its own at 145 poses: the mass/deviation trade-off, iterations, KKT residuals and times.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from bench.report import write_report
from ffrf.geometry.design_velocity import SECTION_PARAMETERS
from ffrf.output.sensors import path_sensors
from ffrf.paper.bennett_scene import _paper_loop, bennett_options
from ffrf.scenes.builder import morphed_body
from ffrf.scenes.linkage_run import run_linkage
from ffrf.scenes.linkage_scene import build_linkage
from ffrf.scenes.path_sensitivity import section_sensitivity, section_velocities
from ffrf.scenes.section_design import DesignProblem, optimise_section
from ffrf.solvers.static_solver import static_equilibrium

POSES = 13
STEPS = (1e-2, 1e-3, 1e-4, 1e-5)
REMESH_STEP = 0.5e-3
BOUNDS_MM = (0.1, 0.14, 0.2, 0.3)
DESIGN_POSES = 37
CHECK_POSES = 145


def _morphed(scene, result, velocities: dict, change: float) -> dict:
    """:func:`_re_solved` on ``scene`` with every link in ``velocities`` morphed by ``change`` (m) of the dimension."""
    moved = scene
    for (k, _), velocity in velocities.items():
        moved = moved.with_body(morphed_body(scene, k, scene.bodies[k].mesh_model.mesh.points + change * velocity))
    return _re_solved(result, moved)


def _errors(plus: dict, minus: dict, step: float, coupler: np.ndarray, torque: np.ndarray) -> dict:
    """The largest difference between central differences of the sensors ``plus`` and ``minus`` at ``+-step`` and
    our derivatives, relative to the largest derivative: coupler point and driving torque."""
    return {
        "coupler_error": _error(coupler, (plus["coupler_point"] - minus["coupler_point"]) / (2 * step)),
        "torque_error": _error(torque, (plus["driving_torque"] - minus["driving_torque"]) / (2 * step)),
    }


def _re_solved(result, system_scene) -> dict:
    """The path sensors of ``system_scene`` at ``result``'s times, each equilibrium re-solved from ``result``'s."""
    solved = []
    for q, t in zip(result.q, result.time, strict=True):
        first = static_equilibrium(system_scene.system, q, t=float(t), tolerance=1e-13)
        solved.append(static_equilibrium(system_scene.system, first.q, t=float(t), tolerance=1e-15))
    q = np.array([s.q for s in solved])
    return path_sensors(system_scene, result.time, q, np.array([s.multipliers for s in solved]))


def _error(ours: np.ndarray, theirs: np.ndarray) -> float:
    return float(np.abs(ours - theirs).max() / np.abs(theirs).max())


def gradients() -> list[dict]:
    loop, options = _paper_loop(), bennett_options("pla")
    scene = build_linkage(loop, options)
    started = time.perf_counter()
    result = run_linkage(scene, mode="quasi_static", n_outputs=POSES, sensors="path")
    run_s = time.perf_counter() - started
    assert result.multipliers is not None  # a quasi-static run keeps its equilibria's multipliers
    rows = []
    for parameter in SECTION_PARAMETERS:
        started = time.perf_counter()
        velocities = section_velocities(scene, (parameter,))
        exact = section_sensitivity(
            scene, result.time, result.q, result.multipliers, (parameter,), velocities=velocities
        )
        sensitivity_s = time.perf_counter() - started
        coupler, torque = exact.coupler_point.sum(axis=2), exact.driving_torque.sum(axis=1)
        value = getattr(options.design, parameter)

        steps = []
        for relative in STEPS:
            plus, minus = (_morphed(scene, result, velocities, sign * relative * value) for sign in (1.0, -1.0))
            steps.append({"relative_step": relative, **_errors(plus, minus, relative * value, coupler, torque)})
        sides = []
        for sign in (1.0, -1.0):
            design = replace(options.design, **{parameter: value + sign * REMESH_STEP})
            built = build_linkage(loop, replace(options, design=design))
            sides.append((_re_solved(result, built), sum(b.moments.mass for b in built.system.bodies)))
        assert exact.mass is not None
        remeshed = _errors(sides[0][0], sides[1][0], REMESH_STEP, coupler, torque)
        remeshed["mass_error"] = abs((sides[0][1] - sides[1][1]) / (2 * REMESH_STEP) / exact.mass.sum() - 1.0)
        best = min(steps, key=lambda s: s["coupler_error"])
        row = {
            "parameter": parameter,
            "largest_coupler_derivative_m_per_m": float(np.abs(coupler).max()),
            "mass_derivative_kg_per_m": float(exact.mass.sum()),
            "steps": steps,
            "best_coupler_error": best["coupler_error"],
            "remeshed": remeshed,
            "sensitivity_s": sensitivity_s,
            "run_s": run_s,
            # per link, as ours: central differences need two runs per link and dimension
            "speedup_vs_central_differences": 2.0 * len(velocities) * run_s / sensitivity_s,
        }
        print(parameter, best, remeshed, flush=True)
        rows.append(row)
    return rows


def designs() -> list[dict]:
    loop, options = _paper_loop(), bennett_options("pla")
    rows = []
    for bound in BOUNDS_MM:
        problem = DesignProblem(
            ("arm_width", "arm_thickness"), (8e-3, 8e-3), (30e-3, 30e-3), bound * 1e-3, DESIGN_POSES
        )
        started = time.perf_counter()
        design = optimise_section(loop, options, problem)
        seconds = time.perf_counter() - started
        chosen = dict(zip(problem.parameters, design.optimum.values, strict=True))
        check = build_linkage(loop, replace(options, design=replace(options.design, **chosen)))
        result = run_linkage(check, mode="quasi_static", n_outputs=CHECK_POSES, sensors="path")
        row = {
            "bound_mm": bound,
            "start": {"mass_g": 1e3 * design.start.mass, "max_deviation_mm": 1e3 * design.start.max_deviation},
            "arm_width_mm": 1e3 * chosen["arm_width"],
            "arm_thickness_mm": 1e3 * chosen["arm_thickness"],
            "mass_g": 1e3 * design.optimum.mass,
            "max_deviation_mm": 1e3 * design.optimum.max_deviation,
            "check_max_deviation_mm": 1e3 * float(np.linalg.norm(result.sensors["coupler_deviation"], axis=1).max()),
            "iterations": design.iterations,
            "evaluations": len(design.history),
            "success": design.success,
            "message": design.message,
            "kkt_residual": design.kkt_residual,
            "seconds": seconds,
        }
        print(bound, {k: row[k] for k in ("arm_width_mm", "arm_thickness_mm", "mass_g", "kkt_residual")}, flush=True)
        rows.append(row)
    return rows


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, required=True)
    args = parser.parse_args()
    gradient_rows = gradients()
    header = {"poses": POSES, "design_poses": DESIGN_POSES, "check_poses": CHECK_POSES}
    write_report({**header, "gradients": gradient_rows, "designs": []}, args.json)  # partial: the gradients
    write_report({**header, "gradients": gradient_rows, "designs": designs()}, args.json)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
