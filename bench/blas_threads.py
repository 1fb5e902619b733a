"""BLAS threads for our dense linear algebra (issue #22): the default Bennett scene's quasi-static revolution and a
5 s dynamic window (4 ms steps) with 1 and with 2 OpenBLAS threads, in one process (threadpoolctl), warm kernels,
best of ``--repeat``; then again with ``--busy`` processes spinning beside it (another program using the cores).
Our dense matrices are small (the default scene has 74 coordinates): a second BLAS thread changes little when the
machine is quiet and costs when it is busy. ``python -m ffrf`` uses ``--blas-threads``
(default 1).

Usage::

    .venv/bin/python -m bench blas_threads --json out/blas_threads.json
"""

from __future__ import annotations

import argparse
import multiprocessing
import time
import warnings
from pathlib import Path

from threadpoolctl import threadpool_limits

from bench.report import write_report
from ffrf.paper.bennett_scene import build_bennett
from ffrf.scenes.linkage_run import run_linkage


def best_times(scene, repeat: int) -> dict[str, float]:
    """Best wall times (s) of a quasi-static revolution (241 outputs) and of 5 s of dynamic run at 4 ms steps."""
    quasi_static, dynamic = [], []
    for _ in range(repeat):
        started = time.perf_counter()
        run_linkage(scene, "quasi_static", 241)
        quasi_static.append(time.perf_counter() - started)
        started = time.perf_counter()
        run_linkage(scene, "dynamic", 101, t_end=5.0, step=4e-3)
        dynamic.append(time.perf_counter() - started)
    return {"quasi_static_revolution_s": min(quasi_static), "dynamic_5s_s": min(dynamic)}


def _spin() -> None:
    while True:  # a busy neighbour: another program using a core
        pass


def measure(repeat: int) -> dict:
    """Best times with 1 and 2 BLAS threads, alternated so that a change of the machine's load touches both."""
    scene = build_bennett("pla")
    run_linkage(scene, "quasi_static", 5, t_end=0.5)  # compile and warm the kernels outside the timings
    run_linkage(scene, "dynamic", 5, t_end=0.05, step=4e-3)
    rows: dict[str, dict[str, float]] = {}
    for threads in (1, 2, 1, 2):
        with threadpool_limits(limits=threads, user_api="blas"):
            times = best_times(scene, repeat)
        row = rows.setdefault(f"threads_{threads}", times)
        rows[f"threads_{threads}"] = {key: min(row[key], value) for key, value in times.items()}
    rows["two_over_one"] = {  # ratios: the keys lose their unit suffix
        key.removesuffix("_s"): rows["threads_2"][key] / rows["threads_1"][key] for key in rows["threads_1"]
    }
    return rows


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--busy", type=int, default=2, help="busy neighbour processes for the second measurement")
    parser.add_argument("--json", type=Path, required=True)
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    report: dict = {"scene": "default PLA Bennett (6 mm P2, 4 modes per link)", "quiet": measure(args.repeat)}
    neighbours = [multiprocessing.Process(target=_spin, daemon=True) for _ in range(args.busy)]
    for process in neighbours:
        process.start()
    try:
        report[f"busy_{args.busy}"] = measure(1)
    finally:
        for process in neighbours:
            process.terminate()
    write_report(report, args.json)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
