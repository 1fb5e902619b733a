"""Run a registered benchmark and keep what it measured as a result file of the docs.

``python -m bench record RESULT`` runs the recording of ``docs/results/RESULT.json`` listed in
``bench/registry.py`` (``python`` is this interpreter), reads the JSON the command wrote (one file: its content;
several: ``{file stem: content}``) and writes ``{"meta": ..., "results": ...}``: the command, the UTC date, the
machine (CPU, cores, load averages at start and end), the versions of the installed packages and the git commit
(``ffrf/output/provenance.py``). The numbers in ``README.md`` and ``docs/*.md`` are links into these files;
``scripts/update_docs.py`` rewrites them from the files.

A recording refuses a working tree with uncommitted changes: the commit in its meta must be the code it measured,
which is what ``python -m bench stale`` compares with today's code. The command runs with a disk cache of built
scenes of its own (``FFRF_CACHE_DIR``, a fresh temporary folder), so that what it measures does not depend on an
earlier run's cache; a benchmark that measures the cache sets it itself.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from bench import ROOT
from bench.registry import Benchmark, Recording
from ffrf.output.provenance import git_commit, load_average, provenance

__all__ = ["DirtyTree", "keyed_rows", "record", "require_clean_tree"]


class DirtyTree(RuntimeError):
    """The repository has uncommitted changes to tracked files: a recording would not name the code it measured."""


def require_clean_tree(root: Path = ROOT) -> dict[str, object]:
    """The ``{"commit", "dirty"}`` of ``root``; :class:`DirtyTree` unless it is a clean git working tree."""
    state = git_commit(root)
    if state is None:
        raise DirtyTree(f"{root} is not a git working tree: a recording must name the commit it measured")
    if state["dirty"]:
        raise DirtyTree(
            f"uncommitted changes in {root} (git status): commit or stash them, then record again; "
            "a result file names the commit it measured"
        )
    return state


def keyed_rows(value: Any, field: str, name: str) -> Any:
    """``value`` with every list of dicts under a key ``rows`` keyed by ``field`` and renamed ``name``."""
    if isinstance(value, dict):
        out = {}
        for key, item in value.items():
            if key == "rows" and isinstance(item, list) and all(isinstance(r, dict) and field in r for r in item):
                out[name] = {str(r[field]): keyed_rows(r, field, name) for r in item}
            else:
                out[key] = keyed_rows(item, field, name)
        return out
    if isinstance(value, list):
        return [keyed_rows(v, field, name) for v in value]
    return value


def command_line(entry: Benchmark, recording: Recording, out: Path) -> list[str]:
    """The recording's command (``python -m MODULE ARGS``) with its output folder ``out``."""
    return [sys.executable, "-m", entry.runnable, *(arg.replace("{out}", str(out)) for arg in recording.args)]


#: Run before every recording, untimed: numba's kernels compiled (or loaded) into the cache the command then uses, so
#: that no figure counts their first compilation (a cold cache put 24 s of it into a 6 s revolution). Benchmarks
#: that time compilation give their runs a fresh cache of their own.
WARM_UP = ("-m", "ffrf", "warmup")


def record(
    entry: Benchmark,
    recording: Recording,
    results_dir: Path = ROOT / "docs" / "results",
    root: Path = ROOT,
    warm_up: tuple[str, ...] = WARM_UP,
) -> Path:
    """Run ``recording`` of ``entry`` from the clean working tree ``root`` and write its result file; its path.
    ``warm_up``: the arguments of ``python`` run first, with the same environment (:data:`WARM_UP`; empty: none).

    Raises :class:`DirtyTree` before running anything if the tree has uncommitted changes, ValueError if the
    recording has no recipe or its command wrote none of its outputs.
    """
    if recording.recipe_missing:
        raise ValueError(f"{recording.result} cannot be recorded by the runner: {recording.recipe_missing}")
    require_clean_tree(root)
    with tempfile.TemporaryDirectory(prefix="bench-") as folder, tempfile.TemporaryDirectory(prefix="ffrf-") as cache:
        out = Path(folder)
        command = command_line(entry, recording, out)
        shown = " ".join([*recording.env, "python", *command[1:]]).replace(str(out), "OUT")
        own = {name: value for name, _, value in (item.partition("=") for item in recording.env)}
        env = {**os.environ, "FFRF_CACHE_DIR": cache, **own}
        if warm_up:
            subprocess.run([sys.executable, *warm_up], cwd=root, env=env, stdout=subprocess.DEVNULL, check=True)
        load = load_average()
        started = time.perf_counter()
        status = subprocess.run(command, cwd=root, env=env).returncode
        wall = time.perf_counter() - started
        missing = [name for name in recording.outputs if not (out / name).is_file()]
        if missing:
            raise ValueError(f"{shown} wrote no {', '.join(missing)} (exit status {status}); nothing recorded")
        found = {Path(name).stem: json.loads((out / name).read_text()) for name in recording.outputs}
    results: Any = next(iter(found.values())) if len(found) == 1 else found
    if recording.select:
        results = {key: results[key] for key in recording.select if key in results}
    if recording.rows_by:
        results = keyed_rows(results, recording.rows_by, recording.rows_name)
    meta = provenance(shown, load_at_start=load, wall_time_s=wall, root=root)
    meta["exit_status"] = status
    path = results_dir / f"{recording.result}.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps({"meta": meta, "results": results}, indent=1) + "\n")
    return path
