"""Run pytest and keep what the run found as a result file of the docs.

    python scripts/record_tests.py docs/results/NAME.json [--coverage] -- PYTEST ARGS...

runs ``python -m pytest PYTEST ARGS...`` and writes ``{"meta": ..., "results": ...}`` (``docs/architecture.md``,
"Figures in the docs"): the results are the number of tests per outcome (passed, failed, error, skipped, xfailed,
xpassed, deselected, collection errors), the ids of the failing tests, pytest's arguments and exit status and the
wall time; the meta the command, date, machine, versions and git commit (``ffrf/output/provenance.py``).
``--coverage`` measures statement coverage of the packages with numba's JIT off (``NUMBA_DISABLE_JIT=1``, so that
the kernels run, and count, as Python) and adds it in total and per package (a file's folder).

A working tree with uncommitted changes is measured but not recorded: a result file names the commit it measured.
The tests run with a disk cache of built scenes of their own (``FFRF_CACHE_DIR``, a fresh temporary folder).
Exits with pytest's status. Used by ``scripts/run-slow-tests.sh`` and ``scripts/coverage.sh``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: The packages whose coverage ``--coverage`` measures.
PACKAGES = ("kinematics", "ffrf", "identification", "validation")


class Outcomes:
    """A pytest plugin that counts the tests by outcome.

    A test's outcome is its call phase's, or its setup's when the setup failed or skipped; a failing
    teardown makes it an error as well (pytest's own summary counts it the same way).
    """

    def __init__(self) -> None:
        self.counts: Counter[str] = Counter()
        self.failing: list[str] = []

    def pytest_runtest_logreport(self, report: pytest.TestReport) -> None:
        if report.when == "call":
            if hasattr(report, "wasxfail"):
                outcome = "xfailed" if report.skipped else "xpassed" if report.passed else "failed"
            else:
                outcome = report.outcome
        elif report.failed:
            outcome = "error"
        elif report.when == "setup" and report.skipped:
            outcome = "skipped"
        else:
            return
        self.counts[outcome] += 1
        if outcome in ("failed", "error"):
            self.failing.append(report.nodeid)

    def pytest_collectreport(self, report: pytest.CollectReport) -> None:
        if report.failed:
            self.counts["collection_errors"] += 1
            self.failing.append(report.nodeid)

    def pytest_deselected(self, items: list[pytest.Item]) -> None:
        self.counts["deselected"] += len(items)


def run_pytest(out: Path, pytest_args: list[str]) -> int:
    """Run pytest in this process with :class:`Outcomes` and write its summary to ``out``; pytest's status.

    Imports nothing of the project's packages, so that coverage sees them imported by the tests.
    """
    outcomes = Outcomes()
    started = time.perf_counter()
    status = int(pytest.main(list(pytest_args), plugins=[outcomes]))  # pytest adds its addopts to the list
    summary = {
        "pytest_args": pytest_args,
        "exit_status": status,
        "duration_s": round(time.perf_counter() - started, 1),
        "counts": dict(sorted(outcomes.counts.items())),
        "failing": outcomes.failing,
    }
    out.write_text(json.dumps(summary, indent=1) + "\n")
    return status


def coverage_summary(report: dict) -> dict[str, object]:
    """Total and per-package statement coverage from coverage.py's JSON ``report``."""
    packages: dict[str, Counter[str]] = {}
    for path, data in report["files"].items():
        counts = packages.setdefault(".".join(Path(path).parent.parts), Counter())
        counts["statements"] += data["summary"]["num_statements"]
        counts["covered"] += data["summary"]["covered_lines"]

    def percent(statements: int, covered: int) -> dict[str, object]:
        return {
            "statements": statements,
            "covered": covered,
            "percent": round(100 * covered / statements, 1) if statements else None,
        }

    totals = report["totals"]
    return {
        "total": percent(totals["num_statements"], totals["covered_lines"]),
        "packages": {name: percent(c["statements"], c["covered"]) for name, c in sorted(packages.items())},
    }


def report_lines(result: dict) -> list[str]:
    """A result file written by :func:`main` in a few lines of text."""
    meta, summary = result["meta"], result["results"]
    counts = ", ".join(f"{n} {outcome}" for outcome, n in summary["counts"].items())
    git = meta.get("git") or {}
    lines = [f"pytest {' '.join(summary['pytest_args'])}: {counts} in {summary['duration_s']:.0f} s"]
    lines.append(f"commit {git.get('commit')}{' with uncommitted changes' if git.get('dirty') else ''}, {meta['date']}")
    lines += [f"  failing: {nodeid}" for nodeid in summary["failing"]]
    if "coverage" in summary:
        total = summary["coverage"]["total"]
        lines.append(f"coverage: {total['percent']} % of {total['statements']} statements")
        lines += [f"  {name}: {c['percent']} %" for name, c in summary["coverage"]["packages"].items()]
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("result", type=Path, help="the result file to write, docs/results/NAME.json")
    parser.add_argument("--coverage", action="store_true", help="measure statement coverage, JIT off")
    parser.add_argument("--run", action="store_true", help=argparse.SUPPRESS)  # the child: pytest, its summary
    argv = list(sys.argv[1:] if argv is None else argv)
    split = argv.index("--") if "--" in argv else len(argv)
    args, pytest_args = parser.parse_args(argv[:split]), argv[split + 1 :]
    if args.run:
        sys.path.insert(0, str(ROOT))  # as `python -m pytest` from the repository root
        return run_pytest(args.result, pytest_args)

    from ffrf.output.provenance import git_commit, load_average, provenance  # here: the child must not import ffrf

    state = git_commit(ROOT)
    clean = state is not None and not state["dirty"]
    if not clean:
        print(f"record_tests: uncommitted changes in {ROOT}: the run is not recorded in {args.result}")
    with tempfile.TemporaryDirectory(prefix="record-tests-") as folder, tempfile.TemporaryDirectory() as cache:
        out = Path(folder)
        env = {**os.environ, "FFRF_CACHE_DIR": cache}
        extra: list[str] = []
        if args.coverage:
            env["NUMBA_DISABLE_JIT"] = "1"
            extra = [*(f"--cov={package}" for package in PACKAGES), f"--cov-report=json:{out / 'coverage.json'}"]
        command = [sys.executable, __file__, str(out / "summary.json"), "--run", "--", *pytest_args, *extra]
        load, started = load_average(), time.perf_counter()
        subprocess.run(command, cwd=ROOT, env=env)
        wall = time.perf_counter() - started
        summary = json.loads((out / "summary.json").read_text())
        summary["pytest_args"] = pytest_args  # without the coverage options' temporary paths
        if args.coverage:
            summary["coverage"] = coverage_summary(json.loads((out / "coverage.json").read_text()))
    shown = " ".join(["python", *sys.argv] if argv is None else ["python", __file__, *argv])
    meta = provenance(shown.replace(str(ROOT) + "/", ""), load_at_start=load, wall_time_s=wall, root=ROOT)
    meta["exit_status"] = summary["exit_status"]
    if args.coverage:
        meta["environment"] = {"NUMBA_DISABLE_JIT": "1"}
    result = {"meta": meta, "results": summary}
    if clean:
        args.result.parent.mkdir(parents=True, exist_ok=True)
        args.result.write_text(json.dumps(result, indent=1) + "\n")
        print(f"record_tests: {args.result}")
    print("\n".join(report_lines(result)))
    return int(summary["exit_status"])


if __name__ == "__main__":
    sys.exit(main())
