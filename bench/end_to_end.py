"""End to end from a cold start, ours against Exudyn (issue #38): the default PLA Bennett, set-up included.

    .venv/bin/python -m bench record end_to_end                      # docs/results/end_to_end.json
    .venv/bin/python -m bench end_to_end --json out/e2e.json [--no-dynamic]

Our kernels are compiled first (numba's cache; their compilation is ``bench/compile_times.py``'s), the scene cache is
empty (a fresh ``FFRF_CACHE_DIR``), and each solver's run counts its set-up: ours meshes the links, assembles M and
K, reduces them and builds the scene; Exudyn reduces our matrices and builds its twin (the mesh and matrices it
borrows from us are not counted: its totals are lower bounds). Two runs of the default discretisation (P2, 6 mm, 4
modes): the quasi-static ramp and revolution at 361 drive angles, and the dynamic ramp and revolution
(generalized-alpha at the default step, 10 ms, rho_inf 0.9), each solver from its own static assembly; both paths
compared. The set-up is built once per solver and counted in both runs' totals. BLAS pinned to one thread.
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path

for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")

import numpy as np  # noqa: E402 - after the thread counts above, which BLAS reads when numpy loads

from bench.report import write_report  # noqa: E402

#: The default discretisation (``build_bennett``'s) and dynamic step (``ffrf.scenes.assembly.dynamic_step``).
ORDER, H, MODES, STEP, RHO_INF = 2, 6e-3, 4, 0.01, 0.9
QUASI_STATIC_POSES = 361


def _row(run: dict, setup_s: float) -> dict:
    return {"setup_s": setup_s, "run_s": run["integration_s"], "total_s": setup_s + run["integration_s"]}


def _compare(out: dict, setup: dict) -> dict:
    ours, theirs = out["ffrf"], out["exudyn"]
    rows = {"ours": _row(ours, setup["ours"]), "exudyn": _row(theirs, setup["exudyn"])}
    scale = float(np.max(np.abs(theirs["torque"])))
    return rows | {
        "ratio_total": rows["exudyn"]["total_s"] / rows["ours"]["total_s"],
        "ratio_run": rows["exudyn"]["run_s"] / rows["ours"]["run_s"],
        "coupler_difference_m": float(np.max(np.linalg.norm(ours["coupler"] - theirs["coupler"], axis=1))),
        "torque_difference_rel": float(np.max(np.abs(ours["torque"] - theirs["torque"]))) / scale,
    }


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path)
    parser.add_argument("--no-dynamic", action="store_true", help="the quasi-static revolution only")
    args = parser.parse_args(argv)

    from bench.speed_vs_error import run_dynamic, run_quasi_static
    from ffrf.paper.bennett_scene import build_bennett
    from validation.twin_clock import compiled_kernels

    kernels_s = compiled_kernels(None)
    report: dict = {"order": ORDER, "h": H, "modes": MODES, "kernels_before_s": kernels_s}
    with tempfile.TemporaryDirectory() as cache:
        os.environ["FFRF_CACHE_DIR"] = cache  # the scene cache empty: the first set-up is a cold one
        t_end = build_bennett("pla", h=2 * H, order=1, n_modes=2).t_end  # the default ramp and revolution
        times = np.linspace(0.0, t_end, QUASI_STATIC_POSES)
        scenes: dict = {}  # built once, counted in both runs
        quasi_static = run_quasi_static(ORDER, H, MODES, times, True, scenes)
        (setup_ours,) = (setup for _, setup in scenes.values())
        setup = {"ours": setup_ours, "exudyn": quasi_static["exudyn"]["setup_s"]}
        report["quasi_static"] = {"poses": QUASI_STATIC_POSES, **_compare(quasi_static, setup)}
        print(f"quasi-static, set-up included: Exudyn / ours {report['quasi_static']['ratio_total']:.1f}x", flush=True)
        if not args.no_dynamic:
            dynamic = run_dynamic(ORDER, H, MODES, STEP, RHO_INF, t_end, True, scenes)
            setup["exudyn"] = dynamic["exudyn"]["setup_s"]
            steps = len(dynamic["ffrf"]["time"]) - 1
            report["dynamic"] = {"step_s": STEP, "steps": steps, **_compare(dynamic, setup)}
            print(f"dynamic, set-up included: Exudyn / ours {report['dynamic']['ratio_total']:.1f}x", flush=True)
    if args.json:
        write_report(report, args.json, echo=False)
    return report


if __name__ == "__main__":
    main()
