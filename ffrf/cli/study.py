"""``python -m ffrf study STUDY.toml``: a tolerance or design study of many linkage variants on Dask
(:mod:`ffrf.studies`, ``docs/studies.md``), its rows and ``report.md`` in ``--out``."""

from __future__ import annotations

import argparse
from pathlib import Path

from ffrf.cli.arguments import output_folder, positive_count
from ffrf.errors import Interrupted, SceneError
from ffrf.paper.bennett_scene import STUDY_BASES
from ffrf.studies.spec import load_study

__all__ = ["HELP", "configure", "run"]

HELP = "run a tolerance or design study of many linkage variants on Dask (docs/studies.md)"


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("study", type=Path, help="study file (TOML), see ffrf.studies.spec and docs/studies.md")
    parser.add_argument("--out", type=Path, required=True, help="output folder (rows/*.parquet, report.md)")
    parser.add_argument(
        "--scheduler", help="address of a Dask scheduler, e.g. tcp://host:8786 (default: a local cluster)"
    )
    parser.add_argument("--workers", type=positive_count, help="worker processes of the local cluster (default: cores)")
    parser.add_argument("--no-report", action="store_true", help="do not write report.md after the run")


def run(args: argparse.Namespace) -> int:
    study = load_study(args.study, STUDY_BASES)  # checked before any worker starts
    if args.scheduler is not None and args.workers is not None:
        raise SceneError("--workers sizes the local cluster; a scheduler (--scheduler) has its own workers")
    out = output_folder(args.out)
    # Dask, pyarrow and matplotlib take seconds to import: only the command that uses them does
    from ffrf.studies.report import write_report
    from ffrf.studies.runner import run_study

    try:
        result = run_study(study, out, scheduler=args.scheduler, workers=args.workers)
    except Interrupted as error:  # the rows of the finished variants are written (run_study's finally)
        message = f"{error}: the finished variants' rows are in {out}; the same command runs the rest"
        raise Interrupted(message) from None
    print(
        f"{study.name}: {result.design} variants, {result.skipped} finished before, {result.ok} ok and "
        f"{result.failed} failed now, {result.lost} lost (a rerun runs them); {result.wall_time_s:.1f} s -> {out}"
    )
    if not args.no_report:
        print(f"report: {write_report(out)}")
    return 1 if result.lost else 0
