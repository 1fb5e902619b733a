"""``python -m ffrf study STUDY.toml``: a tolerance or design study of many linkage variants on Dask
(:mod:`ffrf.studies`, ``docs/studies.md``), its rows and ``report.md`` in ``--out``."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from ffrf.cli.arguments import number_in, output_folder, positive_count
from ffrf.errors import Interrupted, SceneError, SensitivityError
from ffrf.paper.bennett_scene import STUDY_BASES
from ffrf.studies.linear_tolerance import check_linear, linear_report
from ffrf.studies.spec import Study, load_study

__all__ = ["HELP", "configure", "run"]

HELP = "run a tolerance or design study of many linkage variants on Dask (docs/studies.md)"


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("study", type=Path, help="study file (TOML), see ffrf.studies.spec and docs/studies.md")
    parser.add_argument("--out", type=Path, required=True, help="output folder (rows/*.parquet, report.md)")
    parser.add_argument(
        "--scheduler", help="address of a Dask scheduler, e.g. tcp://host:8786 (default: a local cluster)"
    )
    parser.add_argument(
        "--scheduler-file",
        type=Path,
        help="the file a Dask scheduler wrote (dask scheduler --scheduler-file F, as a batch job starts one)",
    )
    parser.add_argument("--workers", type=positive_count, help="worker processes of the local cluster (default: cores)")
    parser.add_argument("--no-report", action="store_true", help="do not write report.md after the run")
    parser.add_argument(
        "--linear",
        action="store_true",
        help="bore-error studies: to first order instead (exact sensitivities of the base path, docs/studies.md): "
        "--prints random prints in seconds, checked against --check prints run in full; writes linear.json",
    )
    parser.add_argument(
        "--second-order",
        action="store_true",
        help="--linear: to second order in the errors (Eq. (D11): k (k + 1) full runs of the base, for k parameters); "
        "the driving torque, of second order in the errors, needs it",
    )
    parser.add_argument("--prints", type=positive_count, default=10**6, help="prints of --linear (default 10^6)")
    parser.add_argument(
        "--check", type=positive_count, default=8, help="prints of the study's design --linear runs in full (default 8)"
    )
    parser.add_argument(
        "--target",
        type=number_in(0.0, math.inf, closed_low=False, unit=" mm"),
        metavar="MM",
        help="--linear: the tolerances that keep the --level percentile of the largest coupler deviation within MM",
    )
    parser.add_argument(
        "--level",
        type=number_in(0.0, 100.0, closed_low=False, unit=" %"),
        default=95.0,
        help="percentile of --target (default 95)",
    )


def run(args: argparse.Namespace) -> int:
    study = load_study(args.study, STUDY_BASES)  # checked before any worker starts
    if args.scheduler is not None and args.scheduler_file is not None:
        raise SceneError("give the scheduler once: --scheduler ADDRESS or --scheduler-file FILE, not both")
    if (args.scheduler is not None or args.scheduler_file is not None) and args.workers is not None:
        raise SceneError("--workers sizes the local cluster; a scheduler (--scheduler) has its own workers")
    if args.scheduler_file is not None:
        from ffrf.studies.runner import check_scheduler_file

        check_scheduler_file(args.scheduler_file)  # before the output folder, as every refusal
    if args.linear:
        try:
            check_linear(study)  # before the output folder: a refused study leaves none behind
        except ValueError as error:
            raise SceneError(str(error)) from None
    out = output_folder(args.out)
    if args.linear:
        return _linear(study, out, args.prints, args.check, args.target, args.level, args.second_order)
    # Dask, pyarrow and matplotlib take seconds to import: only the command that uses them does
    from ffrf.studies.report import write_report
    from ffrf.studies.runner import run_study

    try:
        scheduler_file = None if args.scheduler_file is None else str(args.scheduler_file)
        result = run_study(study, out, scheduler=args.scheduler, workers=args.workers, scheduler_file=scheduler_file)
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


def _linear(study: Study, out: Path, prints: int, checks: int, target: float | None, level: float, second: bool) -> int:
    """``--linear``: the study to first order, or to second (:func:`ffrf.studies.linear_tolerance.linear_report`),
    ``linear.json`` in ``out``; exit 3 when a full run disagrees with the model (the estimate did not check
    itself)."""
    from tqdm import tqdm

    with tqdm(unit="run", desc="second order", disable=not second) as bar:

        def progress(done: int, total: int) -> None:
            bar.total = total
            bar.update(done - bar.n)

        metres = None if target is None else 1e-3 * target
        try:
            report = linear_report(study, prints, checks, metres, level, second, progress)
        except SensitivityError as error:  # the second order's full runs left the base's smooth path
            print(f"error: {error}", file=sys.stderr)
            return 3
    order = "first" if report["order"] == 1 else "second"
    second_s = report["seconds"].get("second_order")
    path = out / "linear.json"
    path.write_text(json.dumps(report, indent=2) + "\n")
    p = report["max_coupler_deviation_m"]
    print(
        f"{study.name}, to {order} order: {prints} prints in {report['seconds']['prints']:.2f} s (base run "
        f"{report['seconds']['base_run']:.1f} s, sensitivities {report['seconds']['sensitivities']:.1f} s"
        + ("" if second_s is None else f", second order {second_s:.1f} s")
        + "); largest "
        "coupler deviation "
        + ", ".join(
            f"{name} {1e3 * v['value']:.4g} mm [{_mm(v['low'], '-inf')}, {_mm(v['high'], 'inf')}]"
            for name, v in p.items()
        )
        + f" -> {path}"
    )
    torque = report["max_abs_driving_torque_Nm"]
    print(
        f"largest driving torque: {torque['refused']}: not given to {order} order"
        if "refused" in torque
        else "largest driving torque " + ", ".join(f"{name} {1e3 * v['value']:.4g} N mm" for name, v in torque.items())
    )
    allocation = report.get("allocation")
    if allocation is not None:
        print(
            f"p{level:g} of the largest deviation within {target:g} mm: every tolerance times "
            f"{allocation['common_factor']:.3g} at once, or with equal effect "
            f"({1e3 * allocation['equal_move_m']:.3g} mm per standard deviation) the stds "
            + ", ".join(f"{name} {a['equal_effect_std']:.3g}" for name, a in allocation["per_parameter"].items())
        )
    worst = max(report["checks"], key=lambda row: row["relative_difference"])
    verdict = (
        f"verified: true ({len(report['checks'])} prints run in full within {100 * report['check_tolerance']:g} % of "
        f"the model; largest difference {100 * worst['relative_difference']:.2g} %)"
        if report["verified"]
        else f"verified: false: print {worst['id']} run in full deviates {1e3 * worst['full_m']:.4g} mm, the model "
        f"says {1e3 * worst['linear_m']:.4g} mm ({100 * worst['relative_difference']:.2g} %): the errors are too large "
        f"for the {order} order; run the study in full"
    )
    print(verdict)
    return 0 if report["verified"] else 3


def _mm(value: float | None, unbounded: str) -> str:
    """A length in mm for a line, or ``unbounded`` where an interval has no end."""
    return unbounded if value is None else f"{1e3 * value:.4g}"
