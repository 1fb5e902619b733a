"""Bennett scene speed, reference Python path against the fast path (whole-system numba kernels,
:mod:`ffrf.system.packed_system`), in the same process, with the results compared.

For each path: generalized-alpha from the assembled state at rest (``--t-dynamic`` s, step
``--step``) in ms per step, and the quasi-static revolution (ramp plus one revolution,
``--outputs`` equilibria, as ``python -m ffrf bennett --quasi-static``) in s and Newton
iterations per pose; the fast path's quasi-static run is also timed without the predictor and
secant updates (``predictor_order=0, secant=False``: plain modified Newton from the previous
equilibrium, Eqs. (S2), (S3) of ``docs/formulation.md``) and with the quadratic predictor instead of the
default quartic one. Kernels are warm (numba cache);
``--cold`` also times the fast path's first calls in a fresh process with an empty numba cache
(compilation: residual, iteration matrix, one generalized-alpha step and one quasi-static pose).

BLAS threads: on a small shared machine OpenBLAS threads on ~100 x 100 matrices spin against
other processes (a 105 x 105 SVD took 0.5 s instead of 8 ms); this script pins BLAS to one
thread unless ``--blas-threads`` says otherwise.

Run: .venv/bin/python -m bench bennett_speed [--h 0.006 --modes 4] [--cold] [--skip-quasi-static] [--json FILE]
"""

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from bench.report import write_report


def _pin_blas(threads: int) -> None:
    for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(name, str(threads))


_COLD = """
import time, numpy as np
started = time.perf_counter()
from ffrf.paper.bennett_scene import build_bennett
from ffrf.system.packed_system import pack_system
scene = build_bennett("pla", h={h}, order={order}, n_modes={modes})
built = time.perf_counter()
packed = pack_system(scene.system)
q, z, lam = scene.q_start, np.zeros_like(scene.q_start), np.zeros(scene.system.n_constraints)
packed.residual(q, z, z, lam, 0.0)
packed.iteration_matrix(q, z, z, lam, 0.0, 1.0, 1e-6, 1e-3)
from ffrf.solvers.generalized_alpha import generalized_alpha
from ffrf.solvers.static_solver import quasi_static
generalized_alpha(scene.system, q, z, 2e-4, 1e-4)
quasi_static(scene.system, q, np.array([0.0, 0.1]))
print(time.perf_counter() - built)
"""


def cold_compile_seconds(h: float, order: int, modes: int) -> float:
    """First residual, iteration matrix, dynamic step and static pose in a fresh process with an
    empty numba cache."""
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache, PYTHONPATH=os.getcwd())
        out = subprocess.run(
            [sys.executable, "-c", _COLD.format(h=h, order=order, modes=modes)],
            env=env,
            check=True,
            capture_output=True,
            text=True,
        )
    return float(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--h", type=float, default=6e-3, help="tetrahedron size (m)")
    parser.add_argument("--order", type=int, choices=(1, 2), default=2, help="tetrahedron order")
    parser.add_argument("--modes", type=int, default=4, help="fixed-interface modes per link")
    parser.add_argument("--t-dynamic", type=float, default=0.3, help="dynamic run length (s)")
    parser.add_argument("--step", type=float, default=1e-3, help="generalized-alpha step (s)")
    parser.add_argument(
        "--outputs", type=int, default=361, help="quasi-static equilibria over the ramp and revolution (1 deg apart)"
    )
    parser.add_argument("--skip-quasi-static", action="store_true")
    parser.add_argument("--cold", action="store_true", help="also time numba compilation with an empty cache")
    parser.add_argument("--blas-threads", type=int, default=1)
    parser.add_argument("--json", type=Path, help="also write the figures here (SI units)")
    args = parser.parse_args()
    _pin_blas(args.blas_threads)

    import numpy as np

    from ffrf.paper.bennett_scene import assemble, build_bennett
    from ffrf.solvers.generalized_alpha import generalized_alpha
    from ffrf.solvers.static_solver import quasi_static
    from ffrf.system.packed_system import pack_system

    started = time.perf_counter()
    scene = build_bennett("pla", h=args.h, order=args.order, n_modes=args.modes)
    built = time.perf_counter()
    system = scene.system
    q0 = assemble(scene).q
    report = {
        "h_m": args.h,
        "order": args.order,
        "modes": args.modes,
        "n_coordinates": system.n_coordinates,
        "build_s": built - started,
        "assembly_s": time.perf_counter() - built,
    }
    print(
        f"PLA Bennett, h = {1e3 * args.h:g} mm, {args.modes} modes per link: {system.n_coordinates} coordinates, "
        f"{system.n_constraints} constraints; fast path supported: {pack_system(system) is not None}"
    )
    for fast in (False, True):  # load (or compile) both paths' kernels before timing
        generalized_alpha(system, q0, np.zeros_like(q0), 2 * args.step, args.step, fast_path=fast)
        quasi_static(system, q0, np.array([0.0, 1.0]), fast_path=fast)

    runs = {}
    for fast in (False, True):
        result = generalized_alpha(system, q0, np.zeros_like(q0), args.t_dynamic, args.step, fast_path=fast)
        runs[fast] = result
    steps = len(runs[True].newton_iterations)
    print(f"dynamic {args.t_dynamic:g} s, step {1e3 * args.step:g} ms ({steps} steps):")
    for fast in (False, True):
        r = runs[fast]
        print(
            f"  {'fast     ' if fast else 'reference'}  {1e3 * r.wall_time / steps:8.3f} ms/step  "
            f"{r.newton_iterations.mean():.2f} iterations/step"
        )
    report["dynamic"] = {
        "t_end_s": args.t_dynamic,
        "step_s": args.step,
        "steps": steps,
        **{
            name: {
                "per_step_s": runs[fast].wall_time / steps,
                "iterations_per_step": runs[fast].newton_iterations.mean(),
            }
            for name, fast in (("reference", False), ("fast", True))
        },
        "speed_up": runs[False].wall_time / runs[True].wall_time,
    }
    lam_ref = runs[False].multipliers
    print(
        f"  speed-up {runs[False].wall_time / runs[True].wall_time:.1f}x; max |q_fast - q_ref| = "
        f"{np.abs(runs[True].q - runs[False].q).max():.1e}, max |lambda| difference relative "
        f"{np.abs(runs[True].multipliers - lam_ref).max() / np.abs(lam_ref).max():.1e}"
    )

    if not args.skip_quasi_static:
        times = np.linspace(0.0, scene.t_end, args.outputs)
        variants: dict[str, dict[str, Any]] = {
            "reference": dict(fast_path=False),
            "fast, plain modified Newton": dict(predictor_order=0, secant=False),
            "fast, quadratic predictor": dict(predictor_order=2),
            "fast": dict(),
        }
        solutions, seconds = {}, {}
        for label, options in variants.items():
            started = time.perf_counter()
            solutions[label] = quasi_static(system, q0, times, **options)
            seconds[label] = time.perf_counter() - started
        print(f"quasi-static revolution ({scene.t_end:.1f} s of drive, {args.outputs} equilibria):")
        for label in variants:
            iterations = solutions[label].iterations
            print(
                f"  {label:28s} {seconds[label]:8.2f} s  {sum(iterations)} Newton iterations "
                f"({np.mean(iterations):.2f} per pose)"
            )
        report["quasi_static"] = {
            "equilibria": args.outputs,
            **{
                label.replace(", ", "_").replace(" ", "_"): {
                    "wall_s": seconds[label],
                    "iterations_per_pose": float(np.mean(solutions[label].iterations)),
                }
                for label in variants
            },
            "speed_up": seconds["reference"] / seconds["fast"],
        }
        ref, fastest = solutions["reference"], solutions["fast"]
        torque_difference = np.abs(fastest.multipliers[:, -1] - ref.multipliers[:, -1]).max()
        print(
            f"  speed-up {seconds['reference'] / seconds['fast']:.1f}x; max |q_fast - q_ref| = "
            f"{np.abs(fastest.q - ref.q).max():.1e}, driving torque relative "
            f"{torque_difference / np.abs(ref.multipliers[:, -1]).max():.1e}"
        )
    if args.cold:
        report["cold_compile_s"] = cold_compile_seconds(args.h, args.order, args.modes)
        print(f"numba cold compile (first residual + iteration matrix, empty cache): {report['cold_compile_s']:.1f} s")
    if args.json:
        write_report(report, args.json, echo=False)


if __name__ == "__main__":
    main()
