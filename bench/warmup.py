"""First-run compilation (issue #22): ``python -m ffrf warmup`` and the main job's Bennett run, each as a fresh
process with numba's cache in a fresh folder (cold: every kernel compiles) and again (warm: loaded from the cache),
and the main run after a cold warmup (does the warmup cover what the main job compiles?). Each numba cache folder
has a scene cache folder of its own (``FFRF_CACHE_DIR``), empty at first as on a fresh install: a warm run also
reads its meshes, FE models and reductions from disk.

Usage::

    .venv/bin/python -m bench warmup --json out/warmup.json
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench import ROOT
from bench.report import write_report

WARMUP = [sys.executable, "-m", "ffrf", "warmup"]


def timed(command: list[str], cache: Path) -> float:
    """Wall time (s) of ``command`` in a fresh process, numba's cache in ``cache``, the scene cache next to it."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache), FFRF_CACHE_DIR=f"{cache}_scenes", PYTHONPATH=str(ROOT))
    started = time.perf_counter()
    subprocess.run(command, cwd=ROOT, env=env, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - started


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", type=Path, required=True)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        base = Path(folder)
        main_run = [sys.executable, "-m", "ffrf", "bennett", "--variant", "pla", "--out", str(base / "out")]
        report = {
            "main_job_command": "python -m ffrf bennett --variant pla",
            "main_cold_s": timed(main_run, base / "cache_a"),
            "main_warm_s": timed(main_run, base / "cache_a"),
            "warmup_cold_s": timed(WARMUP, base / "cache_b"),
            "warmup_warm_s": timed(WARMUP, base / "cache_b"),
            "main_after_warmup_s": timed(main_run, base / "cache_b"),
            "cpu_count": os.cpu_count(),
        }
    write_report(report, args.json)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
