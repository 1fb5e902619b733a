"""Speed against error for the Bennett PLA scene, ours and Exudyn's on the same points (issue 9).

For each point of a sweep over element order, mesh edge length and fixed-interface modes, both
solvers build (ours: mesh, M, K, Craig-Bampton; Exudyn: its Craig-Bampton on our matrices) and
run the paper's 1 rpm revolution quasi-statically (ours: static assembly + equilibria; Exudyn:
its static assembly + one SolveStatic sweep), at ``--outputs`` drive angles. Recorded per
point and solver: set-up and solution wall time, peak traced memory (``tracemalloc``: numpy and
Python allocations of this process during the point), and the errors against a converged
reference: the largest distance of the coupler point from the reference's at the same drive
angle (m) and the largest driving-torque difference relative to the reference's maximum.
Exudyn's set-up excludes the mesh and the M and K it borrows from us, so its totals are lower
bounds.

Reference (``--reference``, default ``2,0.004,32``): quadratic tetrahedra at 4 mm with 32
modes per link. Why converged: P2 at 4 mm is within 0.5 % of beam theory in frequency where P1
needs 1 mm (``bench/bench_fe_beam_convergence.py``), and the modes are refined until the
coupler changes by less than the finest sweep point's error (printed as ``modes check``).

Output: ``DIR/results.json`` (a list of points: ``solver``, ``order``, ``h``, ``modes``,
``mode``, ``setup_s``, ``integration_s``, ``peak_mem_mb``, ``coupler_error_m``,
``torque_error_rel``), ``DIR/pareto.png`` (error against time, both solvers) and
``DIR/cheapest.md``: the cheapest setting reaching 1 mm, 0.1 mm, 0.01 mm and 1 um of coupler
accuracy, our time, Exudyn's and their ratio.

Usage::

    .venv/bin/python bench/speed_vs_error.py --out out/speed_vs_error                  # full sweep (long)
    .venv/bin/python bench/speed_vs_error.py --points 1,0.006,2 1,0.004,8 --out /tmp/sve   # a few points
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

DEFAULT_POINTS = [f"1,{h},{m}" for h in (0.006, 0.004, 0.003) for m in (2, 4, 8, 16)] + \
                 [f"2,{h},{m}" for h in (0.006, 0.004) for m in (4, 8, 16)]
THRESHOLDS_M = (1e-3, 1e-4, 1e-5, 1e-6)


def _parse(point: str) -> tuple[int, float, int]:
    order, h, modes = point.split(",")
    return int(order), float(h), int(modes)


def run_point(order: int, h: float, modes: int, outputs: int, exudyn: bool) -> dict:
    """Both solvers on one discretisation: coupler rows, torques, times, memory."""
    from ffrf.bennett_run import run_bennett
    from ffrf.bennett_scene import build_bennett

    out = {}
    tracemalloc.start()
    started = time.perf_counter()
    scene = build_bennett("pla", h=h, order=order, n_modes=modes)
    setup = time.perf_counter() - started
    result = run_bennett(scene, mode="quasi_static", n_outputs=outputs)
    timings = result.metadata["timings_s"]
    peak = tracemalloc.get_traced_memory()[1] / 2**20
    tracemalloc.stop()
    out["ffrf"] = {"setup_s": setup, "integration_s": timings["assembly"] + timings["solve"], "peak_mem_mb": peak,
                   "coupler": result.sensors["coupler_point"], "torque": result.sensors["driving_torque"]}
    if exudyn:
        from validation.exudyn_bennett import assemble_exudyn_bennett, bennett_bodies, quasi_static_exudyn_bennett
        from validation.exudyn_twin import twin_bases

        tracemalloc.start()
        started = time.perf_counter()
        bases = twin_bases(bennett_bodies(scene))
        setup = time.perf_counter() - started
        started = time.perf_counter()
        start = assemble_exudyn_bennett(scene, bases)
        trajectory = quasi_static_exudyn_bennett(scene, start, result.time, bases=bases)
        solve = time.perf_counter() - started
        peak = tracemalloc.get_traced_memory()[1] / 2**20
        tracemalloc.stop()
        out["exudyn"] = {"setup_s": setup, "integration_s": solve, "peak_mem_mb": peak,
                         "coupler": trajectory.coupler, "torque": trajectory.torque}
    return out


def _errors(run: dict, reference: dict) -> tuple[float, float]:
    coupler = float(np.linalg.norm(run["coupler"] - reference["coupler"], axis=1).max())
    torque = float(np.abs(run["torque"] - reference["torque"]).max() / np.abs(reference["torque"]).max())
    return coupler, torque


def cheapest_table(points: list[dict]) -> str:
    """Markdown: for each accuracy threshold the cheapest point of each solver that reaches it."""
    lines = ["| coupler accuracy | ours: setting, time (s) | Exudyn: setting, time (s) | Exudyn / ours |", "|---|---|---|---|"]
    for threshold in THRESHOLDS_M:
        cells, times = [], {}
        for solver in ("ffrf", "exudyn"):
            ok = [p for p in points if p["solver"] == solver and p["coupler_error_m"] <= threshold]
            if not ok:
                cells.append("not reached")
                continue
            best = min(ok, key=lambda p: p["setup_s"] + p["integration_s"])
            times[solver] = best["setup_s"] + best["integration_s"]
            cells.append(f"P{best['order']}, {1e3 * best['h']:g} mm, {best['modes']} modes, {times[solver]:.2f}")
        ratio = f"{times['exudyn'] / times['ffrf']:.1f}" if len(times) == 2 else ""
        lines.append(f"| {1e3 * threshold:g} mm | {cells[0]} | {cells[1]} | {ratio} |")
    return "\n".join(lines)


def pareto_figure(points: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    for solver, style in (("ffrf", dict(color="tab:blue", marker="o", label="ours")),
                          ("exudyn", dict(color="tab:red", marker="s", label="Exudyn"))):
        chosen = [p for p in points if p["solver"] == solver]
        if chosen:
            ax.loglog([p["setup_s"] + p["integration_s"] for p in chosen], [p["coupler_error_m"] for p in chosen],
                      ls="none", **style)
    ax.set_xlabel("wall time: set-up + quasi-static revolution (s)")
    ax.set_ylabel("coupler error against the reference (m)")
    ax.grid(alpha=0.3, which="both")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None) -> list[dict]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", nargs="+", default=DEFAULT_POINTS, help="order,h,modes triples")
    parser.add_argument("--reference", default="2,0.004,32")
    parser.add_argument("--outputs", type=int, default=121, help="drive angles over ramp + revolution")
    parser.add_argument("--no-exudyn", action="store_true")
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)

    order, h, modes = _parse(args.reference)
    print(f"reference: P{order}, h = {h} m, {modes} modes", flush=True)
    reference = run_point(order, h, modes, args.outputs, exudyn=False)["ffrf"]
    check = run_point(order, h, modes // 2, args.outputs, exudyn=False)["ffrf"]
    print(f"modes check: {modes // 2} vs {modes} modes differ by {_errors(check, reference)[0]:.3e} m", flush=True)
    points = []
    for spec in args.points:
        order, h, modes = _parse(spec)
        runs = run_point(order, h, modes, args.outputs, exudyn=not args.no_exudyn)
        for solver, run in runs.items():
            coupler, torque = _errors(run, reference)
            points.append({"solver": solver, "order": order, "h": h, "modes": modes, "mode": "quasi_static",
                           "setup_s": run["setup_s"], "integration_s": run["integration_s"],
                           "peak_mem_mb": run["peak_mem_mb"], "coupler_error_m": coupler, "torque_error_rel": torque})
            print(f"{solver:7s} P{order} h={1e3 * h:g} mm {modes:2d} modes: set-up {run['setup_s']:6.2f} s, "
                  f"run {run['integration_s']:6.2f} s, {run['peak_mem_mb']:7.1f} MiB, coupler {coupler:.3e} m, "
                  f"torque {torque:.2e}", flush=True)
        (args.out / "results.json").write_text(json.dumps(points, indent=2))  # partial results survive
    pareto_figure(points, args.out / "pareto.png")
    (args.out / "cheapest.md").write_text(cheapest_table(points) + "\n")
    print(cheapest_table(points))
    return points


if __name__ == "__main__":
    main()
