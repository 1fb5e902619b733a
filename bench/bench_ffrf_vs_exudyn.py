"""Benchmark: time per step of our FFRF solver and Exudyn on the flexible pendulum scene.

The scene is the one of ``tests/test_validation`` (``validation.single_body_scenes.pendulum_scene``):
PLA-like bar 0.2 x 0.02 x 0.01 m hinged at one end, released from horizontal, rho_inf = 0.8,
beta = 1e-3 s, HCB with 6 + ``--modes`` modes, area weights. Two mesh sizes with the same m;
the bore node count grows with the mesh, which is what Exudyn's marker cost depends on.

For ours (default Newton of ``ffrf.solvers.generalized_alpha``, and full Newton), "cold" is the
first run in a fresh interpreter (numba loads its on-disk cache or compiles, first calls of
scipy/LAPACK), "warm" the best of ``--repeat`` runs afterwards.
Exudyn is always warm (best of ``--repeat``). Both use full Newton; Exudyn is also timed with
its default modified Newton. Also printed: the largest tip difference between the solvers
and, with ``--convergence``, the tip difference at h, h/2, h/4 (both solvers) and the
self-convergence of each.

Usage::

    .venv/bin/python bench/bench_ffrf_vs_exudyn.py                     # meshes 8x2x2 and 24x4x4, 1 s at h = 1e-3
    .venv/bin/python bench/bench_ffrf_vs_exudyn.py --t-end 0.5 --repeat 2 --convergence
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

MESHES = {"coarse": (8, 2, 2), "fine": (24, 4, 4)}


def scene_for(mesh: str, modes: int, step: float, t_end: float):
    from validation.reduced_body import bar_body
    from validation.single_body_scenes import pendulum_scene

    body = bar_body(divisions=MESHES[mesh], n_modes=modes, weights="area")
    return pendulum_scene(body, step=step, t_end=t_end, beta=1e-3, rho_inf=0.8)


def cold_run(mesh: str, modes: int, step: float, t_end: float) -> dict:
    """Our solver's first run in a fresh interpreter (prints JSON on stdout)."""
    code = (
        f"import time; t = time.perf_counter(); import json, sys; sys.path.insert(0, {str(ROOT)!r});"
        f"from bench.bench_ffrf_vs_exudyn import scene_for;"
        f"from validation.exudyn_ffrf import run_ffrf;"
        f"s = scene_for({mesh!r}, {modes}, {step}, {t_end}); r = run_ffrf(s);"
        f"print(json.dumps({{'per_step': r.time_per_step, 'total': time.perf_counter() - t}}))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT)
    return json.loads(out.stdout.strip().splitlines()[-1])


def best_of(function, repeat: int):
    runs = [function() for _ in range(repeat)]
    return min(runs, key=lambda r: r.integration_time)


def bench_mesh(mesh: str, modes: int, step: float, t_end: float, repeat: int) -> dict:
    from validation.exudyn_ffrf import run_exudyn, run_ffrf

    cold = cold_run(mesh, modes, step, t_end)
    scene = scene_for(mesh, modes, step, t_end)
    ours = best_of(lambda: run_ffrf(scene), repeat)
    ours_full = best_of(lambda: run_ffrf(scene, modified_newton=False), repeat)
    full = best_of(lambda: run_exudyn(scene), repeat)
    modified = best_of(
        lambda: run_exudyn(scene, modified_newton=True, relative_tolerance=1e-10, absolute_tolerance=1e-12), repeat
    )
    return {
        "mesh": mesh,
        "nodes": len(scene.body.nodes),
        "bore nodes": len(scene.body.frame_nodes),
        "m": scene.body.n_modes,
        "steps": scene.n_steps,
        "ours cold ms/step": 1e3 * cold["per_step"],
        "ours cold total s (import, JIT/cache, setup, run)": cold["total"],
        "ours warm ms/step": 1e3 * ours.time_per_step,
        "ours warm total s (setup + run)": ours.setup_time + ours.integration_time,
        "ours it/step": ours.newton_iterations / scene.n_steps,
        "ours full Newton ms/step": 1e3 * ours_full.time_per_step,
        "ours full Newton it/step": ours_full.newton_iterations / scene.n_steps,
        "exudyn full ms/step": 1e3 * full.time_per_step,
        "exudyn full it/step": full.newton_iterations / scene.n_steps,
        "exudyn modified ms/step": 1e3 * modified.time_per_step,
        "ratio ours warm / exudyn full": ours.time_per_step / full.time_per_step,
        "ratio ours warm / exudyn modified": ours.time_per_step / modified.time_per_step,
        "max tip difference (m)": float(np.abs(ours.tracked - full.tracked).max()),
        "max tip difference vs modified Newton (m)": float(np.abs(ours.tracked - modified.tracked).max()),
        "exudyn version": full.version,
    }


def convergence(modes: int, step: float, t_end: float) -> None:
    """Tip difference ours vs Exudyn and self-convergence |x(h) - x(h/2)| at h, h/2, h/4 (coarse mesh)."""
    from validation.exudyn_ffrf import run_exudyn, run_ffrf

    runs = []
    for k in range(3):
        scene = scene_for("coarse", modes, step / 2**k, t_end)
        runs.append((scene.step, run_ffrf(scene), run_exudyn(scene)))
    print(f"\n{'h (s)':>10} {'|ours-exudyn| (m)':>18} {'|ours(h)-ours(h/2)|':>20} {'|ex(h)-ex(h/2)|':>16}")
    for k, (h, ours, theirs) in enumerate(runs):
        diff = np.abs(ours.tracked - theirs.tracked).max()
        if k + 1 < len(runs):
            _, ours_f, theirs_f = runs[k + 1]
            self_ours = np.abs(ours.tracked - ours_f.tracked[::2]).max()
            self_ex = np.abs(theirs.tracked - theirs_f.tracked[::2]).max()
            print(f"{h:10.3g} {diff:18.3e} {self_ours:20.3e} {self_ex:16.3e}")
        else:
            print(f"{h:10.3g} {diff:18.3e} {'':>20} {'':>16}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--modes", type=int, default=4, help="fixed-interface modes (m = 6 + modes)")
    parser.add_argument("--step", type=float, default=1e-3)
    parser.add_argument("--t-end", type=float, default=1.0)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--meshes", nargs="+", default=list(MESHES), choices=list(MESHES))
    parser.add_argument("--convergence", action="store_true", help="also print the h-refinement table")
    args = parser.parse_args()
    started = time.perf_counter()
    rows = [bench_mesh(mesh, args.modes, args.step, args.t_end, args.repeat) for mesh in args.meshes]
    for row in rows:
        print()
        for key, value in row.items():
            print(f"  {key:50s} {value:.4g}" if isinstance(value, float) else f"  {key:50s} {value}")
    if args.convergence:
        convergence(args.modes, args.step, args.t_end)
    print(f"\ntotal bench time {time.perf_counter() - started:.1f} s")


if __name__ == "__main__":
    main()
