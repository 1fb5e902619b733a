"""Run pytest and write what the run found as a small JSON file.

    python scripts/pytest_summary.py OUT.json [--coverage COVERAGE.json] -- PYTEST ARGS...

``OUT.json`` gets the number of tests per outcome (passed, failed, error, skipped, xfailed, xpassed,
deselected), collection errors, the ids of the failing tests, pytest's exit status and the wall time.
With ``--coverage``, the JSON report coverage.py wrote there (``--cov-report=json:COVERAGE.json``
among the pytest arguments) is summarised too: statements, covered statements and percent, in total
and per package (the dotted name of a file's folder).

Run under ``scripts/record.py``, which adds the commit, machine and date (``scripts/run-slow-tests.sh``,
``scripts/coverage.sh``). Exits with pytest's status.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import Counter
from pathlib import Path

import pytest


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


def coverage_summary(report: dict) -> dict[str, object]:
    """Total and per-package statement coverage from coverage.py's JSON ``report``."""
    packages: dict[str, Counter[str]] = {}
    for path, data in report["files"].items():
        package = ".".join(Path(path).parent.parts) or "."
        counts = packages.setdefault(package, Counter())
        counts["statements"] += data["summary"]["num_statements"]
        counts["covered"] += data["summary"]["covered_lines"]

    def percent(counts: Counter[str] | dict) -> dict[str, object]:
        total, covered = counts["statements"], counts["covered"]
        return {"statements": total, "covered": covered, "percent": round(100 * covered / total, 1) if total else None}

    totals = report["totals"]
    return {
        "total": percent({"statements": totals["num_statements"], "covered": totals["covered_lines"]}),
        "packages": {name: percent(packages[name]) for name in sorted(packages)},
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path, help="the JSON summary to write")
    parser.add_argument("--coverage", type=Path, help="coverage.py's JSON report to summarise as well")
    argv = list(sys.argv[1:] if argv is None else argv)
    split = argv.index("--") if "--" in argv else len(argv)
    args, pytest_args = parser.parse_args(argv[:split]), argv[split + 1 :]

    outcomes = Outcomes()
    started = time.perf_counter()
    status = int(pytest.main(list(pytest_args), plugins=[outcomes]))  # pytest adds its addopts to the list
    summary: dict[str, object] = {
        "pytest_args": pytest_args,
        "exit_status": status,
        "duration_s": round(time.perf_counter() - started, 1),
        "counts": dict(sorted(outcomes.counts.items())),
        "failing": outcomes.failing,
    }
    if args.coverage is not None:
        summary["coverage"] = coverage_summary(json.loads(args.coverage.read_text()))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(summary, indent=1) + "\n")
    return status


if __name__ == "__main__":
    sys.exit(main())
