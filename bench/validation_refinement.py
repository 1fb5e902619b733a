"""Refinement study: both solvers converge to the same answer as the time step shrinks.

The Bennett scene (``--variant``, coarse by default), each solver from its own static
assembly, generalized-alpha over ``--t-end`` with steps ``--steps``: for every step ``h`` the
largest difference of the coupler point and tracked nodes of each solver against itself at
``h/2`` (its time-discretisation error; second order expected), and of ours against Exudyn
at the same ``h``. Ours runs with Exudyn's gravity model (``equivalent``) and, with
``--exudyn-jacobian``, also with Exudyn's marker Jacobian; then the two solve the same
discrete equations and differ by round-off at every step.

Usage::

    .venv/bin/python -m bench validation_refinement                       # pla, h = 6 mm, 2 modes
    .venv/bin/python -m bench validation_refinement --variant pla1 --exudyn-jacobian
    .venv/bin/python -m bench validation_refinement --h 4e-3 --modes 8 --json out.json
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from bench.report import write_report


def _points(run) -> np.ndarray:
    from validation.bennett_trajectory import tracked_nodes

    return np.concatenate([run.sensors["coupler_point"][:, None, :], tracked_nodes(run)], axis=1)


def _diff_at_common_times(fine, coarse) -> float:
    """Max distance at the coarse run's times (the fine run has twice the rows)."""
    a, b = _points(fine)[::2], _points(coarse)
    return float(np.linalg.norm(a - b, axis=2).max())


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--variant", default="pla")
    parser.add_argument("--h", type=float, default=6e-3)
    parser.add_argument("--modes", type=int, default=2)
    parser.add_argument("--t-end", type=float, default=0.4)
    parser.add_argument("--steps", default="4e-3,2e-3,1e-3,5e-4")
    parser.add_argument("--rho-inf", type=float, default=0.9)
    parser.add_argument("--exudyn-jacobian", action="store_true")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args(argv)

    from ffrf.paper.bennett_scene import assemble, build_bennett
    from validation.bennett_validation import dynamic_solve, run_ours
    from validation.exudyn_bennett import assemble_exudyn_bennett, bennett_bodies, run_exudyn_bennett
    from validation.exudyn_conventions import exudyn_convention_system
    from validation.twin_bases import twin_bases

    scene = build_bennett(args.variant, h=args.h, order=1, n_modes=args.modes).with_exact_gravity(False)
    convert = (lambda s: exudyn_convention_system(s, True)) if args.exudyn_jacobian else None
    system = scene.system if convert is None else convert(scene.system)
    q_ours = assemble(scene, convert=convert).q
    bases = twin_bases(bennett_bodies(scene))
    start = assemble_exudyn_bennett(scene, bases)
    steps = [float(s) for s in args.steps.split(",")]
    ours, theirs = {}, {}
    for h in steps:
        times = h * np.arange(int(round(args.t_end / h)) + 1)
        ours[h] = run_ours("equivalent", scene, system, times, q_ours, 0.0, dynamic_solve(h, args.rho_inf))
        theirs[h] = run_exudyn_bennett(scene, start[4], args.t_end, h, args.rho_inf, bases=bases)
    rows = []
    print(
        f"{args.variant}, h = {args.h} m, {args.modes} modes, {args.t_end} s, exudyn_jacobian = {args.exudyn_jacobian}"
    )
    print(
        f"{'step':>8} {'ours: h vs h/2':>15} {'Exudyn: h vs h/2':>17} {'ours vs Exudyn':>15} "
        f"{'ours s':>7} {'Exudyn s':>9}"
    )
    for h in steps:
        row = {
            "step": h,
            "ours_vs_exudyn_m": float(np.linalg.norm(_points(ours[h]) - _points(theirs[h]), axis=2).max()),
            "ours_s": ours[h].metadata["timings_s"]["solve"],
            "exudyn_s": theirs[h].metadata["timings_s"]["solve"],
        }
        if h / 2 in ours:
            row["ours_self_m"] = _diff_at_common_times(ours[h / 2], ours[h])
            row["exudyn_self_m"] = _diff_at_common_times(theirs[h / 2], theirs[h])
        rows.append(row)
        print(
            f"{h:8.1e} {row.get('ours_self_m', float('nan')):15.3e} {row.get('exudyn_self_m', float('nan')):17.3e} "
            f"{row['ours_vs_exudyn_m']:15.3e} {row['ours_s']:7.2f} {row['exudyn_s']:9.2f}"
        )
    out = {"settings": vars(args) | {"json": None}, "rows": rows}
    if args.json:
        write_report(out, args.json, echo=False)
    return out


if __name__ == "__main__":
    main()
