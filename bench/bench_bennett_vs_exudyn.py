"""Benchmark and comparison: our FFRF solver against the Exudyn twin of the flexible Bennett scene.

Builds ``build_bennett(variant, h, order=1, n_modes=modes, exact_gravity=False)``, runs Exudyn's twin
(``validation.exudyn_bennett``) and our generalized-alpha on three systems from ``scene.q_start``
over ``--t-end`` with ``--step``:

* ``exudyn``: ``scene.system`` with Exudyn's marker rotation Jacobian (should agree to round-off),
* ``production``: ``scene.system`` (body-frame joint offsets as Exudyn, our exact Jacobian;
  the issue's targets apply),
* ``marker``: the same scene with joint offsets in the marker frame (``joint_offsets="marker"``).

and the static equilibrium at t = 0 (Exudyn ``SolveStatic`` vs ours). Prints timings (scene
build, Exudyn set-up, integration of each) and the largest differences of the coupler point,
tracked nodes, modal coordinates and driving torque; ``--json FILE`` writes them.

Usage::

    .venv/bin/python bench/bench_bennett_vs_exudyn.py                           # coarse: h = 6 mm, 2 modes, 0.2 s
    .venv/bin/python bench/bench_bennett_vs_exudyn.py --h 4e-3 --modes 8 --t-end 0.1   # default discretisation
    .venv/bin/python bench/bench_bennett_vs_exudyn.py --start assembled --t-end 1.0    # from each solver's assembly
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--variant", default="pla")
    parser.add_argument("--h", type=float, default=6e-3, help="mesh size (m)")
    parser.add_argument("--modes", type=int, default=2, help="fixed-interface modes per link")
    parser.add_argument("--t-end", type=float, default=0.2)
    parser.add_argument("--step", type=float, default=1e-3)
    parser.add_argument("--rho-inf", type=float, default=0.9)
    parser.add_argument("--exudyn-tolerance", type=float, default=1e-14)
    parser.add_argument("--systems", default="exudyn,production,marker")
    parser.add_argument("--no-static", action="store_true")
    parser.add_argument(
        "--start",
        choices=("q_start", "assembled"),
        default="q_start",
        help="q_start: undeformed links at rest (gravity excites them); assembled: each solver "
        "starts from its own static equilibrium of its system (Exudyn: SolveStatic)",
    )
    parser.add_argument("--json", type=Path)
    args = parser.parse_args(argv)

    import exudyn

    from ffrf.paper.bennett_scene import build_bennett
    from validation.bennett_trajectory import compare, run_ffrf_bennett, static_ffrf_bennett
    from validation.exudyn_bennett import run_exudyn_bennett, static_exudyn_bennett
    from validation.exudyn_conventions import exudyn_convention_system

    started = time.perf_counter()
    scene = build_bennett(args.variant, h=args.h, order=1, n_modes=args.modes, exact_gravity=False)
    build = time.perf_counter() - started
    out = {
        "variant": args.variant,
        "h": args.h,
        "modes": args.modes,
        "t_end": args.t_end,
        "step": args.step,
        "rho_inf": args.rho_inf,
        "exudyn": exudyn.__version__,
        "build_s": build,
        "modes_per_link": [link.reduction.n_modes for link in scene.links],
        "nodes_per_link": [int(link.fe.nodes.shape[0]) for link in scene.links],
        "n_coordinates": scene.system.n_coordinates,
        "n_constraints": scene.system.n_constraints,
    }
    print(
        f"scene {args.variant}: h = {args.h}, modes {out['modes_per_link']}, nodes {out['nodes_per_link']}, "
        f"built in {build:.1f} s",
        flush=True,
    )
    marker_scene = build_bennett(
        args.variant, h=args.h, order=1, n_modes=args.modes, exact_gravity=False, joint_offsets="marker"
    )
    systems = {
        "production": scene.system,
        "marker": marker_scene.system,
        "exudyn": exudyn_convention_system(scene.system, exudyn_jacobian=True),
    }
    starts = {name: scene.q_start for name in systems}
    start_exudyn = scene.q_start
    if args.start == "assembled":
        start_exudyn = static_exudyn_bennett(scene, scene.q_start, 0.0, tolerance=1e-12)[0]
        starts = {name: static_ffrf_bennett(scene, system, scene.q_start)[0] for name, system in systems.items()}
    out["start"] = args.start
    theirs = run_exudyn_bennett(
        scene, start_exudyn, args.t_end, args.step, args.rho_inf, tolerance=args.exudyn_tolerance
    )
    steps = len(theirs.time) - 1
    out["exudyn_run"] = {
        "setup_s": theirs.setup_time,
        "integration_s": theirs.integration_time,
        "ms_per_step": 1e3 * theirs.integration_time / steps,
        "newton_iterations": theirs.newton_iterations,
        "solver": theirs.solver,
    }
    print(
        f"{theirs.solver}: set-up {theirs.setup_time:.2f} s, {steps} steps in {theirs.integration_time:.2f} s "
        f"({out['exudyn_run']['ms_per_step']:.2f} ms/step, {theirs.newton_iterations} Newton iterations)",
        flush=True,
    )
    for name in args.systems.split(","):
        ours = run_ffrf_bennett(scene, systems[name], starts[name], args.t_end, args.step, args.rho_inf, label=name)
        d = compare(ours, theirs)
        out[name] = dict(
            d,
            integration_s=ours.integration_time,
            ms_per_step=1e3 * ours.integration_time / steps,
            newton_iterations=ours.newton_iterations,
        )
        print(
            f"ffrf [{name}]: {ours.integration_time:.2f} s ({out[name]['ms_per_step']:.2f} ms/step, "
            f"{ours.newton_iterations} it); coupler {d['coupler_m']:.3e} m ({d['coupler_relative_to_motion']:.2e} of "
            f"its motion {d['coupler_motion_m']:.3e} m), tracked {d['tracked_m']:.3e} m, zeta {d['zeta']:.3e} "
            f"({d['zeta_relative']:.2e}), torque {d['torque_Nm']:.3e} N m ({d['torque_relative']:.2e} of "
            f"{d['torque_scale_Nm']:.3e})",
            flush=True,
        )
    if not args.no_static:
        started = time.perf_counter()
        q_e, torque_e, coupler_e, tracked_e, _ = static_exudyn_bennett(scene, scene.q_start, 0.0)
        out["static_exudyn_s"] = time.perf_counter() - started
        out["static"] = {}
        for name in args.systems.split(","):
            q_o, torque_o, coupler_o, tracked_o = static_ffrf_bennett(scene, systems[name], scene.q_start)
            s = {
                "q": float(np.abs(q_o - q_e).max()),
                "torque_relative": abs(torque_o - torque_e) / abs(torque_e),
                "coupler_m": float(np.abs(coupler_o - coupler_e).max()),
                "tracked_m": float(np.abs(tracked_o - tracked_e).max()),
                "torque_Nm": torque_e,
            }
            out["static"][name] = s
            print(
                f"static [{name}]: q {s['q']:.3e}, coupler {s['coupler_m']:.3e} m, tracked {s['tracked_m']:.3e} m, "
                f"torque {s['torque_relative']:.2e} relative (Exudyn {torque_e:.6e} N m, sign flipped)",
                flush=True,
            )
    if args.json:
        args.json.write_text(json.dumps(out, indent=2, default=float))
    return out


if __name__ == "__main__":
    main()
