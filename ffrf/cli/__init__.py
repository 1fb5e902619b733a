"""Command line interface: ``python -m ffrf <subcommand> ...``, a thin layer over the facade (:mod:`ffrf.model`).

One module per subcommand (``HELP``, ``configure(parser)``, ``run(args) -> exit status``), registered in
:data:`SUBCOMMANDS` (name -> (help, configure, run)), so others can add theirs without touching the existing ones;
the argument types and rules they share are in :mod:`ffrf.cli.arguments` (:func:`~ffrf.cli.arguments.count_at_least`
and :func:`~ffrf.cli.arguments.number_in` also serve ``python -m validation``), stopping on SIGINT/SIGTERM in
:mod:`ffrf.cli.stop`, and the report of a linkage run in :mod:`ffrf.cli.report`. Exit status: 0 done (and verified),
1 the run stopped, 2 bad input, 3 a check of the run failed, 130 interrupted.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
from collections.abc import Callable, Sequence

from threadpoolctl import threadpool_limits

from ffrf.cli import bennett, compensate, design, export, linkage, mesh, run, study, study_report, warmup
from ffrf.cli.arguments import positive_count
from ffrf.cli.stop import STOP
from ffrf.errors import FEInputError, Interrupted, NewtonDivergence, StaticDivergence
from ffrf.scenes.scene_cache import CACHE_DIR_VARIABLE
from ffrf.solvers.stability import check_judged_at_equilibria

__all__ = ["main", "SUBCOMMANDS"]

#: name -> (help, configure(parser), run(args) -> exit status)
SUBCOMMANDS: dict[str, tuple[str, Callable[[argparse.ArgumentParser], None], Callable[[argparse.Namespace], int]]] = {
    name: (module.HELP, module.configure, module.run)
    for name, module in (
        ("warmup", warmup),
        ("mesh", mesh),
        ("run", run),
        ("bennett", bennett),
        ("linkage", linkage),
        ("export", export),
        ("study", study),
        ("study-report", study_report),
        ("design", design),
        ("compensate", compensate),
    )
}


def main(argv: Sequence[str] | None = None) -> int:
    """Parse ``argv`` (default the command line's), run the subcommand, return its exit status."""
    parser = argparse.ArgumentParser(prog="python -m ffrf", description="In-house flexible multibody solver (FFRF)")
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress")
    parser.add_argument(
        "--blas-threads",
        type=positive_count,
        default=1,
        help="threads of the BLAS library (default 1: our dense matrices are small; bench/blas_threads.py)",
    )
    parser.add_argument(
        "--no-cache",
        action="store_true",
        help=f"build meshes, FE models and reductions afresh, not from the disk cache (as {CACHE_DIR_VARIABLE}=off)",
    )
    sub = parser.add_subparsers(dest="command", required=True)
    for name, (help_text, configure, _run) in SUBCOMMANDS.items():
        configure(sub.add_parser(name, help=help_text))
    args = parser.parse_args(argv)
    if args.no_cache:  # in the environment: every scene cache reads it, also those of the workers a study starts
        os.environ[CACHE_DIR_VARIABLE] = "off"
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING)
    try:
        stability, mode = getattr(args, "stability", False), getattr(args, "mode", None)
        check_judged_at_equilibria(mode or "", stability, "run quasi-statically (drop --dynamic)")
        with threadpool_limits(limits=args.blas_threads, user_api="blas"), STOP.installed():
            return SUBCOMMANDS[args.command][2](args)
    except Interrupted as exc:  # SIGINT or SIGTERM: one line, what was computed is written (ffrf.cli.stop.StopRequest)
        print(exc, file=sys.stderr)
        return 130
    except FEInputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except (StaticDivergence, NewtonDivergence) as exc:  # not bad input: the model's path ends (a fold, a snap)
        print(f"error: the run stopped: {exc}", file=sys.stderr)
        return 1
