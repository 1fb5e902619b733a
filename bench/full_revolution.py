"""A whole dynamic run of the PLA Bennett scene, ours against Exudyn in the same process: the
1 s cosine ramp and one revolution at 1 rpm (61 s of drive), generalized-alpha index 3 at
``--step`` with ``--rho-inf``, each solver from its own static assembly at rest.

This is issue 9's speed target ("a dynamic revolution of the PLA scene at least 10x faster than
Exudyn at equal accuracy"): both solvers integrate the same discretisation with the same step,
so they are at equal accuracy when their coupler paths agree (printed). Timings: set-up
(ours: mesh, FE matrices, reduction; Exudyn: its reduction on our matrices and the twin), static
assembly, and time integration apart, in ms per step; our factorisations of the iteration
matrix are counted. BLAS is pinned to one thread.

Run: .venv/bin/python -m bench full_revolution [--order 2 --h 0.006 --modes 4] [--step 0.004]
     [--no-exudyn] [--json out/full_revolution.json]
"""

from __future__ import annotations

import argparse
import importlib
import os
from pathlib import Path

from bench.report import write_report

for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

import numpy as np  # noqa: E402 - after the thread counts above, which BLAS reads when numpy loads


def count_factorisations() -> dict[str, int]:
    """Wrap the generalized-alpha module's factorisation so that its calls are counted in the returned ``{"n": ...}``
    (from now on, in this process; also used by ``bench/dynamic_step_rule.py``)."""
    module = importlib.import_module("ffrf.solvers.generalized_alpha")
    original = module._factor_iteration_matrix
    counter = {"n": 0}

    def counted(*args, **kwargs):
        counter["n"] += 1
        return original(*args, **kwargs)

    vars(module)["_factor_iteration_matrix"] = counted  # replaced in the module's namespace, where _step finds it
    return counter


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--order", type=int, default=2, help="tetrahedron order (default: the scene's)")
    parser.add_argument("--h", type=float, default=6e-3, help="mesh size (m)")
    parser.add_argument("--modes", type=int, default=4)
    parser.add_argument("--step", type=float, default=4e-3)
    parser.add_argument("--rho-inf", type=float, default=0.9)
    parser.add_argument("--t-end", type=float, default=None, help="default: ramp + one revolution")
    parser.add_argument("--no-exudyn", action="store_true")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args(argv)

    from bench.speed_vs_error import run_dynamic
    from ffrf.paper.bennett_scene import build_bennett

    counter = count_factorisations()
    t_end = args.t_end if args.t_end is not None else build_bennett("pla", h=6e-3, order=1, n_modes=2).t_end
    print(f"t_end {t_end:.3f} s, {int(round(t_end / args.step))} steps of {args.step} s", flush=True)
    out = run_dynamic(args.order, args.h, args.modes, args.step, args.rho_inf, t_end, not args.no_exudyn)
    steps = len(out["ffrf"]["time"]) - 1
    report = {
        "order": args.order,
        "h": args.h,
        "modes": args.modes,
        "step": args.step,
        "rho_inf": args.rho_inf,
        "t_end": t_end,
        "steps": steps,
        "factorisations": counter["n"],
    }
    for solver, run in out.items():
        solve = run["integration_s"] - run["assembly_s"]
        report[solver] = {
            "setup_s": run["setup_s"],
            "assembly_s": run["assembly_s"],
            "solve_s": solve,
            "ms_per_step": 1e3 * solve / steps,
            "max_torque_Nm": float(np.max(np.abs(run["torque"]))),
        }
        print(
            f"{solver:7s} set-up {run['setup_s']:7.2f} s  assembly {run['assembly_s']:6.2f} s  "
            f"integration {solve:8.2f} s  ({1e3 * solve / steps:.2f} ms/step)",
            flush=True,
        )
    if "exudyn" in out:
        ours, theirs = out["ffrf"], out["exudyn"]
        report["coupler_difference_m"] = float(np.max(np.linalg.norm(ours["coupler"] - theirs["coupler"], axis=1)))
        report["torque_difference_rel"] = float(
            np.max(np.abs(ours["torque"] - theirs["torque"])) / np.max(np.abs(theirs["torque"]))
        )
        report["ratio_integration"] = report["exudyn"]["solve_s"] / report["ffrf"]["solve_s"]
        print(
            f"coupler difference {report['coupler_difference_m']:.2e} m, torque {report['torque_difference_rel']:.1e}"
            f" relative; Exudyn / ours, integration: {report['ratio_integration']:.1f}x",
            flush=True,
        )
    print(f"our factorisations of the iteration matrix: {counter['n']} for {steps} steps", flush=True)
    if args.json:
        write_report(report, args.json, echo=False)
    return report


if __name__ == "__main__":
    main()
