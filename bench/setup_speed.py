"""Set-up of the default scene (issue #22): ``build_bennett("pla")`` (P2 tetrahedra, h = 6 mm, 4 fixed-interface modes
per link) in a fresh process, cold (empty disk cache: gmsh, scikit-fem, Craig-Bampton, the rigid loop) and warm (a
second process reading the scene cache's disk files), with the cold build's breakdown by stage.

Each run is a new process (``--child``) with the scene cache in a folder of this benchmark's own
(``FFRF_CACHE_DIR``): ``cold_no_cache`` with the disk cache off, ``cold`` writing it, ``warm`` reading it. The
stages are timed by wrapping the functions that do them (the same functions the build calls), each call's wall time
added up: ``bodies_s`` is the wall time of meshing, assembling and reducing all the bodies together, the reductions
running in threads (``ffrf.scenes.builder.REDUCTION_THREADS``) while the next bodies are meshed, so the stages inside
it (meshing, assembly, Craig-Bampton and its parts) add up the threads' times and may exceed it; ``import_s`` is the
import of the solver, outside the build.

Usage::

    .venv/bin/python -m bench setup_speed --json out/setup_speed.json
"""

from __future__ import annotations

import argparse
import functools
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

from bench import ROOT
from bench.memory_probe import SETUP_STAGES
from bench.report import write_report

#: (module, function, stage): the functions whose time makes the stages of a cold build (keys in s).
STAGES = tuple(
    (module, name, f"{stage}_s")
    for module, name, stage in (("ffrf.scenes.builder", "_meshed_and_reduced", "bodies"), *SETUP_STAGES)
)


def _timed_stages() -> dict[str, float]:
    """Wrap every function of :data:`STAGES` so that its calls add their wall time to the returned dict."""
    import importlib

    seconds: dict[str, float] = defaultdict(float)
    for module_name, name, stage in STAGES:
        module = importlib.import_module(module_name)
        function = getattr(module, name)

        def timed(*args, _function=function, _stage=stage, **kwargs):
            started = time.perf_counter()
            try:
                return _function(*args, **kwargs)
            finally:
                seconds[_stage] += time.perf_counter() - started

        setattr(module, name, functools.wraps(function)(timed))
    return seconds


def child() -> None:
    """One build in this process; print its times and the cache's counts as JSON."""
    started = time.perf_counter()
    from ffrf.paper.bennett_scene import build_bennett
    from ffrf.scenes.scene_cache import PROCESS_CACHE

    imported = time.perf_counter()
    seconds = _timed_stages()
    build_bennett("pla")
    built = time.perf_counter()
    report = {"import_s": imported - started, "build_s": built - imported, "stages": dict(seconds)}
    print(json.dumps(dict(report, cache=PROCESS_CACHE.stats())))


def run(cache: str) -> dict:
    """A build in a new process with ``FFRF_CACHE_DIR=cache``."""
    env = dict(os.environ, FFRF_CACHE_DIR=cache, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1")
    out = subprocess.run(
        [sys.executable, "-m", "bench.setup_speed", "--child"],
        cwd=ROOT,
        env=env,
        check=True,
        capture_output=True,
        text=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def _load() -> list[float]:
    return [float(x) for x in Path("/proc/loadavg").read_text().split()[:3]] if Path("/proc/loadavg").exists() else []


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, required=True)
    parser.add_argument("--repeats", type=int, default=3, help="runs of each kind (the median is reported)")
    args = parser.parse_args()
    runs: dict[str, list[dict]] = {"cold_no_cache": [], "cold": [], "warm": []}
    load_start = _load()
    for _ in range(args.repeats):
        runs["cold_no_cache"].append(run("off"))
        with tempfile.TemporaryDirectory(prefix="ffrf-setup-") as folder:
            runs["cold"].append(run(folder))
            runs["warm"].append(run(folder))
            disk_mb = sum(p.stat().st_size for p in Path(folder).iterdir()) / 1e6
    report = {
        "scene": 'build_bennett("pla"): P2, h = 6 mm, 4 fixed-interface modes per link',
        "repeats": args.repeats,
        "load_average_start": load_start,
        "load_average_end": _load(),
        "cache_disk_mb": disk_mb,
    }
    for kind, measured in runs.items():
        builds = [r["build_s"] for r in measured]
        report[f"{kind}_build_s"] = statistics.median(builds)
        report[f"{kind}_build_all_s"] = builds
        report[f"{kind}_import_s"] = statistics.median(r["import_s"] for r in measured)
    report["cold_stages_s"] = {
        stage: statistics.median(r["stages"].get(stage, 0.0) for r in runs["cold_no_cache"]) for *_, stage in STAGES
    }
    report["warm_cache"] = runs["warm"][-1]["cache"]
    write_report(report, args.json)
    return 0


if __name__ == "__main__":
    if "--child" in sys.argv:
        child()
        raise SystemExit(0)
    raise SystemExit(main())
