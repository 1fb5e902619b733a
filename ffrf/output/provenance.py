"""Provenance of a measured result: what ran, when, where and with which versions.

Every figure in the README and ``docs/`` links to a result file ``docs/results/NAME.json`` of the
form ``{"meta": provenance(...), "results": {...}}`` (``docs/architecture.md``, "Figures in the
docs"). Versions are read from the installed distributions with :mod:`importlib.metadata`, so this
module imports none of the packages it reports (in particular not Exudyn).
"""

from __future__ import annotations

import os
import platform
import subprocess
import sys
from datetime import UTC, datetime
from importlib import metadata
from pathlib import Path

__all__ = ["DISTRIBUTIONS", "cpu_model", "git_commit", "load_average", "provenance", "versions"]

#: Distributions whose versions a result file records (those not installed are left out).
DISTRIBUTIONS = ("numpy", "scipy", "scikit-fem", "numba", "gmsh", "meshio", "exudyn", "ngsolve")


def versions(distributions=DISTRIBUTIONS) -> dict[str, str]:
    """Python's version and those of the installed ``distributions``."""
    found = {"python": platform.python_version()}
    for name in distributions:
        try:
            found[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            continue
    return found


def cpu_model() -> str:
    """The CPU's model name (``/proc/cpuinfo``; ``platform.processor()`` elsewhere)."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def load_average() -> list[float] | None:
    """The 1, 5 and 15 minute load averages, or None where the system has none."""
    try:
        return [round(x, 2) for x in os.getloadavg()]
    except (AttributeError, OSError):
        return None


#: Tracked paths whose changes leave a tree clean for :func:`git_commit`: the measured results themselves, so that the
#: result files of one commit can be recorded one after another (``python -m bench record``).
RESULTS_PATHSPEC = ":(exclude)docs/results"


def git_commit(root: Path | None = None) -> dict[str, object] | None:
    """``{"commit": HEAD, "dirty": tracked files differ from HEAD}`` of the repository at ``root``; changed result
    files (``docs/results/``) do not count: they are what a measurement writes, not code it runs."""
    root = root or Path(__file__).resolve().parents[2]
    try:
        head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=root, capture_output=True, text=True, check=True)
        diff = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no", "--", ".", RESULTS_PATHSPEC],
            cwd=root,
            capture_output=True,
            text=True,
            check=True,
        )
    except (OSError, subprocess.CalledProcessError):
        return None
    return {"commit": head.stdout.strip(), "dirty": bool(diff.stdout.strip())}


def provenance(
    command: list[str] | str | None = None,
    load_at_start: list[float] | None = None,
    wall_time_s: float | None = None,
    root: Path | None = None,
) -> dict[str, object]:
    """The ``meta`` block of a result file.

    Parameters
    ----------
    command : the command that measured the results (default: this process's ``sys.argv``).
    load_at_start : load averages when the measurement started (the load at the end is read now).
    wall_time_s : wall time of the whole measurement (s).
    root : the working tree whose code ran (default: the one this module is imported from, which differs where a
        clone shares another tree's environment and its editable install).
    """
    if command is None:
        command = [Path(sys.executable).name, *sys.argv]
    meta: dict[str, object] = {
        "command": command if isinstance(command, str) else " ".join(command),
        "date": datetime.now(UTC).isoformat(timespec="seconds"),
        "machine": {
            "cpu": cpu_model(),
            "cores": os.cpu_count(),
            "load_average_start": load_at_start,
            "load_average_end": load_average(),
        },
        "versions": versions(),
        "git": git_commit(root),
    }
    if wall_time_s is not None:
        meta["wall_time_s"] = round(wall_time_s, 1)
    return meta
