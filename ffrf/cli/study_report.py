"""``python -m ffrf study-report FOLDER``: ``report.md`` of a study's rows (percentiles, sensitivities)."""

from __future__ import annotations

import argparse
from pathlib import Path

from ffrf.errors import SceneError

__all__ = ["HELP", "configure", "run"]

HELP = "write report.md of a study's rows (percentiles, sensitivities)"


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("folder", type=Path, help="a study's output folder (python -m ffrf study ... --out FOLDER)")


def run(args: argparse.Namespace) -> int:
    from ffrf.studies.report import write_report  # pyarrow and matplotlib: only the command that uses them

    if not (args.folder / "study.json").is_file():
        raise SceneError(f"{args.folder} holds no study (no study.json); give the --out folder of python -m ffrf study")
    try:
        path = write_report(args.folder)
    except FileNotFoundError as error:
        raise SceneError(str(error)) from error
    print(f"report: {path}")
    return 0
