"""Speed of a tolerance study (issues #19 and #22): the paper's PLA Bennett with its base's joint-3 bore twisted
(normal, std 0.5 deg) and shifted (normal, std 0.1 mm) as misfits on the nominal meshes, quasi-static, 121 outputs,
the default discretisation (P2, 6 mm, 4 modes).

* In one process: the first variant (scene cache empty; numba's kernels from its disk cache, ``python -m ffrf
  warmup``), then warm variants (:func:`ffrf.studies.variant.run_variant`, median and least) with their parts:
  ``build`` (the scene, from the cache), ``assembly`` (static assembly and its stresses), ``path`` (the
  quasi-static equilibria) and ``outputs`` (the row's sensors and values); ``revolution`` = assembly + path.
* Through the Dask runner (:func:`ffrf.studies.runner.run_study` on the runner's own local cluster,
  ``ffrf.studies.runner._client``) with 1, 2, 4 and 8 worker processes: the cluster's start, each worker's first
  variant (run on every worker with ``Client.run`` before timing, so that every worker has its cache), then the
  wall time of a study of ``--variants`` variants over their number (``per_variant_s``) and the median of the rows'
  own ``wall_time_s``, with the cores the study's processes used and those the machine's other processes used
  meanwhile (``/proc/stat``). The machine is shared: each timed part starts once other processes use less than
  0.2 cores (waiting up to 4 min), and a Dask study during which they used more is run again (``--attempts``),
  the quietest run kept. Efficiency ``t1 / (k t_k)``. The machine has 2 cores: 4 and 8 workers oversubscribe them,
  so their figures show the runner's overhead and the cost of sharing cores, not a speed-up.
* ``nanny_environment``: why a Dask worker was 2.5 times slower than one process: one worker of a default
  ``LocalCluster``, whose nanny starts it with ``MALLOC_TRIM_THRESHOLD_=65536``, running ``run_variant``, against
  one of the runner's cluster (started without it; its task sets glibc's thresholds where a worker has it): wall
  time, system time and minor page faults per variant, on the worker.
* The projection of 10^4 variants on 2 workers: start + first variant + 10^4 per-variant times, against 30 min.
* ``outputs``: the row's three path values of two variants at 121, 123, 241, 481 and 961 outputs, against 1921
  (the maxima are taken over the outputs, so they depend on how densely the path is sampled), with the run's time;
  121 outputs are 0.508 s apart, beyond the 3 deg cap of a quasi-static step (0.5 s at 1 rpm), so each interval
  takes two equilibria; 123 outputs (0.5 s apart) take one: ``in_process_123_outputs`` times them and counts the
  variants whose path then stops.

Usage::

    OPENBLAS_NUM_THREADS=1 .venv/bin/python -m bench study_speed --json out/study_speed.json
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

from bench.report import write_report
from ffrf.errors import StaticDivergence
from ffrf.paper.bennett_scene import STUDY_BASES
from ffrf.scenes.linkage_run import run_linkage
from ffrf.scenes.scene_cache import PROCESS_CACHE
from ffrf.studies.runner import _client, _worker_variant, read_rows, run_study
from ffrf.studies.sampling import study_design
from ffrf.studies.spec import Study, study_from_document
from ffrf.studies.variant import build_variant, run_variant

TARGET_S = 1800.0  # issue #19: 10^4 variants in under 30 minutes on 2 cores
REVOLUTION_TARGET_S = 0.25  # issue #19: assembly + the quasi-static revolution, warm, one core
VARIANTS = 10_000
#: Other processes below this many cores leave the machine quiet enough to time on (it is shared).
QUIET_CORES = 0.2
#: Longest wait for a quiet machine before each timed part (s).
WAIT_S = 240.0


def bennett_study(samples: int, seed: int, outputs: int = 121) -> Study:
    """The study of the module docstring with ``samples`` Monte-Carlo variants."""
    return study_from_document(
        {
            "study": {"name": "bore errors", "method": "monte_carlo", "samples": samples, "seed": seed},
            "base": {"bennett": "pla", "mode": "quasi_static", "outputs": outputs, "bore_error_model": "misfit"},
            "parameters": [
                {
                    "name": "twist_deg",
                    "target": "bore_twist_deg",
                    "joint": 3,
                    "link": 0,
                    "normal": {"mean": 0.0, "std": 0.5},
                },
                {
                    "name": "offset_mm",
                    "target": "bore_offset_mm",
                    "joint": 3,
                    "link": 0,
                    "normal": {"mean": 0.0, "std": 0.1},
                },
            ],
        },
        bases=STUDY_BASES,
    )


def in_process(warm: int, outputs: int) -> dict[str, Any]:
    """The first variant (the scene cache empty when this runs first) and ``warm`` more in this process, and the
    parts of ``warm`` more, at ``outputs`` outputs; a variant whose path stops is counted (``failed``) and left out
    of the parts."""
    study = bennett_study(2 * warm + 1, seed=1, outputs=outputs)
    design = study_design(study)
    started = time.perf_counter()
    first = run_variant(study, design[0])
    cold = time.perf_counter() - started
    totals, failed = [], [] if first["status"] == "ok" else [first["reason"]]
    for variant in design[1 : warm + 1]:
        started = time.perf_counter()
        row = run_variant(study, variant)
        totals.append(time.perf_counter() - started)
        if row["status"] != "ok":
            failed.append(row["reason"])
    parts: dict[str, list[float]] = {"build": [], "assembly": [], "path": [], "outputs": [], "revolution": []}
    for variant in design[warm + 1 :]:
        started = time.perf_counter()
        scene, run = build_variant(study, variant.values)
        built = time.perf_counter()
        try:
            result = run_linkage(scene, mode=run["mode"], n_outputs=run["outputs"], sensors="path")
        except StaticDivergence as error:
            failed.append(str(error))
            continue
        result.summary()
        done = time.perf_counter()
        timings = result.metadata["timings_s"]
        parts["build"].append(built - started)
        parts["assembly"].append(timings["assembly"])
        parts["path"].append(timings["solve"])
        parts["outputs"].append(done - built - timings["assembly"] - timings["solve"])
        parts["revolution"].append(timings["assembly"] + timings["solve"])
    return {
        "outputs": outputs,
        "first_variant_s": cold,
        "warm_variant_s": statistics.median(totals),
        "warm_variant_min_s": min(totals),
        "variants": len(design),
        "failed": len(failed),
        "first_failure": failed[0] if failed else None,
        "parts_median_s": {name: statistics.median(values) for name, values in parts.items()},
        "parts_min_s": {name: min(values) for name, values in parts.items()},
        "revolution_target_s": REVOLUTION_TARGET_S,
        "cache": PROCESS_CACHE.stats(),
    }


def _first_variant(study: Study) -> float:
    """A worker's first variant (its cache empty), timed on the worker."""
    started = time.perf_counter()
    _worker_variant(study, study_design(study)[0])
    return time.perf_counter() - started


def _cache_stats() -> dict:
    """The scene cache's counts of the process this runs in (imported here: a function of this script is sent to
    the workers by value, with the globals it names)."""
    from ffrf.scenes.scene_cache import PROCESS_CACHE as worker_cache

    return worker_cache.stats()


def _cpu_seconds() -> float:
    """This process's CPU time (user + system, s)."""
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def _machine_busy_seconds() -> float:
    """CPU time all processes of the machine have spent so far (``/proc/stat``: user, nice, system, irq, softirq,
    steal; s)."""
    ticks = [int(x) for x in Path("/proc/stat").read_text().splitlines()[0].split()[1:9]]
    return (sum(ticks) - ticks[3] - ticks[4]) / os.sysconf("SC_CLK_TCK")


def wait_for_quiet(limit_s: float) -> float:
    """Wait until the machine's processes use less than :data:`QUIET_CORES` cores over 5 s (this process and its
    idle workers included), at most ``limit_s``; the cores they used in the last 5 s."""
    deadline = time.monotonic() + limit_s
    while True:
        busy = _machine_busy_seconds()
        time.sleep(5.0)
        cores = (_machine_busy_seconds() - busy) / 5.0
        if cores < QUIET_CORES or time.monotonic() > deadline:
            return cores
        time.sleep(10.0)


def through_dask(workers: int, variants: int, folder: Path, attempts: int) -> dict[str, Any]:
    """The runner's local cluster of ``workers`` processes: start, first variants, then a study of ``variants``
    variants, run again (up to ``attempts`` times, each after :func:`wait_for_quiet`) while other processes took
    more than :data:`QUIET_CORES` cores during it; the run with the least such load is kept."""
    started = time.perf_counter()
    client, cluster = _client(None, workers)
    start = time.perf_counter() - started
    kept: dict[str, Any] = {}
    try:
        first = client.run(_first_variant, bennett_study(1, seed=99))
        study = bennett_study(variants, seed=1001)  # the same design for every number of workers
        for attempt in range(1, attempts + 1):
            wait_for_quiet(WAIT_S)
            ours = _cpu_seconds() + sum(client.run(_cpu_seconds).values())
            busy = _machine_busy_seconds()
            run = run_study(study, folder / f"workers{workers}-{attempt}", client=client, progress=False)
            busy = _machine_busy_seconds() - busy
            ours = _cpu_seconds() + sum(client.run(_cpu_seconds).values()) - ours
            table = read_rows(folder / f"workers{workers}-{attempt}")
            if table is None:
                raise RuntimeError(f"the study in {folder} wrote no rows")
            rows = table.to_pylist()
            other = (busy - ours) / run.wall_time_s
            if not kept or other < kept["other_processes_cpu_cores"]:
                kept = {
                    "study_wall_s": run.wall_time_s,
                    "per_variant_s": run.wall_time_s / variants,
                    "worker_variant_median_s": statistics.median(r["wall_time_s"] for r in rows),
                    "worker_processes": len({r["worker"] for r in rows}),
                    "failed": run.failed,
                    "lost": run.lost,
                    "failures": [
                        f"{r['twist_deg']} deg, {r['offset_mm']} mm: {r['reason']}" for r in rows if r["status"] != "ok"
                    ],
                    "study_cpu_cores": ours / run.wall_time_s,
                    "study_cpu_per_variant_s": ours / variants,
                    "other_processes_cpu_cores": other,
                    "attempt": attempt,
                }
            if other < QUIET_CORES:
                break
        stats = client.run(_cache_stats)
    finally:
        client.close()
        cluster.close()
    return {
        "workers": workers,
        "start_s": start,
        "first_variant_s": max(first.values()),
        "variants": variants,
        **kept,
        "fe_model_misses_per_worker": sorted(s["fe_models"]["misses"] for s in stats.values()),
    }


def _measured_variant(study: Study, index: int, fixed: bool) -> tuple[float, float, int]:
    """Wall time, system time and minor page faults of variant ``index`` on a worker, run by the runner's task
    (``fixed``, :func:`ffrf.studies.runner._worker_variant`) or by :func:`run_variant` alone."""
    before, started = resource.getrusage(resource.RUSAGE_SELF), time.perf_counter()
    (_worker_variant if fixed else run_variant)(study, study_design(study)[index])
    after = resource.getrusage(resource.RUSAGE_SELF)
    return time.perf_counter() - started, after.ru_stime - before.ru_stime, after.ru_minflt - before.ru_minflt


def nanny_environment(variants: int) -> dict[str, Any]:
    """One worker of a default ``LocalCluster`` (its nanny sets ``MALLOC_TRIM_THRESHOLD_=65536``) running
    :func:`run_variant` as a task, against one of the runner's cluster running its task: per variant, medians over
    ``variants`` warm variants, and the first one (its scene built afresh)."""
    from dask.distributed import Client, LocalCluster

    study = bennett_study(variants + 1, seed=7)
    out: dict[str, Any] = {}
    for name, fixed in (("runner", True), ("default_nanny", False)):
        if fixed:
            client, cluster = _client(None, 1)
        else:
            cluster = LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None)
            client = Client(cluster)
        try:
            runs = [client.submit(_measured_variant, study, k, fixed, pure=False).result() for k in range(variants + 1)]
            environment = next(iter(client.run(os.environ.get, "MALLOC_TRIM_THRESHOLD_").values()))
        finally:
            client.close()
            cluster.close()
        warm = runs[1:]
        out[name] = {
            "worker_MALLOC_TRIM_THRESHOLD_": environment,
            "first_variant_s": runs[0][0],
            "first_variant_system_s": runs[0][1],
            "first_variant_page_faults": runs[0][2],
            "variant_s": statistics.median(r[0] for r in warm),
            "variant_system_s": statistics.median(r[1] for r in warm),
            "variant_page_faults": statistics.median(r[2] for r in warm),
        }
    out["slowdown_first"] = out["default_nanny"]["first_variant_s"] / out["runner"]["first_variant_s"]
    out["slowdown_warm"] = out["default_nanny"]["variant_s"] / out["runner"]["variant_s"]
    return out


def outputs_needed() -> dict[str, Any]:
    """The row's path values of two variants at several output counts, against 1921 outputs, and the run's time."""
    names = ("max_coupler_deviation_m", "max_coupler_distance_to_path_m", "max_abs_driving_torque_Nm")
    study = bennett_study(2, seed=1)
    out: dict[str, Any] = {}
    for variant in study_design(study):
        scene, _ = build_variant(study, variant.values)
        reference = run_linkage(scene, mode="quasi_static", n_outputs=1921, sensors="path").summary()
        for n in (121, 123, 241, 481, 961):
            started = time.perf_counter()
            summary = run_linkage(scene, mode="quasi_static", n_outputs=n, sensors="path").summary()
            elapsed = time.perf_counter() - started
            entry = out.setdefault(str(n), {"outputs": n, "run_s": [], **{f"{k}_error": [] for k in names}})
            entry["run_s"].append(elapsed)
            for name in names:
                entry[f"{name}_error"].append(summary[name] - reference[name])
    for entry in out.values():
        entry["run_s"] = max(entry["run_s"])
        for name in names:
            errors = entry.pop(f"{name}_error")
            entry[f"{name}_largest_error"] = max(abs(e) for e in errors)
            if name == "max_abs_driving_torque_Nm":
                entry["max_abs_driving_torque_largest_error_rel"] = entry[f"{name}_largest_error"] / abs(
                    reference[name]
                )
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, required=True)
    parser.add_argument("--warm", type=int, default=15, help="warm variants in one process (each loop)")
    parser.add_argument("--variants", type=int, default=40, help="variants per Dask run")
    parser.add_argument("--workers", type=int, nargs="*", default=[1, 2, 4, 8])
    parser.add_argument("--nanny-variants", type=int, default=8, help="warm variants of the nanny comparison")
    parser.add_argument("--attempts", type=int, default=2, help="timed Dask runs at most, until one is quiet")
    args = parser.parse_args()
    report: dict[str, Any] = {"cpu_count": os.cpu_count(), "quiet_cores": QUIET_CORES}
    with tempfile.TemporaryDirectory() as folder:  # first: the most sensitive to other processes
        report["dask"] = {str(w): through_dask(w, args.variants, Path(folder), args.attempts) for w in args.workers}
    report["other_processes_cpu_cores_before_in_process"] = wait_for_quiet(WAIT_S)
    report["in_process"] = in_process(args.warm, 121)
    # One equilibrium per output (0.5 s apart, the 3 deg cap) instead of two: cheaper, but does every path pass?
    report["in_process_123_outputs"] = in_process(args.warm, 123)  # its first variant finds the cache warm
    report["outputs"] = outputs_needed()
    # Last: a default LocalCluster's nanny also sets the variable in this process's environment.
    report["nanny_environment"] = nanny_environment(args.nanny_variants)
    dask = report["dask"]
    one = dask["1"]["per_variant_s"] if "1" in dask else None
    if one is not None:
        report["scaling"] = {
            key: {"speedup": one / d["per_variant_s"], "efficiency": one / (d["workers"] * d["per_variant_s"])}
            for key, d in dask.items()
        }
    if "2" in dask:
        two = dask["2"]
        total = two["start_s"] + two["first_variant_s"] + VARIANTS * two["per_variant_s"]
        report["projection"] = {
            "variants": VARIANTS,
            "workers": 2,
            "total_s": total,
            "total_min": total / 60.0,
            "target_s": TARGET_S,
            "over_target": total / TARGET_S,
            "per_variant_needed_s": (TARGET_S - two["start_s"] - two["first_variant_s"]) / VARIANTS,
        }

    write_report(report, args.json)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
