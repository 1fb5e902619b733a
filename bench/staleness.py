"""Which result files of the docs are older than the code they measure.

A result file ``docs/results/NAME.json`` names in its meta the commit it was recorded at and whether the tree was
clean (``ffrf/output/provenance.py``). It is stale when

* it was recorded from a dirty tree (or its meta does not say), so no commit holds the code it measured;
* a path its benchmark measures (``bench/registry.py``: the packages, the benchmark's own module) changed between
  that commit and ``HEAD`` (``git diff <commit> HEAD -- <paths>``);
* its commit is not in this repository, or no benchmark of the registry records it.

``python -m bench stale`` lists them with the reason; docs' figures may still agree with the files
(``scripts/update_docs.py --check``), this says whether the files agree with today's code.
"""

from __future__ import annotations

import json
import subprocess
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path

from bench import ROOT
from bench.registry import recordings

__all__ = ["Stale", "stale_results"]


@dataclass(frozen=True)
class Stale:
    """A result file older than the code it measures, and why."""

    path: Path
    reason: str

    def __str__(self) -> str:
        return f"{self.path.name}: {self.reason}"


def _git(root: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(["git", *args], cwd=root, capture_output=True, text=True)


def _changed(root: Path, commit: str, paths: Iterable[str]) -> list[str]:
    """The files under ``paths`` that differ between ``commit`` and ``HEAD``."""
    diff = _git(root, "diff", "--name-only", commit, "HEAD", "--", *paths)
    return diff.stdout.split()


def why_stale(path: Path, sources: tuple[str, ...] | None, root: Path = ROOT) -> str | None:
    """Why the result file ``path`` is older than the code at ``sources`` (repository paths), or None if it is not.

    ``sources`` None: no benchmark records the file.
    """
    if sources is None:
        return "no benchmark in bench/registry.py records it"
    try:
        git = json.loads(path.read_text()).get("meta", {}).get("git")
    except (OSError, ValueError, AttributeError) as error:
        return f"no readable meta ({error})"
    if not isinstance(git, dict) or not git.get("commit"):
        return "its meta names no commit"
    commit = str(git["commit"])
    if git.get("dirty") is None:
        return f"recorded at {commit[:10]} from a tree not known to be clean"
    if git["dirty"]:
        return f"recorded from a dirty tree (uncommitted changes on {commit[:10]})"
    if _git(root, "cat-file", "-e", f"{commit}^{{commit}}").returncode != 0:
        return f"commit {commit[:10]} is not in this repository"
    changed = _changed(root, commit, sources)
    if changed:
        shown = ", ".join(changed[:3]) + (f" and {len(changed) - 3} more" if len(changed) > 3 else "")
        return f"{len(changed)} measured files changed since {commit[:10]}: {shown}"
    return None


def stale_results(
    results_dir: Path = ROOT / "docs" / "results",
    sources: Mapping[str, tuple[str, ...]] | None = None,
    root: Path = ROOT,
) -> list[Stale]:
    """Every result file of ``results_dir`` older than the code it measures, in name order.

    ``sources``: result stem -> the repository paths it measures (default: from ``bench/registry.py``).
    """
    if sources is None:
        sources = {stem: entry.sources() for stem, (entry, _) in recordings().items()}
    found = []
    for path in sorted(results_dir.glob("*.json")):
        reason = why_stale(path, sources.get(path.stem), root)
        if reason is not None:
            found.append(Stale(path, reason))
    return found
