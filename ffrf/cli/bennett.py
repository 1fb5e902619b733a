"""``python -m ffrf bennett``: the paper's flexible Bennett linkage (a variant), run and reported as every linkage
(:func:`ffrf.cli.report.run_and_report`)."""

from __future__ import annotations

import argparse
import sys
import time

from ffrf.cli.arguments import check_run_length, configure_linkage_run, output_folder, run_options
from ffrf.cli.report import run_and_report
from ffrf.model import load
from ffrf.paper.bennett_scene import build_bennett, paper_max_coupler_deviation

__all__ = ["HELP", "configure", "run"]

HELP = "simulate the paper's flexible Bennett linkage and write its sensors"


def configure(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--variant",
        choices=("rigid", "pla", "pla1", "pla2"),
        default="pla",
        help="paper's variant: rigid, PLA, PLA with alpha_3 = 91 or 92 deg",
    )
    parser.add_argument(
        "--links-at-joint-points",
        dest="collision_free",
        action="store_false",
        help="housings centred on the joint points (links that pass through each other) instead of the default "
        "collision-free stacking, where every two links keep 1 mm along the revolution",
    )
    configure_linkage_run(parser)


def run(args: argparse.Namespace) -> int:
    started = time.perf_counter()
    check_run_length(args)
    output_folder(args.out)
    print(
        f"Building the {args.variant} Bennett scene: 4 links, h = {1e3 * args.h:g} mm, P{args.order}, "
        f"{args.modes} fixed-interface modes per link ...",
        file=sys.stderr,
    )
    scene = build_bennett(
        args.variant,
        h=args.h,
        order=args.order,
        n_modes=args.modes,
        joint_offsets=args.joint_offsets,
        collision_free=args.collision_free,
    )
    return run_and_report(
        load(scene), args.out, args.variant, started, run_options(args), paper_max_coupler_deviation(args.variant)
    )
